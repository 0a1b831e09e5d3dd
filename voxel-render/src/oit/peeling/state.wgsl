// Peeling to convergence with volumes (after limits.wgsl and volume.wgsl): a layer is its
// face with the volume in front of it, from the layer before, and passes on the medium
// the ray is in after it.

struct PeelLayer {
    // The layer's straight colour and alpha.
    @location(0) color: vec4<f32>,
    // The state after it (`peel_state` in limits.wgsl).
    @location(1) state: vec4<u32>,
};

// The layer of a fragment at `position` of straight colour `c`, whose part in the medium
// is `info` with block look `look` (`fragment_info`, `medium_look`).
fn peel_layer(position: vec4<f32>, c: vec4<f32>, look: vec4<f32>, info: u32) -> PeelLayer {
    let start = peel_from(position.xy);
    let medium = start.medium;
    let segment = medium_segment(medium, ray_length(position.xy, start.depth, position.z));
    let p = in_front_of(segment, c);
    let next = medium_after(medium, look, info);
    var out: PeelLayer;
    out.color = select(vec4<f32>(0.0), vec4<f32>(p.rgb / p.a, p.a), p.a > 0.0);
    out.state = vec4<u32>(pack2x16float(next.rg), pack2x16float(next.ba), bitcast<u32>(position.z), 1u);
    return out;
}
