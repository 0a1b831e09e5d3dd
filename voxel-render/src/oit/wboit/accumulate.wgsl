// Weighted blended OIT, accumulation (appended to common.wgsl and the constants made in
// Rust: WEIGHT_* ids, WEIGHT_ANY, WEIGHT_SPECIALISED, TILES, PROFILE_LEN, TABLE_VEC4S,
// MAX_FITTED_DEPTH). McGuire & Bavoil 2013.
//
// accumulation (RGBA16F, blend ONE, ONE on all channels) += (C·α, α) · w · scale
// revealage    (R8,      blend ZERO, ONE_MINUS_SRC)     *= (1 − α)
//
// `scale` (params.accum_scale) keeps fp16 sums finite; it cancels in the composite's ratio.

// The technique's own uniforms (`WboitParams` in mod.rs, checked equal by a test).
struct WboitParams {
    weight_fn: u32,
    accum_scale: f32,
    // Nearest and farthest view depth of the visible translucent chunks (fitted weight).
    depth_range: vec2<f32>,
    // Optical depth of a layer of the eye's medium (fitted weight; 0 in air).
    medium_depth: f32,
    // ln of the range's near end, and (PROFILE_LEN - 1) / ln(far / near): the table's index
    // is an affine function of ln(depth), one log per fragment (fitted weight).
    log_near: f32,
    log_scale: f32,
    // Per screen tile, the optical depth in front of log-spaced depths (fitted weight).
    optical_depth: array<vec4<f32>, TABLE_VEC4S>,
};

@group(2) @binding(0) var<uniform> params: WboitParams;

// Standard (not reversed) window depth in [0, 1], 0 at the near plane, from the reverse-Z
// fragment depth: the `gl_FragCoord.z` of the published weight functions.
fn standard_depth(frag_z: f32) -> f32 {
    return 1.0 - frag_z;
}

// Weight functions: the same formulas as `weights.rs` (unit-tested there, and a GPU test
// checks this shader against them).
fn cube(x: f32) -> f32 {
    return x * x * x;
}

// The eye's medium in front of a fragment: its surface (the way out) dims every fragment
// behind the first medium surface at the pixel (`medium.rs`).
fn medium_in_front(pixel: vec2<f32>, frag_z: f32) -> f32 {
    if frame.medium == NO_MEDIUM || frag_z >= boundary_depth(pixel) {
        return 0.0;
    }
    return params.medium_depth;
}

// The weight in force: the one a chunk pipeline was built for (WEIGHT_SPECIALISED, a
// constant, so that the driver keeps only that case of the switch below: a CPU rasteriser
// runs every case of a switch on a uniform, masked), or the uniform's in games' pipelines.
fn weight_id() -> u32 {
    if WEIGHT_SPECIALISED == WEIGHT_ANY {
        return params.weight_fn;
    }
    return WEIGHT_SPECIALISED;
}

fn weight(pixel: vec2<f32>, frag_z: f32, z: f32, depth: f32, a: f32) -> f32 {
    let d = abs(depth);
    switch weight_id() {
        case WEIGHT_FLAT: {
            let zz = clamp(z, 1e-5, 3e4);
            return clamp(a * max(1e-2, 3e3 * cube(1.0 - zz * 0.001)), 1e-2, 3e4);
        }
        case WEIGHT_ALPHA_CUBED: {
            return clamp(cube(a) * 3000.0 * cube(1.0 - z), 0.01, 3000.0);
        }
        case WEIGHT_EQ7: {
            let q = d / 5.0;
            return a * clamp(10.0 / (1e-5 + q * q + pow(d / 200.0, 6.0)), 1e-2, 3e3);
        }
        case WEIGHT_EQ8: {
            return a * clamp(10.0 / (1e-5 + cube(d / 10.0) + pow(d / 200.0, 6.0)), 1e-2, 3e3);
        }
        case WEIGHT_EQ9: {
            return a * clamp(0.03 / (1e-5 + pow(d / 200.0, 4.0)), 1e-2, 3e3);
        }
        case WEIGHT_EQ10: {
            return a * max(1e-2, 3e3 * cube(1.0 - z));
        }
        default: {
            // WEIGHT_FITTED: the estimated transmittance in front of the fragment.
            return 3e3 * exp(-optical_depth_at(pixel, d) - medium_in_front(pixel, frag_z));
        }
    }
}

// WeightFit::optical_depth_at in fit.rs: the tables of the four screen tiles around the
// fragment, interpolated in log depth, then between the tiles' centres.
fn table(tile: vec2<u32>, k: u32) -> f32 {
    let i = (tile.y * TILES + tile.x) * PROFILE_LEN + k;
    return params.optical_depth[i / 4u][i % 4u];
}

fn tile_depth(tile: vec2<u32>, k: u32, t: f32) -> f32 {
    return mix(table(tile, k), table(tile, k + 1u), t);
}

fn optical_depth_at(pixel: vec2<f32>, d: f32) -> f32 {
    let last_k = f32(PROFILE_LEN - 1u);
    let x = clamp((log(d) - params.log_near) * params.log_scale, 0.0, last_k);
    let k = min(u32(floor(x)), PROFILE_LEN - 2u);
    let t = x - f32(k);
    let last = f32(TILES - 1u);
    let p = clamp(pixel / frame.viewport * f32(TILES) - 0.5, vec2<f32>(0.0), vec2<f32>(last));
    let t0 = min(vec2<u32>(floor(p)), vec2<u32>(TILES - 2u));
    let s = p - vec2<f32>(t0);
    let top = mix(tile_depth(t0, k, t), tile_depth(t0 + vec2<u32>(1u, 0u), k, t), s.x);
    let bottom = mix(
        tile_depth(t0 + vec2<u32>(0u, 1u), k, t),
        tile_depth(t0 + vec2<u32>(1u, 1u), k, t),
        s.x,
    );
    return min(mix(top, bottom, s.y), MAX_FITTED_DEPTH);
}

// The weighted, premultiplied contribution of colour `c` (straight, alpha its opacity) at
// `position` (a fragment's) and `view_depth`: what the accumulation target sums.
fn wboit_accumulation(position: vec4<f32>, view_depth: f32, c: vec4<f32>) -> vec4<f32> {
    let w = weight(position.xy, position.z, standard_depth(position.z), view_depth, c.a)
        * params.accum_scale;
    return vec4<f32>(c.rgb * c.a, c.a) * w;
}
