// Exact reference, pass 1 (appended to common.wgsl and types.wgsl): every translucent
// fragment of the tile in front of the opaque surfaces is appended to its pixel's linked
// list (an A-buffer).

@group(2) @binding(0) var<storage, read_write> heads: array<atomic<u32>>;
@group(2) @binding(1) var<storage, read_write> nodes: array<Node>;
@group(2) @binding(2) var<storage, read_write> counters: Counters;
@group(2) @binding(3) var<uniform> params: Params;
@group(2) @binding(4) var opaque_depth: texture_depth_2d;

@fragment
fn fs_abuffer(in: VsOut, @builtin(front_facing) front: bool) {
    // Derivatives first, while every invocation of the quad still runs.
    let slope = vec2<f32>(dpdx(in.clip.z), dpdy(in.clip.z));
    let c = translucent_color(in, front);
    let p = vec2<u32>(in.clip.xy);
    // The depth test, in the shader: a fragment with storage writes may run them before a
    // late depth test would have dropped it. The scissor keeps fragments in the tile.
    if in.clip.z <= textureLoad(opaque_depth, vec2<i32>(p), 0) || c.a <= 0.0 {
        return;
    }
    let index = atomicAdd(&counters.nodes, 1u);
    if index >= params.capacity {
        return;
    }
    nodes[index].color = vec2<u32>(pack2x16float(c.rg), pack2x16float(c.ba));
    nodes[index].depth = in.clip.z;
    nodes[index].slope = slope;
    nodes[index].next = atomicExchange(&heads[head_index(p)], index + 1u);
}
