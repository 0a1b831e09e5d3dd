// Exact reference, pass 2 (appended to fullscreen.wgsl, the scene group as group 1 with
// the volume functions, and types.wgsl): sort each pixel's fragments by depth and blend
// them front to back, with the volumes between them (the path inside each medium, from
// the eye in the eye's medium or from the face where the ray enters it, to the one where
// it leaves or to the opaque surface);
// the result goes over the opaque image with (One, OneMinusSrcAlpha):
// out = Σ layers (exact "over" order) + Π(1 − α) · opaque.

@group(0) @binding(0) var<storage, read> heads: array<u32>;
@group(0) @binding(1) var<storage, read> nodes: array<Node>;
@group(0) @binding(2) var<storage, read_write> counters: Counters;
@group(0) @binding(3) var<uniform> params: Params;

fn tie_key(c: vec2<u32>) -> u32 {
    return c.x ^ (c.y * 2654435761u);
}

// Whether fragment a lies in front of fragment b. Two fragments of the same depth are two
// faces meeting on an edge through the pixel centre. The rasterizer gives such a pixel to
// a triangle only when the edge is a top or left one (the top-left rule): the triangle lies
// to the right of the edge, or below it when the edge is flat. Both faces contain the edge,
// so their gradients differ across it only: the one in front just inside (larger
// reverse-Z depth) has the larger slope to the right, or down for a flat edge. The colour
// bits order what is left, so that the order never depends on which won the race to the
// list.
fn in_front(a: Node, b: Node) -> bool {
    if a.depth != b.depth {
        return a.depth > b.depth;
    }
    if a.slope.x != b.slope.x {
        return a.slope.x > b.slope.x;
    }
    if a.slope.y != b.slope.y {
        return a.slope.y > b.slope.y;
    }
    return tie_key(a.color) > tie_key(b.color);
}

@fragment
fn fs_resolve(in: FullscreenOut) -> @location(0) vec4<f32> {
    let p = vec2<u32>(in.clip.xy);
    var next = heads[head_index(p)];
    // The medium the ray is in (a look; absorption 0: none) since depth `last`: from the
    // eye, in the eye's medium.
    var medium = eye_medium();
    var last = EYE_Z;
    if next == 0u && medium.a <= 0.0 {
        discard;
    }
    // The nearest MAX_LAYERS fragments of the first MAX_WALK of the list, nearest (largest reverse-Z depth) first, by
    // insertion while walking the list; a farther fragment than all kept ones of a full
    // list is dropped, a nearer one replaces the farthest kept.
    var kept: array<Node, MAX_LAYERS>;
    var n = 0u;
    var total = 0u;
    while next != 0u && total < MAX_WALK {
        let node = nodes[next - 1u];
        next = node.next;
        total += 1u;
        if n == MAX_LAYERS && !in_front(node, kept[n - 1u]) {
            continue;
        }
        var i = min(n, MAX_LAYERS - 1u);
        while i > 0u && in_front(node, kept[i - 1u]) {
            kept[i] = kept[i - 1u];
            i -= 1u;
        }
        kept[i] = node;
        n = min(n + 1u, MAX_LAYERS);
    }
    var acc = vec4<f32>(0.0);
    for (var i = 0u; i < n; i += 1u) {
        let node = kept[i];
        let c = vec4<f32>(unpack2x16float(node.color.x), unpack2x16float(node.color.y));
        let segment = medium_segment(medium, ray_length(in.clip.xy, last, node.depth));
        acc += (1.0 - acc.a) * in_front_of(segment, c);
        medium = medium_after(medium, medium_look(node.info & 0xffffu), node.info);
        last = node.depth;
    }
    if medium.a > 0.0 {
        let segment = medium_segment(medium, ray_length(in.clip.xy, last, walk_end(in.clip.xy, last)));
        acc += (1.0 - acc.a) * segment;
    }
    if total > MAX_LAYERS {
        atomicAdd(&counters.capped, 1u);
        // A list walked only in part (its MAX_WALK latest fragments) may have dropped
        // nearer ones: never exact.
        if 1.0 - acc.a > 0.5 / 255.0 || next != 0u {
            atomicAdd(&counters.capped_visible, 1u);
        }
    }
    return acc;
}
