//! Chunk meshes on the GPU: the quads of every mesh in one arena of large buffers
//! ([`crate::arena`]), one record per chunk (origin, fade-in alpha) in a storage array
//! indexed by the chunk's *slot*, frustum culling, and the draw lists of a frame: one
//! indirect draw command per visible mesh (`first_vertex` = its place in the page,
//! `first_instance` = its slot), issued with `multi_draw_indirect` per page, or one direct
//! draw per mesh where the adapter lacks indirect first-instance draws (logged).
//!
//! A frame finds its visible meshes in one pass ([`ChunkStore::cull`]): chunks are grouped
//! into regions of [`REGION_CHUNKS`] (Sodium's 8 × 4 × 8), whose box is tested first, so that
//! a region outside the frustum costs one test and one wholly inside costs none per chunk;
//! only the chunks of regions the frustum's planes cut are tested one by one. The result is
//! exactly what testing every chunk with [`Frustum::chunk_distance`] finds (a randomized
//! test).
//!
//! Each upload of a chunk gets a new *generation* number, so that what a technique derives
//! from a chunk's quads (a sort structure) can be cached by position and generation and
//! recomputed only when the chunk is remeshed. The planes of its translucent mesh
//! ([`crate::layers`]) are summed up at the upload and kept with the region's records, so
//! that the culling hands them over in its walk when asked to.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};
use std::sync::Arc;

use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Mat4, Vec3, Vec4};
use voxel_core::{CHUNK_SIZE, ChunkPos, Face};
use voxel_mesh::{ChunkMeshes, PackedQuad};

use crate::arena::{Alloc, ArenaStats, QuadArena};
use crate::bindings::ChunkUniforms;
use crate::fetch::{QuadFetch, Records};
use crate::gpu;
use crate::layers::{self, LayerBuffer, Plane, VisibleLayers};
use crate::{Error, GpuContext, Result};

/// A fast hasher for small keys of integers (chunk positions): a multiply-rotate per word
/// and a final mix, instead of SipHash (the store and the techniques look chunks up by
/// position every frame; nothing here needs resistance to chosen keys).
#[derive(Clone, Copy, Debug, Default)]
pub struct PosHasher(u64);

impl PosHasher {
    const K: u64 = 0x9e37_79b9_7f4a_7c15;

    fn add(&mut self, word: u64) {
        self.0 = (self.0.rotate_left(26) ^ word).wrapping_mul(Self::K);
    }
}

impl Hasher for PosHasher {
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.add(u64::from(b));
        }
    }

    fn write_u32(&mut self, v: u32) {
        self.add(u64::from(v));
    }

    fn write_i32(&mut self, v: i32) {
        self.add(u64::from(v as u32));
    }

    fn write_u64(&mut self, v: u64) {
        self.add(v);
    }

    fn write_usize(&mut self, v: usize) {
        self.add(v as u64);
    }

    fn finish(&self) -> u64 {
        // The table takes its bucket from the low bits and its tag from the high ones: mix
        // both.
        let h = self.0 ^ (self.0 >> 32);
        let h = h.wrapping_mul(0xd6e8_feb8_6659_fd93);
        h ^ (h >> 29)
    }
}

/// A hash map keyed by chunk position (or another small integer key), with [`PosHasher`].
pub type PosMap<K, V> = HashMap<K, V, BuildHasherDefault<PosHasher>>;

/// Which of a chunk's three meshes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MeshKind {
    /// Drawn in the opaque pass.
    Opaque = 0,
    /// Drawn in the cutout (alpha-tested) pass.
    Cutout = 1,
    /// Drawn by the transparency technique.
    Translucent = 2,
}

/// How meshes are drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum DrawMode {
    /// One `multi_draw_indirect` per page and pass (the default where the adapter can).
    #[default]
    Indirect,
    /// One direct draw per mesh (the fallback, and the baseline of the measurements).
    PerChunk,
}

impl DrawMode {
    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            DrawMode::Indirect => "indirect",
            DrawMode::PerChunk => "per-chunk",
        }
    }
}

/// A chunk on the GPU: where its meshes are, and what techniques derive from.
#[derive(Debug)]
pub struct GpuChunk {
    pos: ChunkPos,
    meshes: [Option<Alloc>; 3],
    /// The translucent quads in their current GPU order, kept for techniques that derive
    /// something from them (sorting, the fitted WBOIT weight).
    translucent: Vec<PackedQuad>,
    /// The box of the translucent quads, chunk-local blocks (min, max).
    translucent_bounds: Option<([f64; 3], [f64; 3])>,
    /// The distinct planes of the translucent quads: face and chunk-local coordinate along
    /// its axis.
    translucent_planes: Vec<(Face, u8)>,
    /// Whether a translucent quad is of a volume (a block type with absorption).
    volume: bool,
    /// Changes with every upload of the chunk.
    generation: u64,
}

impl GpuChunk {
    /// Where the mesh of `kind` lives, if not empty.
    pub fn mesh(&self, kind: MeshKind) -> Option<Alloc> {
        self.meshes[kind as usize]
    }

    /// Where the chunk is.
    pub fn pos(&self) -> ChunkPos {
        self.pos
    }

    /// Whether the translucent mesh has a face of a volume (a block type with absorption,
    /// [`voxel_core::BlockDef::absorption`]).
    pub fn has_volume(&self) -> bool {
        self.volume
    }

    /// The translucent quads in their current GPU order.
    pub fn translucent_quads(&self) -> &[PackedQuad] {
        &self.translucent
    }

    /// The box the translucent quads span, in world blocks (min, max).
    pub fn translucent_bounds(&self) -> Option<([f64; 3], [f64; 3])> {
        let o = self.pos.origin().map(|v| v as f64);
        self.translucent_bounds.map(|(lo, hi)| {
            (
                [0, 1, 2].map(|a| lo[a] + o[a]),
                [0, 1, 2].map(|a| hi[a] + o[a]),
            )
        })
    }

    /// The translucent quads as the sorted techniques order a game's objects against them
    /// (`oit::sorted::interleave`): their box and their distinct planes, world blocks.
    pub fn translucent_surfaces(&self) -> Option<Surfaces<'_>> {
        let (lo, hi) = self.translucent_bounds()?;
        Some(Surfaces {
            lo: DVec3::from(lo),
            hi: DVec3::from(hi),
            origin: self.pos.origin().map(|v| v as f64),
            planes: &self.translucent_planes,
            quads: &self.translucent,
        })
    }

    /// A number that changes with every upload (remesh) of this chunk, never repeated by
    /// the store.
    pub fn generation(&self) -> u64 {
        self.generation
    }
}

/// A chunk's translucent quads seen from afar: their box and their planes.
#[derive(Clone, Copy, Debug)]
pub struct Surfaces<'a> {
    /// The box's lowest corner, world blocks.
    pub lo: DVec3,
    /// The box's highest corner, world blocks.
    pub hi: DVec3,
    /// The chunk's origin, world blocks.
    pub origin: [f64; 3],
    /// The distinct planes: which way the quads face, chunk-local coordinate on the axis.
    pub planes: &'a [(Face, u8)],
    /// The quads, in their drawn order.
    pub quads: &'a [PackedQuad],
}

impl Surfaces<'_> {
    /// Distances from `eye` to the box: its nearest point, its centre, its farthest corner.
    pub fn distances(&self, eye: DVec3) -> [f64; 3] {
        let near = eye.clamp(self.lo, self.hi).distance(eye);
        let mid = ((self.lo + self.hi) * 0.5).distance(eye);
        let far = (eye - self.lo).abs().max((eye - self.hi).abs()).length();
        [near, mid, far]
    }
}

/// The distinct planes (facing, position along its axis) of a translucent mesh, sorted,
/// from its layers (a layer is a plane, facing and block: every quad lies in one).
fn distinct_planes(layers: &[Plane]) -> Vec<(Face, u8)> {
    let mut planes: Vec<(Face, u8)> = layers
        .iter()
        .map(|p| (p.face, p.lo[p.face.axis()] as u8))
        .collect();
    planes.sort_unstable_by_key(|&(f, c)| (f as u8, c));
    planes.dedup();
    planes
}

/// The box a translucent mesh spans, chunk-local blocks, from its layers.
fn layers_bounds(layers: &[Plane]) -> Option<([f64; 3], [f64; 3])> {
    let (lo, hi) = layers::bounds(layers)?;
    Some((lo.as_dvec3().to_array(), hi.as_dvec3().to_array()))
}

/// One draw command, as `multi_draw_indirect` reads it with [`QuadFetch::Storage`] (with
/// [`QuadFetch::Instanced`] each is a direct draw of its own).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct DrawCommand {
    /// Vertices: 6 per quad.
    pub vertex_count: u32,
    /// Always 1.
    pub instance_count: u32,
    /// The mesh's first quad in its page, times 6.
    pub first_vertex: u32,
    /// The chunk's slot.
    pub first_instance: u32,
}

/// A run of commands drawing from one page.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Run {
    page: u32,
    first: u32,
    count: u32,
}

/// The draws of one pass: runs of commands in a frame's [`FrameDraws`].
#[derive(Clone, Debug, Default)]
pub struct DrawList {
    runs: Vec<Run>,
    meshes: usize,
    quads: u64,
}

impl DrawList {
    /// Whether it draws nothing.
    pub fn is_empty(&self) -> bool {
        self.meshes == 0
    }

    /// Meshes drawn.
    pub fn meshes(&self) -> usize {
        self.meshes
    }

    /// Quads drawn.
    pub fn quads(&self) -> u64 {
        self.quads
    }

    /// Draw calls it records: one per run of a page with indirect draws, one per mesh
    /// without.
    pub fn calls(&self, mode: DrawMode) -> usize {
        match mode {
            DrawMode::Indirect => self.runs.len(),
            DrawMode::PerChunk => self.meshes,
        }
    }
}

/// Every draw command of a frame, on the CPU and in the indirect buffer.
#[derive(Debug)]
pub struct FrameDraws<'a> {
    /// The store whose pages the commands draw from.
    pub store: &'a ChunkStore,
    /// The commands.
    pub commands: &'a [DrawCommand],
    /// How they are issued.
    pub mode: DrawMode,
}

impl FrameDraws<'_> {
    /// Records the draws of `list` (pipeline and group 0 already set; group 1 set here).
    pub fn draw(&self, list: &DrawList, pass: &mut wgpu::RenderPass<'_>) {
        self.draw_range(list, 0..list.meshes, pass);
    }

    /// Records the draws of meshes `range` of `list` (in its order), like [`Self::draw`].
    pub fn draw_range(
        &self,
        list: &DrawList,
        range: std::ops::Range<usize>,
        pass: &mut wgpu::RenderPass<'_>,
    ) {
        let Some(base) = list.runs.first().map(|r| r.first as usize) else {
            return;
        };
        let (lo, hi) = (base + range.start, base + range.end.min(list.meshes));
        for run in &list.runs {
            let (first, end) = (run.first as usize, (run.first + run.count) as usize);
            let (a, b) = (first.max(lo), end.min(hi));
            if a >= b {
                continue;
            }
            let run = &Run {
                page: run.page,
                first: a as u32,
                count: (b - a) as u32,
            };
            if !self.store.bind_page(run.page, pass) {
                continue;
            }
            match self.mode {
                DrawMode::Indirect if self.store.fetch.indirect() => pass.multi_draw_indirect(
                    &self.store.indirect,
                    u64::from(run.first) * std::mem::size_of::<DrawCommand>() as u64,
                    run.count,
                ),
                _ => {
                    let cmds = &self.commands[run.first as usize..(run.first + run.count) as usize];
                    for c in cmds {
                        self.store.draw(run.page, c, 0..c.vertex_count / 6, pass);
                    }
                }
            }
        }
    }

    /// Draws quads `quads` (positions in the mesh's drawn order, clamped to it) of mesh
    /// `index` of `list`: part of a chunk, for objects drawn among its quads.
    pub fn draw_quads(
        &self,
        list: &DrawList,
        index: usize,
        quads: std::ops::Range<u32>,
        pass: &mut wgpu::RenderPass<'_>,
    ) {
        let Some(base) = list.runs.first().map(|r| r.first as usize) else {
            return;
        };
        if index >= list.meshes {
            return;
        }
        let at = (base + index) as u32;
        let Some(run) = list
            .runs
            .iter()
            .find(|r| (r.first..r.first + r.count).contains(&at))
        else {
            return;
        };
        let Some(c) = self.commands.get(at as usize) else {
            return;
        };
        let n = c.vertex_count / 6;
        let (a, b) = (quads.start.min(n), quads.end.min(n));
        if a >= b || !self.store.bind_page(run.page, pass) {
            return;
        }
        self.store.draw(run.page, c, a..b, pass);
    }
}

/// Builds a frame's draw lists: commands appended per list, runs split where the page
/// changes.
#[derive(Debug, Default)]
pub struct DrawBuilder {
    commands: Vec<DrawCommand>,
}

impl DrawBuilder {
    /// A list drawing `meshes` (slot and place of each, as [`Culled::meshes`] gives them),
    /// in order.
    pub fn list(&mut self, meshes: impl IntoIterator<Item = (u32, Alloc)>) -> DrawList {
        let mut list = DrawList::default();
        for (slot, mesh) in meshes {
            let index = self.commands.len() as u32;
            self.commands.push(DrawCommand {
                vertex_count: mesh.quads * 6,
                instance_count: 1,
                first_vertex: mesh.offset * 6,
                first_instance: slot,
            });
            match list.runs.last_mut() {
                Some(r) if r.page == mesh.page => r.count += 1,
                _ => list.runs.push(Run {
                    page: mesh.page,
                    first: index,
                    count: 1,
                }),
            }
            list.meshes += 1;
            list.quads += u64::from(mesh.quads);
        }
        list
    }

    /// Forgets the commands (keeping their room), for the next frame.
    pub fn clear(&mut self) {
        self.commands.clear();
    }

    /// The commands of every list, to be uploaded with [`ChunkStore::upload_draws`].
    pub fn commands(&self) -> &[DrawCommand] {
        &self.commands
    }
}

/// Chunks per region along x, y and z: 8 × 4 × 8 (Sodium's), 256 × 128 × 256 blocks. A
/// frame tests a region's box before the chunks in it.
pub const REGION_CHUNKS: [i32; 3] = [8, 4, 8];

/// What culling needs of a chunk, kept with the other chunks of its region.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Member {
    pos: ChunkPos,
    slot: u32,
    meshes: [Option<Alloc>; 3],
    /// Where its translucent mesh's planes lie in its region's `planes`.
    planes: [u32; 2],
}

/// The chunks of one region.
#[derive(Debug)]
struct Region {
    /// Region coordinates (chunk coordinates divided by [`REGION_CHUNKS`], rounded down).
    key: [i32; 3],
    /// Block coordinates of the region's lowest corner.
    origin: [i64; 3],
    members: Vec<Member>,
    /// The translucent planes of the members ([`crate::layers`]), member by member, and
    /// how many of them belong to no member any more (compacted when more than half).
    planes: Vec<Plane>,
    garbage: usize,
}

impl Region {
    /// Member `index`'s planes.
    fn planes_of(&self, index: usize) -> &[Plane] {
        let [start, end] = self.members[index].planes;
        &self.planes[start as usize..end as usize]
    }

    /// Puts `planes` at the end for member `index` (its old ones become garbage).
    fn set_planes(&mut self, index: usize, planes: &[Plane]) {
        let [start, end] = self.members[index].planes;
        self.garbage += (end - start) as usize;
        let at = self.planes.len() as u32;
        self.planes.extend_from_slice(planes);
        self.members[index].planes = [at, at + planes.len() as u32];
        self.compact_planes();
    }

    /// Copies the members' planes into a new buffer, in member order, when more than half
    /// of the old one is garbage.
    fn compact_planes(&mut self) {
        if self.garbage * 2 <= self.planes.len() {
            return;
        }
        let mut planes = Vec::with_capacity(self.planes.len() - self.garbage);
        for m in &mut self.members {
            let [start, end] = m.planes;
            let at = planes.len() as u32;
            planes.extend_from_slice(&self.planes[start as usize..end as usize]);
            m.planes = [at, planes.len() as u32];
        }
        self.planes = planes;
        self.garbage = 0;
    }
}

/// Where a slot's member is: its region and its index there.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Place {
    region: u32,
    index: u32,
}

/// The chunks grouped by region (CPU only: what [`ChunkStore::cull`] walks).
#[derive(Debug, Default)]
struct Regions {
    regions: Vec<Region>,
    by_key: PosMap<[i32; 3], u32>,
    /// Per slot, where its member is (`None`: no chunk in the slot).
    places: Vec<Option<Place>>,
}

impl Regions {
    fn key(pos: ChunkPos) -> [i32; 3] {
        [
            pos.x.div_euclid(REGION_CHUNKS[0]),
            pos.y.div_euclid(REGION_CHUNKS[1]),
            pos.z.div_euclid(REGION_CHUNKS[2]),
        ]
    }

    /// Adds the chunk of `slot`, or updates its meshes and, when given, the planes of its
    /// translucent mesh (`None` keeps them: the meshes moved, the quads did not change; the
    /// position of a slot never changes while it is held).
    fn set(
        &mut self,
        slot: u32,
        pos: ChunkPos,
        meshes: [Option<Alloc>; 3],
        planes: Option<&[Plane]>,
    ) {
        let s = slot as usize;
        if s >= self.places.len() {
            self.places.resize(s + 1, None);
        }
        if let Some(p) = self.places[s] {
            let region = &mut self.regions[p.region as usize];
            if region.members[p.index as usize].pos == pos {
                region.members[p.index as usize].meshes = meshes;
                if let Some(planes) = planes {
                    region.set_planes(p.index as usize, planes);
                }
                return;
            }
            self.remove(slot);
        }
        let key = Self::key(pos);
        let region = *self.by_key.entry(key).or_insert_with(|| {
            let n = CHUNK_SIZE as i64;
            self.regions.push(Region {
                key,
                origin: [0, 1, 2].map(|k| i64::from(key[k]) * i64::from(REGION_CHUNKS[k]) * n),
                members: Vec::new(),
                planes: Vec::new(),
                garbage: 0,
            });
            self.regions.len() as u32 - 1
        });
        let r = &mut self.regions[region as usize];
        let index = r.members.len();
        self.places[s] = Some(Place {
            region,
            index: index as u32,
        });
        let at = r.planes.len() as u32;
        r.members.push(Member {
            pos,
            slot,
            meshes,
            planes: [at, at],
        });
        r.set_planes(index, planes.unwrap_or_default());
    }

    /// Removes the chunk of `slot` (an empty region goes with it).
    fn remove(&mut self, slot: u32) {
        let Some(p) = self.places.get_mut(slot as usize).and_then(Option::take) else {
            return;
        };
        let region = &mut self.regions[p.region as usize];
        let [start, end] = region.members.swap_remove(p.index as usize).planes;
        region.garbage += (end - start) as usize;
        if let Some(moved) = region.members.get(p.index as usize) {
            self.places[moved.slot as usize] = Some(p);
        }
        if !region.members.is_empty() {
            region.compact_planes();
            return;
        }
        // The last region takes the empty one's index.
        let gone = self.regions.swap_remove(p.region as usize);
        self.by_key.remove(&gone.key);
        if let Some(r) = self.regions.get(p.region as usize) {
            self.by_key.insert(r.key, p.region);
            for m in &r.members {
                if let Some(place) = self.places[m.slot as usize].as_mut() {
                    place.region = p.region;
                }
            }
        }
    }

    /// Calls `visit` with every chunk whose box is not wholly outside one of the frustum's
    /// planes, its distance ([`Frustum::chunk_distance`]: the same chunks, the same
    /// numbers) and its translucent planes, region by region.
    fn cull(&self, frustum: &Frustum, mut visit: impl FnMut(&Member, f64, &[Plane])) {
        let size = REGION_CHUNKS.map(|c| i64::from(c) * CHUNK_SIZE as i64);
        for r in &self.regions {
            match frustum.region_cover(r.origin, size) {
                Cover::Outside => {}
                Cover::Inside => {
                    for (i, m) in r.members.iter().enumerate() {
                        visit(m, frustum.centre_distance(m.pos), r.planes_of(i));
                    }
                }
                Cover::Partial => {
                    for (i, m) in r.members.iter().enumerate() {
                        if let Some(d) = frustum.chunk_distance(m.pos) {
                            visit(m, d, r.planes_of(i));
                        }
                    }
                }
            }
        }
    }
}

/// A visible opaque or cutout mesh in a frame's list: its sort key (page, distance, slot;
/// see [`Culled`]) and where it lives.
#[derive(Clone, Copy, Debug)]
struct NearEntry {
    key: u128,
    mesh: Alloc,
}

/// A visible translucent mesh in a frame's list.
#[derive(Clone, Copy, Debug)]
struct FarEntry {
    /// [`voxel_mesh::order::chunk_order_key`].
    key: u128,
    pos: ChunkPos,
    slot: u32,
    mesh: Alloc,
}

/// One frame's visible meshes of every kind, from [`ChunkStore::cull`], in draw order:
/// opaque and cutout meshes by page, then front to back (early depth rejection; equal
/// distances by slot), translucent ones farthest first by
/// [`voxel_mesh::order::chunk_order_key`] (equal keys by position). Keep one between
/// frames: its vectors keep their room.
#[derive(Debug, Default)]
pub struct Culled {
    near: [Vec<NearEntry>; 2],
    far: Vec<FarEntry>,
    positions: Vec<ChunkPos>,
    keys: Vec<u128>,
    /// The visible translucent chunks' planes, when asked for.
    layers: LayerBuffer,
}

impl Culled {
    /// The meshes of `kind` in draw order: (slot, place).
    pub fn meshes(&self, kind: MeshKind) -> impl Iterator<Item = (u32, Alloc)> + '_ {
        let (near, far): (&[NearEntry], &[FarEntry]) = match kind {
            MeshKind::Opaque => (&self.near[0], &[]),
            MeshKind::Cutout => (&self.near[1], &[]),
            MeshKind::Translucent => (&[], &self.far),
        };
        near.iter()
            .map(|e| (e.key as u32, e.mesh))
            .chain(far.iter().map(|e| (e.slot, e.mesh)))
    }

    /// The positions of the visible translucent meshes, farthest first.
    pub fn translucent_positions(&self) -> &[ChunkPos] {
        &self.positions
    }

    /// The [`voxel_mesh::order::chunk_order_key`] of each visible translucent mesh, in
    /// the order of [`Culled::translucent_positions`] (largest first).
    pub fn translucent_keys(&self) -> &[u128] {
        &self.keys
    }

    /// The store's slot of each visible translucent mesh, in the order of
    /// [`Culled::translucent_positions`] ([`ChunkStore::by_slot`]).
    pub fn translucent_slots(&self) -> impl Iterator<Item = u32> + '_ {
        self.far.iter().map(|e| e.slot)
    }

    /// The planes of the visible translucent meshes ([`crate::layers`]; in no particular
    /// order), when [`ChunkStore::cull`] was asked for them (else empty).
    pub fn translucent_layers(&self) -> VisibleLayers<'_> {
        self.layers.view()
    }
}

/// The sort key of a near-first list: page, then distance, then slot; the distance (never
/// negative: its bits order like the number) in the middle.
fn near_key(page: u32, distance: f64, slot: u32) -> u128 {
    (u128::from(page) << 96) | (u128::from(distance.to_bits()) << 32) | u128::from(slot)
}

/// All chunks on the GPU.
#[derive(Debug)]
pub struct ChunkStore {
    layout: wgpu::BindGroupLayout,
    /// How the chunk pipelines fetch quads: what the pages and records are.
    fetch: QuadFetch,
    arena: QuadArena,
    /// One [`ChunkUniforms`] per slot, and its CPU copy.
    infos: Records,
    info_data: Vec<ChunkUniforms>,
    /// Group 1 per page index: the page's quads and the chunk records (`None` for a page
    /// given back).
    groups: Vec<Option<wgpu::BindGroup>>,
    slots: Vec<Option<GpuChunk>>,
    free_slots: Vec<u32>,
    by_pos: PosMap<ChunkPos, u32>,
    /// The chunks by region, for culling.
    regions: Regions,
    indirect: wgpu::Buffer,
    next_generation: u64,
    /// Whether a frame's draw lists hold places that its submit has not yet drawn (from
    /// [`ChunkStore::lists_built`] to [`ChunkStore::frame_submitted`]).
    in_flight: bool,
    /// Places and slots freed while a frame was in flight: reused only once it is
    /// submitted, so that nothing written before its submit changes what it draws.
    retired: Vec<Alloc>,
    retired_slots: Vec<u32>,
    /// Opacity by block id, for the planes of translucent meshes.
    block_opacity: Arc<[f32]>,
    /// Whether each block id is a volume (has absorption).
    volume_blocks: Arc<[bool]>,
}

const FIRST_SLOTS: usize = 1024;

impl ChunkStore {
    /// An empty store whose bind groups use `layout` (group 1 of
    /// [`crate::SharedLayouts`], for `fetch`).
    /// `block_opacity` (by block id) weighs the planes of translucent meshes
    /// ([`crate::layers`]); `volume_blocks` (by block id) says which block types are
    /// volumes.
    pub fn new(
        ctx: &GpuContext,
        layout: wgpu::BindGroupLayout,
        fetch: QuadFetch,
        block_opacity: Arc<[f32]>,
        volume_blocks: Arc<[bool]>,
    ) -> Self {
        let l = &ctx.caps.limits;
        let infos = Records::new(&ctx.device, fetch, l, FIRST_SLOTS);
        let indirect = Self::indirect_buffer(&ctx.device, FIRST_SLOTS);
        Self {
            layout,
            fetch,
            arena: QuadArena::new(fetch.max_page_bytes(l), fetch.page_usage()),
            infos,
            info_data: Vec::new(),
            groups: Vec::new(),
            slots: Vec::new(),
            free_slots: Vec::new(),
            by_pos: PosMap::default(),
            regions: Regions::default(),
            indirect,
            next_generation: 1,
            in_flight: false,
            retired: Vec::new(),
            retired_slots: Vec::new(),
            block_opacity,
            volume_blocks,
        }
    }

    fn indirect_buffer(device: &wgpu::Device, commands: usize) -> wgpu::Buffer {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("chunk_draws"),
            size: (commands.max(1) * std::mem::size_of::<DrawCommand>()) as u64,
            usage: wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    /// Group 1 of every page, remade after the pages or the record buffer changed. With
    /// [`QuadFetch::Instanced`] the group holds a record only (the page is a vertex
    /// buffer; each draw picks its chunk's record), the same for every page.
    fn remake_groups(&mut self, device: &wgpu::Device) {
        let records = match self.fetch {
            QuadFetch::Storage => None,
            QuadFetch::Instanced => Some(device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("chunk_record"),
                layout: &self.layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 2,
                    resource: self.infos.binding(),
                }],
            })),
        };
        self.groups = (0..self.arena.pages())
            .map(|i| {
                let page = self.arena.page(i)?;
                Some(match &records {
                    Some(group) => group.clone(),
                    None => gpu::bind_group(
                        device,
                        "chunk_page",
                        &self.layout,
                        &[page.as_entire_binding(), self.infos.binding()],
                    ),
                })
            })
            .collect();
    }

    /// Sets what draws from page `page` read: its group 1, or with
    /// [`QuadFetch::Instanced`] the page as vertex buffer 0 (the group goes with each
    /// draw). `false` for a page given back.
    fn bind_page(&self, page: u32, pass: &mut wgpu::RenderPass<'_>) -> bool {
        let (Some(Some(group)), Some(buffer)) = (
            self.groups.get(page as usize),
            self.arena.page(page as usize),
        ) else {
            return false;
        };
        match self.fetch {
            QuadFetch::Storage => pass.set_bind_group(1, group, &[]),
            QuadFetch::Instanced => pass.set_vertex_buffer(0, buffer.slice(..)),
        }
        true
    }

    /// Draws quads `quads` (positions in the mesh) of the mesh of command `c`, in page
    /// `page`, which is bound ([`ChunkStore::bind_page`]).
    fn draw(
        &self,
        page: u32,
        c: &DrawCommand,
        quads: std::ops::Range<u32>,
        pass: &mut wgpu::RenderPass<'_>,
    ) {
        let slot = c.first_instance;
        let first = c.first_vertex / 6 + quads.start;
        let (vertices, instances) = self.fetch.draw_ranges(slot, first, quads.len() as u32);
        if self.fetch == QuadFetch::Instanced
            && let Some(Some(group)) = self.groups.get(page as usize)
        {
            pass.set_bind_group(1, group, &[self.infos.offset(slot)]);
        }
        pass.draw(vertices, instances);
    }

    /// Call once a frame's draw lists hold the meshes' places: from now until
    /// [`ChunkStore::frame_submitted`], freed places and slots are kept from reuse.
    pub fn lists_built(&mut self) {
        self.in_flight = true;
    }

    /// Call once the frame whose lists were built is submitted (or before the next
    /// frame's lists are built, which implies it): the places and slots freed meanwhile
    /// become free, and pages left empty are given back.
    pub fn frame_submitted(&mut self, ctx: &GpuContext) {
        self.in_flight = false;
        let mut dropped = false;
        for a in std::mem::take(&mut self.retired) {
            if self.arena.free(a) {
                dropped |= self.arena.drop_page(a.page);
            }
        }
        self.free_slots.append(&mut self.retired_slots);
        if dropped {
            self.remake_groups(&ctx.device);
        }
    }

    /// Frees a place now, or once the frame in flight is submitted; gives its page back
    /// when that leaves it empty. Returns whether the pages changed.
    fn free_place(&mut self, a: Alloc) -> bool {
        if self.in_flight {
            self.retired.push(a);
            return false;
        }
        self.arena.free(a) && self.arena.drop_page(a.page)
    }

    /// The layout of group 1.
    pub fn layout(&self) -> &wgpu::BindGroupLayout {
        &self.layout
    }

    /// Writes slot `slot`'s record (growing the record buffer when needed).
    fn write_info(&mut self, ctx: &GpuContext, slot: u32, info: ChunkUniforms) {
        let i = slot as usize;
        if i >= self.info_data.len() {
            self.info_data.resize(i + 1, ChunkUniforms::default());
        }
        self.info_data[i] = info;
        if i >= self.infos.capacity() {
            let slots = (self.infos.capacity() * 2).max(i + 1);
            self.infos = Records::new(&ctx.device, self.fetch, &ctx.caps.limits, slots);
            self.infos
                .write(&ctx.queue, 0, bytemuck::cast_slice(&self.info_data));
            self.remake_groups(&ctx.device);
        } else {
            self.infos.write(&ctx.queue, i, bytemuck::bytes_of(&info));
        }
    }

    /// Room for `quads` in the arena (a new page, with its bind group, when needed), with
    /// the quads written. `Ok(None)` for a mesh the arena refuses (checked before).
    fn alloc(&mut self, ctx: &GpuContext, quads: &[PackedQuad]) -> Result<Option<Alloc>> {
        let Ok(n) = u32::try_from(quads.len()) else {
            return Ok(None);
        };
        let Some((a, grew)) = self.arena.alloc(&ctx.device, n)? else {
            return Ok(None);
        };
        if grew {
            self.remake_groups(&ctx.device);
        }
        self.arena.write(&ctx.queue, a, quads);
        Ok(Some(a))
    }

    /// Uploads (or replaces) a chunk's meshes. A chunk whose meshes are all empty is
    /// removed: no quad and no draw exists for an empty mesh. A mesh of more quads than
    /// one page holds ([`crate::arena::QuadArena::max_mesh_quads`]: the adapter's storage
    /// binding; a 32³ chunk has at most 196 608 quads) is an [`Error::TooLarge`] and
    /// changes nothing. A new page the device cannot make is an [`Error::Gpu`].
    ///
    /// The places a frame in flight draws are never written: a replaced mesh keeps its
    /// place until that frame is submitted ([`ChunkStore::frame_submitted`]).
    pub fn upload(&mut self, ctx: &GpuContext, pos: ChunkPos, meshes: &ChunkMeshes) -> Result<()> {
        let limit = self.arena.max_mesh_quads();
        for (kind, quads) in [
            ("opaque", &meshes.opaque),
            ("cutout", &meshes.cutout),
            ("translucent", &meshes.translucent),
        ] {
            if quads.len() as u64 > u64::from(limit) {
                return Err(Error::TooLarge {
                    what: format!("the {kind} mesh of chunk {pos:?}, in quads,"),
                    value: quads.len() as u64,
                    limit_name: match self.fetch {
                        QuadFetch::Storage => "max_storage_buffer_binding_size (in 8-byte quads)",
                        QuadFetch::Instanced => "max_buffer_size (in 8-byte quads)",
                    },
                    limit: u64::from(limit),
                });
            }
        }
        if meshes.is_empty() {
            self.remove(ctx, pos);
            return Ok(());
        }
        // Place the new meshes before freeing the old ones: a failure changes nothing, and
        // the old places (which a frame in flight may draw) are not reused by the new.
        let mut allocs = [None; 3];
        for (k, quads) in [&meshes.opaque, &meshes.cutout, &meshes.translucent]
            .into_iter()
            .enumerate()
        {
            if quads.is_empty() {
                continue;
            }
            match self.alloc(ctx, quads) {
                Ok(Some(a)) => allocs[k] = Some(a),
                failed => {
                    let mut changed = false;
                    for a in allocs.into_iter().flatten() {
                        changed |= self.arena.free(a) && self.arena.drop_page(a.page);
                    }
                    if changed {
                        self.remake_groups(&ctx.device);
                    }
                    return Err(failed.err().unwrap_or_else(|| {
                        Error::Unsupported(format!(
                            "the quad arena found no room for {} quads",
                            quads.len()
                        ))
                    }));
                }
            }
        }
        let (slot, alpha) = match self.by_pos.get(&pos) {
            Some(&s) => {
                self.free_meshes(ctx, s);
                // A chunk fading in goes on fading from where it was.
                (s, self.info_data.get(s as usize).map_or(1.0, |i| i.alpha))
            }
            None => {
                let s = self.free_slots.pop().unwrap_or(self.slots.len() as u32);
                if s as usize == self.slots.len() {
                    self.slots.push(None);
                }
                self.by_pos.insert(pos, s);
                (s, 1.0)
            }
        };
        let origin = pos.origin().map(|v| v as i32);
        self.write_info(ctx, slot, ChunkUniforms { origin, alpha });
        // One pass over the translucent quads; their box and distinct planes follow.
        let planes = layers::planes(&meshes.translucent, &self.block_opacity);
        self.regions.set(slot, pos, allocs, Some(&planes));
        self.slots[slot as usize] = Some(GpuChunk {
            pos,
            meshes: allocs,
            translucent: meshes.translucent.clone(),
            translucent_bounds: layers_bounds(&planes),
            translucent_planes: distinct_planes(&planes),
            volume: meshes.translucent.iter().any(|q| {
                let block = q.unpack().map_or(0, |u| u.block.index());
                self.volume_blocks.get(block).copied().unwrap_or(false)
            }),
            generation: self.next_generation,
        });
        self.next_generation += 1;
        Ok(())
    }

    fn free_meshes(&mut self, ctx: &GpuContext, slot: u32) {
        if let Some(c) = self.slots.get_mut(slot as usize).and_then(Option::take) {
            let mut changed = false;
            for a in c.meshes.into_iter().flatten() {
                changed |= self.free_place(a);
            }
            if changed {
                self.remake_groups(&ctx.device);
            }
        }
    }

    /// Removes a chunk and frees its quads (once the frame in flight is submitted, if
    /// one is); a page left empty is given back.
    pub fn remove(&mut self, ctx: &GpuContext, pos: ChunkPos) {
        if let Some(slot) = self.by_pos.remove(&pos) {
            self.free_meshes(ctx, slot);
            self.regions.remove(slot);
            if self.in_flight {
                self.retired_slots.push(slot);
            } else {
                self.free_slots.push(slot);
            }
        }
    }

    /// Removes every chunk.
    pub fn clear(&mut self, ctx: &GpuContext) {
        let all: Vec<ChunkPos> = self.by_pos.keys().copied().collect();
        for pos in all {
            self.remove(ctx, pos);
        }
    }

    /// The chunk at `pos`, if uploaded.
    pub fn get(&self, pos: ChunkPos) -> Option<&GpuChunk> {
        let slot = *self.by_pos.get(&pos)?;
        self.by_slot(slot)
    }

    /// The chunk in `slot` (what [`Culled::translucent_slots`] names), without a lookup
    /// by position.
    pub fn by_slot(&self, slot: u32) -> Option<&GpuChunk> {
        self.slots.get(slot as usize)?.as_ref()
    }

    /// Number of chunks on the GPU.
    pub fn len(&self) -> usize {
        self.by_pos.len()
    }

    /// Whether no chunk is on the GPU.
    pub fn is_empty(&self) -> bool {
        self.by_pos.is_empty()
    }

    /// The chunks on the GPU.
    pub fn iter(&self) -> impl Iterator<Item = &GpuChunk> {
        self.slots.iter().flatten()
    }

    /// What the arena holds, and the bytes of the chunk records.
    pub fn memory(&self) -> (ArenaStats, u64) {
        (self.arena.stats(), self.infos.bytes())
    }

    /// Bytes of the indirect command buffer.
    pub fn indirect_bytes(&self) -> u64 {
        self.indirect.size()
    }

    /// Rewrites a chunk's translucent quads in a new order (the same quads: a permutation
    /// of [`GpuChunk::translucent_quads`]), for sorting. The generation stays.
    pub fn reorder_translucent(&mut self, ctx: &GpuContext, pos: ChunkPos, quads: Vec<PackedQuad>) {
        let Some(&slot) = self.by_pos.get(&pos) else {
            return;
        };
        let Some(c) = self.slots[slot as usize].as_mut() else {
            return;
        };
        if let Some(a) = c.meshes[MeshKind::Translucent as usize]
            && quads.len() == a.quads as usize
        {
            self.arena.write(&ctx.queue, a, &quads);
            c.translucent = quads;
        }
    }

    /// Sets a chunk's whole-chunk opacity (fade-in).
    pub fn set_alpha(&mut self, ctx: &GpuContext, pos: ChunkPos, alpha: f32) {
        if let Some(&slot) = self.by_pos.get(&pos) {
            let info = ChunkUniforms {
                origin: pos.origin().map(|v| v as i32),
                alpha: alpha.clamp(0.0, 1.0),
            };
            self.write_info(ctx, slot, info);
        }
    }

    /// Finds the visible meshes of every kind in one pass over the regions (see the module
    /// docs) and puts them in draw order into `out` (see [`Culled`]): the meshes of every
    /// chunk whose box [`Frustum::chunk_distance`] does not put outside the frustum. With
    /// `layers`, it also copies the visible translucent meshes' planes
    /// ([`Culled::translucent_layers`]).
    pub fn cull(&self, frustum: &Frustum, layers: bool, out: &mut Culled) {
        for list in &mut out.near {
            list.clear();
        }
        out.far.clear();
        out.positions.clear();
        out.keys.clear();
        out.layers.clear();
        let eye = frustum.eye.to_array();
        let [opaque, cutout] = &mut out.near;
        let (far, buffer) = (&mut out.far, &mut out.layers);
        self.regions.cull(frustum, |m, distance, planes| {
            for (list, mesh) in [(&mut *opaque, m.meshes[0]), (&mut *cutout, m.meshes[1])] {
                if let Some(mesh) = mesh {
                    list.push(NearEntry {
                        key: near_key(mesh.page, distance, m.slot),
                        mesh,
                    });
                }
            }
            if let Some(mesh) = m.meshes[2] {
                far.push(FarEntry {
                    key: voxel_mesh::order::chunk_order_key(m.pos, eye),
                    pos: m.pos,
                    slot: m.slot,
                    mesh,
                });
                if layers {
                    buffer.push(m.pos, planes);
                }
            }
        });
        // Every key is unique (it holds the slot, or the position): an unstable sort gives
        // the one order.
        for list in &mut out.near {
            list.sort_unstable_by_key(|e| e.key);
        }
        out.far
            .sort_unstable_by(|a, b| b.key.cmp(&a.key).then(a.pos.cmp(&b.pos)));
        out.positions.extend(out.far.iter().map(|e| e.pos));
        out.keys.extend(out.far.iter().map(|e| e.key));
    }

    /// Uploads a frame's draw commands to the indirect buffer (growing it when needed).
    pub fn upload_draws(&mut self, ctx: &GpuContext, commands: &[DrawCommand]) {
        let bytes = std::mem::size_of_val(commands) as u64;
        if bytes > self.indirect.size() {
            self.indirect = Self::indirect_buffer(&ctx.device, commands.len() * 2);
        }
        if !commands.is_empty() {
            ctx.queue
                .write_buffer(&self.indirect, 0, bytemuck::cast_slice(commands));
        }
    }

    /// Moves the meshes off the arena's emptiest page when more than half of the arena is
    /// free (see [`crate::arena`]). Returns whether a page was freed. Runs only between
    /// frames (no frame in flight: see [`ChunkStore::frame_submitted`]).
    ///
    /// The copies are submitted at once, on an encoder of their own: a write to a moved
    /// mesh's new place made after this (a technique re-sorting its quads this frame, an
    /// upload before the frame's submit) lands after the copy, never under it.
    pub fn compact(&mut self, ctx: &GpuContext) -> bool {
        if self.in_flight {
            return false;
        }
        let Some(page) = self.arena.page_to_compact() else {
            return false;
        };
        let moving: Vec<(usize, usize, Alloc)> = self
            .slots
            .iter()
            .enumerate()
            .filter_map(|(s, c)| c.as_ref().map(|c| (s, c)))
            .flat_map(|(s, c)| {
                c.meshes
                    .iter()
                    .enumerate()
                    .filter_map(move |(k, a)| a.filter(|a| a.page == page).map(|a| (s, k, a)))
            })
            .collect();
        let allocs: Vec<Alloc> = moving.iter().map(|m| m.2).collect();
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("quad_arena_compaction"),
            });
        let Some(crate::arena::Compacted { placed }) =
            self.arena.compact(&mut encoder, page, &allocs)
        else {
            return false;
        };
        ctx.queue.submit([encoder.finish()]);
        for ((s, k, _), to) in moving.iter().zip(placed) {
            if let Some(c) = self.slots[*s].as_mut() {
                c.meshes[*k] = Some(to);
                self.regions.set(*s as u32, c.pos, c.meshes, None);
            }
        }
        self.remake_groups(&ctx.device);
        true
    }
}

/// The six planes of a camera-relative view frustum, and the eye they are relative to.
#[derive(Clone, Debug)]
pub struct Frustum {
    planes: [Vec4; 6],
    eye: DVec3,
}

impl Frustum {
    /// From a camera-relative view-projection (clip z in [0, w], either direction).
    pub fn new(view_proj: Mat4, eye: DVec3) -> Self {
        let r = [
            view_proj.row(0),
            view_proj.row(1),
            view_proj.row(2),
            view_proj.row(3),
        ];
        let planes = [
            r[3] + r[0],
            r[3] - r[0],
            r[3] + r[1],
            r[3] - r[1],
            r[2],
            r[3] - r[2],
        ];
        Self { planes, eye }
    }

    /// Distance from the eye to the chunk's centre, or `None` when the chunk's box lies
    /// wholly outside one plane.
    pub fn chunk_distance(&self, pos: ChunkPos) -> Option<f64> {
        let s = CHUNK_SIZE as f64;
        let min = self.relative(pos);
        let lo = min.as_vec3();
        let hi = (min + DVec3::splat(s)).as_vec3();
        for p in &self.planes {
            let n = p.truncate();
            // The box corner farthest along the plane normal.
            let v = Vec3::select(n.cmpge(Vec3::ZERO), hi, lo);
            if n.dot(v) + p.w < 0.0 {
                return None;
            }
        }
        Some(self.centre_distance(pos))
    }

    /// The chunk's lowest corner relative to the eye.
    fn relative(&self, pos: ChunkPos) -> DVec3 {
        let o = pos.origin();
        DVec3::new(o[0] as f64, o[1] as f64, o[2] as f64) - self.eye
    }

    /// Distance from the eye to the chunk's centre (the number
    /// [`Frustum::chunk_distance`] gives).
    fn centre_distance(&self, pos: ChunkPos) -> f64 {
        (self.relative(pos) + DVec3::splat(CHUNK_SIZE as f64 / 2.0)).length()
    }

    /// Where the box from block `origin` of `size` blocks lies: wholly outside one plane,
    /// wholly inside all of them, or neither, decided only where the decision holds for
    /// [`Frustum::chunk_distance`]'s test of every chunk in the box despite rounding. That
    /// test rounds the box corners to f32 and sums three products and the plane's offset
    /// in f32: at most about 3.2·10⁻⁷ of `S` = Σ|nᵢ|·|corner coordinateᵢ| + |w| off the
    /// exact value, and so is this one's. A chunk's exact value lies between this box's
    /// nearest and farthest exact values, so with a margin of 4·10⁻⁶·`S` (over ten times
    /// both errors) "outside" and "inside" here are what the chunk test finds too; closer
    /// calls are [`Cover::Partial`], left to the chunk test.
    fn region_cover(&self, origin: [i64; 3], size: [i64; 3]) -> Cover {
        let min = DVec3::new(origin[0] as f64, origin[1] as f64, origin[2] as f64) - self.eye;
        let max = min + DVec3::new(size[0] as f64, size[1] as f64, size[2] as f64);
        let (lo, hi) = (min.as_vec3(), max.as_vec3());
        let reach = lo.abs().max(hi.abs());
        let mut inside = true;
        for p in &self.planes {
            let n = p.truncate();
            let positive = n.cmpge(Vec3::ZERO);
            let margin = 4e-6 * (n.abs().dot(reach) + p.w.abs());
            let far = Vec3::select(positive, hi, lo);
            if n.dot(far) + p.w < -margin {
                return Cover::Outside;
            }
            let near = Vec3::select(positive, lo, hi);
            // NaN counts as "not sure".
            inside &= n.dot(near) + p.w > margin;
        }
        if inside {
            Cover::Inside
        } else {
            Cover::Partial
        }
    }
}

/// Where a region's box lies against the frustum.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Cover {
    /// Wholly outside one plane: none of its chunks is visible.
    Outside,
    /// Wholly inside every plane: all of its chunks are.
    Inside,
    /// Cut by a plane (or too close to call): test its chunks one by one.
    Partial,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Camera;
    use crate::arena::tests::rng;

    #[test]
    fn frustum_keeps_chunks_in_view_and_drops_the_rest() {
        let cam = Camera::look_at(
            DVec3::new(16.0, 16.0, 100.0),
            DVec3::new(16.0, 16.0, 0.0),
            60.0,
            0.1,
            500.0,
        )
        .unwrap();
        let f = Frustum::new(cam.view_proj(1.0), cam.eye);
        assert!(
            f.chunk_distance(ChunkPos::new(0, 0, 0)).is_some(),
            "straight ahead"
        );
        assert!(
            f.chunk_distance(ChunkPos::new(0, 0, 5)).is_none(),
            "behind the eye"
        );
        assert!(
            f.chunk_distance(ChunkPos::new(40, 0, 0)).is_none(),
            "far to the side"
        );
        assert!(
            f.chunk_distance(ChunkPos::new(0, 0, -20)).is_none(),
            "past the far plane"
        );
        assert!(
            f.chunk_distance(ChunkPos::new(0, 0, 3)).is_some(),
            "the eye's own chunk"
        );
    }

    fn mesh(page: u32, offset: u32) -> Option<Alloc> {
        Some(Alloc {
            page,
            offset,
            quads: 1,
        })
    }

    /// `n` planes marked with `mark` (their optical depths).
    fn marked_planes(n: u64, mark: u32) -> Vec<Plane> {
        (0..n)
            .map(|k| Plane {
                face: Face::PosY,
                lo: Vec3::ZERO,
                hi: Vec3::ONE,
                tau: (mark * 4 + k as u32) as f32,
            })
            .collect()
    }

    /// Every place points at its slot's member, every region is non-empty and found by its
    /// key, the members are exactly the chunks held, each with its planes, and at most half
    /// of a region's planes are garbage.
    fn check_bookkeeping(regions: &Regions, held: &[Option<(ChunkPos, Vec<Plane>)>]) {
        let mut members = 0;
        for (i, r) in regions.regions.iter().enumerate() {
            assert!(!r.members.is_empty(), "empty region {:?} kept", r.key);
            let live: usize = (0..r.members.len()).map(|j| r.planes_of(j).len()).sum();
            assert_eq!(live + r.garbage, r.planes.len());
            assert!(
                r.garbage * 2 <= r.planes.len(),
                "{} of {}",
                r.garbage,
                r.planes.len()
            );
            assert_eq!(regions.by_key.get(&r.key), Some(&(i as u32)));
            for (j, m) in r.members.iter().enumerate() {
                assert_eq!(Regions::key(m.pos), r.key);
                let place = Place {
                    region: i as u32,
                    index: j as u32,
                };
                assert_eq!(regions.places[m.slot as usize], Some(place));
                let (pos, planes) = held[m.slot as usize].as_ref().unwrap();
                assert_eq!(*pos, m.pos);
                assert_eq!(r.planes_of(j), &planes[..]);
                members += 1;
            }
        }
        assert_eq!(regions.by_key.len(), regions.regions.len());
        assert_eq!(members, held.iter().flatten().count());
    }

    #[test]
    fn regions_follow_uploads_and_removals() {
        let mut next = rng(0x0dd_ba11_5eed);
        let mut regions = Regions::default();
        let mut held: Vec<Option<(ChunkPos, Vec<Plane>)>> = vec![None; 600];
        for step in 0..6000 {
            let slot = (next() % held.len() as u64) as u32;
            if next().is_multiple_of(3) {
                regions.remove(slot);
                held[slot as usize] = None;
            } else {
                let c = |n: u64| (n % 40) as i32 - 20;
                let same = held[slot as usize]
                    .as_ref()
                    .filter(|_| next().is_multiple_of(2))
                    .map(|h| h.0);
                let pos =
                    same.unwrap_or_else(|| ChunkPos::new(c(next()), c(next()) / 4, c(next())));
                // A chunk that stays may keep its planes (its meshes moved).
                let planes = if same.is_some() && next().is_multiple_of(2) {
                    None
                } else {
                    Some(marked_planes(next() % 4, step))
                };
                regions.set(
                    slot,
                    pos,
                    [mesh(0, step), None, mesh(1, step)],
                    planes.as_deref(),
                );
                let kept = held[slot as usize].take().map(|h| h.1);
                held[slot as usize] = Some((pos, planes.or(kept).unwrap_or_default()));
            }
            if step % 500 == 0 {
                check_bookkeeping(&regions, &held);
            }
        }
        check_bookkeeping(&regions, &held);
        for slot in 0..held.len() as u32 {
            regions.remove(slot);
        }
        check_bookkeeping(&regions, &[]);
        assert!(regions.regions.is_empty());
    }

    /// The box and distinct planes of a mesh derived from its layers are what its quads
    /// give directly.
    #[test]
    fn bounds_and_planes_from_layers_are_those_of_the_quads() {
        let mut next = rng(0x1a7e_5eed);
        let blocks = [
            voxel_core::blocks::GLASS,
            voxel_core::blocks::WATER,
            voxel_core::blocks::ICE,
            voxel_core::BlockId(999),
        ];
        let opacity = [0.5f32; 8];
        for round in 0..200 {
            let quads: Vec<PackedQuad> = (0..round % 40)
                .map(|_| {
                    let mut n = |m: u64| (next() % m) as usize;
                    let (w, h) = (1 + n(8), 1 + n(8));
                    let at = [n(24), n(24), n(24)];
                    PackedQuad::new(at, w, h, Face::ALL[n(6)], blocks[n(4)])
                })
                .collect();
            let layers = layers::planes(&quads, &opacity);
            let mut want: Vec<(Face, u8)> = quads
                .iter()
                .filter_map(|q| q.unpack())
                .map(|q| (q.face, q.bounds().0[q.face.axis()] as u8))
                .collect();
            want.sort_unstable_by_key(|&(f, c)| (f as u8, c));
            want.dedup();
            assert_eq!(distinct_planes(&layers), want);
            let bounds = quads
                .iter()
                .filter_map(|q| q.unpack())
                .map(|q| q.bounds())
                .reduce(|(lo, hi), (a, b)| {
                    (
                        [0, 1, 2].map(|k| lo[k].min(a[k])),
                        [0, 1, 2].map(|k| hi[k].max(b[k])),
                    )
                });
            assert_eq!(layers_bounds(&layers), bounds);
        }
    }

    #[test]
    fn region_culling_finds_what_testing_every_chunk_finds() {
        let mut next = rng(0x5eed_cafe_f00d);
        let mut unit = move || (next() % 1_000_000) as f64 / 1e6;
        let mut covers = [0usize; 3];
        for scene in 0..24 {
            // Around the origin, and far out (where f32 corners round to 1/8 block and more).
            let centre = match scene % 3 {
                0 => [0, 0, 0],
                1 => [31_250, -40, -31_250],
                _ => [60_000_000, 100, -60_000_000],
            };
            let mut regions = Regions::default();
            let mut held = Vec::new();
            for slot in 0..2500u32 {
                let c = |u: f64, r: f64| (u * 2.0 * r - r).floor() as i32;
                let pos = ChunkPos::new(
                    centre[0] + c(unit(), 40.0),
                    centre[1] + c(unit(), 6.0),
                    centre[2] + c(unit(), 40.0),
                );
                if regions.by_key.contains_key(&Regions::key(pos)) && unit() < 0.05 {
                    continue;
                }
                let planes = marked_planes(u64::from(slot % 3), slot);
                regions.set(slot, pos, [mesh(0, slot), None, None], Some(&planes));
                held.push((slot, pos, planes));
            }
            for _ in 0..40 {
                let s = CHUNK_SIZE as f64;
                let eye = DVec3::new(
                    (f64::from(centre[0]) + unit() * 60.0 - 30.0) * s,
                    (f64::from(centre[1]) + unit() * 8.0 - 4.0) * s,
                    (f64::from(centre[2]) + unit() * 60.0 - 30.0) * s,
                );
                let far = [50.0, 500.0, 5000.0, crate::MAX_FAR][(unit() * 4.0) as usize];
                let cam = Camera::from_yaw_pitch(
                    eye,
                    unit() * 7.0,
                    unit() * 3.0 - 1.5,
                    10.0 + unit() * 150.0,
                    crate::MIN_NEAR + unit(),
                    far,
                )
                .unwrap();
                let f = Frustum::new(cam.view_proj(0.5 + unit() * 2.0), cam.eye);
                let size = REGION_CHUNKS.map(|c| i64::from(c) * CHUNK_SIZE as i64);
                for r in &regions.regions {
                    covers[f.region_cover(r.origin, size) as usize] += 1;
                }
                let mut found = Vec::new();
                regions.cull(&f, |m, d, planes| {
                    found.push((m.slot, m.pos, d.to_bits(), planes.to_vec()));
                });
                found.sort_unstable_by_key(|e| e.0);
                let every: Vec<_> = held
                    .iter()
                    .filter_map(|(slot, pos, planes)| {
                        Some((
                            *slot,
                            *pos,
                            f.chunk_distance(*pos)?.to_bits(),
                            planes.clone(),
                        ))
                    })
                    .collect();
                assert_eq!(found, every, "eye {eye:?}");
            }
        }
        // Every kind of region was met.
        assert!(covers.iter().all(|&n| n > 100), "{covers:?}");
    }
}
