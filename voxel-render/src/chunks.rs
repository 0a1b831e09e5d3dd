//! Chunk meshes on the GPU: the quads of every mesh in one arena of large buffers
//! ([`crate::arena`]), one record per chunk (origin, fade-in alpha) in a storage array
//! indexed by the chunk's *slot*, frustum culling, and the draw lists of a frame: one
//! indirect draw command per visible mesh (`first_vertex` = its place in the page,
//! `first_instance` = its slot), issued with `multi_draw_indirect` per page, or one direct
//! draw per mesh where the adapter lacks indirect first-instance draws (logged).
//!
//! Each upload of a chunk gets a new *generation* number, so that what a technique derives
//! from a chunk's quads (a sort structure, a summary of its layers) can be cached by
//! position and generation and recomputed only when the chunk is remeshed.

use std::collections::HashMap;

use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Mat4, Vec3, Vec4};
use voxel_core::{CHUNK_SIZE, ChunkPos};
use voxel_mesh::{ChunkMeshes, PackedQuad};

use crate::GpuContext;
use crate::arena::{Alloc, ArenaStats, QuadArena};
use crate::bindings::ChunkUniforms;
use crate::gpu;

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
    /// Changes with every upload of the chunk.
    generation: u64,
}

impl GpuChunk {
    /// Where the mesh of `kind` lives, if not empty.
    pub fn mesh(&self, kind: MeshKind) -> Option<Alloc> {
        self.meshes[kind as usize]
    }

    /// The translucent quads in their current GPU order.
    pub fn translucent_quads(&self) -> &[PackedQuad] {
        &self.translucent
    }

    /// A number that changes with every upload (remesh) of this chunk, never repeated by
    /// the store.
    pub fn generation(&self) -> u64 {
        self.generation
    }
}

/// A visible chunk mesh, with the view distance of the chunk's centre.
#[derive(Clone, Copy, Debug)]
pub struct Visible {
    /// Where the chunk is.
    pub pos: ChunkPos,
    /// Its slot (the instance index its draws carry).
    pub slot: u32,
    /// Where the mesh lives.
    pub mesh: Alloc,
    /// Distance from the eye to the chunk's centre.
    pub distance: f64,
}

/// One draw command, as `multi_draw_indirect` reads it.
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
        for run in &list.runs {
            let Some(group) = self.store.groups.get(run.page as usize) else {
                continue;
            };
            pass.set_bind_group(1, group, &[]);
            match self.mode {
                DrawMode::Indirect => pass.multi_draw_indirect(
                    &self.store.indirect,
                    u64::from(run.first) * std::mem::size_of::<DrawCommand>() as u64,
                    run.count,
                ),
                DrawMode::PerChunk => {
                    let cmds = &self.commands[run.first as usize..(run.first + run.count) as usize];
                    for c in cmds {
                        pass.draw(
                            c.first_vertex..c.first_vertex + c.vertex_count,
                            c.first_instance..c.first_instance + 1,
                        );
                    }
                }
            }
        }
    }
}

/// Builds a frame's draw lists: commands appended per list, runs split where the page
/// changes.
#[derive(Debug, Default)]
pub struct DrawBuilder {
    commands: Vec<DrawCommand>,
}

impl DrawBuilder {
    /// A list drawing `visible`, in order.
    pub fn list(&mut self, visible: &[Visible]) -> DrawList {
        let mut list = DrawList::default();
        for v in visible {
            let index = self.commands.len() as u32;
            self.commands.push(DrawCommand {
                vertex_count: v.mesh.quads * 6,
                instance_count: 1,
                first_vertex: v.mesh.offset * 6,
                first_instance: v.slot,
            });
            match list.runs.last_mut() {
                Some(r) if r.page == v.mesh.page => r.count += 1,
                _ => list.runs.push(Run {
                    page: v.mesh.page,
                    first: index,
                    count: 1,
                }),
            }
            list.meshes += 1;
            list.quads += u64::from(v.mesh.quads);
        }
        list
    }

    /// The commands of every list, to be uploaded with [`ChunkStore::upload_draws`].
    pub fn commands(&self) -> &[DrawCommand] {
        &self.commands
    }
}

/// All chunks on the GPU.
#[derive(Debug)]
pub struct ChunkStore {
    layout: wgpu::BindGroupLayout,
    arena: QuadArena,
    /// One [`ChunkUniforms`] per slot, and its CPU copy.
    infos: wgpu::Buffer,
    info_data: Vec<ChunkUniforms>,
    /// Group 1 per page: the page's quads and the chunk records.
    groups: Vec<wgpu::BindGroup>,
    slots: Vec<Option<GpuChunk>>,
    free_slots: Vec<u32>,
    by_pos: HashMap<ChunkPos, u32>,
    indirect: wgpu::Buffer,
    next_generation: u64,
}

const FIRST_SLOTS: usize = 1024;

impl ChunkStore {
    /// An empty store whose bind groups use `layout` (group 1 of
    /// [`crate::SharedLayouts`]).
    pub fn new(ctx: &GpuContext, layout: wgpu::BindGroupLayout) -> Self {
        let l = &ctx.caps.limits;
        let infos = Self::infos_buffer(&ctx.device, FIRST_SLOTS);
        let indirect = Self::indirect_buffer(&ctx.device, FIRST_SLOTS);
        Self {
            layout,
            arena: QuadArena::new(l.max_storage_buffer_binding_size.min(l.max_buffer_size)),
            infos,
            info_data: Vec::new(),
            groups: Vec::new(),
            slots: Vec::new(),
            free_slots: Vec::new(),
            by_pos: HashMap::new(),
            indirect,
            next_generation: 1,
        }
    }

    fn infos_buffer(device: &wgpu::Device, slots: usize) -> wgpu::Buffer {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("chunk_infos"),
            size: (slots * std::mem::size_of::<ChunkUniforms>()) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    fn indirect_buffer(device: &wgpu::Device, commands: usize) -> wgpu::Buffer {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("chunk_draws"),
            size: (commands.max(1) * std::mem::size_of::<DrawCommand>()) as u64,
            usage: wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    /// Group 1 of every page, remade after the pages or the record buffer changed.
    fn remake_groups(&mut self, device: &wgpu::Device) {
        self.groups = (0..self.arena.pages())
            .filter_map(|i| self.arena.page(i))
            .map(|page| {
                gpu::bind_group(
                    device,
                    "chunk_page",
                    &self.layout,
                    &[page.as_entire_binding(), self.infos.as_entire_binding()],
                )
            })
            .collect();
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
        let size = std::mem::size_of::<ChunkUniforms>();
        if (i + 1) * size > self.infos.size() as usize {
            let slots = (self.infos.size() as usize / size * 2).max(i + 1);
            self.infos = Self::infos_buffer(&ctx.device, slots);
            ctx.queue
                .write_buffer(&self.infos, 0, bytemuck::cast_slice(&self.info_data));
            self.remake_groups(&ctx.device);
        } else {
            ctx.queue
                .write_buffer(&self.infos, (i * size) as u64, bytemuck::bytes_of(&info));
        }
    }

    /// Room for `quads` in the arena (a new page, with its bind group, when needed).
    fn alloc(&mut self, ctx: &GpuContext, quads: &[PackedQuad]) -> Option<Alloc> {
        let (a, grew) = self.arena.alloc(&ctx.device, quads.len() as u32)?;
        if grew {
            self.remake_groups(&ctx.device);
        }
        self.arena.write(&ctx.queue, a, quads);
        Some(a)
    }

    /// Uploads (or replaces) a chunk's meshes. A chunk whose meshes are all empty is
    /// removed: no quad and no draw exists for an empty mesh. A mesh larger than the
    /// adapter's storage binding (impossible for a 32³ chunk) is dropped with a log line.
    pub fn upload(&mut self, ctx: &GpuContext, pos: ChunkPos, meshes: &ChunkMeshes) {
        if meshes.is_empty() {
            self.remove(pos);
            return;
        }
        let slot = match self.by_pos.get(&pos) {
            Some(&s) => {
                self.free_meshes(s);
                s
            }
            None => {
                let s = self.free_slots.pop().unwrap_or(self.slots.len() as u32);
                if s as usize == self.slots.len() {
                    self.slots.push(None);
                }
                self.by_pos.insert(pos, s);
                s
            }
        };
        let mut allocs = [None; 3];
        for (k, quads) in [&meshes.opaque, &meshes.cutout, &meshes.translucent]
            .into_iter()
            .enumerate()
        {
            if !quads.is_empty() {
                allocs[k] = self.alloc(ctx, quads);
                if allocs[k].is_none() {
                    log::warn!(
                        "chunk {pos:?}: a mesh of {} quads found no room",
                        quads.len()
                    );
                }
            }
        }
        let origin = pos.origin().map(|v| v as i32);
        self.write_info(ctx, slot, ChunkUniforms { origin, alpha: 1.0 });
        self.slots[slot as usize] = Some(GpuChunk {
            pos,
            meshes: allocs,
            translucent: meshes.translucent.clone(),
            generation: self.next_generation,
        });
        self.next_generation += 1;
    }

    fn free_meshes(&mut self, slot: u32) {
        if let Some(c) = self.slots.get_mut(slot as usize).and_then(Option::take) {
            for a in c.meshes.into_iter().flatten() {
                self.arena.free(a);
            }
        }
    }

    /// Removes a chunk and frees its quads.
    pub fn remove(&mut self, pos: ChunkPos) {
        if let Some(slot) = self.by_pos.remove(&pos) {
            self.free_meshes(slot);
            self.free_slots.push(slot);
        }
    }

    /// Removes every chunk.
    pub fn clear(&mut self) {
        let all: Vec<ChunkPos> = self.by_pos.keys().copied().collect();
        for pos in all {
            self.remove(pos);
        }
    }

    /// The chunk at `pos`, if uploaded.
    pub fn get(&self, pos: ChunkPos) -> Option<&GpuChunk> {
        let slot = *self.by_pos.get(&pos)?;
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
        (self.arena.stats(), self.infos.size())
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

    /// The meshes of `kind` of the chunks inside the view frustum, in no particular order.
    pub fn visible(&self, kind: MeshKind, frustum: &Frustum) -> Vec<Visible> {
        self.slots
            .iter()
            .enumerate()
            .filter_map(|(slot, c)| {
                let c = c.as_ref()?;
                let mesh = c.meshes[kind as usize]?;
                frustum.chunk_distance(c.pos).map(|distance| Visible {
                    pos: c.pos,
                    slot: slot as u32,
                    mesh,
                    distance,
                })
            })
            .collect()
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
    /// free (see [`crate::arena`]); records the copies in `encoder`. Returns whether a page
    /// was freed.
    pub fn compact(&mut self, ctx: &GpuContext, encoder: &mut wgpu::CommandEncoder) -> bool {
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
        let Some(crate::arena::Compacted { placed, renamed }) =
            self.arena.compact(encoder, page, &allocs)
        else {
            return false;
        };
        for ((s, k, _), to) in moving.iter().zip(placed) {
            if let Some(c) = self.slots[*s].as_mut() {
                c.meshes[*k] = Some(to);
            }
        }
        if let Some((from, to)) = renamed {
            for c in self.slots.iter_mut().flatten() {
                for a in c.meshes.iter_mut().flatten() {
                    if a.page == from {
                        a.page = to;
                    }
                }
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
        let o = pos.origin();
        let min = DVec3::new(o[0] as f64, o[1] as f64, o[2] as f64) - self.eye;
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
        Some((min + DVec3::splat(s / 2.0)).length())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Camera;

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
}
