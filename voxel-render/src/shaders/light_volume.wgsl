// The light field around the eye (`light_volume.rs`, `docs/light.md`, "Light for a game's
// things"), for a game's shaders: `light_wgsl(group)` puts its bindings at that group.
// Positions are camera-relative, as the frame's view_proj takes them.

struct VoxelLightFrame {
    // The volume's first block, camera-relative.
    origin: vec3<f32>,
    // 1 with a volume, else 0.
    on: u32,
    // The eye's place in the textures (the eye modulo the volume's blocks).
    eye_texel: vec3<f32>,
    brightness: f32,
    // The volume's blocks along x, y and z.
    size: vec3<f32>,
    ambient: f32,
    // Unit direction toward the sun.
    sun_dir: vec3<f32>,
    _pad: f32,
};

@group(GROUP) @binding(0) var<uniform> voxel_light_frame: VoxelLightFrame;
// Per cell its sky (and block) light times its openness, the openness (1 where light
// enters the cell) in alpha: a filtered sample over its alpha is the mean of the open cells.
@group(GROUP) @binding(1) var voxel_sky_light: texture_3d<f32>;
@group(GROUP) @binding(2) var voxel_block_light: texture_3d<f32>;
@group(GROUP) @binding(3) var voxel_light_sampler: sampler;

// Linear RGB light, 0 to 1.
struct VoxelLight {
    sky: vec3<f32>,
    block: vec3<f32>,
};

// The light at camera-relative `p`: the mean of the open cells of the 2 × 2 × 2 around it;
// full sky light and no block light outside the volume, without one, or where none of
// them is open (the light of a world drawn unlit).
fn voxel_light(p: vec3<f32>) -> VoxelLight {
    var out = VoxelLight(vec3<f32>(1.0), vec3<f32>(0.0));
    let f = voxel_light_frame;
    let local = p - f.origin;
    if f.on == 0u || any(local < vec3<f32>(0.0)) || any(local > f.size) {
        return out;
    }
    // Within half a cell of the volume's side, its last cells only (the textures are a
    // torus: the other side lies past it).
    let inside = clamp(local, vec3<f32>(0.5), f.size - vec3<f32>(0.5));
    let uvw = (f.eye_texel + p + (inside - local)) / f.size;
    let sky = textureSampleLevel(voxel_sky_light, voxel_light_sampler, uvw, 0.0);
    if sky.a < 1.0 / 512.0 {
        return out;
    }
    let block = textureSampleLevel(voxel_block_light, voxel_light_sampler, uvw, 0.0);
    out.sky = sky.rgb / sky.a;
    out.block = block.rgb / sky.a;
    return out;
}

// What a surface of unit normal `n` (zero: lit as a face turned to the sky) at `p` is lit
// with, as the world's faces are without ambient occlusion: the sky's light (Lambert with
// the sun plus ambient, times the brightness) times the sky light, or the block light
// where brighter, per channel.
fn voxel_shade(p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let f = voxel_light_frame;
    let l = voxel_light(p);
    var facing = n;
    if dot(n, n) == 0.0 {
        facing = vec3<f32>(0.0, 1.0, 0.0);
    }
    let sky = f.brightness * (f.ambient + (1.0 - f.ambient) * max(dot(facing, f.sun_dir), 0.0));
    return max(l.sky * sky, l.block);
}
