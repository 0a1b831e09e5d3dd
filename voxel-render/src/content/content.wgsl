// A game's content drawn through the renderer's stages (draw.rs): boxes turned any way
// and camera-facing particles, 36 vertices a box and 6 a particle, each instance a `Prim`
// (from a storage buffer, `content_storage.wgsl`, or per-instance vertex attributes,
// `content_instanced.wgsl`, appended after this). Lit like the world's faces, by the light
// field around it where the renderer has a light volume (`voxel_shade` of
// `light_volume.wgsl`, appended before the instances' entry: Lambert with the sun plus
// ambient at the light's brightness, times the sky light there, or the block light where
// brighter), each box vertex half a block in front of its face, a particle at its centre as
// a face turned to the sky; plus the light it gives off, in multiples of its linear colour.

struct View {
    view_proj: mat4x4<f32>,
    right: vec4<f32>,
    up: vec4<f32>,
};

struct Prim {
    // Camera-relative centre.
    center: vec3<f32>,
    // 0: box, 1: particle.
    kind: u32,
    // Box axes scaled by the half extents; a particle's half size in axis_x.x.
    axis_x: vec3<f32>,
    // The light it gives off, in multiples of its linear colour.
    emissive: f32,
    axis_y: vec4<f32>,
    axis_z: vec4<f32>,
    // Linear colour and opacity.
    color: vec4<f32>,
};

@group(0) @binding(0) var<uniform> view: View;

struct ContentOut {
    // Invariant, as depth peeling needs of every translucent surface.
    @builtin(position) @invariant position: vec4<f32>,
    @location(0) color: vec4<f32>,
};

// The two triangles of a square, counter-clockwise in its (u, v).
const SQUARE = array<vec2<f32>, 6>(
    vec2(-1.0, -1.0), vec2(1.0, -1.0), vec2(1.0, 1.0),
    vec2(-1.0, -1.0), vec2(1.0, 1.0), vec2(-1.0, 1.0),
);

// The colour of `p` lit by `light`, plus its own light.
fn content_color(p: Prim, light: vec3<f32>) -> vec4<f32> {
    return vec4<f32>(p.color.rgb * (light + p.emissive), p.color.a);
}

// Vertex `vi` of primitive `p`.
fn content_vertex(vi: u32, p: Prim) -> ContentOut {
    var out: ContentOut;
    let c = SQUARE[vi % 6u];
    if p.kind == 1u {
        if vi >= 6u {
            // A particle is drawn with 6 vertices; any more collapse to nothing.
            out.position = vec4<f32>(0.0, 0.0, 0.0, 1.0);
            out.color = vec4<f32>(0.0);
            return out;
        }
        let world = p.center + (view.right.xyz * c.x + view.up.xyz * c.y) * p.axis_x.x;
        out.position = view.view_proj * vec4<f32>(world, 1.0);
        out.color = content_color(p, voxel_shade(p.center, vec3<f32>(0.0)));
        return out;
    }
    // Face f of a box: axis f / 2, on its + side for even f.
    let face = vi / 6u;
    let axis = face / 2u;
    let sign = select(-1.0, 1.0, (face & 1u) == 0u);
    var axes = array<vec3<f32>, 3>(p.axis_x, p.axis_y.xyz, p.axis_z.xyz);
    let n = axes[axis] * sign;
    let u = axes[(axis + 1u) % 3u];
    let v = axes[(axis + 2u) % 3u];
    // u × v points along +axis: a − face takes its corners mirrored, to face outward too.
    let k = select(vec2<f32>(c.y, c.x), c, sign > 0.0);
    let world = p.center + n + u * k.x + v * k.y;
    out.position = view.view_proj * vec4<f32>(world, 1.0);
    let normal = normalize(n);
    out.color = content_color(p, voxel_shade(world + normal * 0.5, normal));
    return out;
}

@fragment
fn fs_opaque(in: ContentOut) -> @location(0) vec4<f32> {
    return vec4<f32>(in.color.rgb, 1.0);
}
