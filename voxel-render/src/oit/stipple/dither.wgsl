// Screen-door transparency (Mulder, Groen & van Wijk 1998): the technique's own group 2 (appended to
// common.wgsl and the constant BAYER_OFFSETS made in Rust).

// The packed 32-bit shading state (`StippleParams` in mod.rs, checked equal by a test),
// padded to the 16 bytes WebGL2 binds.
struct StippleParams {
    shading_state: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
};

@group(2) @binding(0) var<uniform> params: StippleParams;
// The 2×2, 4×4, 8×8 and 16×16 Bayer matrices one after the other, made in Rust
// (`bayer::bayer_levels`, tested equal to the tables as commonly printed), four levels to a
// vec4: a uniform array's elements are 16 bytes apart, and a uniform (not a storage buffer)
// is what every device has, WebGL2 included.
@group(2) @binding(1) var<uniform> bayer_levels: array<vec4<u32>, BAYER_VEC4S>;

// The threshold: the Bayer level at the pixel, over n² (Bayer 1973). Pattern codes: 0 = 2×2,
// 1 = 4×4, 2 = 8×8, 3 = 16×16.
fn bayer_threshold(pattern: u32, frag_xy: vec2<f32>) -> f32 {
    let n = 2u << (pattern & 3u);
    let p = vec2<u32>(frag_xy) % n;
    let i = BAYER_OFFSETS[pattern & 3u] + p.y * n + p.x;
    return f32(bayer_levels[i / 4u][i % 4u]) / f32(n * n);
}

// The state's bit layout: bits 0-7 alpha, 8-9 mode (always stipple here), 10-11 pattern.
struct ShadingParams {
    uniform_alpha: f32,
    dither_pattern: u32,
};

fn unpack_shading_state(packed: u32) -> ShadingParams {
    return ShadingParams(f32(packed & 0xffu) / 255.0, (packed >> 10u) & 0x3u);
}

// Whether a pixel of coverage `alpha` is dropped. `alpha < threshold`, as often written,
// keeps one pixel in n² at alpha 0, where alpha 0 should always discard; with
// `<=` alpha k/n² keeps exactly k pixels of each n×n tile, 0 keeps none and 1 keeps all.
fn screen_door(alpha: f32, pattern: u32, frag_xy: vec2<f32>) -> bool {
    return alpha <= bayer_threshold(pattern, frag_xy);
}

// A fragment of colour `c` at `position`: kept opaque, or discarded. The alpha is the
// fragment's times the uniform alpha of the shading state.
fn stipple(position: vec4<f32>, c: vec4<f32>) -> vec4<f32> {
    let s = unpack_shading_state(params.shading_state);
    if screen_door(c.a * s.uniform_alpha, s.dither_pattern, position.xy) {
        discard;
    }
    return vec4<f32>(c.rgb, 1.0);
}
