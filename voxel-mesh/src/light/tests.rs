//! The lit mesher against a per-face reference written from the rules of the module docs
//! (fixed scenes and random ones), and the scenes a player checks: a torch's falloff, a
//! wall that keeps a room dark, chunk borders without seams, light through green glass.

// Corners and channels of parallel arrays (reference and mesh) are compared by index.
#![allow(clippy::needless_range_loop)]

use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;

use voxel_core::{
    BlockId, BlockRegistry, Chunk, ChunkPos, Face, Light, LightField, RenderClass, World, WorldPos,
    blocks, light_blocks,
};

use super::*;
use crate::{ChunkMeshes, MeshOptions, Mesher, PackedQuad, UV_AXES};

/// A world over the registry with light sources, with air chunks loaded in `min..=max`
/// (chunk coordinates).
fn world(min: [i32; 3], max: [i32; 3]) -> World {
    let mut w = World::new(Arc::new(BlockRegistry::with_lights()));
    for x in min[0]..=max[0] {
        for y in min[1]..=max[1] {
            for z in min[2]..=max[2] {
                w.insert_chunk(ChunkPos::new(x, y, z), Chunk::default())
                    .expect("valid");
            }
        }
    }
    w
}

fn fill(w: &mut World, min: [i32; 3], max: [i32; 3], id: BlockId) {
    w.fill_box(
        WorldPos::new(min[0], min[1], min[2]),
        WorldPos::new(max[0], max[1], max[2]),
        id,
    )
    .expect("loaded");
}

fn pos(p: [i32; 3]) -> WorldPos {
    WorldPos::new(p[0], p[1], p[2])
}

fn levels(l: Light) -> [u16; 6] {
    let [a, b, c] = l.sky;
    let [d, e, f] = l.block;
    [a, b, c, d, e, f].map(u16::from)
}

fn class(w: &World, p: [i32; 3]) -> RenderClass {
    w.registry()
        .class(w.get_block(pos(p)))
        .expect("known block")
}

/// The light of a cell that counts in a corner's mean: open and lit.
fn counted(w: &World, f: &LightField, p: [i32; 3]) -> Option<Light> {
    if class(w, p) == RenderClass::Opaque {
        None
    } else {
        f.get(pos(p))
    }
}

fn add(a: [i32; 3], b: [i32; 3]) -> [i32; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn unit(axis: usize, s: i32) -> [i32; 3] {
    let mut v = [0; 3];
    v[axis] = s;
    v
}

/// The reference: the corner lights of the face `face` of the block at `p`, corners in the
/// order (u0, v0), (u1, v0), (u0, v1), (u1, v1), one face at a time from the rules.
fn reference(w: &World, f: &LightField, p: [i32; 3], face: Face) -> [[u16; 6]; 4] {
    let front = add(p, face.normal());
    let translucent = class(w, p) == RenderClass::Translucent;
    let own = counted(w, f, front);
    let [ua, va] = UV_AXES[face.axis()];
    [(-1, -1), (1, -1), (-1, 1), (1, 1)].map(|(su, sv)| {
        if translucent {
            return own.map_or([0; 6], levels);
        }
        let s1 = add(front, unit(ua, su));
        let s2 = add(front, unit(va, sv));
        let diag = add(s1, unit(va, sv));
        let walled = class(w, s1) == RenderClass::Opaque && class(w, s2) == RenderClass::Opaque;
        let mut cells = vec![front, s1, s2];
        if !walled {
            cells.push(diag);
        }
        let lit: Vec<[u16; 6]> = cells
            .into_iter()
            .filter_map(|c| counted(w, f, c))
            .map(levels)
            .collect();
        if lit.is_empty() {
            return [0; 6];
        }
        let n = lit.len() as u16;
        std::array::from_fn(|ch| (lit.iter().map(|l| l[ch]).sum::<u16>() + n / 2) / n)
    })
}

/// Every unit face of a chunk's lit meshes: world block position and face → (the light
/// the quad gives each of its corners, interpolated over the quad as the renderer does,
/// times the quad's area `w · h` to stay exact; that area; its AO byte).
type LitFaces = BTreeMap<([i32; 3], usize), ([[i64; 6]; 4], i64, u8)>;

fn lit_faces(m: &ChunkMeshes, chunk: ChunkPos) -> LitFaces {
    let origin = chunk.origin().map(|v| v as i32);
    let mut out = BTreeMap::new();
    for (quads, lights) in [
        (&m.opaque, &m.light.opaque),
        (&m.cutout, &m.light.cutout),
        (&m.translucent, &m.light.translucent),
    ] {
        assert_eq!(quads.len(), lights.len(), "one light entry per quad");
        for (q, l) in quads.iter().zip(lights) {
            let u = q.unpack().expect("valid quad");
            let corners = m.light.corners(*l).expect("indices inside the palette");
            let [ua, va] = UV_AXES[u.face.axis()];
            let (w, h) = (i64::from(u.size[0]), i64::from(u.size[1]));
            for i in 0..i32::from(u.size[0]) {
                for j in 0..i32::from(u.size[1]) {
                    let mut p = add(origin, u.pos.map(i32::from));
                    p[ua] += i;
                    p[va] += j;
                    // Bilinear over the quad; exact where the light changes along one
                    // axis only (what merging keeps), as the renderer's triangles are.
                    let at = |cu: i32, cv: i32| -> [i64; 6] {
                        let (s, t) = (i64::from(i + cu), i64::from(j + cv));
                        let c = corners.map(levels);
                        std::array::from_fn(|ch| {
                            let v = |k: usize| i64::from(c[k][ch]);
                            (w - s) * (h - t) * v(0)
                                + s * (h - t) * v(1)
                                + (w - s) * t * v(2)
                                + s * t * v(3)
                        })
                    };
                    let face = [at(0, 0), at(1, 0), at(0, 1), at(1, 1)];
                    let old = out.insert((p, u.face as usize), (face, w * h, q.ao()));
                    assert!(old.is_none(), "face covered twice");
                }
            }
        }
    }
    out
}

/// The unit faces and AO bytes of an unlit mesh.
fn unlit_faces(m: &ChunkMeshes, chunk: ChunkPos) -> BTreeMap<([i32; 3], usize), u8> {
    let origin = chunk.origin().map(|v| v as i32);
    let mut out = BTreeMap::new();
    for q in m.opaque.iter().chain(&m.cutout).chain(&m.translucent) {
        let u = q.unpack().expect("valid quad");
        let [ua, va] = UV_AXES[u.face.axis()];
        for i in 0..i32::from(u.size[0]) {
            for j in 0..i32::from(u.size[1]) {
                let mut p = add(origin, u.pos.map(i32::from));
                p[ua] += i;
                p[va] += j;
                out.insert((p, u.face as usize), q.ao());
            }
        }
    }
    out
}

/// A face's corner lights (the interpolated values over the quad's area).
fn light(e: &([[i64; 6]; 4], i64, u8)) -> [[f64; 6]; 4] {
    e.0.map(|c| c.map(|v| v as f64 / e.1 as f64))
}

fn mesh_lit(w: &World, f: &LightField, p: ChunkPos, options: MeshOptions) -> ChunkMeshes {
    let mut mesher = Mesher::with_options(w.registry(), options);
    mesher
        .mesh_lit(w.chunk(p).expect("loaded"), w.neighbourhood(p), f, p)
        .expect("meshes")
}

/// Checks every lit chunk of `w`: the lit mesh covers the faces of the unlit one with the
/// same AO, and every unit face's interpolated corner light is the reference's.
/// Returns the faces by chunk.
fn check_against_reference(
    w: &World,
    f: &LightField,
    options: MeshOptions,
) -> Vec<(ChunkPos, LitFaces)> {
    let mut plain = Mesher::with_options(w.registry(), options);
    let mut all = Vec::new();
    for (p, chunk) in w.iter() {
        let lit = mesh_lit(w, f, p, options);
        let unlit = plain.mesh(chunk, w.neighbourhood(p)).expect("meshes");
        assert!(unlit.light.is_empty() && unlit.light.palette.is_empty());
        let faces = lit_faces(&lit, p);
        let want = unlit_faces(&unlit, p);
        let got: BTreeMap<_, _> = faces.iter().map(|(k, (_, _, ao))| (*k, *ao)).collect();
        assert_eq!(
            got, want,
            "lit faces and AO of chunk {p:?} are the unlit ones"
        );
        for ((bp, face), (corners, area, _)) in &faces {
            let face = Face::from_index(*face).expect("face");
            let r = reference(w, f, *bp, face);
            for k in 0..4 {
                let want = r[k].map(|v| i64::from(v) * area);
                assert_eq!(
                    corners[k], want,
                    "chunk {p:?}, block {bp:?}, face {face:?}, corner {k}"
                );
            }
        }
        all.push((p, faces));
    }
    all
}

/// A stone room `min..=max` (outer walls included), air inside.
fn room(w: &mut World, min: [i32; 3], max: [i32; 3]) {
    fill(w, min, max, blocks::STONE);
    fill(w, add(min, [1; 3]), add(max, [-1; 3]), BlockId::AIR);
}

#[test]
fn a_torch_falls_off_smoothly_across_the_floor() {
    let mut w = world([0, 0, 0], [0, 0, 0]);
    room(&mut w, [0, 0, 0], [31, 8, 31]);
    w.set_block(pos([5, 1, 16]), light_blocks::TORCH)
        .expect("loaded");
    let f = LightField::new(&w);
    let faces = check_against_reference(&w, &f, MeshOptions::default());
    let floor = &faces[0].1;
    // The floor's top faces along z = 16, away from the torch: the red block light at
    // their (u0, v0) corner, that is the vertex at x.
    let red: Vec<f64> = (6..30)
        .map(|x| light(&floor[&([x, 0, 16], Face::PosY as usize)])[0][3])
        .collect();
    assert!(red[0] > 200.0, "bright next to the torch: {red:?}");
    assert_eq!(red[red.len() - 1], 0.0, "dark out of reach: {red:?}");
    for pair in red.windows(2) {
        assert!(pair[1] <= pair[0], "falls off: {red:?}");
        assert!(
            pair[0] - pair[1] <= 16.0,
            "no step above the falloff: {red:?}"
        );
    }
    // Smooth: the vertex between two cells takes levels between theirs, not only the
    // levels of the cells (which step by 16 a block).
    let cells: Vec<u8> = (6..30)
        .map(|x| f.get(pos([x, 1, 16])).expect("lit").block[0])
        .collect();
    assert!(
        red.iter()
            .any(|&v| !cells.iter().any(|&c| f64::from(c) == v)),
        "corner levels are means of cells: {red:?} vs cells {cells:?}"
    );
}

#[test]
fn a_wall_keeps_the_dark_room_dark() {
    // Two rooms in one box, split by a diagonal staircase wall one block thick: cells of the
    // two rooms touch only at corners, which the light does not cross but a corner's
    // diagonal cell would.
    let mut w = world([0, 0, 0], [0, 0, 0]);
    room(&mut w, [0, 0, 0], [20, 6, 20]);
    for x in 1..20 {
        for z in 1..20 {
            if x + z == 20 {
                fill(&mut w, [x, 1, z], [x, 5, z], blocks::STONE);
            }
        }
    }
    // The torch in the room where x + z > 20.
    w.set_block(pos([15, 1, 15]), light_blocks::TORCH)
        .expect("loaded");
    let f = LightField::new(&w);
    let faces = check_against_reference(&w, &f, MeshOptions::default());
    let (mut lit_room, mut dark_room) = (0, 0);
    for ((p, face), e) in &faces[0].1 {
        let corners = light(e);
        let front = add(*p, Face::from_index(*face).expect("face").normal());
        let inside = (1..20).contains(&front[0])
            && (1..6).contains(&front[1])
            && (1..20).contains(&front[2]);
        if !inside {
            continue;
        }
        let any = corners.iter().flatten().any(|&v| v > 0.0);
        if front[0] + front[2] < 20 {
            assert!(!any, "a face of the dark room is lit: {p:?} face {face}");
            dark_room += 1;
        } else if any {
            lit_room += 1;
        }
    }
    assert!(dark_room > 100 && lit_room > 100, "{dark_room} {lit_room}");
}

#[test]
fn no_seam_across_chunk_borders() {
    // A floor across four chunks, a torch and a green glass roof near their corner.
    let mut w = world([-1, 0, -1], [0, 1, 0]);
    fill(&mut w, [-20, 0, -20], [19, 0, 19], blocks::STONE);
    fill(&mut w, [-6, 9, -6], [5, 9, 5], blocks::GREEN_GLASS);
    fill(&mut w, [-3, 3, 4], [3, 6, 4], blocks::STONE);
    w.set_block(pos([1, 1, -2]), light_blocks::TORCH)
        .expect("loaded");
    w.set_block(pos([-2, 1, 1]), light_blocks::TORCH)
        .expect("loaded");
    let f = LightField::new(&w);
    let faces = check_against_reference(&w, &f, MeshOptions::default());
    // Every vertex of a face direction seen from several chunks has one light.
    let mut vertices: HashMap<([i32; 3], usize), (ChunkPos, [f64; 6])> = HashMap::new();
    let mut shared = 0;
    let mut lit_shared = 0;
    for (chunk, faces) in &faces {
        for ((p, face), e) in faces {
            // Translucent faces take their front cell's light, flat: they differ at a
            // shared vertex wherever their front cells do, inside a chunk too.
            if class(&w, *p) == RenderClass::Translucent {
                continue;
            }
            let corners = light(e);
            let face_ = Face::from_index(*face).expect("face");
            let [ua, va] = UV_AXES[face_.axis()];
            let mut base = *p;
            if face_.is_positive() {
                base[face_.axis()] += 1;
            }
            for (k, (cu, cv)) in [(0, 0), (1, 0), (0, 1), (1, 1)].into_iter().enumerate() {
                let mut v = base;
                v[ua] += cu;
                v[va] += cv;
                match vertices.get(&(v, *face)) {
                    Some((other, l)) if other != chunk => {
                        assert_eq!(*l, corners[k], "vertex {v:?} face {face}: a seam");
                        shared += 1;
                        lit_shared += usize::from(l[3] > 0.0);
                    }
                    Some(_) => {}
                    None => {
                        vertices.insert((v, *face), (*chunk, corners[k]));
                    }
                }
            }
        }
    }
    assert!(shared > 50 && lit_shared > 10, "{shared} {lit_shared}");
}

#[test]
fn deep_water_darkens_the_sides_of_a_pillar_with_depth() {
    // A sea over the whole chunk and a stone pillar standing out of it: the layers of water
    // hold different sky light, so the pillar's side faces take a gradient of them.
    let mut w = world([0, 0, 0], [0, 0, 0]);
    fill(&mut w, [0, 0, 0], [31, 0, 31], blocks::STONE);
    fill(&mut w, [0, 1, 0], [31, 20, 31], blocks::WATER);
    fill(&mut w, [16, 1, 16], [17, 25, 17], blocks::STONE);
    let f = LightField::new(&w);
    let faces = check_against_reference(&w, &f, MeshOptions::default());
    let side = |y| light(&faces[0].1[&([17, y, 16], Face::PosX as usize)]);
    // Corner (u0, v0) is at the face's lower y; (u1, v0) at the upper (U is y on x faces).
    for y in 2..20 {
        let c = side(y);
        assert!(c[0][2] < c[1][2], "lighter upwards: y {y} {c:?}");
        assert_eq!(c[1], side(y + 1)[0], "one light at the shared vertex");
    }
    assert!(side(21)[0][0] > side(19)[0][0], "air above the water");
}

#[test]
fn green_glass_tints_the_sky_light_below() {
    let mut w = world([0, 0, 0], [0, 0, 0]);
    fill(&mut w, [0, 0, 0], [31, 0, 31], blocks::STONE);
    fill(&mut w, [8, 6, 8], [23, 6, 23], blocks::GREEN_GLASS);
    let f = LightField::new(&w);
    let faces = check_against_reference(&w, &f, MeshOptions::default());
    let floor = |x, z| light(&faces[0].1[&([x, 0, z], Face::PosY as usize)])[0];
    let under = floor(16, 16);
    assert!(
        under[1] > under[0] && under[1] > under[2] && under[1] < 255.0,
        "green-ish under the pane: {under:?}"
    );
    assert_eq!(floor(2, 2)[..3], [255.0; 3], "white in the open");
    // The glass's own top face takes the open sky in front of it; its bottom face the
    // tinted light under it.
    let top = light(&faces[0].1[&([16, 6, 16], Face::PosY as usize)])[0];
    let bottom = light(&faces[0].1[&([16, 6, 16], Face::NegY as usize)])[0];
    assert_eq!(top[..3], [255.0; 3]);
    assert!(bottom[1] > bottom[0], "{bottom:?}");
}

#[test]
fn unlit_meshing_is_unchanged_and_uniform_light_merges_as_unlit() {
    // Pillars and a floor under the open sky: every open cell holds full sky light, so the
    // lit mesh is the unlit one quad for quad, every corner on one palette entry.
    let mut w = world([-1, -1, -1], [1, 1, 1]);
    fill(&mut w, [-32, -32, -32], [63, 2, 63], blocks::STONE);
    for (x, z, h) in [(4, 4, 6), (10, 20, 9), (11, 20, 4), (25, 7, 12)] {
        fill(&mut w, [x, 3, z], [x, h, z], blocks::STONE);
    }
    let f = LightField::new(&w);
    let p = ChunkPos::new(0, 0, 0);
    for options in [
        MeshOptions::default(),
        MeshOptions {
            ambient_occlusion: false,
            ..MeshOptions::default()
        },
    ] {
        let lit = mesh_lit(&w, &f, p, options);
        let mut plain = Mesher::with_options(w.registry(), options);
        let unlit = plain
            .mesh(w.chunk(p).expect("loaded"), w.neighbourhood(p))
            .expect("meshes");
        assert!(unlit.light.is_empty() && unlit.light.palette.is_empty());
        let quads = |m: &ChunkMeshes| -> [Vec<PackedQuad>; 3] {
            [&m.opaque, &m.cutout, &m.translucent].map(|v| {
                let mut v = v.clone();
                v.sort_unstable_by_key(|q| (q.geometry, q.block));
                v
            })
        };
        assert_eq!(quads(&lit), quads(&unlit));
        let sky = PackedLight::new(Light {
            sky: [255; 3],
            block: [0; 3],
        });
        assert_eq!(lit.light.palette, vec![sky]);
    }
    check_against_reference(&w, &f, MeshOptions::default());
}

#[test]
fn layout_round_trips_and_is_eight_bytes() {
    assert_eq!(std::mem::size_of::<QuadLight>(), 8);
    assert_eq!(std::mem::size_of::<PackedLight>(), 8);
    let q = QuadLight::new([1, 0xfffe, 3, 0x8000]);
    assert_eq!((q.v0, q.v1), (1 | 0xfffe << 16, 3 | 0x8000 << 16));
    assert_eq!(q.corners(), [1, 0xfffe, 3, 0x8000]);
    assert_eq!((q.corner(1, 0), q.corner(0, 1)), (0xfffe, 3));
    let l = Light {
        sky: [1, 2, 3],
        block: [250, 128, 7],
    };
    let p = PackedLight::new(l);
    assert_eq!((p.sky, p.block), (0x03_02_01, 0x07_80_fa));
    assert_eq!(p.unpack(), l);
}

fn xorshift(mut s: u64) -> impl FnMut() -> u64 {
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        s
    }
}

/// Random blocks (stone, glass, water, leaves, torches, glowing glass, much air) around the
/// corner of eight chunks, lit: every merged quad's corner light against the per-face
/// reference, with and without ambient occlusion.
#[test]
fn random_scenes_match_the_per_face_reference() {
    let ids = [
        blocks::STONE,
        blocks::STONE,
        blocks::STONE,
        blocks::GLASS,
        blocks::GREEN_GLASS,
        blocks::WATER,
        blocks::LEAVES,
        light_blocks::TORCH,
        light_blocks::GLOW_GLASS,
    ];
    let mut next = xorshift(0x5eed_1234_abcd_0042);
    for case in 0..6 {
        let mut w = world([0, 0, 0], [1, 1, 1]);
        // A floor, then random blocks in a box across the chunk borders; denser in
        // later cases.
        fill(&mut w, [0, 20, 0], [63, 20, 63], blocks::STONE);
        let density = 6 + 6 * case as u64;
        for x in 22..42 {
            for y in 21..44 {
                for z in 22..42 {
                    if next() % 100 < density {
                        let id = ids[(next() % ids.len() as u64) as usize];
                        w.set_block(pos([x, y, z]), id).expect("loaded");
                    }
                }
            }
        }
        let f = LightField::new(&w);
        for options in [
            MeshOptions::default(),
            MeshOptions {
                ambient_occlusion: false,
                translucent_occlusion: false,
            },
            MeshOptions {
                ambient_occlusion: true,
                translucent_occlusion: true,
            },
        ] {
            check_against_reference(&w, &f, options);
        }
        // Packed chunks mesh alike.
        let mut packed = w.clone();
        packed.pack_all();
        for (p, _) in w.iter() {
            let options = MeshOptions::default();
            assert_eq!(
                mesh_lit(&packed, &f, p, options),
                mesh_lit(&w, &f, p, options),
                "{p:?}"
            );
        }
    }
}

/// A chunk whose neighbours are not lit: their cells do not count (the border faces take
/// the light of the lit cells alone), and packed chunks give the same meshes.
#[test]
fn unlit_neighbours_do_not_count_and_forms_agree() {
    let mut w = world([0, 0, 0], [1, 0, 0]);
    fill(&mut w, [0, 0, 0], [63, 0, 31], blocks::STONE);
    w.set_block(pos([30, 1, 10]), light_blocks::TORCH)
        .expect("loaded");
    let mut f = LightField::new(&w);
    let full = mesh_lit(&w, &f, ChunkPos::new(0, 0, 0), MeshOptions::default());
    f.remove_chunk(&w, ChunkPos::new(1, 0, 0))
        .expect("same registry");
    // The reference reads unlit cells as not counted too.
    let alone = mesh_lit(&w, &f, ChunkPos::new(0, 0, 0), MeshOptions::default());
    let p = ChunkPos::new(0, 0, 0);
    let faces = lit_faces(&alone, p);
    for ((bp, face), e) in &faces {
        let r = reference(&w, &f, *bp, Face::from_index(*face).expect("face"));
        for k in 0..4 {
            assert_eq!(
                e.0[k],
                r[k].map(|v| i64::from(v) * e.1),
                "{bp:?} {face} {k}"
            );
        }
    }
    assert_ne!(
        full.light, alone.light,
        "the border reads the neighbour's light"
    );
    let mut packed = w.clone();
    packed.pack_all();
    let again = mesh_lit(&packed, &f, p, MeshOptions::default());
    assert_eq!(again, alone);
}

/// A torch placed with its light: `mesh_dirty_lit` remeshes the edited chunk and the
/// neighbours its light reached, each as `mesh_lit` meshes it.
#[test]
fn mesh_dirty_lit_remeshes_where_light_changed() {
    let mut w = world([0, 0, 0], [2, 0, 0]);
    fill(&mut w, [0, 0, 0], [95, 0, 31], blocks::STONE);
    let mut f = LightField::new(&w);
    w.take_dirty();
    f.take_changed();
    // Near the border of chunks 0 and 1, out of reach of chunk 2.
    w.set_block_lit(&mut f, pos([30, 1, 10]), light_blocks::TORCH)
        .expect("same registry");
    let meshes = crate::mesh_dirty_lit(&mut w, &mut f).expect("meshes");
    let got: Vec<ChunkPos> = meshes.iter().map(|(p, _)| *p).collect();
    assert!(got.contains(&ChunkPos::new(0, 0, 0)) && got.contains(&ChunkPos::new(1, 0, 0)));
    for (p, m) in &meshes {
        assert_eq!(*m, mesh_lit(&w, &f, *p, MeshOptions::default()), "{p:?}");
        assert!(!m.light.is_empty());
    }
    assert!(w.dirty().is_empty() && f.take_changed().is_empty());
    let again = crate::mesh_dirty_lit(&mut w, &mut f).expect("meshes");
    assert!(again.is_empty(), "nothing changed since");
}

/// The field keeps each dense layer's odd cells once made (the mesher reads them): edits
/// after a mesh rewrite them, and meshes after the edits still match the reference.
#[test]
fn meshes_after_edits_match_the_per_face_reference() {
    let mut w = world([0, 0, 0], [1, 1, 1]);
    fill(&mut w, [0, 20, 0], [63, 20, 63], blocks::STONE);
    fill(&mut w, [10, 21, 10], [50, 26, 50], blocks::WATER);
    let mut next = xorshift(0x0dd_ce11_5eed_0001);
    for _ in 0..300 {
        let p = [20 + next() % 24, 21 + next() % 20, 20 + next() % 24].map(|v| v as i32);
        w.set_block(pos(p), blocks::STONE).expect("loaded");
    }
    let mut f = LightField::new(&w);
    // Mesh once, so that the field has made the odd cells of the layers it read.
    check_against_reference(&w, &f, MeshOptions::default());
    let ids = [
        light_blocks::TORCH,
        light_blocks::GLOW_GLASS,
        blocks::STONE,
        blocks::GLASS,
        BlockId::AIR,
    ];
    for round in 0..4 {
        for _ in 0..6 {
            let p = [18 + next() % 28, 21 + next() % 20, 18 + next() % 28].map(|v| v as i32);
            let id = ids[(next() % ids.len() as u64) as usize];
            w.set_block_lit(&mut f, pos(p), id).expect("same registry");
        }
        if round == 2 {
            f.compact();
        }
        check_against_reference(&w, &f, MeshOptions::default());
    }
}
