// The window example's own passes over the renderer's frame (`window.rs`).

struct Uniforms {
    // The drawn camera's camera-relative view-projection.
    view_proj: mat4x4<f32>,
    // The selection box's corners relative to the eye (xyz), and the window size in
    // pixels (lo.w, hi.w).
    lo: vec4<f32>,
    hi: vec4<f32>,
};
@group(0) @binding(0) var<uniform> u: Uniforms;

// The 12 edges of the box, as a line list of 24 corners.
@vertex
fn vs_box(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let corner = array<u32, 24>(0, 1, 2, 3, 4, 5, 6, 7, 0, 2, 1, 3, 4, 6, 5, 7, 0, 4, 1, 5, 2, 6, 3, 7)[i];
    let pick = vec3<bool>((corner & 1u) != 0u, (corner & 2u) != 0u, (corner & 4u) != 0u);
    return u.view_proj * vec4<f32>(select(u.lo.xyz, u.hi.xyz, pick), 1.0);
}

@fragment
fn fs_box() -> @location(0) vec4<f32> {
    return vec4<f32>(1.0, 0.85, 0.1, 1.0);
}

// The HUD: a crosshair of two quads of 24 x 2 pixels, six corners each.
@vertex
fn vs_hud(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let k = array(vec2(-1.0, -1.0), vec2(1.0, -1.0), vec2(1.0, 1.0), vec2(-1.0, -1.0), vec2(1.0, 1.0), vec2(-1.0, 1.0))[i % 6u];
    let half = select(vec2(12.0, 1.0), vec2(1.0, 12.0), i >= 6u);
    return vec4<f32>(k * half / (vec2(u.lo.w, u.hi.w) / 2.0), 0.0, 1.0);
}

@fragment
fn fs_hud() -> @location(0) vec4<f32> {
    return vec4<f32>(1.0);
}
