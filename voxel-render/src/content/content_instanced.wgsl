// Instances as per-instance vertex attributes (`QuadFetch::Instanced`: no storage buffers
// in the vertex stage, as under WebGL2), the fields of `Prim` at locations 0 to 6.

struct PrimIn {
    @location(0) center: vec3<f32>,
    @location(1) kind: u32,
    @location(2) axis_x: vec3<f32>,
    @location(3) emissive: f32,
    @location(4) axis_y: vec4<f32>,
    @location(5) axis_z: vec4<f32>,
    @location(6) color: vec4<f32>,
};

@vertex
fn vs_content(@builtin(vertex_index) vi: u32, p: PrimIn) -> ContentOut {
    return content_vertex(vi, Prim(p.center, p.kind, p.axis_x, p.emissive, p.axis_y, p.axis_z, p.color));
}
