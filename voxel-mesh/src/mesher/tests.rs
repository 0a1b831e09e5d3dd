//! The face rules against a naive mesher written from them, block by block (fixed cases
//! and random chunks, in every storage form), greedy merging and ambient occlusion.

use std::collections::BTreeSet;

use super::*;
use voxel_core::BlockDef;
use voxel_core::blocks::*;

/// One visible block face: (block position, face, block), possibly outside the chunk
/// for neighbour blocks in the naive model.
type UnitFace = ([usize; 3], usize, u16);

fn registry() -> BlockRegistry {
    BlockRegistry::default()
}

/// Meshes `chunk` as it is, and again in each of the 2^7 combinations of storage forms
/// (masks or packed) of the centre and the six neighbours, checking that every
/// combination gives the same quads.
fn mesh(chunk: &Chunk, nb: Neighbours<'_>) -> ChunkMeshes {
    let mut mesher = Mesher::new(&registry());
    let m = mesher.mesh(chunk, nb).expect("known blocks");
    let forms = |c: &Chunk| {
        let (mut masks, mut packed) = (c.clone(), c.clone());
        masks.unpack();
        packed.pack();
        [masks, packed]
    };
    let centre = forms(chunk);
    let nbs = nb.map(|n| n.map(forms));
    for combo in 0..1 << 7 {
        let pick = |slot: usize| combo >> slot & 1;
        let nb: Neighbours<'_> = std::array::from_fn(|i| nbs[i].as_ref().map(|f| &f[pick(i + 1)]));
        let other = mesher.mesh(&centre[pick(0)], nb).expect("known blocks");
        assert!(
            same_quads(&m, &other),
            "forms {combo:#09b} mesh differently"
        );
    }
    m
}

/// The blocks whose faces quad `u` covers; panics on a quad that leaves the chunk.
fn covered_blocks(u: crate::Quad) -> impl Iterator<Item = [usize; 3]> {
    let [ua, va] = crate::UV_AXES[u.face.axis()];
    let (w, h) = (usize::from(u.size[0]), usize::from(u.size[1]));
    (0..w).flat_map(move |i| {
        (0..h).map(move |j| {
            let mut p = u.pos.map(usize::from);
            p[ua] += i;
            p[va] += j;
            assert!(p.iter().all(|&c| c < 32), "quad {u:?} leaves the chunk");
            p
        })
    })
}

/// Every unit face covered by `quads`; panics on a face covered twice.
fn unit_faces(quads: &[PackedQuad]) -> BTreeSet<UnitFace> {
    let mut set = BTreeSet::new();
    for q in quads {
        let u = q.unpack().expect("valid quad");
        for p in covered_blocks(u) {
            assert!(
                set.insert((p, u.face as usize, u.block.0)),
                "face twice: {p:?} {u:?}"
            );
        }
    }
    set
}

const VOLUME: usize = 32 * 32 * 32;
/// Marks an interface face in a [`FaceMap`] (the test registries have far fewer ids).
const INTERFACE_BIT: u16 = 1 << 15;

/// Every unit face of one chunk as a dense table: for each mesh (opaque, cutout,
/// translucent), face direction and block position, the block id plus one (0: no face),
/// with [`INTERFACE_BIT`] set on a face flagged as an interface, and the face's AO byte
/// in bits 16..24.
/// Much faster to fill and compare than a set, so that the property test can afford
/// hundreds of chunks.
#[derive(PartialEq, Eq)]
struct FaceMap(Vec<u32>);

impl FaceMap {
    fn new() -> Self {
        Self(vec![0; 3 * 6 * VOLUME])
    }

    /// Records a face of `block` (an interface when `interface`); false if that face
    /// was there already.
    fn insert(
        &mut self,
        mesh: usize,
        face: usize,
        p: [usize; 3],
        block: BlockId,
        interface: bool,
        ao: u8,
    ) -> bool {
        let slot = &mut self.0[(mesh * 6 + face) * VOLUME + (p[0] * 32 + p[1]) * 32 + p[2]];
        let was = *slot;
        *slot = u32::from((block.0 + 1) | if interface { INTERFACE_BIT } else { 0 })
            | u32::from(ao) << 16;
        was == 0
    }

    /// Number of unit faces.
    fn count(&self) -> usize {
        self.0.iter().filter(|&&v| v != 0).count()
    }

    /// `None` when equal, else how many faces differ and the first of them.
    fn diff(&self, want: &Self) -> Option<String> {
        let mut bad = (0..self.0.len()).filter(|&i| self.0[i] != want.0[i]);
        let i = bad.next()?;
        let (mesh, face, p) = (i / (6 * VOLUME), i / VOLUME % 6, i % VOLUME);
        Some(format!(
            "{} unit faces differ; first: mesh {mesh} (0 opaque, 1 cutout, 2 translucent), \
             {:?} of block ({}, {}, {}): mesher has id+1 = {} AO {:08b}, the rules {} AO {:08b}",
            bad.count() + 1,
            Face::ALL[face],
            p / 1024,
            p / 32 % 32,
            p % 32,
            self.0[i] & 0xffff,
            self.0[i] >> 16,
            want.0[i] & 0xffff,
            want.0[i] >> 16,
        ))
    }
}

/// The unit faces of the three meshes; panics on a face covered twice, or a quad that
/// leaves the chunk.
fn face_map(m: &ChunkMeshes) -> FaceMap {
    let mut map = FaceMap::new();
    for (k, quads) in [&m.opaque, &m.cutout, &m.translucent]
        .into_iter()
        .enumerate()
    {
        for q in quads {
            let u = q.unpack().expect("valid quad");
            let interface = q.flags() & crate::FLAG_INTERFACE != 0;
            for p in covered_blocks(u) {
                assert!(
                    map.insert(k, u.face as usize, p, u.block, interface, q.ao()),
                    "face twice: {p:?} {u:?}"
                );
            }
        }
    }
    map
}

/// The face rules and the ambient occlusion rule (with the default options) written
/// the slow, obvious way, one block at a time, from the whole 3×3×3 neighbourhood.
fn naive<'n>(reg: &BlockRegistry, chunk: &Chunk, nb: impl Into<Neighbourhood<'n>>) -> FaceMap {
    let nb: Neighbourhood<'n> = nb.into();
    let class = |id: BlockId| reg.class(id).expect("known");
    let dense = chunk.to_dense();
    let nb_dense: Vec<([i32; 3], Vec<BlockId>)> = Neighbourhood::OFFSETS
        .iter()
        .filter_map(|&d| Some((d, nb.get(d)?.to_dense())))
        .collect();
    let get = |p: [i64; 3]| -> BlockId {
        let wrap = p.map(|v| v.rem_euclid(32) as usize);
        let at = |d: &[BlockId]| d[Chunk::dense_index(wrap[0], wrap[1], wrap[2])];
        let d = p.map(|v| (v.div_euclid(32)) as i32);
        if d == [0; 3] {
            return at(&dense);
        }
        nb_dense
            .iter()
            .find(|(o, _)| *o == d)
            .map_or(AIR, |(_, blocks)| at(blocks))
    };
    let opaque_at = |p: [i64; 3]| class(get(p)) == RenderClass::Opaque;
    // The AO byte of a face of block `b` in direction `face`: per corner (u, v) of the
    // face's (U, V) axes, the sides and the corner in the layer in front.
    let ao_of = |b: [i64; 3], face: Face| -> u8 {
        let [ua, va] = crate::UV_AXES[face.axis()];
        let n = face.normal();
        let front = [0, 1, 2].map(|a| b[a] + i64::from(n[a]));
        let mut ao = 0;
        for v in 0..2 {
            for u in 0..2 {
                let (du, dv) = (2 * u as i64 - 1, 2 * v as i64 - 1);
                let mut s1 = front;
                s1[ua] += du;
                let mut s2 = front;
                s2[va] += dv;
                let mut c = s1;
                c[va] += dv;
                let value = crate::ao::vertex_ao(opaque_at(s1), opaque_at(s2), opaque_at(c));
                ao |= value << (2 * (u + 2 * v));
            }
        }
        ao
    };
    let mut out = FaceMap::new();
    for x in 0..32 {
        for y in 0..32 {
            for z in 0..32 {
                let a = dense[Chunk::dense_index(x, y, z)];
                let ca = class(a);
                if ca == RenderClass::Air {
                    continue;
                }
                // The translucent type a cell holds: its block's, or the medium it stands in.
                let holds = |id: BlockId| {
                    if class(id) == RenderClass::Translucent {
                        Some(id)
                    } else {
                        reg.get(id).expect("known").medium
                    }
                };
                for face in Face::ALL {
                    let n = face.normal();
                    let b = get([
                        x as i64 + i64::from(n[0]),
                        y as i64 + i64::from(n[1]),
                        z as i64 + i64::from(n[2]),
                    ]);
                    // The block's own face: an opaque neighbour hides it, and a translucent
                    // one the cells that hold its type (waterlogged blocks hold their medium).
                    let hidden = class(b) == RenderClass::Opaque
                        || (ca == RenderClass::Translucent && holds(b) == Some(a));
                    if !hidden && ca != RenderClass::Air {
                        let k = match ca {
                            RenderClass::Cutout => 1,
                            RenderClass::Translucent => 2,
                            _ => 0,
                        };
                        // A translucent face toward another translucent type.
                        let interface =
                            ca == RenderClass::Translucent && holds(b).is_some_and(|t| t != a);
                        let ao = if ca == RenderClass::Translucent {
                            AO_NONE
                        } else {
                            ao_of([x, y, z].map(|v| v as i64), face)
                        };
                        out.insert(k, face as usize, [x, y, z], a, interface, ao);
                    }
                    // A block standing in a medium holds it: the medium's face where the
                    // neighbour neither hides it nor holds the medium too.
                    if let Some(m) = reg.get(a).expect("known").medium
                        && class(b) != RenderClass::Opaque
                        && holds(b) != Some(m)
                    {
                        let interface = holds(b).is_some();
                        out.insert(2, face as usize, [x, y, z], m, interface, AO_NONE);
                    }
                }
            }
        }
    }
    out
}

/// Panics, saying `what` and where, unless `m` holds exactly the faces of the rules.
fn assert_rules<'n>(
    m: &ChunkMeshes,
    reg: &BlockRegistry,
    chunk: &Chunk,
    nb: impl Into<Neighbourhood<'n>>,
    what: &str,
) {
    if let Some(d) = face_map(m).diff(&naive(reg, chunk, nb)) {
        panic!("{what}: {d}");
    }
}

fn has(m: &[PackedQuad], pos: [usize; 3], face: Face) -> bool {
    unit_faces(m)
        .iter()
        .any(|f| f.0 == pos && f.1 == face as usize)
}

const NONE: Neighbours<'static> = [None; 6];

#[test]
fn opaque_hides_everything_behind_it() {
    let mut c = Chunk::default();
    c.set(5, 5, 5, STONE).unwrap();
    c.set(6, 5, 5, WATER).unwrap();
    c.set(5, 6, 5, LEAVES).unwrap();
    c.set(5, 5, 6, STONE).unwrap();
    let m = mesh(&c, NONE);
    assert!(
        !has(&m.translucent, [6, 5, 5], Face::NegX),
        "water face against stone"
    );
    assert!(
        has(&m.opaque, [5, 5, 5], Face::PosX),
        "stone face against water stays"
    );
    assert!(
        !has(&m.cutout, [5, 6, 5], Face::NegY),
        "leaves face against stone"
    );
    assert!(
        has(&m.opaque, [5, 5, 5], Face::PosY),
        "stone face against leaves stays"
    );
    assert!(
        !has(&m.opaque, [5, 5, 5], Face::PosZ),
        "stone against stone"
    );
    assert!(
        !has(&m.opaque, [5, 5, 6], Face::NegZ),
        "stone against stone"
    );
}

#[test]
fn same_translucent_type_is_culled() {
    let mut c = Chunk::default();
    c.fill_box([0, 0, 0], [1, 0, 0], WATER).unwrap();
    let m = mesh(&c, NONE);
    assert!(!has(&m.translucent, [0, 0, 0], Face::PosX));
    assert!(!has(&m.translucent, [1, 0, 0], Face::NegX));
    // The two blocks' outer faces merge: 1 + 1 ends, 4 sides of 2×1.
    assert_eq!(unit_faces(&m.translucent).len(), 10);
    assert_eq!(m.translucent.len(), 6);
}

#[test]
fn different_translucent_types_keep_both_faces() {
    let mut c = Chunk::default();
    c.set(3, 3, 3, WATER).unwrap();
    c.set(3, 3, 4, GLASS).unwrap();
    let m = mesh(&c, NONE);
    assert!(
        has(&m.translucent, [3, 3, 3], Face::PosZ),
        "water toward glass"
    );
    assert!(
        has(&m.translucent, [3, 3, 4], Face::NegZ),
        "glass toward water"
    );
    assert_eq!(unit_faces(&m.translucent).len(), 12);
}

#[test]
fn cutout_faces_stay_against_air_translucent_and_cutout() {
    let mut c = Chunk::default();
    c.set(8, 8, 8, LEAVES).unwrap();
    c.set(9, 8, 8, LEAVES).unwrap();
    c.set(8, 9, 8, GLASS).unwrap();
    c.set(8, 8, 9, STONE).unwrap();
    let m = mesh(&c, NONE);
    assert!(
        has(&m.cutout, [8, 8, 8], Face::PosX),
        "leaves toward leaves"
    );
    assert!(
        has(&m.cutout, [9, 8, 8], Face::NegX),
        "leaves toward leaves"
    );
    assert!(has(&m.cutout, [8, 8, 8], Face::PosY), "leaves toward glass");
    assert!(
        has(&m.translucent, [8, 9, 8], Face::NegY),
        "glass toward leaves"
    );
    assert!(has(&m.cutout, [8, 8, 8], Face::NegX), "leaves toward air");
    assert!(
        !has(&m.cutout, [8, 8, 8], Face::PosZ),
        "leaves toward stone"
    );
}

#[test]
fn border_faces_look_at_the_neighbour_chunk() {
    let mut c = Chunk::default();
    c.set(31, 4, 4, STONE).unwrap();
    c.set(0, 4, 4, WATER).unwrap();
    c.set(4, 31, 4, WATER).unwrap();
    let mut px = Chunk::default();
    px.set(0, 4, 4, STONE).unwrap();
    let mut nx = Chunk::default();
    nx.set(31, 4, 4, WATER).unwrap();
    let mut py = Chunk::default();
    py.set(4, 0, 4, GLASS).unwrap();
    // Missing neighbours count as air: every border face is there.
    let alone = mesh(&c, NONE);
    assert!(has(&alone.opaque, [31, 4, 4], Face::PosX));
    assert!(has(&alone.translucent, [0, 4, 4], Face::NegX));
    assert!(has(&alone.translucent, [4, 31, 4], Face::PosY));
    let nb = [Some(&px), Some(&nx), Some(&py), None, None, None];
    let m = mesh(&c, nb);
    assert!(
        !has(&m.opaque, [31, 4, 4], Face::PosX),
        "stone against neighbour stone"
    );
    assert!(
        !has(&m.translucent, [0, 4, 4], Face::NegX),
        "water against neighbour water"
    );
    assert!(
        has(&m.translucent, [4, 31, 4], Face::PosY),
        "water against neighbour glass"
    );
    assert_rules(&m, &registry(), &c, nb, "borders");
}

#[test]
fn empty_uniform_and_enclosed_chunks() {
    assert!(mesh(&Chunk::default(), NONE).is_empty());
    let stone = Chunk::uniform(STONE);
    assert!(mesh(&stone, [Some(&stone); 6]).is_empty(), "enclosed");
    // A mixed but all-opaque chunk inside stone has no faces either.
    let mut mixed = Chunk::uniform(STONE);
    mixed.fill_box([3, 3, 3], [9, 9, 9], DIRT).unwrap();
    assert!(mesh(&mixed, [Some(&stone); 6]).is_empty());
    // Alone, a uniform chunk is one 32×32 quad per side.
    let m = mesh(&stone, NONE);
    assert_eq!(m.opaque.len(), 6);
    assert!(m.opaque.iter().all(|q| q.area() == 1024));
    // Water under air, above stone, beside water: only the top layer.
    let water = Chunk::uniform(WATER);
    let nb = [
        Some(&water),
        Some(&water),
        None,
        Some(&stone),
        Some(&water),
        Some(&water),
    ];
    let m = mesh(&water, nb);
    assert_eq!(m.translucent.len(), 1);
    assert_eq!(m.translucent[0].unpack().unwrap().face, Face::PosY);
    assert_rules(&m, &registry(), &water, nb, "water");
    // A partly open neighbour layer: faces exactly where it is open.
    let mut holey = Chunk::uniform(STONE);
    holey.fill_box([0, 0, 3], [31, 0, 5], AIR).unwrap();
    let nb = [
        Some(&stone),
        Some(&stone),
        Some(&holey),
        Some(&stone),
        Some(&stone),
        Some(&stone),
    ];
    assert_rules(&mesh(&stone, nb), &registry(), &stone, nb, "holey");
    assert_eq!(unit_faces(&mesh(&stone, nb).opaque).len(), 32 * 3);
}

#[test]
fn greedy_merges_coplanar_faces_of_the_same_block_only() {
    let mut c = Chunk::default();
    c.fill_box([0, 0, 0], [31, 0, 31], STONE).unwrap();
    let m = mesh(&c, NONE);
    let top: Vec<_> = m
        .opaque
        .iter()
        .filter(|q| q.face_index() == Face::PosY as usize)
        .collect();
    assert_eq!(top.len(), 1);
    assert_eq!(top[0].area(), 1024);
    c.fill_box([0, 0, 0], [15, 0, 31], DIRT).unwrap();
    let m = mesh(&c, NONE);
    let top: Vec<_> = m
        .opaque
        .iter()
        .filter(|q| q.face_index() == Face::PosY as usize)
        .collect();
    assert_eq!(top.len(), 2, "stone and dirt halves stay apart");
}

#[test]
fn unknown_blocks_are_an_error() {
    let mut c = Chunk::default();
    c.set(0, 0, 0, BlockId(40)).unwrap();
    let mut mesher = Mesher::new(&registry());
    assert_eq!(mesher.mesh(&c, NONE), Err(Error::UnknownBlock(BlockId(40))));
    let ok = Chunk::uniform(STONE);
    assert_eq!(
        mesher.mesh(&ok, [Some(&c), None, None, None, None, None]),
        Err(Error::UnknownBlock(BlockId(40)))
    );
    c.pack();
    assert!(c.is_packed());
    assert_eq!(mesher.mesh(&c, NONE), Err(Error::UnknownBlock(BlockId(40))));
    assert_eq!(
        mesher.mesh(&ok, [None, None, None, None, None, Some(&c)]),
        Err(Error::UnknownBlock(BlockId(40)))
    );
}

#[test]
fn uniform_cutout_chunks_keep_every_inner_face() {
    // Leaves hide nothing, leaves included (the uniform shortcut kept only
    // the borders, 6 quads alone and none between stone).
    let reg = registry();
    let leaves = Chunk::uniform(LEAVES);
    let m = mesh(&leaves, NONE);
    assert_eq!(face_map(&m).count(), 6 * 32 * 32 * 32);
    assert_eq!((m.cutout.len(), m.len()), (6 * 32, 6 * 32));
    assert_rules(&m, &reg, &leaves, NONE, "leaves alone");
    // Between stone only the faces against the stone go. The stone around each inner
    // layer's rim darkens its edge rows (4 edges and 4 corners of different occlusion
    // beside the open middle: 9 quads a layer).
    let stone = Chunk::uniform(STONE);
    let m = mesh(&leaves, [Some(&stone); 6]);
    assert_eq!(face_map(&m).count(), 6 * 31 * 32 * 32);
    assert_eq!((m.cutout.len(), m.len()), (6 * 31 * 9, 6 * 31 * 9));
    assert_rules(&m, &reg, &leaves, [Some(&stone); 6], "leaves in stone");
    // Leaves beside leaves, water and air: every face.
    let water = Chunk::uniform(WATER);
    let nb = [Some(&leaves), Some(&water), None, Some(&leaves), None, None];
    assert_eq!(face_map(&mesh(&leaves, nb)).count(), 6 * 32 * 32 * 32);
}

/// The AO byte of the unit face of `pos` facing `face` (panics if there is none).
fn ao_at(quads: &[PackedQuad], pos: [usize; 3], face: Face) -> u8 {
    quads
        .iter()
        .find(|q| {
            let u = q.unpack().expect("valid quad");
            u.face == face && covered_blocks(u).any(|p| p == pos)
        })
        .map(|q| q.ao())
        .unwrap_or_else(|| panic!("no {face:?} face at {pos:?}"))
}

#[test]
fn occlusion_reads_edge_and_corner_neighbours() {
    // A stone floor at the top of the chunk; its top faces look into the +y neighbour.
    let mut floor = Chunk::default();
    floor.fill_box([0, 31, 0], [31, 31, 31], STONE).unwrap();
    let top = [31, 31, 31];
    // One stone block in the corner chunk (+1, +1, +1), touching only the vertex
    // (32, 32, 32): corner (u1, v1) of the +y face of block (31, 31, 31) drops to 2.
    let mut corner = Chunk::default();
    corner.set(0, 0, 0, STONE).unwrap();
    let nb = Neighbourhood::from_fn(|d| (d == [1, 1, 1]).then_some(&corner));
    let m = Mesher::new(&registry()).mesh(&floor, nb).unwrap();
    assert_eq!(ao_at(&m.opaque, top, Face::PosY), 0b10_11_11_11);
    assert_rules(&m, &registry(), &floor, nb, "corner neighbour");
    // A stone block in the edge chunk (+1, +1, 0) at z = 31 is a side of the +y face
    // of block (31, 31, 31) along +x, its V axis: both (u, v1) corners drop to 2.
    let mut edge = Chunk::default();
    edge.set(0, 0, 31, STONE).unwrap();
    let nb = Neighbourhood::from_fn(|d| (d == [1, 1, 0]).then_some(&edge));
    let m = Mesher::new(&registry()).mesh(&floor, nb).unwrap();
    assert_eq!(ao_at(&m.opaque, top, Face::PosY), 0b10_10_11_11);
    assert_rules(&m, &registry(), &floor, nb, "edge neighbour");
    // Without the edge and corner neighbours (six faces only) nothing occludes.
    let m = Mesher::new(&registry()).mesh(&floor, NONE).unwrap();
    assert_eq!(ao_at(&m.opaque, top, Face::PosY), AO_NONE);
    assert_eq!(m.opaque.iter().filter(|q| q.face_index() == 2).count(), 1);
}

#[test]
fn faces_merge_only_with_equal_occlusion() {
    // A 32×32 stone floor with one block on it: the floor's top faces around the block
    // are darkened, each of the 8 around it with its own corners; the rest merges.
    let mut c = Chunk::default();
    c.fill_box([0, 0, 0], [31, 0, 31], STONE).unwrap();
    c.set(10, 1, 10, STONE).unwrap();
    let m = Mesher::new(&registry()).mesh(&c, NONE).unwrap();
    assert_rules(&m, &registry(), &c, NONE, "block on a floor");
    let tops: Vec<_> = m
        .opaque
        .iter()
        .filter(|q| q.face_index() == Face::PosY as usize && q.unpack().unwrap().pos[1] == 0)
        .collect();
    let shaded: Vec<_> = tops.iter().filter(|q| q.ao() != AO_NONE).collect();
    assert_eq!(shaded.len(), 8, "one quad per darkened face: {shaded:?}");
    assert!(shaded.iter().all(|q| q.area() == 1));
    // Beside the block (a side occluder): the two corners toward it are 2, the others 3.
    let beside = ao_at(&m.opaque, [11, 0, 10], Face::PosY);
    let values: Vec<u8> = (0..4).map(|i| beside >> (2 * i) & 3).collect();
    assert_eq!(values.iter().filter(|&&v| v == 2).count(), 2, "{values:?}");
    assert_eq!(values.iter().filter(|&&v| v == 3).count(), 2, "{values:?}");
    // Options off: no occlusion, and the floor's open faces merge as before.
    let plain = Mesher::with_options(
        &registry(),
        MeshOptions {
            ambient_occlusion: false,
            ..MeshOptions::default()
        },
    )
    .mesh(&c, NONE)
    .unwrap();
    assert!(plain.opaque.iter().all(|q| q.ao() == AO_NONE));
    assert!(plain.opaque.len() < m.opaque.len());
}

/// Deterministic xorshift64 for the property test.
struct XorShift(u64);

impl XorShift {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }

    fn pick<T: Copy>(&mut self, v: &[T]) -> T {
        v[self.below(v.len())]
    }
}

/// What a chunk slot of a property-test case holds.
#[derive(Clone, Copy, Debug)]
enum Kind {
    /// No chunk (a missing neighbour; counts as air).
    Missing,
    /// `Chunk::uniform(id)`.
    Uniform(BlockId),
    /// Several block types: see [`mixed_chunk`].
    Mixed,
}

/// A chunk of at least two types from `ids`: a random base, random boxes (runs to
/// merge), then 1, 40 or 2000 random single blocks, from nearly uniform to noise; the
/// types come from a pool of two to four picks or from all of `ids`.
fn mixed_chunk(rng: &mut XorShift, ids: &[BlockId]) -> Chunk {
    let pool: Vec<BlockId> = if rng.below(3) == 0 {
        ids.to_vec()
    } else {
        (0..2 + rng.below(3)).map(|_| rng.pick(ids)).collect()
    };
    let mut c = Chunk::uniform(rng.pick(&pool));
    for _ in 0..rng.below(30) {
        let id = rng.pick(&pool);
        let r = rng.next();
        let p = [r % 32, (r >> 8) % 32, (r >> 16) % 32].map(|v| v as usize);
        let e = [(r >> 32) % 12, (r >> 40) % 12, (r >> 48) % 12].map(|v| v as usize);
        let q = [0, 1, 2].map(|i| (p[i] + e[i]).min(31));
        c.fill_box(p, q, id).unwrap();
    }
    for _ in 0..rng.pick(&[1, 40, 2000]) {
        let id = rng.pick(&pool);
        let r = rng.next();
        let p = [r % 32, (r >> 8) % 32, (r >> 16) % 32].map(|v| v as usize);
        c.set(p[0], p[1], p[2], id).unwrap();
    }
    if let Some(u) = c.as_uniform() {
        let other = ids.iter().copied().find(|&i| i != u).expect("two ids");
        let r = rng.next();
        c.set((r % 32) as usize, ((r >> 8) % 32) as usize, 0, other)
            .unwrap();
    }
    assert!(c.as_uniform().is_none());
    c
}

/// The property test: every unit face the mesher emits, and no other, is one the
/// one-block-at-a-time [`naive`] rules emit, on 264 chunks with their neighbours.
///
/// Two registries: the default one (13 blocks, one cutout type) and one with two more
/// cutout types, two more translucent types and one more opaque type (18 blocks). For
/// each, the centre is in turn uniform of every block of the registry (air, every
/// opaque, every cutout, every translucent type) and then mixed (random boxes and
/// single blocks, from nearly uniform to noise); each centre meets eight neighbour
/// patterns: all missing, all uniform of random blocks, all uniform of the centre's
/// block, all uniform opaque (enclosed), all mixed, and three where each of the 26
/// neighbours is independently missing, uniform of a random block or mixed. The test
/// checks that every centre class (air, opaque, cutout, translucent, mixed) met every
/// neighbour kind (missing, uniform air, opaque, cutout or translucent, mixed). The
/// neighbours are all 26 around the centre (the edge and corner ones matter to ambient
/// occlusion), and the rules' oracle checks every face's corner occlusion too.
///
/// Storage forms: each mixed chunk (centre or neighbour) is packed or left in mask form
/// at random, and every case is meshed again with each mixed chunk in the other form,
/// which must give the same quads; the test checks that every centre form (uniform,
/// masks, packed) met every neighbour form (missing, uniform, masks, packed).
///
/// The test this replaced drew only mixed centres, so it never met the uniform
/// shortcut, and missed that uniform cutout centres lost every inner face.
#[test]
fn random_chunks_match_the_naive_rules_exactly() {
    let mut extended = registry();
    for def in [
        BlockDef::cutout("vines", [40, 110, 30]),
        BlockDef::cutout("autumn_leaves", [190, 90, 30]),
        BlockDef::new("tinted_glass", [60, 50, 70], 0.6),
        BlockDef::new("slime", [110, 200, 90], 0.85),
        BlockDef::new("basalt", [50, 50, 55], 1.0),
        // Standing in water and in the tinted glass: they hide those faces.
        BlockDef::cutout("kelp", [40, 120, 60]).in_medium(voxel_core::blocks::WATER),
    ] {
        extended.register(def).unwrap();
    }
    let tinted = extended.id("tinted_glass").unwrap();
    extended
        .register(BlockDef::cutout("reeds", [150, 160, 70]).in_medium(tinted))
        .unwrap();
    let mut rng = XorShift(0x9e37_79b9_7f4a_7c15);
    let mut covered = BTreeSet::new();
    let mut forms = BTreeSet::new();
    let mut forms_rng = XorShift(0x2545_f491_4f6c_dd1d);
    let mut cases = 0;
    for reg in [registry(), extended] {
        let ids: Vec<BlockId> = reg.iter().map(|(id, _)| id).collect();
        let class = |id| reg.class(id).unwrap();
        let opaque: Vec<BlockId> = ids
            .iter()
            .copied()
            .filter(|&id| class(id) == RenderClass::Opaque)
            .collect();
        let label = |k: Kind| match k {
            Kind::Missing => "missing".to_owned(),
            Kind::Uniform(id) => format!("uniform {:?}", class(id)),
            Kind::Mixed => "mixed".to_owned(),
        };
        let mut mesher = Mesher::new(&reg);
        let centres = ids.iter().map(|&id| Kind::Uniform(id));
        for centre_kind in centres.chain([Kind::Mixed]) {
            for pattern in 0..8 {
                let same = match centre_kind {
                    Kind::Uniform(id) => id,
                    _ => rng.pick(&ids),
                };
                // Face neighbours first, then edges and corners (`Neighbourhood::OFFSETS`).
                let nb_kinds: [Kind; 26] = std::array::from_fn(|_| match pattern {
                    0 => Kind::Missing,
                    1 => Kind::Uniform(rng.pick(&ids)),
                    2 => Kind::Uniform(same),
                    3 => Kind::Uniform(rng.pick(&opaque)),
                    4 => Kind::Mixed,
                    _ => match rng.below(3) {
                        0 => Kind::Missing,
                        1 => Kind::Uniform(rng.pick(&ids)),
                        _ => Kind::Mixed,
                    },
                });
                // A mixed chunk is packed or left in mask form at random (its own
                // stream, so that the chunks drawn stay those of the test before forms).
                let mut make = |k: Kind| match k {
                    Kind::Missing => None,
                    Kind::Uniform(id) => Some(Chunk::uniform(id)),
                    Kind::Mixed => {
                        let mut c = mixed_chunk(&mut rng, &ids);
                        if forms_rng.below(2) == 0 {
                            c.pack();
                        }
                        Some(c)
                    }
                };
                let centre = make(centre_kind).expect("a centre");
                let nbs = nb_kinds.map(&mut make);
                fn around(nbs: &[Option<Chunk>; 26]) -> Neighbourhood<'_> {
                    Neighbourhood::from_fn(|d| {
                        let i = Neighbourhood::OFFSETS.iter().position(|&o| o == d)?;
                        nbs[i].as_ref()
                    })
                }
                let nb = around(&nbs);
                let m = mesher.mesh(&centre, nb).unwrap();
                let what = format!(
                    "case {cases}: {} blocks, centre {centre_kind:?} {}, neighbours {nb_kinds:?} {:?}",
                    reg.len(),
                    form(Some(&centre)),
                    nbs.each_ref().map(|c| form(c.as_ref()))
                );
                assert_rules(&m, &reg, &centre, nb, &what);
                // The same chunks with every mixed one in the other form: the same quads.
                let flip = |c: &Chunk| {
                    let mut c = c.clone();
                    if c.is_packed() {
                        c.unpack();
                    } else {
                        c.pack();
                    }
                    c
                };
                let centre2 = flip(&centre);
                let nbs2 = nbs.each_ref().map(|c| c.as_ref().map(flip));
                let m2 = mesher.mesh(&centre2, around(&nbs2)).unwrap();
                assert!(
                    same_quads(&m, &m2),
                    "{what}: the other forms mesh differently"
                );
                for k in nb_kinds {
                    covered.insert((label(centre_kind), label(k)));
                }
                for (c, n) in [(&centre, &nbs), (&centre2, &nbs2)] {
                    for n in n {
                        forms.insert((form(Some(c)), form(n.as_ref())));
                    }
                }
                cases += 1;
            }
        }
    }
    assert_eq!(cases, (14 + 21) * 8);
    assert_eq!(covered.len(), 5 * 6, "{covered:?}");
    assert_eq!(forms.len(), 3 * 4, "{forms:?}");
}

/// The storage form of a chunk slot, for the property test's coverage.
fn form(c: Option<&Chunk>) -> &'static str {
    match c {
        None => "missing",
        Some(c) if c.as_uniform().is_some() => "uniform",
        Some(c) if c.is_packed() => "packed",
        Some(_) => "masks",
    }
}

/// Whether two meshes hold the same quads, in any order.
fn same_quads(a: &ChunkMeshes, b: &ChunkMeshes) -> bool {
    let sorted = |v: &[PackedQuad]| {
        let mut v: Vec<_> = v.iter().map(|q| (q.geometry, q.block)).collect();
        v.sort_unstable();
        v
    };
    [
        (&a.opaque, &b.opaque),
        (&a.cutout, &b.cutout),
        (&a.translucent, &b.translucent),
    ]
    .into_iter()
    .all(|(x, y)| sorted(x) == sorted(y))
}

/// A waterlogged block holds its water: where a kelp column pokes out of a pool, the water
/// stands around and over it (Minecraft's rule: the medium of a waterlogged block ends at
/// the block's top when no water is above it), and no water face lies inside the column.
#[test]
fn a_waterlogged_block_above_the_water_line_holds_its_water() {
    let mut reg = registry();
    let kelp = reg
        .register(BlockDef::cutout("kelp", [40, 120, 60]).in_medium(WATER))
        .unwrap();
    let mut c = Chunk::default();
    // A pool 4 deep (y 0..=3) and a kelp column from its floor to y = 6.
    c.fill_box([0, 0, 0], [9, 3, 9], WATER).unwrap();
    c.fill_box([5, 0, 5], [5, 6, 5], kelp).unwrap();
    let m = Mesher::new(&reg).mesh(&c, NONE).expect("known blocks");
    let water = |pos: [usize; 3], face: Face| {
        unit_faces(&m.translucent).contains(&(pos, face as usize, WATER.0))
    };
    // Over the column's top, and around it above the water line.
    assert!(
        water([5, 6, 5], Face::PosY),
        "the water over the kelp's top"
    );
    for y in 4..=6 {
        for face in [Face::PosX, Face::NegX, Face::PosZ, Face::NegZ] {
            assert!(
                water([5, y, 5], face),
                "the water around the kelp at y = {y}, {face:?}"
            );
        }
    }
    // Inside the column (the water line at y = 3 → 4) and toward the pool: none.
    assert!(!water([5, 3, 5], Face::PosY) && !water([5, 4, 5], Face::NegY));
    for face in [Face::PosX, Face::NegX, Face::PosZ, Face::NegZ] {
        assert!(
            !water([5, 2, 5], face),
            "no water face inside the pool at the kelp"
        );
    }
    // The pool's surface all around the column, none over it.
    assert!(water([4, 3, 5], Face::PosY) && water([6, 3, 5], Face::PosY));
    // The kelp's own faces are cutout, unchanged.
    assert!(has(&m.cutout, [5, 6, 5], Face::PosY));
    // A column of kelp alone (no water anywhere in the chunk) still holds its water.
    let mut dry = Chunk::default();
    dry.fill_box([2, 2, 2], [2, 4, 2], kelp).unwrap();
    let m = Mesher::new(&reg).mesh(&dry, NONE).expect("known blocks");
    assert_eq!(
        unit_faces(&m.translucent).len(),
        14,
        "a 1×3×1 column of water around the kelp"
    );
}
