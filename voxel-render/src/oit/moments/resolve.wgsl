// Moment-based OIT, pass 2's bindings (after moments.wgsl): pass 1's sums, read at the
// fragment's pixel.

@group(2) @binding(1) var mboit_b0: texture_2d<f32>;
@group(2) @binding(2) var mboit_sums: texture_2d<f32>;

// The premultiplied colour of `c` (straight, alpha its opacity) at `position` (a
// fragment's) and `view_depth`, weighted by the transmittance in front of it.
fn mboit_resolve(position: vec4<f32>, view_depth: f32, c: vec4<f32>) -> vec4<f32> {
    let p = vec2<i32>(position.xy);
    let t = mboit_transmittance(
        textureLoad(mboit_b0, p, 0).r,
        textureLoad(mboit_sums, p, 0),
        mboit_warp(view_depth),
    );
    return vec4<f32>(c.rgb * c.a, c.a) * t;
}
