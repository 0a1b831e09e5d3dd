// Peeling to convergence, after the last layer (appended to fullscreen.wgsl and the
// scene group as group 1 with the volume functions): the volume between each pixel's last
// layer and the opaque surface, under-blended into the front accumulation.

@group(0) @binding(0) var final_state: texture_2d<u32>;

@fragment
fn fs_last_volume(in: FullscreenOut) -> @location(0) vec4<f32> {
    let s = textureLoad(final_state, vec2<i32>(in.clip.xy), 0);
    // Before any layer the ray is still in the eye's medium, from the eye.
    var medium = eye_medium();
    var start = EYE_Z;
    if s.w != 0u {
        medium = vec4<f32>(unpack2x16float(s.x), unpack2x16float(s.y));
        start = bitcast<f32>(s.z);
    }
    if medium.a <= 0.0 {
        discard;
    }
    return medium_segment(medium, ray_length(in.clip.xy, start, walk_end(in.clip.xy, start)));
}
