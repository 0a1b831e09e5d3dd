//! The three-way binary greedy mesher: one chunk plus its six neighbours in, opaque, cutout
//! and translucent quads out.
//!
//! Face rules (the unit tests below check each one): a face of a non-air block is emitted
//! where its neighbour does not hide it.
//! - An opaque neighbour hides every face.
//! - A translucent block hides the faces of blocks of its own type (no water-water walls),
//!   nothing else: water against glass keeps both faces.
//! - Air and cutout blocks hide nothing, so cutout faces stay against air, translucent and
//!   other cutout blocks, leaves against leaves included (the holes of one leaf block show
//!   the leaves behind it, as in Minecraft's fancy leaves).
//! - Across a chunk border the neighbour chunk decides; a missing neighbour counts as air,
//!   so the edge of a loaded area is closed by faces rather than left with holes.
//!
//! The algorithm works on the chunk's storage directly: every block type present has its
//! blocks as bits, in vertical columns and in rows along x ([`Occupancy`]). For each type,
//! the visible faces of a layer are one AND-NOT between its rows and the "hides me" rows of
//! the next layer; they are then covered with rectangles by [`greedy_rects`]. Bits are per
//! block type, so merged quads never mix blocks and no per-block comparison is needed. Cost
//! grows with the number of block types in the chunk, which is small (4 to 9 on terrain).
//!
//! Greedy merging is applied to all three meshes. For cutout and translucent blocks it is
//! as correct as for opaque ones: texture coordinates come from world position, so a merged
//! quad shows the same texels as the unit faces it replaces, and coverage is identical. It
//! makes translucent quads larger, so per-quad sorting is coarser; the exact reference and
//! depth peeling are per pixel and do not care.

use voxel_core::{
    BlockId, BlockRegistry, CHUNK_AREA, CHUNK_SIZE, Chunk, ColumnMask, Face, Occupancy,
    RenderClass, row_index,
};

use crate::bits::greedy_rects;
use crate::{Error, PackedQuad, Result};

/// The quads of one chunk, split by the pass that draws them.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ChunkMeshes {
    /// Opaque faces, drawn first with depth write.
    pub opaque: Vec<PackedQuad>,
    /// Alpha-tested faces (leaves).
    pub cutout: Vec<PackedQuad>,
    /// Blended faces (water, glass), drawn by the transparency technique.
    pub translucent: Vec<PackedQuad>,
}

impl ChunkMeshes {
    /// Whether all three meshes are empty.
    pub fn is_empty(&self) -> bool {
        self.opaque.is_empty() && self.cutout.is_empty() && self.translucent.is_empty()
    }

    /// Total number of quads.
    pub fn len(&self) -> usize {
        self.opaque.len() + self.cutout.len() + self.translucent.len()
    }

    /// Empties the meshes, keeping their allocations.
    pub fn clear(&mut self) {
        self.opaque.clear();
        self.cutout.clear();
        self.translucent.clear();
    }

    fn for_class(&mut self, class: RenderClass) -> &mut Vec<PackedQuad> {
        match class {
            RenderClass::Cutout => &mut self.cutout,
            RenderClass::Translucent => &mut self.translucent,
            RenderClass::Opaque | RenderClass::Air => &mut self.opaque,
        }
    }
}

/// The neighbours of a chunk in [`Face`] order (`[+x, -x, +y, -y, +z, -z]`); `None` is air.
pub type Neighbours<'a> = [Option<&'a Chunk>; 6];

type Plane = [u32; CHUNK_SIZE];

/// Per-call working memory, kept between calls to avoid allocation.
#[derive(Clone)]
struct Scratch {
    /// The chunk's opaque blocks, in both layouts of [`Occupancy`].
    opaque: Occupancy,
    /// For a translucent type: `opaque` plus the blocks of that type.
    hide: Occupancy,
    /// Opaque blocks of each neighbour's touching layer, in the plane layout of that face.
    nb_opaque: [Plane; 6],
}

/// Meshes chunks against a block registry. Holds scratch memory: keep one per thread.
#[derive(Clone)]
pub struct Mesher {
    classes: Vec<RenderClass>,
    s: Box<Scratch>,
}

impl std::fmt::Debug for Mesher {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Mesher")
            .field("blocks", &self.classes.len())
            .finish_non_exhaustive()
    }
}

/// The 32 rows of layer `i` of a layout (a slab x of `by_y`, a layer y of `by_x`).
#[inline]
fn layer(mask: &ColumnMask, i: usize) -> &Plane {
    let rows = &mask[i * CHUNK_SIZE..(i + 1) * CHUNK_SIZE];
    rows.try_into().unwrap_or(&[0; CHUNK_SIZE])
}

/// The layer of `bits` that touches a chunk across `face`, in that face's plane layout:
/// rows z bits y for x faces, rows z bits x for y faces, rows y bits x for z faces.
fn touching_layer(bits: &Occupancy, face: Face) -> Plane {
    let last = CHUNK_SIZE - 1;
    match face {
        Face::PosX => *layer(&bits.by_y, 0),
        Face::NegX => *layer(&bits.by_y, last),
        Face::PosY => *layer(&bits.by_x, 0),
        Face::NegY => *layer(&bits.by_x, last),
        Face::PosZ => std::array::from_fn(|y| bits.by_x[row_index(y, 0)]),
        Face::NegZ => std::array::from_fn(|y| bits.by_x[row_index(y, last)]),
    }
}

fn or_into(dst: &mut [u32], src: &[u32]) {
    dst.iter_mut().zip(src).for_each(|(d, s)| *d |= s);
}

/// Emits the rectangles covering the faces in `rows` (layer `layer` of `face`) as quads.
#[inline]
fn emit_plane(
    rows: &mut Plane,
    face: Face,
    layer: usize,
    block: BlockId,
    out: &mut Vec<PackedQuad>,
) {
    greedy_rects(rows, |r, h, b, w| {
        let q = match face.axis() {
            0 => PackedQuad::new([layer, b, r], w, h, face, block),
            1 => PackedQuad::new([b, layer, r], h, w, face, block),
            _ => PackedQuad::new([b, r, layer], w, h, face, block),
        };
        out.push(q);
    });
}

const EMPTY_OCCUPANCY: Occupancy = Occupancy {
    by_y: [0; CHUNK_AREA],
    by_x: [0; CHUNK_AREA],
};

impl Mesher {
    /// A mesher for chunks whose ids come from `registry`.
    pub fn new(registry: &BlockRegistry) -> Self {
        Self {
            classes: registry.iter().map(|(_, d)| d.class).collect(),
            s: Box::new(Scratch {
                opaque: EMPTY_OCCUPANCY,
                hide: EMPTY_OCCUPANCY,
                nb_opaque: [[0; CHUNK_SIZE]; 6],
            }),
        }
    }

    fn class(&self, id: BlockId) -> Result<RenderClass> {
        self.classes
            .get(id.index())
            .copied()
            .ok_or(Error::UnknownBlock(id))
    }

    /// Meshes `chunk` against its `neighbours`.
    pub fn mesh(&mut self, chunk: &Chunk, neighbours: Neighbours<'_>) -> Result<ChunkMeshes> {
        let mut out = ChunkMeshes::default();
        self.mesh_into(chunk, neighbours, &mut out)?;
        Ok(out)
    }

    /// Meshes `chunk` into `out`, reusing its allocations. Fails if the chunk or a
    /// neighbour holds a block id the registry does not know.
    pub fn mesh_into(
        &mut self,
        chunk: &Chunk,
        neighbours: Neighbours<'_>,
        out: &mut ChunkMeshes,
    ) -> Result<()> {
        out.clear();
        for c in neighbours.iter().flatten().chain([&chunk]) {
            for (id, _) in c.palette() {
                self.class(id)?;
            }
        }
        if chunk.as_uniform() == Some(BlockId::AIR) {
            return Ok(());
        }
        let classes = &self.classes;
        let is_opaque = |id: BlockId| classes[id.index()] == RenderClass::Opaque;
        let s = &mut *self.s;

        // What hides our faces: our opaque blocks and the neighbours' touching layers.
        s.opaque.by_y.fill(0);
        s.opaque.by_x.fill(0);
        for (_, bits) in chunk.palette().filter(|(id, _)| is_opaque(*id)) {
            or_into(&mut s.opaque.by_y, &bits.by_y);
            or_into(&mut s.opaque.by_x, &bits.by_x);
        }
        for face in Face::ALL {
            let plane = &mut s.nb_opaque[face as usize];
            *plane = [0; CHUNK_SIZE];
            if let Some(n) = neighbours[face as usize] {
                for (_, bits) in n.palette().filter(|(id, _)| is_opaque(*id)) {
                    or_into(plane, &touching_layer(bits, face));
                }
            }
        }
        let full = |rows: &[u32]| rows.iter().all(|&r| r == u32::MAX);
        if full(&s.opaque.by_y) && s.nb_opaque.iter().all(|p| full(p)) {
            return Ok(()); // fully enclosed: nothing can be seen
        }

        for (id, bits) in chunk.palette() {
            let class = self.classes[id.index()];
            if class == RenderClass::Air {
                continue;
            }
            let s = &mut *self.s;
            let mut nb_hide = s.nb_opaque;
            let hide = if class == RenderClass::Translucent {
                // Blocks of the same type hide too, inside the chunk and across borders.
                for (h, (o, m)) in [
                    (&mut s.hide.by_y, (&s.opaque.by_y, &bits.by_y)),
                    (&mut s.hide.by_x, (&s.opaque.by_x, &bits.by_x)),
                ] {
                    h.iter_mut()
                        .zip(o.iter().zip(m))
                        .for_each(|(h, (o, m))| *h = o | m);
                }
                for face in Face::ALL {
                    if let Some(same) = neighbours[face as usize].and_then(|n| n.occupancy(id)) {
                        or_into(&mut nb_hide[face as usize], &touching_layer(same, face));
                    }
                }
                &s.hide
            } else {
                &s.opaque
            };
            let out = out.for_class(class);
            if chunk.as_uniform().is_some() {
                // A uniform chunk hides all its inner faces: only its borders can show.
                for face in Face::ALL {
                    let mut rows = nb_hide[face as usize].map(|h| !h);
                    let border = if face.is_positive() {
                        CHUNK_SIZE - 1
                    } else {
                        0
                    };
                    emit_plane(&mut rows, face, border, id, out);
                }
            } else {
                mesh_type(bits, hide, &nb_hide, id, out);
            }
        }
        Ok(())
    }
}

/// Emits the visible faces of one block type, hidden where `hide` (inside the chunk) or
/// `nb_hide` (the neighbours' touching layers) is set. Each face direction is the AND-NOT
/// of a layer and the next one: x faces on vertical columns (slab x), y faces on rows along
/// x (layer y), z faces on rows along x again (gathering rows z of every layer y).
fn mesh_type(
    m: &Occupancy,
    hide: &Occupancy,
    nb_hide: &[Plane; 6],
    id: BlockId,
    out: &mut Vec<PackedQuad>,
) {
    let empty = |rows: &Plane| rows.iter().all(|&r| r == 0);
    for (mine, theirs, faces) in [
        (&m.by_y, &hide.by_y, [Face::PosX, Face::NegX]),
        (&m.by_x, &hide.by_x, [Face::PosY, Face::NegY]),
    ] {
        for i in 0..CHUNK_SIZE {
            let rows = layer(mine, i);
            if empty(rows) {
                continue;
            }
            for (face, next) in faces.into_iter().zip([i + 1, i.wrapping_sub(1)]) {
                let next = if next < CHUNK_SIZE {
                    layer(theirs, next)
                } else {
                    &nb_hide[face as usize]
                };
                let mut faces: Plane = std::array::from_fn(|r| rows[r] & !next[r]);
                emit_plane(&mut faces, face, i, id, out);
            }
        }
    }

    // z: which z hold any block of this type (OR of the rows of every layer y).
    let mut z_any: Plane = [0; CHUNK_SIZE];
    for y in 0..CHUNK_SIZE {
        or_into(&mut z_any, layer(&m.by_x, y));
    }
    for z in (0..CHUNK_SIZE).filter(|&z| z_any[z] != 0) {
        for (face, next) in [(Face::PosZ, z + 1), (Face::NegZ, z.wrapping_sub(1))] {
            let mut faces: Plane = std::array::from_fn(|y| {
                let h = if next < CHUNK_SIZE {
                    hide.by_x[row_index(y, next)]
                } else {
                    nb_hide[face as usize][y]
                };
                m.by_x[row_index(y, z)] & !h
            });
            emit_plane(&mut faces, face, z, id, out);
        }
    }
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeSet;

    use super::*;
    use voxel_core::blocks::*;

    /// One visible block face: (block position, face, block), possibly outside the chunk
    /// for neighbour blocks in the naive model.
    type UnitFace = ([usize; 3], usize, u16);

    fn registry() -> BlockRegistry {
        BlockRegistry::default()
    }

    fn mesh(chunk: &Chunk, nb: Neighbours<'_>) -> ChunkMeshes {
        Mesher::new(&registry())
            .mesh(chunk, nb)
            .expect("known blocks")
    }

    /// Every unit face covered by `quads`; panics on a face covered twice.
    fn unit_faces(quads: &[PackedQuad]) -> BTreeSet<UnitFace> {
        let mut set = BTreeSet::new();
        for q in quads {
            let u = q.unpack().expect("valid quad");
            let [ua, va] = crate::UV_AXES[u.face.axis()];
            for i in 0..usize::from(u.size[0]) {
                for j in 0..usize::from(u.size[1]) {
                    let mut p = u.pos.map(usize::from);
                    p[ua] += i;
                    p[va] += j;
                    assert!(p.iter().all(|&c| c < 32), "quad {u:?} leaves the chunk");
                    assert!(
                        set.insert((p, u.face as usize, u.block.0)),
                        "face twice: {p:?} {u:?}"
                    );
                }
            }
        }
        set
    }

    /// The face rules written the slow, obvious way, one block at a time.
    fn naive(chunk: &Chunk, nb: Neighbours<'_>) -> [BTreeSet<UnitFace>; 3] {
        let reg = registry();
        let class = |id: BlockId| reg.class(id).expect("known");
        let get = |p: [i64; 3]| -> BlockId {
            let inside = |v: i64| (0..32).contains(&v);
            if p.iter().all(|&v| inside(v)) {
                return chunk
                    .get(p[0] as usize, p[1] as usize, p[2] as usize)
                    .unwrap();
            }
            let face = Face::ALL
                .into_iter()
                .find(|f| {
                    let v = p[f.axis()];
                    if f.is_positive() { v == 32 } else { v == -1 }
                })
                .expect("one step outside");
            let wrap = p.map(|v| v.rem_euclid(32) as usize);
            nb[face as usize].map_or(AIR, |c| c.get(wrap[0], wrap[1], wrap[2]).unwrap())
        };
        let mut out: [BTreeSet<UnitFace>; 3] = Default::default();
        for x in 0..32 {
            for y in 0..32 {
                for z in 0..32 {
                    let a = chunk.get(x, y, z).unwrap();
                    let ca = class(a);
                    if ca == RenderClass::Air {
                        continue;
                    }
                    for face in Face::ALL {
                        let n = face.normal();
                        let b = get([
                            x as i64 + i64::from(n[0]),
                            y as i64 + i64::from(n[1]),
                            z as i64 + i64::from(n[2]),
                        ]);
                        let hidden = class(b) == RenderClass::Opaque
                            || (ca == RenderClass::Translucent && a == b);
                        if !hidden {
                            let k = match ca {
                                RenderClass::Cutout => 1,
                                RenderClass::Translucent => 2,
                                _ => 0,
                            };
                            out[k].insert(([x, y, z], face as usize, a.0));
                        }
                    }
                }
            }
        }
        out
    }

    fn faces_of(m: &ChunkMeshes) -> [BTreeSet<UnitFace>; 3] {
        [
            unit_faces(&m.opaque),
            unit_faces(&m.cutout),
            unit_faces(&m.translucent),
        ]
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
        assert_eq!(faces_of(&m), naive(&c, nb));
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
        assert_eq!(faces_of(&m), naive(&water, nb));
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
        assert_eq!(faces_of(&mesh(&stone, nb)), naive(&stone, nb));
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
    }

    #[test]
    fn random_chunks_match_the_naive_rules_exactly() {
        let mut s = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
        let reg = registry();
        let mut mesher = Mesher::new(&reg);
        for round in 0..6 {
            let mut chunks: Vec<Chunk> = Vec::new();
            for _ in 0..7 {
                let mut c = Chunk::default();
                // Boxes of random blocks give runs to merge; single blocks give noise.
                for _ in 0..(40 + round * 20) {
                    let r = next();
                    let id = BlockId((r % 13) as u16);
                    let p = [(r >> 8) % 32, (r >> 16) % 32, (r >> 24) % 32].map(|v| v as usize);
                    let e = [(r >> 32) % 9, (r >> 40) % 9, (r >> 48) % 9].map(|v| v as usize);
                    let q = [0, 1, 2].map(|i| (p[i] + e[i]).min(31));
                    c.fill_box(p, q, id).unwrap();
                }
                for _ in 0..2000 {
                    let r = next();
                    c.set(
                        (r % 32) as usize,
                        ((r >> 8) % 32) as usize,
                        ((r >> 16) % 32) as usize,
                        BlockId(((r >> 24) % 13) as u16),
                    )
                    .unwrap();
                }
                chunks.push(c);
            }
            let (center, nbs) = chunks.split_first().unwrap();
            let nb: Neighbours<'_> = std::array::from_fn(|i| (i != round).then(|| &nbs[i]));
            let m = mesher.mesh(center, nb).unwrap();
            let faces = faces_of(&m);
            assert!(
                faces.iter().all(|f| f.len() > 100),
                "all three meshes exercised"
            );
            assert_eq!(faces, naive(center, nb), "round {round}");
        }
    }
}
