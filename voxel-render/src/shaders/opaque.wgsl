// Opaque and cutout passes (appended to common.wgsl). A chunk fading in (alpha < 1)
// dissolves in through a screen door (`faded_out`).

@fragment
fn fs_opaque(in: VsOut) -> @location(0) vec4<f32> {
    let a = albedo(in);
    if faded_out(in) {
        discard;
    }
    return vec4<f32>(light(a.rgb, in), 1.0);
}

// Alpha test on texture alpha (leaves): one half, the usual threshold.
const ALPHA_TEST: f32 = 0.5;

@fragment
fn fs_cutout(in: VsOut) -> @location(0) vec4<f32> {
    let a = albedo(in);
    if a.a < ALPHA_TEST || faded_out(in) {
        discard;
    }
    return vec4<f32>(light(a.rgb, in), 1.0);
}
