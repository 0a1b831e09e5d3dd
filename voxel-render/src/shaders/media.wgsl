// The media over the opaque picture, before the technique draws (real-time techniques;
// appended to fullscreen.wgsl, the volume functions and `path.wgsl`, with the renderer's
// scene group as group 0): each pixel's opaque surface (or the sky) seen through the path
// in front of it, the eye's medium up to its boundary and the nearest volume up to where
// volumes end. Output (the light the path adds, 1 − its transmittance), blended One,
// OneMinusSrcAlpha. The translucent fragments drawn after it are seen through their own
// part of the path (`fogged`): together the path split at every layer.

@fragment
fn fs_media(in: FullscreenOut) -> @location(0) vec4<f32> {
    // The opaque depth (the far plane under the sky); without a volume only the eye's
    // medium counts, up to its boundary, which lies in front of the opaque surface.
    var z = 0.0;
    if frame.volumes == MEDIA_VOLUMES {
        z = depth_at(opaque_copy, in.clip.xy);
    }
    return path_to(in.clip.xy, z);
}
