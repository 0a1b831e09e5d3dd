// Exact reference, pass 1 (appended to common.wgsl and types.wgsl): every translucent
// fragment of the tile in front of the opaque surfaces is appended to its pixel's linked
// list (an A-buffer).

@group(2) @binding(0) var<storage, read_write> heads: array<atomic<u32>>;
@group(2) @binding(1) var<storage, read_write> nodes: array<Node>;
@group(2) @binding(2) var<storage, read_write> counters: Counters;
@group(2) @binding(3) var<uniform> params: Params;
// Read with group 0's nearest sampler (`gpu::DEPTH_READ`).
@group(2) @binding(4) var opaque_depth: texture_2d<f32>;

// The `info` of a game's object (`fragment_info` in volume.wgsl: OBJECT_BLOCK).
const ABUFFER_OBJECT: u32 = 0xffffu;

// Appends a fragment of colour `c` at `position` (its depth's screen-space `slope`) to its
// pixel's list, if it lies in front of the opaque surface and counts (`c.a > 0`) or
// changes the medium (`keep`); `info` says how (`fragment_info` in volume.wgsl).
fn abuffer_append(position: vec4<f32>, slope: vec2<f32>, c: vec4<f32>, info: u32, keep: bool) {
    let p = vec2<u32>(position.xy);
    // The depth test, in the shader: a fragment with storage writes may run them before a
    // late depth test would have dropped it. The scissor keeps fragments in the tile.
    let uv = depth_uv(position.xy, textureDimensions(opaque_depth));
    if position.z <= textureSampleLevel(opaque_depth, depth_sampler, uv, 0.0).x || (c.a <= 0.0 && !keep) {
        return;
    }
    let index = atomicAdd(&counters.nodes, 1u);
    if index >= params.capacity {
        return;
    }
    nodes[index].color = vec2<u32>(pack2x16float(c.rg), pack2x16float(c.ba));
    nodes[index].depth = position.z;
    nodes[index].slope = slope;
    nodes[index].info = info;
    nodes[index].next = atomicExchange(&heads[head_index(p)], index + 1u);
}
