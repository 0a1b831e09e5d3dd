// Instances pulled from a storage buffer in the vertex stage (`QuadFetch::Storage`).

@group(1) @binding(0) var<storage, read> prims: array<Prim>;

@vertex
fn vs_content(@builtin(vertex_index) vi: u32, @builtin(instance_index) ii: u32) -> ContentOut {
    return content_vertex(vi, prims[ii]);
}
