// Opaque and cutout passes (appended to common.wgsl).

@fragment
fn fs_opaque(in: VsOut) -> @location(0) vec4<f32> {
    return vec4<f32>(light(albedo(in).rgb, in.face), 1.0);
}

// Alpha test on texture alpha (leaves): seed 001's alpha-test threshold.
const ALPHA_TEST: f32 = 0.5;

@fragment
fn fs_cutout(in: VsOut) -> @location(0) vec4<f32> {
    let a = albedo(in);
    if a.a < ALPHA_TEST {
        discard;
    }
    return vec4<f32>(light(a.rgb, in.face), 1.0);
}
