// Sorted alpha blending (appended to common.wgsl): the classic forward pass. Meshes arrive
// farthest first; blending is SrcAlpha, OneMinusSrcAlpha into the HDR scene colour.

@fragment
fn fs_sorted(in: VsOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    return translucent_color(in, front);
}
