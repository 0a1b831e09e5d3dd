// Fog of the eye's medium over the way to its first surface (appended to fullscreen.wgsl;
// `medium.rs` has the model). Output (fog colour, 1 − transmittance) blended
// SrcAlpha, OneMinusSrcAlpha over the composited scene.

struct FogParams {
    color: vec3<f32>,
    density: f32,
    tan_half: vec2<f32>,
    near_far: vec2<f32>,
    viewport: vec2<f32>,
};

// A depth texture, read as a float one (`gpu::DEPTH_READ`).
@group(0) @binding(0) var boundary: texture_2d<f32>;
@group(0) @binding(1) var<uniform> fog: FogParams;
@group(0) @binding(2) var depth_sampler: sampler;

@fragment
fn fs_fog(in: FullscreenOut) -> @location(0) vec4<f32> {
    let z = textureSampleLevel(boundary, depth_sampler, depth_uv(in.clip.xy, textureDimensions(boundary)), 0.0).x;
    let n = fog.near_far.x;
    let f = fog.near_far.y;
    // Reverse-Z window depth to view depth; the far plane where nothing was drawn.
    let view_depth = n * f / (z * (f - n) + n);
    // Along the pixel's ray, not the view axis.
    let ndc = vec2<f32>(in.clip.x / fog.viewport.x * 2.0 - 1.0, 1.0 - in.clip.y / fog.viewport.y * 2.0);
    let ray = length(vec3<f32>(ndc * fog.tan_half, 1.0));
    let transmittance = exp(-fog.density * view_depth * ray);
    return vec4<f32>(fog.color, 1.0 - transmittance);
}
