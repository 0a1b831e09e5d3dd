// Exact reference, pass 2 (appended to fullscreen.wgsl): sort each pixel's fragments by
// depth and blend them front to back; the result goes over the opaque image with
// (One, OneMinusSrcAlpha): out = Σ layers (exact "over" order) + Π(1 − α) · opaque.

@group(0) @binding(0) var<storage, read> heads: array<u32>;
@group(0) @binding(1) var<storage, read> nodes: array<Node>;
@group(0) @binding(2) var<storage, read_write> counters: Counters;
@group(0) @binding(3) var<uniform> params: Params;

fn tie_key(c: vec2<u32>) -> u32 {
    return c.x ^ (c.y * 2654435761u);
}

// Most fragments one pixel can hold; a longer list is counted in `truncated`.
const MAX_LAYERS: u32 = 128u;

@fragment
fn fs_resolve(in: FullscreenOut) -> @location(0) vec4<f32> {
    let p = vec2<u32>(in.clip.xy);
    var next = heads[p.y * params.width + p.x];
    if next == 0u {
        discard;
    }
    var depth: array<f32, MAX_LAYERS>;
    var color: array<vec2<u32>, MAX_LAYERS>;
    var n = 0u;
    // Insertion sort while walking the list: nearest (largest reverse-Z depth) first.
    // Fragments at exactly the same depth (two faces meeting on an edge that passes
    // through the pixel centre) are ordered by their colour bits, so that the order does
    // not depend on which fragment won the race to the list.
    while next != 0u && n < MAX_LAYERS {
        let node = nodes[next - 1u];
        var i = n;
        while i > 0u && (depth[i - 1u] < node.depth
            || (depth[i - 1u] == node.depth && tie_key(color[i - 1u]) < tie_key(node.color))) {
            depth[i] = depth[i - 1u];
            color[i] = color[i - 1u];
            i -= 1u;
        }
        depth[i] = node.depth;
        color[i] = node.color;
        n += 1u;
        next = node.next;
    }
    if next != 0u {
        atomicAdd(&counters.truncated, 1u);
    }
    var acc = vec4<f32>(0.0);
    for (var i = 0u; i < n; i += 1u) {
        let c = vec4<f32>(unpack2x16float(color[i].x), unpack2x16float(color[i].y));
        acc += (1.0 - acc.a) * vec4<f32>(c.rgb * c.a, c.a);
    }
    return acc;
}
