// Bevy's opaque pass and the voxel frame, composed both ways (see `src/composite.rs`).
//
// `fs_into_world`: in the frame's opaque stage, Bevy's opaque pixels go into the crate's
// scene colour and depth where they are nearer than the world's (depth test `Greater`).
// `fs_into_bevy`: after the frame, the world's opaque depth goes back into Bevy's depth
// buffer, so that Bevy's later passes (its transparent phase, gizmos) are hidden by it.
//
// Bevy's projection is reverse-Z with an infinite far plane (depth = near / distance); the
// crate's is reverse-Z with a far plane F (depth = near (F - d) / ((F - near) d)). With one
// near plane the two are linear in each other: crate = a * bevy + b.

struct Params {
    // crate depth = a * bevy depth + b
    a: f32,
    b: f32,
    // 1: Bevy's colour is LDR, already tonemapped by Bevy: undo the crate's tonemap so that
    // the crate's tonemap gives it back unchanged; 0: linear HDR, tonemapped with the world.
    ldr: u32,
    _pad: u32,
}

@group(0) @binding(0) var bevy_color: texture_2d<f32>;
// A depth texture bound as unfilterable float (WebGPU allows it): GLSL, so WebGL2, has no
// `textureLoad` of a depth texture (naga refuses it), and `.r` is the depth either way.
@group(0) @binding(1) var depth_in: texture_2d<f32>;
@group(0) @binding(2) var<uniform> params: Params;
// Depth is read through a nearest sampler, not `textureLoad`: on WebGL2 a texture read
// without a sampler takes the texture's own filter, linear by default, and a depth texture
// filtered linearly is incomplete in GLES 3.0 (it reads 0: Bevy's meshes vanished there).
@group(0) @binding(3) var nearest: sampler;

// The depth texel under the fragment at `p` (a pixel centre).
fn depth_at(p: vec2<f32>) -> f32 {
    let size = vec2<f32>(textureDimensions(depth_in));
    return textureSampleLevel(depth_in, nearest, p / size, 0.0).r;
}

@vertex
fn vs_fullscreen(@builtin(vertex_index) vi: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((vi << 1u) & 2u), f32(vi & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

// The inverse of the crate's tonemap (voxel-render's tonemap.wgsl): identity up to the
// shoulder, then the inverse of its exponential roll-off; 1.0 itself is out of its range,
// so the top is taken a hair below (which the tonemap maps back to 255 in 8 bits).
const SHOULDER: f32 = 0.8;

fn untonemap(y: f32) -> f32 {
    if y <= SHOULDER {
        return max(y, 0.0);
    }
    let room = 1.0 - SHOULDER;
    let t = min((y - SHOULDER) / room, 0.995);
    return SHOULDER - room * log(1.0 - t);
}

struct WorldOut {
    @location(0) color: vec4<f32>,
    @builtin(frag_depth) depth: f32,
}

@fragment
fn fs_into_world(@builtin(position) p: vec4<f32>) -> WorldOut {
    let xy = vec2<i32>(p.xy);
    let d = depth_at(p.xy);
    let dc = params.a * d + params.b;
    // Nothing Bevy drew (cleared to 0), or past the crate's far plane.
    if d <= 0.0 || dc <= 0.0 {
        discard;
    }
    var c = textureLoad(bevy_color, xy, 0).rgb;
    if params.ldr != 0u {
        c = vec3<f32>(untonemap(c.r), untonemap(c.g), untonemap(c.b));
    }
    var out: WorldOut;
    out.color = vec4<f32>(c, 1.0);
    out.depth = min(dc, 1.0);
    return out;
}

@fragment
fn fs_into_bevy(@builtin(position) p: vec4<f32>) -> @builtin(frag_depth) f32 {
    let dc = depth_at(p.xy);
    if dc <= 0.0 {
        discard;
    }
    return clamp((dc - params.b) / params.a, 0.0, 1.0);
}
