// Stipple (screen-door) transparency, seed 001 (appended to common.wgsl and dither.wgsl).
// No blending, no extra target: a fragment is either kept, fully opaque, or discarded.

@fragment
fn fs_stipple(in: VsOut) -> @location(0) vec4<f32> {
    let s = unpack_shading_state(frame.shading_state);
    // Texture alpha × chunk alpha (fade-in), × the uniform alpha of the shading state.
    let c = translucent_color(in);
    let a = c.a * s.uniform_alpha;
    switch s.transparency_mode {
        case 1u: {
            if screen_door(a, s.dither_pattern, in.clip.xy) {
                discard;
            }
        }
        case 2u: {
            if a < 0.5 {
                discard;
            }
        }
        default: {}
    }
    return vec4<f32>(c.rgb, 1.0);
}
