//! The three-way binary greedy mesher: one chunk plus its six neighbours in, opaque, cutout
//! and translucent quads out.
//!
//! Face rules (the unit tests, in `tests.rs` beside this file, check each one): a face of a
//! non-air block is emitted where its neighbour does not hide it.
//! - An opaque neighbour hides every face.
//! - A translucent block hides the faces of blocks of its own type (no water-water walls),
//!   nothing else: water against glass keeps both faces. A translucent face toward another
//!   translucent type carries [`crate::FLAG_INTERFACE`] (quads never merge across it), so
//!   that the renderer can tell, seen from inside a volume, where it meets air from where it
//!   meets another translucent type.
//! - A block standing in a medium (waterlogged kelp, [`voxel_core::BlockDef::medium`])
//!   holds that medium too: the medium's faces are meshed as if its cell were the
//!   medium's (the volume goes on through it, and where it pokes out of the water the
//!   medium's faces stand around and over it, Minecraft's rule for waterlogged blocks: the
//!   medium of a waterlogged block ends at the block's top when no water is above it).
//! - Air and cutout blocks hide nothing, so cutout faces stay against air, translucent and
//!   other cutout blocks, leaves against leaves included (the holes of one leaf block show
//!   the leaves behind it, as in Minecraft's fancy leaves).
//! - Across a chunk border the neighbour chunk decides; a missing neighbour counts as air,
//!   so the edge of a loaded area is closed by faces rather than left with holes.
//!
//! The algorithm works on bit masks: every block type present has its blocks as bits, in
//! vertical columns and in rows along x ([`Occupancy`]). A chunk in mask form stores exactly
//! these and is meshed from its storage directly; for a packed chunk (the compact resident
//! form, see [`Chunk::pack`]) the mesher first builds the masks of its non-air
//! types into its own scratch memory ([`Chunk::build_masks`], a few µs), and of a
//! neighbour it reads only the touching layer ([`Chunk::side_layers`]), in any form. The
//! quads are the same whatever the forms of the chunk and its neighbours. For each type,
//! the visible faces of a layer are one AND-NOT between its rows and the "hides me" rows of
//! the next layer; they are then covered with rectangles by [`greedy_rects`]. Bits are per
//! block type, so merged quads never mix blocks and no per-block comparison is needed. Cost
//! grows with the number of block types in the chunk, which is small (4 to 9 on terrain).
//!
//! Shortcuts, each exact under the rules: an all-air chunk returns at once; an all-opaque
//! chunk whose six neighbour layers are all opaque returns before any per-type work; a
//! uniform opaque or translucent chunk hides its own inner faces, so only its six border
//! layers are meshed. A uniform cutout chunk hides nothing: all 31 inner layers of each
//! direction are full (one 32×32 quad each), and its border layers are meshed against the
//! neighbours like any other.
//!
//! Ambient occlusion ([`crate::ao`]): every opaque and cutout face gets per-vertex
//! occlusion from the opaque blocks around its corners, across chunk borders too (the
//! edge and corner neighbours of a [`Neighbourhood`] included), and merges only with faces
//! of the same four corner values. Translucent faces take none (see
//! [`MeshOptions::translucent_occlusion`]).
//!
//! Greedy merging is applied to all three meshes. For cutout and translucent blocks it is
//! as correct as for opaque ones: texture coordinates come from world position, so a merged
//! quad shows the same texels as the unit faces it replaces, and coverage is identical. It
//! makes translucent quads larger, so per-quad sorting is coarser; the exact reference and
//! depth peeling are per pixel and do not care.

use voxel_core::{
    BlockId, BlockRegistry, CHUNK_AREA, CHUNK_SIZE, Chunk, ChunkPos, ColumnMask, Face, LayerMask,
    LightChunk, LightField, MaskBuffer, Neighbourhood, Occupancy, RenderClass, row_index,
};

use crate::ao::{AO_NONE, Pad, cover_occluded};
use crate::bits::{greedy_rects_live, live_rows};
use crate::light::{LightScratch, LightStreams, LitCells, LitPlane, QuadLight};
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
    /// The corner light of each quad of the three meshes ([`Mesher::mesh_lit`]); empty when
    /// meshed without light.
    pub light: LightStreams,
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
        self.light.clear();
    }

    /// The mesh of `class` and its light stream.
    fn for_class(&mut self, class: RenderClass) -> (&mut Vec<PackedQuad>, &mut Vec<QuadLight>) {
        match class {
            RenderClass::Cutout => (&mut self.cutout, &mut self.light.cutout),
            RenderClass::Translucent => (&mut self.translucent, &mut self.light.translucent),
            RenderClass::Opaque | RenderClass::Air => (&mut self.opaque, &mut self.light.opaque),
        }
    }
}

/// The face neighbours of a chunk in [`Face`] order (`[+x, -x, +y, -y, +z, -z]`); `None`
/// is air. Converts into a [`Neighbourhood`] whose edge and corner neighbours are air.
pub type Neighbours<'a> = [Option<&'a Chunk>; 6];

/// What the mesher computes besides the faces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MeshOptions {
    /// Per-vertex ambient occlusion of opaque and cutout faces. Default on: without it one-block
    /// steps of terrain cannot be seen (a top face is lit like the one below it). Off, quads
    /// merge as they did before (no occlusion bits), for comparisons.
    pub ambient_occlusion: bool,
    /// Ambient occlusion of translucent faces too. Default off: measured on the benchmark's
    /// terrain it adds translucent quads (which `sorted-quads` sorts every time the eye
    /// crosses a plane) for a shading no one reads through water or glass; see the README.
    pub translucent_occlusion: bool,
}

impl Default for MeshOptions {
    fn default() -> Self {
        Self {
            ambient_occlusion: true,
            translucent_occlusion: false,
        }
    }
}

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
    /// The chunk's translucent blocks (all types), and each neighbour's touching layer of
    /// them: where a translucent face is an interface.
    translucent: Occupancy,
    nb_translucent: [Plane; 6],
    /// Each neighbour's touching layer, per block type.
    nb_layers: [Vec<(BlockId, Plane)>; 6],
}

/// Where faces toward other translucent types are (inside the chunk and in the neighbours'
/// touching layers), for the translucent types, which flag those faces.
#[derive(Clone, Copy)]
struct Split<'a> {
    inside: &'a Occupancy,
    neighbours: &'a [Plane; 6],
}

/// Meshes chunks against a block registry. Holds scratch memory: keep one per thread.
#[derive(Clone)]
pub struct Mesher {
    classes: Vec<RenderClass>,
    /// Per block id, the medium it stands in ([`voxel_core::BlockDef::medium`]).
    media: Vec<Option<BlockId>>,
    options: MeshOptions,
    s: Box<Scratch>,
    /// A packed centre's masks.
    built: MaskBuffer,
    /// Opaque blocks of the chunk and the shell around it, for ambient occlusion.
    pad: Box<Pad>,
    /// An edge neighbour's touching layer, per type.
    edge_layers: Vec<(BlockId, LayerMask)>,
    /// Light of the chunk and the shell around it, for the lit mesher.
    light: Box<LightScratch>,
}

/// Where a plane's faces go: the mesh, and (with ambient occlusion) the occluders of the
/// chunk with the scratch to group faces by them.
struct Sink<'a> {
    out: &'a mut Vec<PackedQuad>,
    ao: Option<&'a Pad>,
    /// When meshing with light: the mesh's light stream and what the corner light needs.
    lit: Option<(&'a mut Vec<QuadLight>, LitPlane<'a, 'a>)>,
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

fn or_into(dst: &mut [u32], src: &[u32]) {
    dst.iter_mut().zip(src).for_each(|(d, s)| *d |= s);
}

/// Emits the rectangles covering the faces in `rows` (layer `layer` of `face`; `live` says
/// which rows hold any) as quads with `flags`; with ambient occlusion, faces an occluder
/// touches are covered first, by rectangles of equal corner values ([`cover_occluded`]).
#[inline]
fn emit_plane(
    rows: &mut Plane,
    live: u32,
    face: Face,
    layer: usize,
    block: BlockId,
    flags: u32,
    sink: &mut Sink<'_>,
) {
    if sink.lit.is_some() {
        emit_plane_lit(rows, live, face, layer, block, flags, sink);
    } else {
        emit_ao(
            rows, live, face, layer, block, flags, sink.out, None, sink.ao,
        );
    }
}

/// [`emit_plane`] without light, or with the same light entry (`light`) for every quad.
#[inline]
#[allow(clippy::too_many_arguments)]
fn emit_ao(
    rows: &mut Plane,
    mut live: u32,
    face: Face,
    layer: usize,
    block: BlockId,
    flags: u32,
    out: &mut Vec<PackedQuad>,
    mut light: Option<(&mut Vec<QuadLight>, QuadLight)>,
    ao: Option<&Pad>,
) {
    if let Some(occ) = ao.and_then(|pad| pad.occluders(face, layer)) {
        live = cover_occluded(rows, live, occ, face.axis(), |r, h, b, w, ao| {
            out.push(quad(face, layer, r, h, b, w, block, flags, ao));
            if let Some((l, e)) = &mut light {
                l.push(*e);
            }
        });
    }
    if live != 0 {
        greedy_rects_live(rows, live, |r, h, b, w| {
            out.push(quad(face, layer, r, h, b, w, block, flags, AO_NONE));
            if let Some((l, e)) = &mut light {
                l.push(*e);
            }
        });
    }
}

/// [`emit_plane`] with light: faces with an odd cell in front of them are covered by
/// their own corner lights ([`LitPlane::emit_odd`]), the others take their layer's
/// reference at every corner and are covered as without light, a run of layers of one
/// reference at a time.
#[inline]
fn emit_plane_lit(
    rows: &mut Plane,
    live: u32,
    face: Face,
    layer: usize,
    block: BlockId,
    flags: u32,
    sink: &mut Sink<'_>,
) {
    let Sink { out, ao, lit } = sink;
    let Some((lout, lp)) = lit.as_mut() else {
        return;
    };
    let axis = face.axis();
    // Padded index of the layer in front: layer + 1 ± 1.
    let next = if face.is_positive() { layer + 2 } else { layer };
    let occ = ao.and_then(|pad| pad.occluders(face, layer));
    let live = lp.emit_odd(rows, live, axis, next, occ, |r, h, b, w, a, l| {
        out.push(quad(face, layer, r, h, b, w, block, flags, a));
        lout.push(l);
    });
    if live == 0 {
        return;
    }
    // Faces of `rows` (live rows `live`) covered as without light, every quad with the
    // light entry of one reference.
    let mut uniform = |rows: &mut Plane, live: u32, reference| {
        let l = crate::light::uniform(reference);
        emit_ao(
            rows,
            live,
            face,
            layer,
            block,
            flags,
            out,
            Some((&mut **lout, l)),
            *ao,
        );
    };
    if axis == 1 {
        uniform(rows, live, lp.s.reference(next));
        return;
    }
    // The front cells of x and z faces are at their own y: bits y of an x plane, rows y
    // of a z plane.
    // The y that hold faces: bits of any row of an x plane, the live rows of a z plane.
    let ys = if axis == 0 {
        rows.iter().fold(0, |acc, &r| acc | r)
    } else {
        live
    };
    let mut y = 0;
    while y < CHUNK_SIZE {
        let mut end = y + 1;
        while end < CHUNK_SIZE && lp.s.same_reference(end + 1, y + 1) {
            end += 1;
        }
        let run = (u32::MAX >> (CHUNK_SIZE - (end - y))) << y;
        if ys & run == 0 {
            y = end;
            continue;
        }
        if ys & !run == 0 {
            // One reference for every face of the plane.
            uniform(rows, live, lp.s.reference(y + 1));
            return;
        }
        let mut sub: Plane = if axis == 0 {
            std::array::from_fn(|r| rows[r] & run)
        } else {
            std::array::from_fn(|r| if run >> r & 1 != 0 { rows[r] } else { 0 })
        };
        let sub_live = live_rows(&sub) & live;
        if sub_live != 0 {
            uniform(&mut sub, sub_live, lp.s.reference(y + 1));
        }
        y = end;
    }
}

/// `rows & !hidden`, and whether it holds any bit (vectorises).
#[inline(always)]
fn and_not(rows: &Plane, hidden: &Plane) -> (Plane, bool) {
    let mut faces = [0; CHUNK_SIZE];
    for (f, (&r, &h)) in faces.iter_mut().zip(rows.iter().zip(hidden)) {
        *f = r & !h;
    }
    let any = faces.iter().fold(0, |acc, &f| acc | f) != 0;
    (faces, any)
}

/// The quad of the rectangle of `h` rows from `r` and `w` bits from `b` in layer `layer`
/// of `face`'s plane.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn quad(
    face: Face,
    layer: usize,
    r: usize,
    h: usize,
    b: usize,
    w: usize,
    block: BlockId,
    flags: u32,
    ao: u8,
) -> PackedQuad {
    let q = match face.axis() {
        0 => PackedQuad::new([layer, b, r], w, h, face, block),
        1 => PackedQuad::new([b, layer, r], h, w, face, block),
        _ => PackedQuad::new([b, r, layer], w, h, face, block),
    };
    q.with_flags(flags).with_ao(ao)
}

/// Emits the faces in `rows` (a plane holding some): those whose neighbour is set in the
/// plane `interface` gives (the same layout) flagged, the others not.
#[inline]
fn emit_split(
    rows: &mut Plane,
    interface: Option<impl FnOnce() -> Plane>,
    face: Face,
    layer: usize,
    block: BlockId,
    sink: &mut Sink<'_>,
) {
    let mut live = live_rows(rows);
    if let Some(next) = interface {
        let next = next();
        let mut flagged: Plane = std::array::from_fn(|r| rows[r] & next[r]);
        let flagged_live = live_rows(&flagged);
        if flagged_live != 0 {
            rows.iter_mut().zip(&flagged).for_each(|(r, f)| *r &= !f);
            live = live_rows(rows);
            emit_plane(
                &mut flagged,
                flagged_live,
                face,
                layer,
                block,
                crate::FLAG_INTERFACE,
                sink,
            );
        }
    }
    if live != 0 {
        emit_plane(rows, live, face, layer, block, 0, sink);
    }
}

const EMPTY_OCCUPANCY: Occupancy = Occupancy {
    by_y: [0; CHUNK_AREA],
    by_x: [0; CHUNK_AREA],
};

impl Mesher {
    /// A mesher for chunks whose ids come from `registry`, with the default
    /// [`MeshOptions`] (ambient occlusion on).
    pub fn new(registry: &BlockRegistry) -> Self {
        Self::with_options(registry, MeshOptions::default())
    }

    /// A mesher with `options`.
    pub fn with_options(registry: &BlockRegistry, options: MeshOptions) -> Self {
        Self {
            classes: registry.iter().map(|(_, d)| d.class).collect(),
            media: registry.iter().map(|(_, d)| d.medium).collect(),
            options,
            pad: Pad::new(),
            edge_layers: Vec::new(),
            light: LightScratch::new(),
            s: Box::new(Scratch {
                opaque: EMPTY_OCCUPANCY,
                hide: EMPTY_OCCUPANCY,
                nb_opaque: [[0; CHUNK_SIZE]; 6],
                translucent: EMPTY_OCCUPANCY,
                nb_translucent: [[0; CHUNK_SIZE]; 6],
                nb_layers: Default::default(),
            }),
            built: MaskBuffer::new(),
        }
    }

    fn class(&self, id: BlockId) -> Result<RenderClass> {
        self.classes
            .get(id.index())
            .copied()
            .ok_or(Error::UnknownBlock(id))
    }

    /// The options this mesher was made with.
    pub fn options(&self) -> MeshOptions {
        self.options
    }

    /// Meshes `chunk` against its `neighbours`: a [`Neighbourhood`] (what
    /// [`voxel_core::World::neighbourhood`] gives), or the six face neighbours alone
    /// ([`Neighbours`]; edges and corners then count as air for ambient occlusion).
    pub fn mesh<'n>(
        &mut self,
        chunk: &Chunk,
        neighbours: impl Into<Neighbourhood<'n>>,
    ) -> Result<ChunkMeshes> {
        let mut out = ChunkMeshes::default();
        self.mesh_into(chunk, neighbours, &mut out)?;
        Ok(out)
    }

    /// Meshes `chunk` into `out`, reusing its allocations. Fails if the chunk or a
    /// neighbour holds a block id the registry does not know. The chunk and its neighbours
    /// may each be in any storage form (uniform, masks or packed): a packed centre has the
    /// masks of its non-air types built into this mesher's scratch memory, a packed
    /// neighbour gives only its touching layer.
    pub fn mesh_into<'n>(
        &mut self,
        chunk: &Chunk,
        neighbours: impl Into<Neighbourhood<'n>>,
        out: &mut ChunkMeshes,
    ) -> Result<()> {
        self.mesh_impl(chunk, neighbours.into(), None, out)
    }

    /// Meshes `chunk`, the chunk at `pos`, with the light of `light`: the quads of
    /// [`Mesher::mesh`] (merged only where their corner lights agree too) and the corner
    /// light of each ([`ChunkMeshes::light`]; see [`crate::light`]). Light across the
    /// chunk's borders is read from the neighbour chunks' light, so two chunks give a
    /// vertex on their shared border the same light; cells of chunks `light` has not lit
    /// do not count. Fails as [`Mesher::mesh`] does, or with [`Error::LightPalette`].
    pub fn mesh_lit<'n>(
        &mut self,
        chunk: &Chunk,
        neighbours: impl Into<Neighbourhood<'n>>,
        light: &LightField,
        pos: ChunkPos,
    ) -> Result<ChunkMeshes> {
        let mut out = ChunkMeshes::default();
        self.mesh_lit_into(chunk, neighbours, light, pos, &mut out)?;
        Ok(out)
    }

    /// [`Mesher::mesh_lit`] into `out`, reusing its allocations.
    pub fn mesh_lit_into<'n>(
        &mut self,
        chunk: &Chunk,
        neighbours: impl Into<Neighbourhood<'n>>,
        light: &LightField,
        pos: ChunkPos,
        out: &mut ChunkMeshes,
    ) -> Result<()> {
        let cells = LitCells::new(light, pos);
        self.mesh_impl(chunk, neighbours.into(), Some(&cells), out)
    }

    /// [`Mesher::mesh_lit_into`] from the light of the chunk and its 26 neighbours as
    /// `light` gives it for each offset (each coordinate −1 to 1; `None` where not lit):
    /// what a mesher on a worker thread reads, from snapshots of the field
    /// ([`LightField::shared`]) taken when the job was made.
    pub fn mesh_lit_from<'n, 'l>(
        &mut self,
        chunk: &Chunk,
        neighbours: impl Into<Neighbourhood<'n>>,
        light: impl Fn([i32; 3]) -> Option<&'l LightChunk>,
        out: &mut ChunkMeshes,
    ) -> Result<()> {
        let cells = LitCells::from_fn(light);
        self.mesh_impl(chunk, neighbours.into(), Some(&cells), out)
    }

    fn mesh_impl<'n>(
        &mut self,
        chunk: &Chunk,
        neighbourhood: Neighbourhood<'n>,
        lit: Option<&LitCells<'_>>,
        out: &mut ChunkMeshes,
    ) -> Result<()> {
        out.clear();
        let around = Neighbourhood::OFFSETS
            .iter()
            .filter_map(|&d| neighbourhood.get(d));
        for c in around.chain([chunk]) {
            for (id, _) in c.palette() {
                self.class(id)?;
            }
        }
        if chunk.as_uniform() == Some(BlockId::AIR) {
            return Ok(());
        }
        let neighbours: Neighbours<'n> = Face::ALL.map(|f| neighbourhood.face(f));
        let Self {
            classes,
            media,
            options,
            s,
            built,
            pad,
            edge_layers,
            light,
        } = self;
        let classes = &*classes;
        let s = &mut **s;
        let class = |id: BlockId| classes[id.index()];
        // A block standing in a medium hides that medium's faces, as the medium does.
        let medium = |id: BlockId| media[id.index()];
        let is_opaque = |id: BlockId| class(id) == RenderClass::Opaque;
        let is_translucent = |id: BlockId| class(id) == RenderClass::Translucent;
        // The translucent type a block's cell holds: its own, or the medium it stands in.
        let holds = |id: BlockId| {
            if is_translucent(id) {
                Some(id)
            } else {
                medium(id)
            }
        };

        // The centre's masks: stored, or built from the packed form (air is never meshed
        // and hides nothing, so it is left out).
        built.clear();
        if chunk.is_packed() {
            chunk.build_masks(built, |id| class(id) != RenderClass::Air);
        }
        let built = &*built;
        let entries = || {
            chunk
                .stored_masks()
                .into_iter()
                .flatten()
                .chain(built.iter())
        };

        // Each neighbour's touching layer, per block type.
        for face in Face::ALL {
            let layers = &mut s.nb_layers[face as usize];
            layers.clear();
            if let Some(n) = neighbours[face as usize] {
                // Only opaque and translucent blocks (and those standing in a medium)
                // hide anything.
                n.side_layers(face.opposite(), layers, |id| {
                    is_opaque(id) || is_translucent(id) || medium(id).is_some()
                });
            }
        }
        let nb_union = |layers: &[(BlockId, Plane)], keep: &dyn Fn(BlockId) -> bool| -> Plane {
            let mut plane = [0; CHUNK_SIZE];
            for (_, rows) in layers.iter().filter(|(id, _)| keep(*id)) {
                or_into(&mut plane, rows);
            }
            plane
        };

        // What hides our faces: our opaque blocks and the neighbours' touching layers.
        s.opaque.by_y.fill(0);
        s.opaque.by_x.fill(0);
        for (_, bits) in entries().filter(|(id, _)| is_opaque(*id)) {
            or_into(&mut s.opaque.by_y, &bits.by_y);
            or_into(&mut s.opaque.by_x, &bits.by_x);
        }
        for face in Face::ALL {
            s.nb_opaque[face as usize] = nb_union(&s.nb_layers[face as usize], &is_opaque);
        }
        // Where translucent faces meet other translucent types: only when the chunk and its
        // neighbours hold two translucent types or more (terrain with water alone skips it).
        let mut types = neighbours
            .iter()
            .flatten()
            .chain([&chunk])
            .flat_map(|c| c.palette())
            .filter_map(|(id, _)| holds(id));
        let interfaces = types
            .next()
            .is_some_and(|first| types.any(|id| id != first));
        if interfaces {
            s.translucent.by_y.fill(0);
            s.translucent.by_x.fill(0);
            // A block standing in a medium holds it (a glass face toward waterlogged kelp
            // meets water).
            for (_, bits) in entries().filter(|(id, _)| holds(*id).is_some()) {
                or_into(&mut s.translucent.by_y, &bits.by_y);
                or_into(&mut s.translucent.by_x, &bits.by_x);
            }
            for face in Face::ALL {
                s.nb_translucent[face as usize] =
                    nb_union(&s.nb_layers[face as usize], &|id| holds(id).is_some());
            }
        }
        let full = |rows: &[u32]| rows.iter().all(|&r| r == u32::MAX);
        if full(&s.opaque.by_y) && s.nb_opaque.iter().all(|p| full(p)) {
            // Every block is opaque and so is every touching neighbour layer: each face is
            // against an opaque block. Only an all-opaque chunk gets here; a chunk holding
            // any cutout or translucent block (uniform leaves included) is meshed below.
            return Ok(());
        }
        if options.ambient_occlusion || lit.is_some() {
            // Nothing opaque anywhere around: no face is occluded, no shell to fill (light
            // reads the shell's opaque cells: it is always filled).
            let any_opaque = lit.is_some()
                || s.opaque.by_y.iter().any(|&r| r != 0)
                || s.nb_opaque.iter().flatten().any(|&r| r != 0)
                || Neighbourhood::OFFSETS[6..].iter().any(|&d| {
                    neighbourhood
                        .get(d)
                        .is_some_and(|c| c.palette().any(|(id, _)| is_opaque(id)))
                });
            if any_opaque {
                pad.fill(
                    &s.opaque,
                    &s.nb_opaque,
                    &neighbourhood,
                    &is_opaque,
                    edge_layers,
                );
            } else {
                pad.clear();
            }
        }
        if let Some(cells) = lit {
            light.build(cells, pad);
        }

        // The media that blocks of this chunk stand in: their cells hold the medium too.
        let mut media_here: Vec<BlockId> = entries().filter_map(|(id, _)| medium(id)).collect();
        media_here.sort_unstable();
        media_here.dedup();
        // Made only where something stands in a medium (8 KiB).
        let mut pooled: Option<Box<Occupancy>> = None;
        // A medium's cells: its blocks and those standing in it.
        let pool = |pooled: &mut Occupancy, m: BlockId, own: Option<&Occupancy>| {
            pooled.by_y = own.map_or([0; CHUNK_AREA], |o| o.by_y);
            pooled.by_x = own.map_or([0; CHUNK_AREA], |o| o.by_x);
            for (_, inside) in entries().filter(|(w, _)| medium(*w) == Some(m)) {
                or_into(&mut pooled.by_y, &inside.by_y);
                or_into(&mut pooled.by_x, &inside.by_x);
            }
        };
        let mut mesh_one = |id: BlockId, bits: &Occupancy, uniform: bool| {
            let class = class(id);
            if class == RenderClass::Air {
                return;
            }
            let mut nb_hide = s.nb_opaque;
            let hide = if class == RenderClass::Translucent {
                // Blocks of the same type hide too, inside the chunk and across borders,
                // and blocks standing in it (waterlogged): the volume goes on through them.
                for (h, (o, m)) in [
                    (&mut s.hide.by_y, (&s.opaque.by_y, &bits.by_y)),
                    (&mut s.hide.by_x, (&s.opaque.by_x, &bits.by_x)),
                ] {
                    h.iter_mut()
                        .zip(o.iter().zip(m))
                        .for_each(|(h, (o, m))| *h = o | m);
                }
                for (_, inside) in entries().filter(|(w, _)| medium(*w) == Some(id)) {
                    or_into(&mut s.hide.by_y, &inside.by_y);
                    or_into(&mut s.hide.by_x, &inside.by_x);
                }
                for face in Face::ALL {
                    let layers = &s.nb_layers[face as usize];
                    for (_, same) in layers
                        .iter()
                        .filter(|(i, _)| *i == id || medium(*i) == Some(id))
                    {
                        or_into(&mut nb_hide[face as usize], same);
                    }
                }
                &s.hide
            } else {
                &s.opaque
            };
            let split = (interfaces && class == RenderClass::Translucent).then_some(Split {
                inside: &s.translucent,
                neighbours: &s.nb_translucent,
            });
            let occludes = options.ambient_occlusion
                && (class != RenderClass::Translucent || options.translucent_occlusion);
            let (quads, lights) = out.for_class(class);
            let mut sink = Sink {
                out: quads,
                ao: occludes.then_some(&**pad),
                lit: lit.map(|cells| {
                    let plane = LitPlane {
                        s: light,
                        cells,
                        pad,
                        flat: class == RenderClass::Translucent,
                    };
                    (lights, plane)
                }),
            };
            if uniform {
                // One block type everywhere. An opaque or translucent type hides itself, so
                // only the border layers can show. A cutout type hides nothing: every inner
                // layer is all faces, one 32×32 quad per layer and direction, exactly what
                // `mesh_type` would find, without its AND-NOTs and rectangle search.
                for face in Face::ALL {
                    let border = if face.is_positive() {
                        CHUNK_SIZE - 1
                    } else {
                        0
                    };
                    if class == RenderClass::Cutout {
                        for l in (0..CHUNK_SIZE).filter(|&l| l != border) {
                            let shaded =
                                sink.ao.is_some_and(|pad| pad.occluders(face, l).is_some());
                            if shaded || sink.lit.is_some() {
                                let mut all = [u32::MAX; CHUNK_SIZE];
                                emit_plane(&mut all, u32::MAX, face, l, id, 0, &mut sink);
                            } else {
                                let mut pos = [0; 3];
                                pos[face.axis()] = l;
                                let full = PackedQuad::new(pos, CHUNK_SIZE, CHUNK_SIZE, face, id);
                                sink.out.push(full);
                            }
                        }
                    }
                    let (mut rows, any) = and_not(&[u32::MAX; CHUNK_SIZE], &nb_hide[face as usize]);
                    if any {
                        let interface = split.map(|sp| || sp.neighbours[face as usize]);
                        emit_split(&mut rows, interface, face, border, id, &mut sink);
                    }
                }
            } else {
                mesh_type(bits, hide, &nb_hide, split, id, &mut sink);
            }
        };
        for (id, bits) in entries() {
            if media_here.contains(&id) {
                let p = pooled.get_or_insert_with(|| Box::new(EMPTY_OCCUPANCY));
                pool(p, id, Some(bits));
                mesh_one(id, p, false);
            } else {
                mesh_one(id, bits, chunk.as_uniform().is_some());
            }
        }
        // A medium only blocks standing in it bring into the chunk (kelp poking out).
        for &m in &media_here {
            if !entries().any(|(id, _)| id == m) {
                let p = pooled.get_or_insert_with(|| Box::new(EMPTY_OCCUPANCY));
                pool(p, m, None);
                mesh_one(m, p, false);
            }
        }
        if lit.is_some() {
            if light.palette.overflow {
                out.clear();
                return Err(Error::LightPalette);
            }
            light.palette.write(&mut out.light.palette);
        }
        Ok(())
    }
}

/// Emits the visible faces of one block type, hidden where `hide` (inside the chunk) or
/// `nb_hide` (the neighbours' touching layers) is set, and flagged where `split` says they
/// meet another translucent type. Each face direction is the AND-NOT of a layer and the
/// next one: x faces on vertical columns (slab x), y faces on rows along x (layer y), z
/// faces on rows along x again (gathering rows z of every layer y).
fn mesh_type(
    m: &Occupancy,
    hide: &Occupancy,
    nb_hide: &[Plane; 6],
    split: Option<Split<'_>>,
    id: BlockId,
    sink: &mut Sink<'_>,
) {
    let empty = |rows: &Plane| rows.iter().fold(0, |acc, &r| acc | r) == 0;
    for (mine, theirs, inter, faces) in [
        (
            &m.by_y,
            &hide.by_y,
            split.map(|s| &s.inside.by_y),
            [Face::PosX, Face::NegX],
        ),
        (
            &m.by_x,
            &hide.by_x,
            split.map(|s| &s.inside.by_x),
            [Face::PosY, Face::NegY],
        ),
    ] {
        for i in 0..CHUNK_SIZE {
            let rows = layer(mine, i);
            if empty(rows) {
                continue;
            }
            for (face, next) in faces.into_iter().zip([i + 1, i.wrapping_sub(1)]) {
                let inside = next < CHUNK_SIZE;
                let hidden = if inside {
                    layer(theirs, next)
                } else {
                    &nb_hide[face as usize]
                };
                let (mut faces, any) = and_not(rows, hidden);
                if !any {
                    continue;
                }
                let interface = split.map(|s| {
                    move || {
                        if inside {
                            inter.map_or([0; CHUNK_SIZE], |t| *layer(t, next))
                        } else {
                            s.neighbours[face as usize]
                        }
                    }
                });
                emit_split(&mut faces, interface, face, i, id, sink);
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
            if faces.iter().fold(0, |acc, &f| acc | f) == 0 {
                continue;
            }
            let interface = split.map(|s| {
                move || -> Plane {
                    std::array::from_fn(|y| {
                        if next < CHUNK_SIZE {
                            s.inside.by_x[row_index(y, next)]
                        } else {
                            s.neighbours[face as usize][y]
                        }
                    })
                }
            });
            emit_split(&mut faces, interface, face, z, id, sink);
        }
    }
}

#[cfg(test)]
mod tests;
