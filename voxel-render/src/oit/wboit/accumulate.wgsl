// Weighted blended OIT, accumulation (appended to common.wgsl). McGuire & Bavoil 2013.
//
// accumulation (RGBA16F, blend ONE, ONE on all channels) += (C·α, α) · w · scale
// revealage    (R8,      blend ZERO, ONE_MINUS_SRC)     *= (1 − α)
//
// `scale` (frame.accum_scale) keeps fp16 sums finite; it cancels in the composite's ratio.

// Weight functions: the same formulas as `weights.rs` (unit-tested there).
fn cube(x: f32) -> f32 {
    return x * x * x;
}

fn weight(pixel: vec2<f32>, z: f32, depth: f32, a: f32) -> f32 {
    let d = abs(depth);
    switch frame.weight_fn {
        case 0u: {
            let zz = clamp(z, 1e-5, 3e4);
            return clamp(a * max(1e-2, 3e3 * cube(1.0 - zz * 0.001)), 1e-2, 3e4);
        }
        case 1u: {
            return clamp(cube(a) * 3000.0 * cube(1.0 - z), 0.01, 3000.0);
        }
        case 2u: {
            let q = d / 5.0;
            return a * clamp(10.0 / (1e-5 + q * q + pow(d / 200.0, 6.0)), 1e-2, 3e3);
        }
        case 3u: {
            return a * clamp(10.0 / (1e-5 + cube(d / 10.0) + pow(d / 200.0, 6.0)), 1e-2, 3e3);
        }
        case 4u: {
            return a * clamp(0.03 / (1e-5 + pow(d / 200.0, 4.0)), 1e-2, 3e3);
        }
        case 5u: {
            return a * max(1e-2, 3e3 * cube(1.0 - z));
        }
        default: {
            // Fitted: the estimated transmittance in front of the fragment.
            return 3e3 * exp(-optical_depth_at(pixel, d));
        }
    }
}

// WeightFit::optical_depth_at in weights.rs: the tables of the four screen tiles around
// the fragment, interpolated in log depth, then between the tiles' centres.
const PROFILE_LEN: u32 = 32u;
const TILES: u32 = 8u;
const MAX_FITTED_DEPTH: f32 = 12.0;

fn table(tile: vec2<u32>, k: u32) -> f32 {
    let i = (tile.y * TILES + tile.x) * PROFILE_LEN + k;
    return frame.optical_depth[i / 4u][i % 4u];
}

fn tile_depth(tile: vec2<u32>, k: u32, t: f32) -> f32 {
    return mix(table(tile, k), table(tile, k + 1u), t);
}

fn optical_depth_at(pixel: vec2<f32>, d: f32) -> f32 {
    let n = max(frame.depth_range.x, 1e-4);
    let f = max(frame.depth_range.y, n * 1.001);
    let x = clamp(log(d / n) / log(f / n), 0.0, 1.0) * f32(PROFILE_LEN - 1u);
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

fn accumulation(in: VsOut) -> vec4<f32> {
    let c = translucent_color(in);
    let w = weight(in.clip.xy, standard_depth(in.clip.z), in.view_depth, c.a) * frame.accum_scale;
    return vec4<f32>(c.rgb * c.a, c.a) * w;
}

struct WboitOut {
    @location(0) accumulation: vec4<f32>,
    @location(1) revealage: vec4<f32>,
};

// Single pass, two targets (needs independent blend).
@fragment
fn fs_accumulate_mrt(in: VsOut) -> WboitOut {
    var out: WboitOut;
    out.accumulation = accumulation(in);
    // α in every channel: the revealage blend multiplies by one minus the source colour.
    out.revealage = vec4<f32>(translucent_color(in).a);
    return out;
}

// Two passes (seed 002): accumulation first, revealage second.
@fragment
fn fs_accumulate(in: VsOut) -> @location(0) vec4<f32> {
    return accumulation(in);
}

@fragment
fn fs_revealage(in: VsOut) -> @location(0) vec4<f32> {
    return vec4<f32>(translucent_color(in).a);
}
