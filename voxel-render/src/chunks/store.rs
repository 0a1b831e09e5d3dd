//! The store of every chunk on the GPU: uploads and removals into the quad arena, the
//! records, and the frame's culling and draw lists.

use std::sync::Arc;

use voxel_core::ChunkPos;
use voxel_mesh::{ChunkMeshes, PackedQuad};

use super::command::DrawCommand;
use super::cull::{Culled, FarEntry, Frustum, NearEntry, Regions, near_key};
use super::gpu_chunk::{GpuChunk, distinct_planes, layers_bounds};
use super::light::{ChunkLight, Palettes, Store};
use super::{MeshKind, PosMap};
use crate::arena::{Alloc, ArenaStats, QuadArena};
use crate::bindings::ChunkUniforms;
use crate::fetch::{QuadFetch, Records};
use crate::layers;
use crate::submission::{FrameWrites, Upload};
use crate::{Error, GpuContext, Result};

/// All chunks on the GPU.
#[derive(Debug)]
pub struct ChunkStore {
    layout: wgpu::BindGroupLayout,
    /// How the chunk pipelines fetch quads: what the pages and records are.
    pub(super) fetch: QuadFetch,
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
    pub(super) indirect: wgpu::Buffer,
    next_generation: u64,
    /// Whether a chunk may hold its translucent quads in an order other than the mesher's
    /// ([`ChunkStore::reorder_translucent`]).
    reordered: bool,
    /// Whether a frame's draw lists hold places that its submit has not yet drawn (from
    /// [`ChunkStore::lists_built`] to [`ChunkStore::frame_submitted`]).
    in_flight: bool,
    /// Places and slots freed while a frame was in flight: reused only once it is
    /// submitted, so that nothing written before its submit changes what it draws.
    retired: Vec<Alloc>,
    retired_slots: Vec<u32>,
    /// Every lit chunk's light palette, and palettes freed while a frame was in flight.
    palettes: Palettes,
    retired_palettes: Vec<(u32, u32)>,
    /// Opacity by block id, for the planes of translucent meshes.
    block_opacity: Arc<[f32]>,
    /// Whether each block id is a volume (has absorption).
    volume_blocks: Arc<[bool]>,
    /// What the frame being recorded writes (its draw commands, a sorted chunk's quad
    /// order, fading records), recorded into its encoder by the renderer.
    writes: FrameWrites,
}

const FIRST_SLOTS: usize = 1024;

impl ChunkStore {
    /// An empty store whose bind groups use `layout` (group 1 of
    /// [`crate::SharedLayouts`], for `fetch`).
    /// `block_opacity` (by block id) weighs the planes of translucent meshes
    /// ([`crate::layers`]); `volume_blocks` (by block id) says which block types are
    /// volumes.
    pub(crate) fn new(
        ctx: &GpuContext,
        layout: wgpu::BindGroupLayout,
        fetch: QuadFetch,
        block_opacity: Arc<[f32]>,
        volume_blocks: Arc<[bool]>,
    ) -> Self {
        let l = &ctx.caps.limits;
        // The records array is bound whole from storage: no more slots at first than the
        // device's binding holds (32-byte records: 512 under a 16 KiB binding).
        let first = match fetch {
            QuadFetch::Storage => FIRST_SLOTS.min(
                (l.max_storage_buffer_binding_size as usize / crate::fetch::RECORD_BYTES).max(1),
            ),
            QuadFetch::Instanced => FIRST_SLOTS,
        };
        let infos = Records::new(&ctx.device, fetch, l, first);
        let indirect = Self::indirect_buffer(ctx, FIRST_SLOTS);
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
            reordered: false,
            in_flight: false,
            retired: Vec::new(),
            retired_slots: Vec::new(),
            palettes: Palettes::new(ctx, fetch),
            retired_palettes: Vec::new(),
            block_opacity,
            volume_blocks,
            writes: FrameWrites::default(),
        }
    }

    /// The buffer of `commands` draw commands; an indirect buffer only where the device
    /// executes indirect draws (WebGL2 and desktop GL 3.3 do not, and wgpu refuses the
    /// usage there): elsewhere the draws are direct and read the commands on the CPU.
    fn indirect_buffer(ctx: &GpuContext, commands: usize) -> wgpu::Buffer {
        let mut usage = wgpu::BufferUsages::COPY_DST;
        if ctx
            .caps
            .downlevel
            .contains(wgpu::DownlevelFlags::INDIRECT_EXECUTION)
        {
            usage |= wgpu::BufferUsages::INDIRECT;
        }
        ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("chunk_draws"),
            size: (commands.max(1) * std::mem::size_of::<DrawCommand>()) as u64,
            usage,
            mapped_at_creation: false,
        })
    }

    /// Group 1 of every page, remade after the pages or the record buffer changed. With
    /// [`QuadFetch::Instanced`] the group holds a record only (the page is a vertex
    /// buffer; each draw picks its chunk's record), the same for every page.
    fn remake_groups(&mut self, device: &wgpu::Device) {
        let records = match self.palettes.store() {
            Store::Buffer(_) => None,
            Store::Table(table) => Some(device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("chunk_record"),
                layout: &self.layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: self.infos.binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 5,
                        resource: wgpu::BindingResource::TextureView(&table.view),
                    },
                ],
            })),
        };
        self.groups = (0..self.arena.pages())
            .map(|i| {
                let page = self.arena.page(i)?;
                if let Some(group) = &records {
                    return Some(group.clone());
                }
                // The page's light and the palettes (where the arena holds no light, the
                // palettes stand in for the light page: no unlit record reads it).
                let Store::Buffer(palettes) = self.palettes.store() else {
                    return None;
                };
                let light = self.arena.light_page(i).unwrap_or(palettes);
                let entries = [
                    (0, page.as_entire_binding()),
                    (1, self.infos.binding()),
                    (3, light.as_entire_binding()),
                    (4, palettes.as_entire_binding()),
                ]
                .map(|(binding, resource)| wgpu::BindGroupEntry { binding, resource });
                crate::cost::created_bind_group();
                Some(device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("chunk_page"),
                    layout: &self.layout,
                    entries: &entries,
                }))
            })
            .collect();
    }

    /// Sets what draws from page `page` read: its group 1, or with
    /// [`QuadFetch::Instanced`] the page as vertex buffer 0 (the group goes with each
    /// draw). `false` for a page given back.
    pub(super) fn bind_page(&self, page: u32, pass: &mut crate::gpu::CountedPass<'_, '_>) -> bool {
        let (Some(Some(group)), Some(buffer)) = (
            self.groups.get(page as usize),
            self.arena.page(page as usize),
        ) else {
            return false;
        };
        match self.fetch {
            QuadFetch::Storage => pass.set_bind_group(1, group, &[]),
            QuadFetch::Instanced => {
                pass.set_vertex_buffer(0, buffer.slice(..));
                // The quads' light (the page itself stands in where the arena holds no
                // light: no unlit record reads it).
                let light = self.arena.light_page(page as usize).unwrap_or(buffer);
                pass.set_vertex_buffer(1, light.slice(..));
            }
        }
        true
    }

    /// Draws quads `quads` (positions in the mesh) of the mesh of command `c`, in page
    /// `page`, which is bound ([`ChunkStore::bind_page`]).
    pub(super) fn draw(
        &self,
        page: u32,
        c: &DrawCommand,
        quads: std::ops::Range<u32>,
        pass: &mut crate::gpu::CountedPass<'_, '_>,
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
    pub(crate) fn lists_built(&mut self) {
        self.in_flight = true;
    }

    /// Call once the frame whose lists were built is submitted (or before the next
    /// frame's lists are built, which implies it): the places and slots freed meanwhile
    /// become free, and pages left empty are given back.
    pub(crate) fn frame_submitted(&mut self, ctx: &GpuContext) {
        self.in_flight = false;
        let mut dropped = false;
        for a in std::mem::take(&mut self.retired) {
            if self.arena.free(a) {
                dropped |= self.arena.drop_page(a.page);
            }
        }
        self.free_slots.append(&mut self.retired_slots);
        for (base, len) in self.retired_palettes.drain(..) {
            self.palettes.free(base, len);
        }
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

    /// Writes slot `slot`'s record (growing the record buffer when needed): at the next
    /// submit, or `in_frame` in the frame being recorded ([`ChunkStore::writes`]).
    fn write_info(&mut self, ctx: &GpuContext, slot: u32, info: ChunkUniforms, in_frame: bool) {
        let i = slot as usize;
        if i >= self.info_data.len() {
            self.info_data.resize(i + 1, ChunkUniforms::default());
        }
        self.info_data[i] = info;
        if i >= self.infos.capacity() {
            let slots = (self.infos.capacity() * 2).max(i + 1);
            self.infos = Records::new(&ctx.device, self.fetch, &ctx.caps.limits, slots);
            // A new buffer: no frame recorded before reads it.
            self.infos.write(
                &mut Upload::Queue(&ctx.queue),
                0,
                bytemuck::cast_slice(&self.info_data),
            );
            self.remake_groups(&ctx.device);
        } else if in_frame {
            let mut to = Upload::Frame(&mut self.writes);
            self.infos.write(&mut to, i, bytemuck::bytes_of(&info));
        } else {
            let mut to = Upload::Queue(&ctx.queue);
            self.infos.write(&mut to, i, bytemuck::bytes_of(&info));
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
        self.arena.write(&mut Upload::Queue(&ctx.queue), a, quads);
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
    ///
    /// `level` is the chunk's level of detail (0: a chunk; see
    /// `Renderer::upload_level_chunk`), `pos` its key: the full-detail chunk where
    /// it starts.
    pub(crate) fn upload(
        &mut self,
        ctx: &GpuContext,
        pos: ChunkPos,
        level: u8,
        meshes: &ChunkMeshes,
    ) -> Result<()> {
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
        let light = self.place_light(ctx, pos, meshes)?;
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
                    if let Some(l) = &light {
                        self.palettes.free(l.palette.0, l.palette.1);
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
        if let Some(l) = &light {
            let streams = &meshes.light;
            for (a, stream) in
                allocs
                    .iter()
                    .zip([&streams.opaque, &streams.cutout, &streams.translucent])
            {
                if let Some(a) = a {
                    self.arena
                        .write_light(&mut Upload::Queue(&ctx.queue), *a, stream);
                }
            }
            debug_assert!(self.arena.is_lit() && l.palette.1 > 0);
        }
        let light_base = light.as_ref().map(|l| l.palette.0);
        self.write_info(ctx, slot, record(pos, level, alpha, light_base), false);
        // One pass over the translucent quads; their box and distinct planes follow.
        let planes = layers::planes(&meshes.translucent, &self.block_opacity);
        self.regions.set(slot, pos, level, allocs, Some(&planes));
        self.slots[slot as usize] = Some(GpuChunk {
            pos,
            level,
            meshes: allocs,
            translucent: meshes.translucent.clone(),
            translucent_bounds: layers_bounds(&planes),
            translucent_planes: distinct_planes(&planes),
            volume: meshes.translucent.iter().any(|q| {
                let block = q.unpack().map_or(0, |u| u.block.index());
                self.volume_blocks.get(block).copied().unwrap_or(false)
            }),
            light,
            generation: self.next_generation,
            mesher_order: None,
            set_aside: None,
            order_stamp: self.next_generation,
        });
        self.next_generation += 1;
        Ok(())
    }

    /// Checks a chunk's light streams against its meshes and places its palette, giving the
    /// arena light pages the first time: `None` for a chunk meshed without light. A stream
    /// whose length is not its mesh's, or an index outside the palette, is an
    /// [`Error::InvalidSetting`].
    fn place_light(
        &mut self,
        ctx: &GpuContext,
        pos: ChunkPos,
        meshes: &ChunkMeshes,
    ) -> Result<Option<ChunkLight>> {
        let streams = &meshes.light;
        if streams.is_empty() && streams.palette.is_empty() {
            return Ok(None);
        }
        for (kind, quads, light) in [
            ("opaque", meshes.opaque.len(), &streams.opaque),
            ("cutout", meshes.cutout.len(), &streams.cutout),
            (
                "translucent",
                meshes.translucent.len(),
                &streams.translucent,
            ),
        ] {
            if light.len() != quads {
                return Err(Error::InvalidSetting(format!(
                    "chunk {pos:?}: its {kind} mesh has {quads} quads and {} light entries \
                     (mesh it with `Mesher::mesh_lit`, or leave `ChunkMeshes::light` empty)",
                    light.len()
                )));
            }
            let n = streams.palette.len();
            if let Some(bad) = light
                .iter()
                .flat_map(|l| l.corners())
                .find(|&i| usize::from(i) >= n)
            {
                return Err(Error::InvalidSetting(format!(
                    "chunk {pos:?}: a quad of its {kind} mesh names light {bad} of a palette \
                     of {n}"
                )));
            }
        }
        let ((base, len), grew) = self.palettes.alloc(ctx, &streams.palette)?;
        match self.arena.enable_light(&ctx.device) {
            Ok(changed) => {
                if changed || grew {
                    self.remake_groups(&ctx.device);
                }
            }
            Err(e) => {
                self.palettes.free(base, len);
                return Err(e);
            }
        }
        Ok(Some(ChunkLight {
            palette: (base, len),
            translucent: meshes
                .translucent
                .iter()
                .copied()
                .zip(streams.translucent.iter().copied())
                .collect(),
        }))
    }

    fn free_meshes(&mut self, ctx: &GpuContext, slot: u32) {
        if let Some(c) = self.slots.get_mut(slot as usize).and_then(Option::take) {
            if let Some(l) = &c.light {
                let (base, len) = l.palette;
                if self.in_flight {
                    self.retired_palettes.push((base, len));
                } else {
                    self.palettes.free(base, len);
                }
            }
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
    pub(crate) fn remove(&mut self, ctx: &GpuContext, pos: ChunkPos) {
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
    pub(crate) fn clear(&mut self, ctx: &GpuContext) {
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
    pub(crate) fn by_slot(&self, slot: u32) -> Option<&GpuChunk> {
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

    /// What the arena holds, the bytes of the chunk records and those of the light palettes.
    pub(crate) fn memory(&self) -> (ArenaStats, u64, u64) {
        // The palettes count once the arena holds light (before, the buffer is a
        // stand-in of 32 KiB).
        let palettes = match self.arena.is_lit() {
            true => self.palettes.bytes(),
            false => 0,
        };
        (self.arena.stats(), self.infos.bytes(), palettes)
    }

    /// Bytes of the indirect command buffer.
    pub(crate) fn indirect_bytes(&self) -> u64 {
        self.indirect.size()
    }

    /// Rewrites a chunk's translucent quads in a new order (the same quads: a permutation
    /// of [`GpuChunk::translucent_quads`]), for sorting, in the frame being recorded
    /// ([`ChunkStore::writes`]): a frame recorded before it keeps its own order. The
    /// generation stays. The write goes into the frame's writes: `_ctx` is not needed.
    pub(crate) fn reorder_translucent(
        &mut self,
        _ctx: &GpuContext,
        pos: ChunkPos,
        quads: Vec<PackedQuad>,
    ) {
        let Some(&slot) = self.by_pos.get(&pos) else {
            return;
        };
        let Some(c) = self.slots[slot as usize].as_mut() else {
            return;
        };
        if let Ok(old) = write_order(&self.arena, &mut self.writes, c, quads) {
            if c.mesher_order.is_none() {
                c.mesher_order = Some(old);
            }
            c.set_aside = None;
            self.reordered = true;
            c.order_stamp = self.next_generation;
            self.next_generation += 1;
        }
    }

    /// Puts every chunk's translucent quads back in the mesher's order (in the frame being
    /// recorded), where a technique re-sorted them: what a technique that draws the
    /// mesher's order (`sorted`) draws then does not depend on the techniques before it.
    /// Costs nothing when no chunk was re-sorted.
    pub(crate) fn restore_mesher_order(&mut self) {
        if !self.reordered {
            return;
        }
        for c in self.slots.iter_mut().flatten() {
            let Some(quads) = c.mesher_order.take() else {
                continue;
            };
            if let Ok(sorted) = write_order(&self.arena, &mut self.writes, c, quads) {
                c.set_aside = Some((sorted, c.order_stamp));
                c.order_stamp = self.next_generation;
                self.next_generation += 1;
            }
        }
        self.reordered = false;
    }

    /// Draws again the order a technique wrote with stamp `stamp` (in the frame being
    /// recorded), where [`Self::restore_mesher_order`] put it aside since: an upload instead
    /// of a sort, when a game switches back. The chunk's order stamp becomes `stamp` again
    /// (the GPU holds that order). False when nothing with that stamp was put aside.
    pub(crate) fn reapply_order(&mut self, pos: ChunkPos, stamp: u64) -> bool {
        let Some(&slot) = self.by_pos.get(&pos) else {
            return false;
        };
        let Some(c) = self.slots[slot as usize].as_mut() else {
            return false;
        };
        let Some((quads, s)) = c.set_aside.take() else {
            return false;
        };
        if s != stamp {
            return false;
        }
        let Ok(mesher) = write_order(&self.arena, &mut self.writes, c, quads) else {
            return false;
        };
        c.mesher_order = Some(mesher);
        c.order_stamp = stamp;
        self.reordered = true;
        true
    }

    /// Sets a chunk's whole-chunk opacity (fade-in): at the next submit, or `in_frame` in
    /// the frame being recorded.
    pub(crate) fn set_alpha(
        &mut self,
        ctx: &GpuContext,
        pos: ChunkPos,
        alpha: f32,
        in_frame: bool,
    ) {
        if let Some(&slot) = self.by_pos.get(&pos) {
            let mut info = self.info_data[slot as usize];
            info.alpha = alpha.clamp(0.0, 1.0);
            self.write_info(ctx, slot, info, in_frame);
        }
    }

    /// The writes of the frame being recorded (its draw commands, sorted quads, fading
    /// records): the renderer records them into the frame's encoder before its first pass.
    pub(crate) fn writes(&mut self) -> &mut FrameWrites {
        &mut self.writes
    }

    /// Finds the visible meshes of every kind in one pass over the regions (see the module
    /// docs) and puts them in draw order into `out` (see [`Culled`]): the meshes of every
    /// chunk whose box [`Frustum::level_chunk_distance`] does not put outside the frustum. With
    /// `layers`, it also copies the visible translucent meshes' planes
    /// ([`Culled::translucent_layers`]).
    pub(crate) fn cull(&self, frustum: &Frustum, layers: bool, out: &mut Culled) {
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
                    key: order_key(m.pos, m.level, eye),
                    pos: m.pos,
                    slot: m.slot,
                    mesh,
                });
                if layers {
                    buffer.push(m.pos, m.level, planes);
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

    /// Uploads a frame's draw commands to the indirect buffer (growing it when needed), in
    /// the frame being recorded ([`ChunkStore::writes`]).
    pub(crate) fn upload_draws(&mut self, ctx: &GpuContext, commands: &[DrawCommand]) {
        let bytes = std::mem::size_of_val(commands) as u64;
        if bytes > self.indirect.size() {
            self.indirect = Self::indirect_buffer(ctx, commands.len() * 2);
        }
        self.writes
            .write(&self.indirect, 0, bytemuck::cast_slice(commands));
    }

    /// Moves the meshes off the arena's emptiest page when more than half of the arena is
    /// free (see [`crate::arena`]). Returns whether a page was freed. Runs only between
    /// frames (no frame in flight: see [`ChunkStore::frame_submitted`]).
    ///
    /// The copies are submitted at once, on an encoder of their own: a write to a moved
    /// mesh's new place made after this (a technique re-sorting its quads this frame, an
    /// upload before the frame's submit) lands after the copy, never under it.
    pub(crate) fn compact(&mut self, ctx: &GpuContext) -> bool {
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
                self.regions.set(*s as u32, c.pos, c.level, c.meshes, None);
            }
        }
        self.remake_groups(&ctx.device);
        true
    }
}

/// Writes `quads` (a permutation of `c`'s translucent quads) as `c`'s GPU order, in the
/// frame being recorded (`writes`), and returns the order it replaces; gives `quads` back
/// when the chunk's translucent mesh holds another number of quads.
fn write_order(
    arena: &QuadArena,
    writes: &mut FrameWrites,
    c: &mut GpuChunk,
    quads: Vec<PackedQuad>,
) -> std::result::Result<Vec<PackedQuad>, Vec<PackedQuad>> {
    match c.meshes[MeshKind::Translucent as usize] {
        Some(a) if quads.len() == a.quads as usize => {
            arena.write(&mut Upload::Frame(writes), a, &quads);
            if let Some(l) = &c.light {
                let light = l.translucent_stream(&quads);
                arena.write_light(&mut Upload::Frame(writes), a, &light);
            }
            Ok(std::mem::replace(&mut c.translucent, quads))
        }
        _ => Err(quads),
    }
}

/// The record of the chunk keyed `pos` (where it starts) of level `level`, lit from the
/// palette at `light_base` when given.
fn record(pos: ChunkPos, level: u8, alpha: f32, light_base: Option<u32>) -> ChunkUniforms {
    ChunkUniforms {
        origin: pos.origin().map(|v| v as i32),
        alpha,
        scale: voxel_core::level_scale(level) as u32,
        light_base: light_base.unwrap_or(0),
        lit: u32::from(light_base.is_some()),
        ..ChunkUniforms::default()
    }
}

/// The draw-order key of the translucent mesh of the chunk keyed `pos` of level `level`
/// (largest first): [`voxel_mesh::order::chunk_order_key`] among the chunks of a level (in
/// the level's own grid, whose cells it is exact for), coarser levels before finer ones.
/// Exact for levels laid out as rings around the eye: each level's chunks cover a
/// square (in x and z) that holds the finer levels' and the eye, so a ray from the eye
/// leaves the finer levels' square before it meets a coarser chunk.
pub(crate) fn order_key(pos: ChunkPos, level: u8, eye: [f64; 3]) -> u128 {
    let s = voxel_core::level_scale(level);
    let in_level = ChunkPos::new(
        (i64::from(pos.x).div_euclid(s)) as i32,
        pos.y,
        (i64::from(pos.z).div_euclid(s)) as i32,
    );
    let eye = [eye[0] / s as f64, eye[1], eye[2] / s as f64];
    (u128::from(level) << 100) | voxel_mesh::order::chunk_order_key(in_level, eye)
}
