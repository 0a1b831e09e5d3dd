// Shared by every chunk pipeline: frame and chunk uniforms (`bindings.rs`, checked equal
// by a test), vertex pulling of the 8-byte packed quads (voxel-mesh's layout), the shading
// all passes use (Lambert with a sun direction plus ambient, the same for opaque and
// translucent surfaces, times the per-vertex ambient occlusion the mesher stored), the
// dissolve of chunks fading in, and which translucent fragments count when the eye is
// inside a translucent volume (`medium.rs`).

// Frame (the per-frame uniforms) comes from frame.wgsl, before this file.


// NO_MEDIUM (no medium) and FLAG_INTERFACE (quad flag, word 1 bit 16: a translucent face
// toward another translucent type) come from `bindings.rs`.

struct ChunkInfo {
    origin: vec3<i32>,
    alpha: f32,
    // Blocks per cell along x and z: 1, or 2^level for a chunk of a level of detail (its
    // cells one block high).
    scale: u32,
    // Where the chunk's light palette starts (`light_palette`), and 1 for a lit chunk (0:
    // drawn with full sky light and no block light, as before light existed).
    light_base: u32,
    lit: u32,
    pad0: u32,
};

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var block_textures: texture_2d_array<f32>;
@group(0) @binding(2) var block_sampler: sampler;
// Inside a medium: per pixel, the depth of the first surface of the medium's volume the
// eye's ray meets (or the opaque depth when nearer); see `medium.rs`.
// A depth texture read as a float one with the nearest sampler below (`gpu.rs`,
// DEPTH_READ): `boundary_depth`.
@group(0) @binding(3) var medium_boundary: texture_2d<f32>;
// The sampler depth textures are read with (every chunk pass's own too).
@group(0) @binding(6) var depth_sampler: sampler;
// Volumes (`medium.rs`): where volumes end (`volume_exit.wgsl`; the exact references: the
// opaque depth), and per block id its look as a medium, TABLE_WIDTH entries a
// row: linear colour and absorption per block (0: a thin surface).
@group(0) @binding(7) var volume_depth: texture_2d<f32>;
@group(0) @binding(8) var block_media: texture_2d<f32>;
// The nearest entry into a volume (a depth texture, read as a float one) and its medium's
// look, and a copy of the opaque depth, when `frame.volumes` is MEDIA_VOLUMES (`path.wgsl`).
@group(0) @binding(9) var volume_entry: texture_2d<f32>;
@group(0) @binding(10) var entry_look: texture_2d<f32>;
@group(0) @binding(11) var opaque_copy: texture_2d<f32>;
// The farthest back face of a volume beyond the second entry (1 where none), and the
// nearest entry into a volume beyond where the nearest one ends with its look, when
// `frame.volumes` is MEDIA_VOLUMES (`volume_exit.wgsl`).
@group(0) @binding(12) var volume_far: texture_2d<f32>;
@group(0) @binding(13) var volume_entry2: texture_2d<f32>;
@group(0) @binding(14) var entry2_look: texture_2d<f32>;
// Sun shadows (`sun.rs`): per block of the shadow volume, how the sun's ray crosses it: 0
// air, SUN_STOP a block that stops it, else a class whose filters lie in `block_media`
// from `frame.sun_table` (`sun_transmittance`).
@group(0) @binding(15) var sun_cells: texture_3d<u32>;

// How quads and their tables reach the vertex stage (`fetch.rs`); a pipeline uses one of
// the two, and binds only that one's resources.
//
// Storage: per block id, the texture layers of its top, bottom and side faces
// (`textures.rs`); group 1: a page of the quad arena, and every chunk's record by slot
// (the instance index of its draws).
@group(0) @binding(4) var<storage, read> block_layers: array<u32>;
@group(1) @binding(0) var<storage, read> quads: array<vec2<u32>>;
@group(1) @binding(1) var<storage, read> chunks: array<ChunkInfo>;
// The light of each quad of the page at the quad's index (voxel-mesh's `QuadLight`: the
// palette indices of its corners (u0,v0), (u1,v0) in word 0 and (u0,v1), (u1,v1) in word 1,
// 16 bits each), and every lit chunk's palette (`PackedLight`: sky R, G, B in the bytes of
// word 0, block R, G, B in those of word 1), from the chunk's `light_base`
// (`chunks/light.rs`). The instanced fetch reads them as below.
@group(1) @binding(3) var<storage, read> quad_lights: array<vec2<u32>>;
@group(1) @binding(4) var<storage, read> light_palette: array<vec2<u32>>;
// Instanced: the block layers in a texture TABLE_WIDTH entries wide (`table_texel`), the
// drawn chunk's record a uniform (bound at its dynamic offset for each draw), the quads the
// instances' attribute.
@group(0) @binding(5) var block_layer_table: texture_2d<u32>;
@group(1) @binding(2) var<uniform> chunk_record: ChunkInfo;
// The light palettes as a table (`table_texel`), each entry a `PackedLight`; the quads'
// light the second instance attribute.
@group(1) @binding(5) var light_palette_table: texture_2d<u32>;

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
    // The quad's flags (word 1, bits 16-31).
    @location(4) @interpolate(flat) flags: u32,
    // The chunk's opacity (fade-in), 1 when settled.
    @location(5) @interpolate(flat) alpha: f32,
    // Ambient-occlusion brightness, interpolated from the quad's corners.
    @location(6) shade: f32,
    // The block texture layer of the face: the block's top, bottom or sides.
    @location(7) @interpolate(flat) layer: u32,
    // Sky and block light (linear, 0 to 1 per channel), interpolated from the quad's
    // corners: the light field's (`docs/light.md`), or full sky and no block light for an
    // unlit chunk.
    @location(8) sky_light: vec3<f32>,
    @location(9) block_light: vec3<f32>,
    // Position relative to the eye's integer part minus its fraction (`frame.eye_int`,
    // `frame.eye_frac`): what sun shadows march from.
    @location(10) pos: vec3<f32>,
};

// The light of a quad's four corners, by corner u + 2v.
struct CornerLights {
    sky: array<vec3<f32>, 4>,
    block: array<vec3<f32>, 4>,
};

// An unlit quad's: full sky light, no block light (what the shading gave before light).
fn unlit_corners() -> CornerLights {
    var out: CornerLights;
    for (var i = 0u; i < 4u; i++) {
        out.sky[i] = vec3<f32>(1.0);
        out.block[i] = vec3<f32>(0.0);
    }
    return out;
}

// The three bytes of `w` (R, G, B from bit 0) as levels 0 to 1.
fn light_levels(w: u32) -> vec3<f32> {
    return vec3<f32>(f32(w & 255u), f32((w >> 8u) & 255u), f32((w >> 16u) & 255u)) / 255.0;
}

// Corners of the two triangles of a quad, counter-clockwise seen from the side the normal
// points to (positive faces); negative faces take them in the other order. The triangles
// share the diagonal (0,0)-(1,1), or (1,0)-(0,1) in the FLIP variants.
const CORNERS_POS = array<vec2<f32>, 6>(
    vec2(0.0, 0.0), vec2(1.0, 0.0), vec2(1.0, 1.0),
    vec2(0.0, 0.0), vec2(1.0, 1.0), vec2(0.0, 1.0),
);
const CORNERS_NEG = array<vec2<f32>, 6>(
    vec2(0.0, 0.0), vec2(1.0, 1.0), vec2(1.0, 0.0),
    vec2(0.0, 0.0), vec2(0.0, 1.0), vec2(1.0, 1.0),
);
const CORNERS_POS_FLIP = array<vec2<f32>, 6>(
    vec2(0.0, 0.0), vec2(1.0, 0.0), vec2(0.0, 1.0),
    vec2(1.0, 0.0), vec2(1.0, 1.0), vec2(0.0, 1.0),
);
const CORNERS_NEG_FLIP = array<vec2<f32>, 6>(
    vec2(0.0, 0.0), vec2(0.0, 1.0), vec2(1.0, 0.0),
    vec2(1.0, 0.0), vec2(0.0, 1.0), vec2(1.0, 1.0),
);

// AO value (3 open .. 0 darkest) of the quad's corner `slot` = u + 2v: word 1 bits 24..32
// hold 3 − value, two bits per corner (voxel-mesh's `ao`).
fn corner_ao(q: vec2<u32>, slot: u32) -> u32 {
    return 3u - ((q.y >> (24u + 2u * slot)) & 3u);
}

// Brightness of corner `c` (each coordinate 0 or 1) of quad `q`.
fn corner_shade(q: vec2<u32>, c: vec2<f32>) -> f32 {
    let ao = corner_ao(q, u32(c.x) + 2u * u32(c.y));
    return 1.0 - frame.ao_strength * AO_DEPTH * f32(3u - ao) / 3.0;
}

// Vertex k (0..6) of a quad: which corner, for the face's side and the diagonal.
fn quad_corner(positive: bool, flip: bool, k: u32) -> vec2<f32> {
    if positive {
        return select(CORNERS_POS[k], CORNERS_POS_FLIP[k], flip);
    }
    return select(CORNERS_NEG[k], CORNERS_NEG_FLIP[k], flip);
}
const NORMALS = array<vec3<f32>, 6>(
    vec3(1.0, 0.0, 0.0), vec3(-1.0, 0.0, 0.0),
    vec3(0.0, 1.0, 0.0), vec3(0.0, -1.0, 0.0),
    vec3(0.0, 0.0, 1.0), vec3(0.0, 0.0, -1.0),
);

// Expands vertex `k` (0..6) of quad `q` of `chunk`, lit by `lights` (the face's layer is the caller's:
// `layer_index` says which entry of its table). The quad is split along the
// diagonal whose corners are brighter in sum (Sodium's rule), so that interpolated
// occlusion is symmetric; with `grow` it grows by OPAQUE_EXPANSION_PX pixels along its
// plane (opaque quads: no crack at T-junctions, `bindings.rs`).
fn quad_vertex(q: vec2<u32>, chunk: ChunkInfo, k: u32, grow: bool, lights: CornerLights) -> VsOut {
    let g = q.x;
    let face = min((g >> 25u) & 7u, 5u);
    let size = vec2<f32>(f32(((g >> 15u) & 31u) + 1u), f32(((g >> 20u) & 31u) + 1u));
    let flip = corner_ao(q, 1u) + corner_ao(q, 2u) > corner_ao(q, 0u) + corner_ao(q, 3u);
    let positive = (face & 1u) == 0u;
    let corner = quad_corner(positive, flip, k);
    let axis = face / 2u;
    let u_axis = (axis + 1u) % 3u;
    let v_axis = (axis + 2u) % 3u;
    var p = vec3<f32>(f32(g & 31u), f32((g >> 5u) & 31u), f32((g >> 10u) & 31u));
    if (face & 1u) == 0u {
        p[axis] += 1.0;
    }
    // Cells to blocks (a level of detail's cells are `scale` blocks wide in x and z); the
    // quad's size and its texture coordinates in blocks.
    let cell = vec3<f32>(f32(chunk.scale), 1.0, f32(chunk.scale));
    p *= cell;
    let size_blocks = size * vec2<f32>(cell[u_axis], cell[v_axis]);
    var uv = corner * size_blocks;
    p[u_axis] += uv.x;
    p[v_axis] += uv.y;
    // Camera-relative position: integer parts cancel exactly before any float rounding.
    let rel = vec3<f32>(chunk.origin - frame.eye_int) + p - frame.eye_frac;
    var out: VsOut;
    out.clip = frame.view_proj * vec4<f32>(rel, 1.0);
    out.pos = rel;
    out.shade = corner_shade(q, corner);
    let slot = u32(corner.x) + 2u * u32(corner.y);
    out.sky_light = lights.sky[slot];
    out.block_light = lights.block[slot];
    if grow && out.clip.w > 0.0 {
        // So far along U and V (outward) that the vertex moves OPAQUE_EXPANSION_PX pixels
        // on screen along each, at most MAX_GROWTH blocks (a quad seen edge-on).
        let outward = corner * 2.0 - 1.0;
        var du = vec3<f32>(0.0);
        du[u_axis] = outward.x;
        var dv = vec3<f32>(0.0);
        dv[v_axis] = outward.y;
        let rate = vec2<f32>(
            screen_rate(out.clip, frame.view_proj * vec4<f32>(du, 0.0)),
            screen_rate(out.clip, frame.view_proj * vec4<f32>(dv, 0.0)),
        );
        let grown = outward * min(vec2<f32>(OPAQUE_EXPANSION_PX) / max(rate, vec2<f32>(1e-6)), vec2<f32>(MAX_GROWTH));
        var offset = vec3<f32>(0.0);
        offset[u_axis] = grown.x;
        offset[v_axis] = grown.y;
        out.clip += frame.view_proj * vec4<f32>(offset, 0.0);
        out.pos += offset;
        uv += grown;
        // The shade the vertex's triangle extends to the grown corner, so that every
        // point of the quad keeps the shade it had.
        let first = k / 3u * 3u;
        let a = quad_corner(positive, flip, first);
        let b = quad_corner(positive, flip, first + 1u);
        let c = quad_corner(positive, flip, first + 2u);
        let e0 = b - a;
        let e1 = c - a;
        let d = corner + grown / size_blocks - a;
        let det = e0.x * e1.y - e1.x * e0.y;
        let beta = (d.x * e1.y - e1.x * d.y) / det;
        let gamma = (e0.x * d.y - d.x * e0.y) / det;
        let sa = corner_shade(q, a);
        out.shade = sa + beta * (corner_shade(q, b) - sa) + gamma * (corner_shade(q, c) - sa);
        // The light likewise.
        let ia = u32(a.x) + 2u * u32(a.y);
        let ib = u32(b.x) + 2u * u32(b.y);
        let ic = u32(c.x) + 2u * u32(c.y);
        let ka = lights.sky[ia];
        out.sky_light = ka + beta * (lights.sky[ib] - ka) + gamma * (lights.sky[ic] - ka);
        let la = lights.block[ia];
        out.block_light = la + beta * (lights.block[ib] - la) + gamma * (lights.block[ic] - la);
    }
    // The level rings as bands (`Renderer::set_level_bands`): odd levels darker (scales
    // 2, 8 and 32: bits 1, 3 and 5; no countTrailingZeros, which GLSL 3.30 lacks).
    if (chunk.scale & 42u) != 0u {
        out.shade *= 1.0 - frame.level_bands;
    }
    out.uv = uv;
    out.block = q.y & 0xffffu;
    out.flags = (q.y >> 16u) | select(0u, FLAG_LIT, chunk.lit != 0u);
    out.alpha = chunk.alpha;
    out.face = face;
    // Reverse-Z perspective: clip.w is the view depth.
    out.view_depth = out.clip.w;
    return out;
}

// Pixels per block that a vertex at `clip` moves on screen along the clip-space direction
// `d` (the derivative of the projected position).
fn screen_rate(clip: vec4<f32>, d: vec4<f32>) -> f32 {
    let w = clip.w;
    return length((d.xy * w - clip.xy * d.w) / (w * w) * frame.viewport * 0.5);
}

// The entry of a block's layer table for `face`: three a block, the face groups +y top
// (0), -y bottom (1), the rest sides (2).
fn layer_index(block: u32, face: u32) -> u32 {
    return block * 3u + select(2u, face - 2u, face == 2u || face == 3u);
}

// Where corner `s` (u + 2v) of a quad whose light is `l` (a `QuadLight`) lies in the
// palettes, for `chunk`.
fn palette_index(l: vec2<u32>, s: u32, chunk: ChunkInfo) -> u32 {
    let word = select(l.x, l.y, s >= 2u);
    return chunk.light_base + ((word >> (16u * (s & 1u))) & 0xffffu);
}

// Storage: the light of quad `i` of the page, of `chunk`.
fn pulled_lights(i: u32, chunk: ChunkInfo) -> CornerLights {
    if chunk.lit == 0u {
        return unlit_corners();
    }
    let l = quad_lights[i];
    var out: CornerLights;
    for (var s = 0u; s < 4u; s++) {
        let entry = light_palette[palette_index(l, s, chunk)];
        out.sky[s] = light_levels(entry.x);
        out.block[s] = light_levels(entry.y);
    }
    return out;
}

// Instanced: the light of the instance's quad, `l` its light attribute, of the drawn chunk.
fn instanced_lights(l: vec2<u32>) -> CornerLights {
    if chunk_record.lit == 0u {
        return unlit_corners();
    }
    var out: CornerLights;
    for (var s = 0u; s < 4u; s++) {
        let texel = table_texel(palette_index(l, s, chunk_record));
        let entry = textureLoad(light_palette_table, texel, 0).xy;
        out.sky[s] = light_levels(entry.x);
        out.block[s] = light_levels(entry.y);
    }
    return out;
}

// Storage: vertex `vi` of the page's quads (a draw starts at its mesh's first quad times
// 6), quad vi / 6, corner vi % 6, of the chunk in slot `slot`.
fn pulled_vertex(vi: u32, slot: u32, grow: bool) -> VsOut {
    let chunk = chunks[slot];
    let i = vi / 6u;
    var out = quad_vertex(quads[i], chunk, vi % 6u, grow, pulled_lights(i, chunk));
    out.layer = block_layers[layer_index(out.block, out.face)];
    return out;
}

// Where entry `i` of a table texture lies.
fn table_texel(i: u32) -> vec2<i32> {
    return vec2<i32>(i32(i % TABLE_WIDTH), i32(i / TABLE_WIDTH));
}

// Instanced: corner vi % 6 of the instance's quad `q` (its light `l`), of the drawn chunk.
fn instanced_vertex(vi: u32, q: vec2<u32>, l: vec2<u32>, grow: bool) -> VsOut {
    var out = quad_vertex(q, chunk_record, vi % 6u, grow, instanced_lights(l));
    out.layer = textureLoad(block_layer_table, table_texel(layer_index(out.block, out.face)), 0).x;
    return out;
}

// Translucent and cutout quads (every technique, the medium boundary): exactly as meshed.
@vertex
fn vs_main(@builtin(vertex_index) vi: u32, @builtin(instance_index) slot: u32) -> VsOut {
    return pulled_vertex(vi, slot, false);
}

// Opaque quads, grown against T-junction cracks.
@vertex
fn vs_solid(@builtin(vertex_index) vi: u32, @builtin(instance_index) slot: u32) -> VsOut {
    return pulled_vertex(vi, slot, true);
}

// The same two, the quads as instances.
@vertex
fn vs_main_instanced(
    @builtin(vertex_index) vi: u32,
    @location(0) q: vec2<u32>,
    @location(1) l: vec2<u32>,
) -> VsOut {
    return instanced_vertex(vi, q, l, false);
}

@vertex
fn vs_solid_instanced(
    @builtin(vertex_index) vi: u32,
    @location(0) q: vec2<u32>,
    @location(1) l: vec2<u32>,
) -> VsOut {
    return instanced_vertex(vi, q, l, true);
}

// Image coordinates of face coordinates `uv` (along the face's U and V axes): side faces
// upright and seen from outside, top and bottom along +x and +z. `image_coords` in
// `textures.rs` is the Rust twin.
fn image_uv(uv: vec2<f32>, face: u32) -> vec2<f32> {
    switch face {
        case 0u: { return vec2<f32>(-uv.y, -uv.x); }
        case 1u: { return vec2<f32>(uv.y, -uv.x); }
        case 2u, 3u: { return uv.yx; }
        case 4u: { return vec2<f32>(uv.x, -uv.y); }
        default: { return vec2<f32>(-uv.x, -uv.y); }
    }
}

// Texture colour (linear) and alpha of a fragment: its face's layer of the block textures.
fn albedo(in: VsOut) -> vec4<f32> {
    return textureSample(block_textures, block_sampler, image_uv(in.uv, in.face), in.layer);
}

// The sky's light (Lambert with the sun plus ambient, at the light's brightness: day and
// night) times the sky light that reaches the face, or the block light where that is
// brighter (per channel, as Minecraft and Cubyz take the larger of the two), times the
// ambient occlusion. An unlit chunk has full sky light and no block light.
fn light(rgb: vec3<f32>, in: VsOut) -> vec3<f32> {
    let n_dot_l = max(dot(NORMALS[in.face], frame.sun_dir), 0.0);
    if n_dot_l > 0.0 {
        let sun = sun_transmittance(in);
        if sun.w > 0.0 {
            // Sun shadows: the sky light lights the ambient share, the sun's own light what
            // reaches the fragment along its ray.
            let sky = frame.brightness
                * (frame.ambient * in.sky_light + (1.0 - frame.ambient) * n_dot_l * sun.xyz);
            return rgb * max(sky, in.block_light) * in.shade;
        }
    }
    let sky = frame.brightness * (frame.ambient + (1.0 - frame.ambient) * n_dot_l);
    return rgb * max(in.sky_light * sky, in.block_light) * in.shade;
}

// Sun shadows (`sun.rs`, `docs/light.md`): the share of the sun's light, per channel, that
// reaches a fragment of a lit chunk along the ray toward the sun, .w = 1; .w = 0 where it
// is not marched (no shadow volume, an unlit chunk, a fragment outside the volume), and
// the sky light stands for it. A voxel march (Amanatides-Woo) from the fragment's cell (the
// cell in front of its face) to where the ray leaves the volume: each cell entered
// multiplies by its filter (`voxel_core::SunMarch`, the CPU twin), a cell that stops the
// sun ends it dark. Air above every block of a tile of 8 × 8 columns is crossed in one
// step.
fn sun_transmittance(in: VsOut) -> vec4<f32> {
    if frame.sun_on == 0u || (in.flags & FLAG_LIT) == 0u {
        return vec4<f32>(0.0);
    }
    let dir = frame.sun_dir;
    if dir.y <= 0.0 {
        return vec4<f32>(0.0, 0.0, 0.0, 1.0);
    }
    let size = vec3<i32>(frame.sun_size);
    let o = in.pos + frame.eye_frac + vec3<f32>(frame.sun_offset) + NORMALS[in.face] * SUN_NUDGE;
    var cell = vec3<i32>(floor(o));
    if any(cell < vec3<i32>(0)) || any(cell >= size) {
        return vec4<f32>(0.0);
    }
    let positive = dir > vec3<f32>(0.0);
    let moving = abs(dir) > vec3<f32>(0.0);
    // (An integer vector `select` is GLSL's `mix` of integers, which GLSL ES 3.00 and
    // GLSL 3.30 lack; an axis the ray does not move along is never stepped.)
    let step = vec3<i32>(sign(dir));
    let delta = select(vec3<f32>(1e30), 1.0 / abs(dir), moving);
    var next = sun_boundaries(cell, o, dir, positive, moving);
    var prev = textureLoad(sun_cells, sun_texel(cell), 0).x;
    if prev == SUN_STOP {
        return vec4<f32>(0.0, 0.0, 0.0, 1.0);
    }
    var t = vec3<f32>(1.0);
    for (var i = 0u; i < MAX_SUN_STEPS; i++) {
        let tile = cell.x / SUN_TILE + 32 * (cell.z / SUN_TILE);
        if prev == 0u && cell.y > frame.sun_tops[tile / 4][tile % 4] {
            // Nothing but air from here to where the ray leaves the tile's columns (it
            // rises): on into the next tile.
            let lo = vec2<f32>(vec2<i32>(cell.x, cell.z) / SUN_TILE * SUN_TILE);
            let d = vec2<f32>(dir.x, dir.z);
            let p = vec2<f32>(o.x, o.z);
            let wall = select(lo, lo + f32(SUN_TILE), d > vec2<f32>(0.0));
            let ts = select(vec2<f32>(1e30), (wall - p) / d, abs(d) > vec2<f32>(0.0));
            if min(ts.x, ts.y) >= 1e29 {
                // Straight up: air to the sky.
                break;
            }
            if ts.x <= ts.y {
                cell.x = select(i32(lo.x) - 1, i32(lo.x) + SUN_TILE, d.x > 0.0);
                cell.z = i32(floor(o.z + dir.z * ts.x));
                cell.y = i32(floor(o.y + dir.y * ts.x));
            } else {
                cell.z = select(i32(lo.y) - 1, i32(lo.y) + SUN_TILE, d.y > 0.0);
                cell.x = i32(floor(o.x + dir.x * ts.y));
                cell.y = i32(floor(o.y + dir.y * ts.y));
            }
            next = sun_boundaries(cell, o, dir, positive, moving);
        } else {
            // The axis whose boundary comes first (x, then y, then z on ties).
            var a = 2;
            if next.x <= next.y && next.x <= next.z {
                a = 0;
            } else if next.y <= next.z {
                a = 1;
            }
            cell[a] += step[a];
            next[a] += delta[a];
        }
        let outside = any(cell < vec3<i32>(0)) || any(cell >= size);
        var here = 0u;
        if !outside {
            here = textureLoad(sun_cells, sun_texel(cell), 0).x;
        }
        if here == SUN_STOP {
            return vec4<f32>(0.0, 0.0, 0.0, 1.0);
        }
        // The light enters the previous cell from this one: through its surface too when
        // this one is of another kind.
        if prev != 0u {
            let entry = frame.sun_table + 2u * (prev - 1u) + select(0u, 1u, here == prev);
            t *= textureLoad(block_media, table_texel(entry), 0).xyz;
        }
        if outside {
            break;
        }
        prev = here;
    }
    return vec4<f32>(t, 1.0);
}

// The texel of the volume's cell `cell` (the volume is a torus, `sun.rs`).
fn sun_texel(cell: vec3<i32>) -> vec3<i32> {
    return vec3<i32>((vec3<u32>(cell) + frame.sun_wrap) % frame.sun_size);
}

// Where the ray from `o` along `dir` leaves `cell` on each axis (its parameter; 1e30 on an
// axis it does not move along).
fn sun_boundaries(
    cell: vec3<i32>,
    o: vec3<f32>,
    dir: vec3<f32>,
    positive: vec3<bool>,
    moving: vec3<bool>,
) -> vec3<f32> {
    let wall = vec3<f32>(cell) + select(vec3<f32>(0.0), vec3<f32>(1.0), positive);
    return select(vec3<f32>(1e30), (wall - o) / dir, moving);
}

// Whether a translucent fragment counts (the model in `medium.rs`): every front face
// does. A back face (drawn only when the eye is inside a medium) counts when it is a face of
// the medium's type where it meets air or a cutout block, and it is the first surface of
// the medium the ray meets: the way out of the eye's own passage through the volume.
fn counts(in: VsOut, front: bool) -> bool {
    if front {
        return true;
    }
    return in.block == frame.medium
        && (in.flags & FLAG_INTERFACE) == 0u
        && in.clip.z == boundary_depth(in.clip.xy);
}

// The medium boundary's depth at pixel `xy`.
fn boundary_depth(xy: vec2<f32>) -> f32 {
    let size = textureDimensions(medium_boundary);
    return textureSampleLevel(medium_boundary, depth_sampler, depth_uv(xy, size), 0.0).x;
}

// The lit colour and opacity of a translucent face: opacity is the texture's (the
// block's opacity, or 1 on glass frames) times the chunk's; 0 for a fragment that does
// not count.
fn surface_color(in: VsOut, front: bool) -> vec4<f32> {
    let a = albedo(in);
    let alpha = select(0.0, clamp(a.a * in.alpha, 0.0, 1.0), counts(in, front));
    return vec4<f32>(light(a.rgb, in), alpha);
}

// A block's look as a medium: linear colour and absorption per block (0: a thin surface);
// nothing for a game's object (OBJECT_BLOCK, `volume.wgsl`).
fn medium_look(block: u32) -> vec4<f32> {
    if block == OBJECT_BLOCK {
        return vec4<f32>(0.0);
    }
    return textureLoad(block_media, table_texel(block), 0);
}

// What every real-time technique composes for a translucent fragment: its face, seen
// through the media in front of it (`fogged`, `path.wgsl`: the eye's medium, the nearest
// volume and the nearest one beyond where that ends, whose paths the media pass also lies
// over the opaque picture). The entry face of a third volume along the ray composes its
// own volume behind it, down to where the second one ends at worst or else the opaque
// surface: exact where that is where it ends, with nothing translucent inside it. The exact
// references walk the media along their sorted fragments themselves and take
// `surface_color`.
fn translucent_color(in: VsOut, front: bool) -> vec4<f32> {
    let c = surface_color(in, front);
    if (frame.volumes != MEDIA_EYE && frame.volumes != MEDIA_VOLUMES) || c.a <= 0.0 {
        return c;
    }
    let m = medium_look(in.block);
    let z = in.clip.z;
    let entry2 = depth_at(volume_entry2, in.clip.xy);
    if frame.volumes == MEDIA_VOLUMES && front && m.a > 0.0 && z < entry2 * (1.0 - PATH_TIE) {
        let v = medium_segment(m, ray_length(in.clip.xy, z, volume_end(in.clip.xy, z)));
        let all = in_front_of(vec4<f32>(0.0), c) + (1.0 - c.a) * v;
        return fogged(in.clip.xy, z, vec4<f32>(all.rgb / all.a, all.a));
    }
    return fogged(in.clip.xy, z, c);
}

// Level of the n×n Bayer matrix (n a power of two) at a pixel, over n²: the matrix
// M₂ₙ = [[4Mₙ, 4Mₙ + 2], [4Mₙ + 3, 4Mₙ + 1]] computed from the bits of the coordinates
// (no table, so nothing is copied into every fragment's private memory).
fn bayer_level(frag_xy: vec2<f32>, n: u32) -> f32 {
    let p = vec2<u32>(frag_xy);
    var level = 0u;
    for (var bit = 1u; bit < n; bit <<= 1u) {
        let x = select(0u, 1u, (p.x & bit) != 0u);
        let y = select(0u, 1u, (p.y & bit) != 0u);
        level = level * 4u + 2u * (x ^ y) + y;
    }
    return f32(level) / f32(n * n);
}

// Whether a fragment of a chunk fading in (alpha < 1) is still dissolved away: a 4×4
// screen door, so that kept pixels grow in as the chunk's alpha ramps up.
fn faded_out(in: VsOut) -> bool {
    return in.alpha < 1.0 && in.alpha <= bayer_level(in.clip.xy, 4u);
}
