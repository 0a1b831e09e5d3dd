// Opaque and cutout passes (appended to common.wgsl and the dithering helpers). A chunk
// fading in (chunk.alpha < 1) dissolves in through the stipple pattern.

fn fading_out(in: VsOut) -> bool {
    return chunk.alpha < 1.0
        && screen_door(chunk.alpha, unpack_shading_state(frame.shading_state).dither_pattern, in.clip.xy);
}

@fragment
fn fs_opaque(in: VsOut) -> @location(0) vec4<f32> {
    let a = albedo(in);
    if fading_out(in) {
        discard;
    }
    return vec4<f32>(light(a.rgb, in.face), 1.0);
}

// Alpha test on texture alpha (leaves): seed 001's alpha-test threshold.
const ALPHA_TEST: f32 = 0.5;

@fragment
fn fs_cutout(in: VsOut) -> @location(0) vec4<f32> {
    let a = albedo(in);
    if a.a < ALPHA_TEST || fading_out(in) {
        discard;
    }
    return vec4<f32>(light(a.rgb, in.face), 1.0);
}
