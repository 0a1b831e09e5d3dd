// Shared by every chunk pipeline: frame and chunk uniforms, vertex pulling of the 8-byte
// packed quads (voxel-mesh's layout), and the shading all passes use (seed 000: Lambert
// with a sun direction plus ambient, the same for opaque and translucent surfaces).

struct Frame {
    view_proj: mat4x4<f32>,
    eye_int: vec3<i32>,
    fov_y: f32,
    eye_frac: vec3<f32>,
    near: f32,
    sun_dir: vec3<f32>,
    ambient: f32,
    sky: vec3<f32>,
    far: f32,
    viewport: vec2<f32>,
    weight_fn: u32,
    accum_scale: f32,
    shading_state: u32,
    frame_index: u32,
    depth_range: vec2<f32>,
    optical_depth: array<vec4<f32>, 512>,
};

struct ChunkInfo {
    origin: vec3<i32>,
    alpha: f32,
};

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var block_textures: texture_2d_array<f32>;
@group(0) @binding(2) var block_sampler: sampler;

@group(1) @binding(0) var<storage, read> quads: array<vec2<u32>>;
@group(1) @binding(1) var<uniform> chunk: ChunkInfo;

struct VsOut {
    // Invariant: the same quad gets bit-identical depths in every pipeline, which depth
    // peeling relies on to tell a peeled layer from the next one without an epsilon.
    @builtin(position) @invariant clip: vec4<f32>,
    // Texture coordinates in blocks: the texture repeats once per block.
    @location(0) uv: vec2<f32>,
    @location(1) @interpolate(flat) block: u32,
    @location(2) @interpolate(flat) face: u32,
    // Distance from the eye along the view direction (positive).
    @location(3) view_depth: f32,
};

// Corners of the two triangles of a quad, counter-clockwise seen from the side the normal
// points to (positive faces); negative faces take them in the other order.
const CORNERS_POS = array<vec2<f32>, 6>(
    vec2(0.0, 0.0), vec2(1.0, 0.0), vec2(1.0, 1.0),
    vec2(0.0, 0.0), vec2(1.0, 1.0), vec2(0.0, 1.0),
);
const CORNERS_NEG = array<vec2<f32>, 6>(
    vec2(0.0, 0.0), vec2(1.0, 1.0), vec2(1.0, 0.0),
    vec2(0.0, 0.0), vec2(0.0, 1.0), vec2(1.0, 1.0),
);
const NORMALS = array<vec3<f32>, 6>(
    vec3(1.0, 0.0, 0.0), vec3(-1.0, 0.0, 0.0),
    vec3(0.0, 1.0, 0.0), vec3(0.0, -1.0, 0.0),
    vec3(0.0, 0.0, 1.0), vec3(0.0, 0.0, -1.0),
);

// Expands vertex `vi` of the quad list: quad vi / 6, corner vi % 6.
@vertex
fn vs_main(@builtin(vertex_index) vi: u32) -> VsOut {
    let q = quads[vi / 6u];
    let g = q.x;
    let face = min((g >> 25u) & 7u, 5u);
    let size = vec2<f32>(f32(((g >> 15u) & 31u) + 1u), f32(((g >> 20u) & 31u) + 1u));
    var corner: vec2<f32>;
    if (face & 1u) == 0u {
        corner = CORNERS_POS[vi % 6u];
    } else {
        corner = CORNERS_NEG[vi % 6u];
    }
    let axis = face / 2u;
    let u_axis = (axis + 1u) % 3u;
    let v_axis = (axis + 2u) % 3u;
    var p = vec3<f32>(f32(g & 31u), f32((g >> 5u) & 31u), f32((g >> 10u) & 31u));
    if (face & 1u) == 0u {
        p[axis] += 1.0;
    }
    let uv = corner * size;
    p[u_axis] += uv.x;
    p[v_axis] += uv.y;
    // Camera-relative position: integer parts cancel exactly before any float rounding.
    let rel = vec3<f32>(chunk.origin - frame.eye_int) + p - frame.eye_frac;
    var out: VsOut;
    out.clip = frame.view_proj * vec4<f32>(rel, 1.0);
    out.uv = uv;
    out.block = q.y & 0xffffu;
    out.face = face;
    // Reverse-Z perspective: clip.w is the view depth.
    out.view_depth = out.clip.w;
    return out;
}

// Texture colour (linear) and alpha of a fragment.
fn albedo(in: VsOut) -> vec4<f32> {
    return textureSample(block_textures, block_sampler, in.uv, in.block);
}

// Lambert with the sun plus ambient.
fn light(rgb: vec3<f32>, face: u32) -> vec3<f32> {
    let n_dot_l = max(dot(NORMALS[face], frame.sun_dir), 0.0);
    return rgb * (frame.ambient + (1.0 - frame.ambient) * n_dot_l);
}

// The lit colour and opacity of a translucent fragment: what every technique composes.
// Opacity is the texture's (the block's opacity, or 1 on glass frames) times the chunk's.
fn translucent_color(in: VsOut) -> vec4<f32> {
    let a = albedo(in);
    return vec4<f32>(light(a.rgb, in.face), clamp(a.a * chunk.alpha, 0.0, 1.0));
}

// Standard (not reversed) window depth in [0, 1], 0 at the near plane, from the reverse-Z
// fragment depth: the `gl_FragCoord.z` of the seeds' weight functions.
fn standard_depth(frag_z: f32) -> f32 {
    return 1.0 - frag_z;
}
