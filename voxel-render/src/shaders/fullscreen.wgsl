// A triangle that covers the screen, for composites and post passes.

struct FullscreenOut {
    @builtin(position) clip: vec4<f32>,
};

@vertex
fn vs_fullscreen(@builtin(vertex_index) vi: u32) -> FullscreenOut {
    let uv = vec2<f32>(f32((vi << 1u) & 2u), f32(vi & 2u));
    var out: FullscreenOut;
    out.clip = vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
    return out;
}

// True when x is infinite or NaN, from its bits (WGSL may assume floats are finite, so
// x != x is not a reliable NaN test).
fn not_finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) == 0x7f800000u;
}

fn any_not_finite(v: vec4<f32>) -> bool {
    return not_finite(v.x) || not_finite(v.y) || not_finite(v.z) || not_finite(v.w);
}
