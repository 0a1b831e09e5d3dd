//! The exact reference: per-pixel fragment lists (an A-buffer) sorted per pixel and
//! blended in depth order. Every other technique is measured against it.
//!
//! Pass 1 appends each translucent fragment in front of the opaque depth to its pixel's
//! list (a storage buffer of nodes, an atomic head pointer per pixel; needs fragment
//! shaders that write storage, `DownlevelFlags::FRAGMENT_WRITABLE_STORAGE`). Pass 2 keeps
//! each pixel's nearest [`MAX_LAYERS`] fragments, sorted, and blends them front to back
//! over the opaque image.
//!
//! Limits, none of them silent ([`ReferenceReport`]):
//! - **Pool**: it starts at four nodes a pixel; after each frame the counters are read back
//!   (a stall: this is a measurement tool), and if nodes ran out the frame is redone with a
//!   pool twice as large, up to the adapter's largest storage binding, then in 2×2, 4×4,
//!   ... screen tiles (each tile re-draws the geometry and reuses the pool), up to
//!   [`MAX_TILES`]² tiles. Fragments that still do not fit are counted as lost.
//! - **Head pointers** are per tile: the first tiling is the smallest whose tile's heads
//!   fit one storage binding, so any render size the adapter's textures allow works.
//! - **Depth complexity**: a pixel with more than [`MAX_LAYERS`] fragments blends its
//!   nearest [`MAX_LAYERS`]; it is counted as *capped*, and as *capped visibly* when more
//!   than half a level (1/510) of light came through the kept layers (then the dropped
//!   ones could change its 8-bit colour: the picture is not exact there). A list longer
//!   than [`MAX_WALK`] fragments is walked for its latest [`MAX_WALK`] only, and counts
//!   as capped visibly.

use wgpu::util::DeviceExt;

use crate::context::Capabilities;
use crate::gpu::{
    self, ChunkPipeline, Depth, DepthMode, FullscreenPipeline, Pass, SidedPipeline, WgslConsts,
};
use crate::ladder::{Limit, Need};
use crate::oit::{
    OitConfig, Setup, Technique, TechniqueKind, TechniqueReport, TranslucentFrame,
    TranslucentTechnique,
};
use crate::stages::{TranslucentVariant, game_group, game_layout, game_prelude};
use crate::submission::FrameWrites;
use crate::timing::GpuPass;
use crate::{Error, GpuContext, Result, readback};

/// Bytes per node (`Node`).
pub(crate) const NODE_BYTES: u64 = std::mem::size_of::<Node>() as u64;
/// Initial pool: nodes per pixel.
pub(crate) const INITIAL_NODES_PER_PIXEL: u64 = 4;
/// Most tiles per axis before giving up on fitting a frame.
pub(crate) const MAX_TILES: u32 = 16;
/// Fragments a pixel blends at most (its nearest ones).
pub(crate) const MAX_LAYERS: u32 = 128;
/// Fragments of a pixel's list the resolve walks at most (the latest appended). Lavapipe
/// (llvmpipe) stops a shader loop silently after about 4 000 iterations, which left pixels
/// of a dense particle cloud empty; on any GPU an unbounded walk is a stall waiting to
/// happen. A longer list counts as capped visibly: its picture is not exact.
pub(crate) const MAX_WALK: u32 = 2048;

/// What the A-buffer did in the last frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ReferenceReport {
    /// Attempts the frame needed (more than 1 after growing the pool or tiling).
    pub attempts: u32,
    /// Tiles per axis of the last attempt.
    pub tiles: u32,
    /// Fragments that did not fit in the pool even with the most tiles (should be 0).
    pub lost_fragments: u64,
    /// Pixels with more than `MAX_LAYERS` fragments (their nearest ones were blended).
    pub capped_pixels: u64,
    /// Capped pixels where the dropped fragments could change the 8-bit colour.
    pub capped_visible_pixels: u64,
}

impl ReferenceReport {
    /// Whether the picture is exact: nothing lost, no pixel capped visibly.
    pub fn exact(&self) -> bool {
        self.lost_fragments == 0 && self.capped_visible_pixels == 0
    }
}

/// One fragment of a pixel's list (`Node` in `types.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct Node {
    /// Colour and alpha as four halves.
    pub color: [u32; 2],
    /// Reverse-Z depth.
    pub depth: f32,
    /// Index + 1 of the next node; 0 ends the list.
    pub next: u32,
    /// The depth's screen-space gradient, which orders fragments of equal depth.
    pub slope: [f32; 2],
    /// Its part in the medium the ray is in (`fragment_info` in `shaders/volume.wgsl`).
    pub info: u32,
    /// Padding.
    pub _pad: u32,
}

/// The counters read back per tile (`Counters` in `types.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct Counters {
    /// Nodes asked for.
    pub nodes: u32,
    /// Pixels with more than [`MAX_LAYERS`] fragments.
    pub capped: u32,
    /// Of those, the ones where the dropped fragments could show.
    pub capped_visible: u32,
    /// Padding.
    pub _pad: u32,
}

/// The tile being drawn (`Params` in `types.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct Params {
    /// Top-left pixel of the tile.
    pub origin: [u32; 2],
    /// Width of the tile (row length of its head pointers).
    pub tile_width: u32,
    /// Nodes in the pool.
    pub capacity: u32,
}

const COUNTERS_BYTES: u64 = std::mem::size_of::<Counters>() as u64;

/// WGSL of the constants and types both passes share.
fn types_wgsl() -> String {
    let consts = WgslConsts::default()
        .u32("MAX_LAYERS", MAX_LAYERS)
        .u32("MAX_WALK", MAX_WALK)
        .finish();
    consts + include_str!("types.wgsl")
}

/// The build pass's shader.
pub(crate) fn build_wgsl() -> String {
    [
        &crate::bindings::common_wgsl(),
        &types_wgsl(),
        include_str!("abuffer.wgsl"),
        include_str!("build.wgsl"),
    ]
    .concat()
}

/// The group-2 entries of the build pass: heads, nodes, counters, the tile's parameters
/// (dynamic offset) and the opaque depth.
fn build_entries() -> [wgpu::BindGroupLayoutEntry; 5] {
    use wgpu::BufferBindingType as B;
    use wgpu::ShaderStages as S;
    let storage = |i| gpu::buffer_entry(i, S::FRAGMENT, B::Storage { read_only: false });
    [
        storage(0),
        storage(1),
        storage(2),
        params_entry(),
        gpu::texture_entry(4, gpu::DEPTH_READ),
    ]
}

/// The fragment stage writes the heads, nodes and counters (storage buffers, atomics), and
/// reads the opaque depth while it is the pass's read-only depth attachment; the frame
/// waits for the counters to learn whether every fragment fitted.
fn reference_needs() -> Vec<Need> {
    vec![
        Need::Downlevel(wgpu::DownlevelFlags::FRAGMENT_WRITABLE_STORAGE),
        Need::Limit(Limit::StorageBuffersPerStage, 3),
        Need::Downlevel(wgpu::DownlevelFlags::READ_ONLY_DEPTH_STENCIL),
        Need::WaitForGpu,
    ]
}

fn params_entry() -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding: 3,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: true,
            min_binding_size: wgpu::BufferSize::new(std::mem::size_of::<Params>() as u64),
        },
        count: None,
    }
}

/// The resolve pass's shader (after `fullscreen.wgsl`); the scene group is its group 1.
pub(crate) fn resolve_wgsl() -> String {
    [
        &crate::bindings::scene_volume_wgsl(1),
        &types_wgsl(),
        include_str!("resolve.wgsl"),
    ]
    .concat()
}

#[derive(Debug)]
struct Buffers {
    heads: wgpu::Buffer,
    nodes: wgpu::Buffer,
    capacity: u32,
    build_group: wgpu::BindGroup,
    resolve_group: wgpu::BindGroup,
}

/// A-buffer resources.
#[derive(Debug)]
pub(crate) struct Reference {
    build: SidedPipeline,
    resolve: wgpu::RenderPipeline,
    build_layout: wgpu::BindGroupLayout,
    resolve_layout: wgpu::BindGroupLayout,
    game_layout: wgpu::BindGroupLayout,
    counters: wgpu::Buffer,
    counters_readback: wgpu::Buffer,
    /// One [`Params`] per tile, at a stride the uniform offset alignment allows.
    params: wgpu::Buffer,
    params_stride: u64,
    buffers: Option<Buffers>,
    backup: Option<wgpu::Texture>,
    size: (u32, u32),
    tiles: u32,
    report: ReferenceReport,
}

impl TechniqueKind for Reference {
    type Key = ();

    fn is_exact(_: Technique) -> bool {
        true
    }

    fn fallback(_: Technique, caps: &Capabilities) -> Option<Technique> {
        crate::ladder::missing(&reference_needs(), caps).map(|_| Technique::PeelReference)
    }

    fn needs(_: Technique, _: &OitConfig, _: &Capabilities) -> Vec<Need> {
        reference_needs()
    }

    fn key(_: Technique, _: &OitConfig, _: &Capabilities) {}

    fn create(setup: &Setup, _: Technique, _: &OitConfig) -> Result<Self> {
        let device = &setup.ctx.device;
        use wgpu::BufferBindingType as B;
        use wgpu::ShaderStages as S;
        let storage = |i, read_only| gpu::buffer_entry(i, S::FRAGMENT, B::Storage { read_only });
        let build_layout = gpu::layout(device, "abuffer_build_layout", &build_entries());
        let resolve_layout = gpu::layout(
            device,
            "abuffer_resolve_layout",
            &[
                storage(0, true),
                storage(1, true),
                storage(2, false),
                params_entry(),
            ],
        );
        let module = gpu::shader(device, "abuffer_build", &[&build_wgsl()]);
        let build = ChunkPipeline {
            label: "abuffer_build",
            module: &module,
            fragment_entry: "fs_abuffer",
            groups: &setup.layouts.with(&[&build_layout]),
            targets: &[],
            depth: DepthMode::ReadOnly,
            samples: 1,
        }
        .build_sided(device);
        let resolve = FullscreenPipeline {
            label: "abuffer_resolve",
            source: &resolve_wgsl(),
            fragment_entry: "fs_resolve",
            groups: &[Some(&resolve_layout), Some(&setup.layouts.scene)],
            targets: &[gpu::scene_target(Some(
                wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING,
            ))],
            writes_depth: false,
            constants: &[],
        }
        .build(device);
        let max_tiles = u64::from(MAX_TILES * MAX_TILES);
        let counters = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("abuffer_counters"),
            size: COUNTERS_BYTES,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let counters_readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("abuffer_counters_readback"),
            size: COUNTERS_BYTES * max_tiles,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let align = u64::from(setup.ctx.caps.limits.min_uniform_buffer_offset_alignment);
        let params_stride = (std::mem::size_of::<Params>() as u64).div_ceil(align) * align;
        let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("abuffer_params"),
            contents: &vec![0; (params_stride * max_tiles) as usize],
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        Ok(Self {
            build,
            resolve,
            build_layout,
            resolve_layout,
            game_layout: game_layout(device, "abuffer_game", &build_entries()),
            counters,
            counters_readback,
            params,
            params_stride,
            buffers: None,
            backup: None,
            size: setup.size,
            tiles: 0,
            report: ReferenceReport::default(),
        })
    }
}

impl Reference {
    fn max_binding(ctx: &GpuContext) -> u64 {
        let l = &ctx.caps.limits;
        l.max_storage_buffer_binding_size.min(l.max_buffer_size)
    }

    /// The largest node pool this adapter can bind.
    fn max_capacity(ctx: &GpuContext) -> u64 {
        (Self::max_binding(ctx) / NODE_BYTES).min(u64::from(u32::MAX))
    }

    /// Tile size for `tiles` per axis.
    fn tile_size(&self, tiles: u32) -> (u32, u32) {
        (self.size.0.div_ceil(tiles), self.size.1.div_ceil(tiles))
    }

    /// The fewest tiles per axis whose head pointers fit one storage binding.
    fn min_tiles(&self, ctx: &GpuContext) -> Result<u32> {
        let max = Self::max_binding(ctx);
        (1..=MAX_TILES)
            .find(|&t| {
                let (w, h) = self.tile_size(t);
                u64::from(w) * u64::from(h) * 4 <= max
            })
            .ok_or_else(|| Error::TooLarge {
                what: format!(
                    "A-buffer head pointers for {}x{} pixels in {MAX_TILES}x{MAX_TILES} tiles (bytes)",
                    self.size.0, self.size.1
                ),
                value: u64::from(self.tile_size(MAX_TILES).0)
                    * u64::from(self.tile_size(MAX_TILES).1)
                    * 4,
                limit_name: "max_storage_buffer_binding_size",
                limit: max,
            })
    }

    /// (Re)creates the head pointers for the current tiling and a pool of `capacity` nodes.
    fn allocate(&mut self, ctx: &GpuContext, frame: &TranslucentFrame<'_>, capacity: u32) {
        let device = &ctx.device;
        let (tw, th) = self.tile_size(self.tiles);
        let heads = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("abuffer_heads"),
            size: u64::from(tw) * u64::from(th) * 4,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let nodes = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("abuffer_nodes"),
            size: u64::from(capacity) * NODE_BYTES,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let params = wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &self.params,
            offset: 0,
            size: wgpu::BufferSize::new(std::mem::size_of::<Params>() as u64),
        });
        let common = [
            heads.as_entire_binding(),
            nodes.as_entire_binding(),
            self.counters.as_entire_binding(),
            params,
        ];
        let mut build = common.to_vec();
        build.push(wgpu::BindingResource::TextureView(&frame.depth.view));
        let build_group = gpu::bind_group(device, "abuffer_build", &self.build_layout, &build);
        let resolve_group =
            gpu::bind_group(device, "abuffer_resolve", &self.resolve_layout, &common);
        self.buffers = Some(Buffers {
            heads,
            nodes,
            capacity,
            build_group,
            resolve_group,
        });
    }

    /// Records one attempt with the current pool and tiling; returns the number of tiles.
    fn record(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        frame: &TranslucentFrame<'_>,
    ) -> Result<u32> {
        let Some(b) = &self.buffers else { return Ok(0) };
        let game = frame.game.map(|g| {
            let own = [
                b.heads.as_entire_binding(),
                b.nodes.as_entire_binding(),
                self.counters.as_entire_binding(),
                wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &self.params,
                    offset: 0,
                    size: wgpu::BufferSize::new(std::mem::size_of::<Params>() as u64),
                }),
                wgpu::BindingResource::TextureView(&frame.depth.view),
            ];
            (
                g,
                game_group(&ctx.device, "abuffer_game", &self.game_layout, g, &own),
            )
        });
        let (width, height) = self.size;
        let (tw, th) = self.tile_size(self.tiles);
        // The tiles in order, and each one's parameters in the encoder before the first
        // (where a frame recorded earlier, not yet submitted, cannot see them).
        let tiles: Vec<(u32, u32)> = (0..self.tiles)
            .flat_map(|ty| (0..self.tiles).map(move |tx| (tx * tw, ty * th)))
            .filter(|&(x, y)| x < width && y < height)
            .collect();
        let mut writes = FrameWrites::default();
        for (k, &(x, y)) in tiles.iter().enumerate() {
            let params = Params {
                origin: [x, y],
                tile_width: tw,
                capacity: b.capacity,
            };
            let offset = k as u64 * self.params_stride;
            writes.write(&self.params, offset, bytemuck::bytes_of(&params));
        }
        writes.record(&ctx.device, encoder)?;
        let mut k = 0u32;
        for &(x, y) in &tiles {
            let (w, h) = (tw.min(width - x), th.min(height - y));
            let offset = u64::from(k) * self.params_stride;
            let dynamic = [offset as u32];
            encoder.clear_buffer(&b.heads, 0, None);
            encoder.clear_buffer(&self.counters, 0, None);
            Pass {
                colors: &[],
                ..Pass::new("abuffer_build", GpuPass::Translucent, &[])
            }
            .depth(Depth::ReadOnly(&frame.depth.view))
            .record(encoder, frame.timer, |pass| {
                pass.set_scissor_rect(x, y, w, h);
                // Volumes: the faces where the ray leaves them (seen from behind) too.
                pass.set_pipeline(self.build.get(frame.two_sided || frame.volumes));
                pass.set_bind_group(2, &b.build_group, &dynamic);
                frame.draw_chunks(pass);
                if let Some((g, group)) = &game {
                    g.draw_offsets(pass, 0, group, &dynamic, 0..g.objects);
                }
            });
            let colors = [gpu::load(&frame.target.view)];
            Pass::new("abuffer_resolve", GpuPass::Composite, &colors).record(
                encoder,
                frame.timer,
                |pass| {
                    pass.set_scissor_rect(x, y, w, h);
                    pass.set_pipeline(&self.resolve);
                    pass.set_bind_group(0, &b.resolve_group, &dynamic);
                    pass.set_bind_group(1, frame.scene, &[]);
                    pass.draw_full_screen();
                },
            );
            encoder.copy_buffer_to_buffer(
                &self.counters,
                0,
                &self.counters_readback,
                COUNTERS_BYTES * u64::from(k),
                COUNTERS_BYTES,
            );
            k += 1;
        }
        Ok(k)
    }

    /// Sums the counters of `tiles` tiles: (lost nodes, most nodes one tile asked for,
    /// capped, capped visibly).
    fn read_counters(&self, ctx: &GpuContext, tiles: u32) -> Result<(u64, u64, u64, u64)> {
        let bytes = readback::map_read(ctx, &self.counters_readback)?;
        let all: &[Counters] = bytemuck::try_cast_slice(&bytes)
            .map_err(|e| Error::ReadbackData(format!("A-buffer counters: {e}")))?;
        let counts = all.get(..tiles as usize).ok_or_else(|| {
            Error::ReadbackData(format!(
                "A-buffer counters: {} tiles read back, {tiles} drawn",
                all.len()
            ))
        })?;
        let capacity = u64::from(self.buffers.as_ref().map_or(0, |b| b.capacity));
        let mut sums = (0, 0, 0, 0);
        for c in counts {
            let nodes = u64::from(c.nodes);
            sums.0 += nodes.saturating_sub(capacity);
            sums.1 = sums.1.max(nodes);
            sums.2 += u64::from(c.capped);
            sums.3 += u64::from(c.capped_visible);
        }
        Ok(sums)
    }
}

impl TranslucentTechnique for Reference {
    fn variants(&self) -> Vec<TranslucentVariant> {
        let own = types_wgsl() + include_str!("abuffer.wgsl");
        vec![TranslucentVariant {
            name: "abuffer_build",
            wgsl: game_prelude(
                &own,
                "// The pass has no colour target: the output goes nowhere.\n\
                 struct OitOutput {\n    @location(0) unused: vec4<f32>,\n};\n\n\
                 // Appends the fragment to its pixel's list, at the depth the exact methods\n\
                 // give an object. Call it in uniform control flow (it takes the depth's\n\
                 // derivatives).\n\
                 fn oit_output(position: vec4<f32>, color: vec4<f32>) -> OitOutput {\n    \
                 let p = oit_object_position(position);\n    \
                 abuffer_append(p, vec2<f32>(dpdx(p.z), dpdy(p.z)), color, ABUFFER_OBJECT, false);\n    \
                 return OitOutput(vec4<f32>(0.0));\n}\n",
            ),
            targets: Vec::new(),
            depth_stencil: gpu::depth_state(DepthMode::ReadOnly),
            layout: self.game_layout.clone(),
        }]
    }

    fn resize(&mut self, _ctx: &GpuContext, width: u32, height: u32) -> Result<()> {
        self.size = (width, height);
        self.buffers = None;
        self.backup = None;
        self.tiles = 0;
        Ok(())
    }

    fn render(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        frame: &TranslucentFrame<'_>,
    ) -> Result<()> {
        let max = Self::max_capacity(ctx);
        let min_tiles = self.min_tiles(ctx)?;
        if self.buffers.is_none() || self.tiles < min_tiles {
            self.tiles = self.tiles.max(min_tiles);
            let (tw, th) = self.tile_size(self.tiles);
            let pixels = u64::from(tw) * u64::from(th);
            self.allocate(
                ctx,
                frame,
                (pixels * INITIAL_NODES_PER_PIXEL).clamp(1024, max) as u32,
            );
        }
        let backup = self
            .backup
            .get_or_insert_with(|| {
                ctx.device.create_texture(&wgpu::TextureDescriptor {
                    label: Some("abuffer_opaque_backup"),
                    size: frame.target.texture.size(),
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: frame.target.texture.format(),
                    usage: wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::COPY_DST,
                    view_formats: &[],
                })
            })
            .clone();
        // Keep the opaque image, in case the frame has to be redone.
        let scene = &frame.target.texture;
        encoder.copy_texture_to_texture(
            scene.as_image_copy(),
            backup.as_image_copy(),
            backup.size(),
        );
        let mut attempts = 0;
        loop {
            attempts += 1;
            let tiles_recorded = self.record(ctx, encoder, frame)?;
            gpu::flush(ctx, encoder)?;
            let (lost, needed, capped, capped_visible) = self.read_counters(ctx, tiles_recorded)?;
            let capacity = self.buffers.as_ref().map_or(0, |b| u64::from(b.capacity));
            let give_up = capacity >= max && self.tiles >= MAX_TILES;
            if lost == 0 || give_up {
                if lost > 0 {
                    log::warn!(
                        "A-buffer: {lost} fragments lost even with {0}x{0} tiles",
                        self.tiles
                    );
                }
                self.report = ReferenceReport {
                    attempts,
                    tiles: self.tiles,
                    lost_fragments: lost,
                    capped_pixels: capped,
                    capped_visible_pixels: capped_visible,
                };
                return Ok(());
            }
            // Redo the frame from the opaque image with more room.
            encoder.copy_texture_to_texture(
                backup.as_image_copy(),
                scene.as_image_copy(),
                backup.size(),
            );
            if capacity < max {
                self.allocate(ctx, frame, needed.next_power_of_two().min(max) as u32);
            } else {
                self.tiles = (self.tiles * 2).min(MAX_TILES);
                self.allocate(ctx, frame, capacity as u32);
            }
        }
    }

    fn report(&self) -> TechniqueReport {
        TechniqueReport {
            reference: Some(self.report),
            ..TechniqueReport::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wgsl_layout::{assert_layout, field, parse};

    #[test]
    fn shared_structs_match_their_wgsl() {
        let build = parse(&build_wgsl());
        assert_layout::<Node>(
            &build,
            "Node",
            &[
                field!(Node, color),
                field!(Node, depth),
                field!(Node, next),
                field!(Node, slope),
                field!(Node, info),
                field!(Node, _pad),
            ],
        );
        assert_layout::<Counters>(
            &build,
            "Counters",
            &[
                field!(Counters, nodes),
                field!(Counters, capped),
                field!(Counters, capped_visible),
                field!(Counters, _pad),
            ],
        );
        assert_layout::<Params>(
            &build,
            "Params",
            &[
                field!(Params, origin),
                field!(Params, tile_width),
                field!(Params, capacity),
            ],
        );
    }
}
