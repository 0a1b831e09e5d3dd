// Fog of the eye's medium over the way to its first surface (appended to fullscreen.wgsl;
// `medium.rs` has the model). Output (fog colour, 1 − transmittance) blended
// SrcAlpha, OneMinusSrcAlpha over the composited scene.

// A depth texture, read as a float one (`gpu::DEPTH_READ`); the frame's uniforms (the eye's
// medium in `medium_look`, the camera's planes and field of view, the light).
@group(0) @binding(0) var boundary: texture_2d<f32>;
@group(0) @binding(1) var<uniform> frame: Frame;
@group(0) @binding(2) var depth_sampler: sampler;

@fragment
fn fs_fog(in: FullscreenOut) -> @location(0) vec4<f32> {
    let z = textureSampleLevel(boundary, depth_sampler, depth_uv(in.clip.xy, textureDimensions(boundary)), 0.0).x;
    let n = frame.near;
    let f = frame.far;
    // Reverse-Z window depth to view depth; the far plane where nothing was drawn.
    let view_depth = n * f / (z * (f - n) + n);
    // Along the pixel's ray, not the view axis.
    let ndc = vec2<f32>(in.clip.x / frame.viewport.x * 2.0 - 1.0, 1.0 - in.clip.y / frame.viewport.y * 2.0);
    let ray = length(vec3<f32>(ndc * frame.tan_half, 1.0));
    let transmittance = exp(-frame.medium_look.a * view_depth * ray);
    return vec4<f32>(frame.medium_look.rgb * frame_sky_light(frame), 1.0 - transmittance);
}
