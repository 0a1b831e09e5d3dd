// Stipple (screen-door) transparency (appended to common.wgsl and dither.wgsl).
// No blending, no extra target: a fragment is either kept, fully opaque, or discarded.

@fragment
fn fs_stipple(in: VsOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    let s = unpack_shading_state(params.shading_state);
    // Texture alpha × chunk alpha (fade-in), × the uniform alpha of the shading state.
    let c = translucent_color(in, front);
    if screen_door(c.a * s.uniform_alpha, s.dither_pattern, in.clip.xy) {
        discard;
    }
    return vec4<f32>(c.rgb, 1.0);
}
