// Stipple (screen-door) transparency (appended to common.wgsl and dither.wgsl).
// No blending, no extra target: a fragment is either kept, fully opaque, or discarded.

@fragment
fn fs_stipple(in: VsOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    // Texture alpha × chunk alpha (fade-in).
    return stipple(in.clip, translucent_color(in, front));
}
