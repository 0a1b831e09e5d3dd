//! The exact reference: per-pixel fragment lists (an A-buffer) sorted per pixel and
//! blended in depth order. Every other technique is measured against it.
//!
//! Pass 1 appends each translucent fragment in front of the opaque depth to its pixel's
//! list (a storage buffer of nodes, an atomic head pointer per pixel; needs fragment
//! shaders that write storage, `DownlevelFlags::FRAGMENT_WRITABLE_STORAGE`). Pass 2 sorts
//! each list (up to 128 fragments a pixel) and blends it front to back over the opaque
//! image.
//!
//! Overflow is counted and reported, never silent. The node pool starts at four nodes a
//! pixel; after each frame the counters are read back (a stall: this is a measurement
//! tool), and if nodes ran out the frame is redone with a pool twice as large, up to the
//! adapter's largest storage binding, then in 2×2, 4×4, ... screen tiles (each tile
//! re-draws the geometry and reuses the pool), up to 16×16. What still does not fit, and
//! pixels with more than 128 fragments, are reported in [`TechniqueReport::overflow`].

use wgpu::util::DeviceExt;

use crate::oit::{OitConfig, TechniqueReport, TranslucentFrame, TranslucentTechnique};
use crate::pipelines::{self, COMMON_WGSL, DepthMode, SharedLayouts, load_attachment};
use crate::{GpuContext, readback};

/// WGSL of the node, counter and parameter structs both passes share.
const TYPES_WGSL: &str = include_str!("types.wgsl");

/// Bytes per node: colour (4 halves), depth, next.
pub const NODE_BYTES: u64 = 16;
/// Initial pool: nodes per pixel.
pub const INITIAL_NODES_PER_PIXEL: u64 = 4;
/// Most tiles per axis before giving up on fitting a frame.
pub const MAX_TILES: u32 = 16;

#[derive(Debug)]
struct Buffers {
    heads: wgpu::Buffer,
    capacity: u32,
    build_group: wgpu::BindGroup,
    resolve_group: wgpu::BindGroup,
    backup: wgpu::Texture,
}

/// A-buffer resources.
#[derive(Debug)]
pub struct Reference {
    build: wgpu::RenderPipeline,
    resolve: wgpu::RenderPipeline,
    build_layout: wgpu::BindGroupLayout,
    resolve_layout: wgpu::BindGroupLayout,
    counters: wgpu::Buffer,
    counters_readback: wgpu::Buffer,
    params: wgpu::Buffer,
    buffers: Option<Buffers>,
    width: u32,
    height: u32,
    tiles: u32,
    report: TechniqueReport,
}

fn storage_entry(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn uniform_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

impl Reference {
    /// Creates the pipelines; buffers come with the first frame.
    pub fn new(ctx: &GpuContext, layouts: &SharedLayouts, config: &OitConfig) -> Self {
        let device = &ctx.device;
        let build_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("abuffer_build_layout"),
            entries: &[
                storage_entry(0, false),
                storage_entry(1, false),
                storage_entry(2, false),
                uniform_entry(3),
                pipelines::texture_entry(4, wgpu::TextureSampleType::Depth),
            ],
        });
        let resolve_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("abuffer_resolve_layout"),
            entries: &[
                storage_entry(0, true),
                storage_entry(1, true),
                storage_entry(2, false),
                uniform_entry(3),
            ],
        });
        let module = pipelines::shader(
            device,
            "abuffer_build",
            &[COMMON_WGSL, TYPES_WGSL, include_str!("abuffer.wgsl")],
        );
        let build = pipelines::chunk_pipeline(
            device,
            "abuffer_build",
            &module,
            "fs_abuffer",
            &[
                Some(&layouts.scene),
                Some(&layouts.chunk),
                Some(&build_layout),
            ],
            &[],
            DepthMode::ReadOnly,
            1,
        );
        let resolve = pipelines::fullscreen_pipeline(
            device,
            "abuffer_resolve",
            &[TYPES_WGSL, include_str!("resolve.wgsl")].concat(),
            "fs_resolve",
            &[Some(&resolve_layout)],
            &[pipelines::scene_target(Some(
                wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING,
            ))],
            false,
            &[],
        );
        let counters = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("abuffer_counters"),
            size: 8,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let counters_readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("abuffer_counters_readback"),
            size: 8 * u64::from(MAX_TILES * MAX_TILES),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("abuffer_params"),
            contents: bytemuck::cast_slice(&[0u32; 4]),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        Self {
            build,
            resolve,
            build_layout,
            resolve_layout,
            counters,
            counters_readback,
            params,
            buffers: None,
            width: config.width,
            height: config.height,
            tiles: 1,
            report: TechniqueReport::default(),
        }
    }

    /// The largest node pool this adapter can bind.
    fn max_capacity(ctx: &GpuContext) -> u64 {
        let bytes = ctx
            .caps
            .limits
            .max_storage_buffer_binding_size
            .min(ctx.caps.limits.max_buffer_size);
        (bytes / NODE_BYTES).min(u64::from(u32::MAX))
    }

    fn allocate(&mut self, ctx: &GpuContext, frame: &TranslucentFrame<'_>, capacity: u32) {
        let device = &ctx.device;
        let pixels = u64::from(self.width) * u64::from(self.height);
        let heads = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("abuffer_heads"),
            size: pixels * 4,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let nodes = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("abuffer_nodes"),
            size: u64::from(capacity) * NODE_BYTES,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        ctx.queue.write_buffer(
            &self.params,
            0,
            bytemuck::cast_slice(&[self.width, capacity, 0, 0]),
        );
        let entries = |with_depth: bool| {
            let mut e = vec![
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: heads.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: nodes.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: self.counters.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: self.params.as_entire_binding(),
                },
            ];
            if with_depth {
                e.push(wgpu::BindGroupEntry {
                    binding: 4,
                    resource: wgpu::BindingResource::TextureView(frame.depth),
                });
            }
            e
        };
        let build_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("abuffer_build"),
            layout: &self.build_layout,
            entries: &entries(true),
        });
        let resolve_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("abuffer_resolve"),
            layout: &self.resolve_layout,
            entries: &entries(false),
        });
        let backup = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("abuffer_opaque_backup"),
            size: frame.target_texture.size(),
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: frame.target_texture.format(),
            usage: wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        self.buffers = Some(Buffers {
            heads,
            capacity,
            build_group,
            resolve_group,
            backup,
        });
    }

    /// Records one attempt with the current pool and tiling; returns the number of tiles.
    fn record(&self, encoder: &mut wgpu::CommandEncoder, frame: &mut TranslucentFrame<'_>) -> u32 {
        let Some(b) = &self.buffers else { return 0 };
        let tiles = self.tiles;
        let (tw, th) = (self.width.div_ceil(tiles), self.height.div_ceil(tiles));
        let mut k = 0;
        for ty in 0..tiles {
            for tx in 0..tiles {
                let (x, y) = (tx * tw, ty * th);
                if x >= self.width || y >= self.height {
                    continue;
                }
                let (w, h) = (tw.min(self.width - x), th.min(self.height - y));
                encoder.clear_buffer(&b.heads, 0, None);
                encoder.clear_buffer(&self.counters, 0, None);
                {
                    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                        label: Some("abuffer_build"),
                        color_attachments: &[],
                        depth_stencil_attachment: pipelines::read_only_depth(frame.depth),
                        timestamp_writes: frame.timestamps("translucent"),
                        occlusion_query_set: None,
                        multiview_mask: None,
                    });
                    pass.set_scissor_rect(x, y, w, h);
                    pass.set_pipeline(&self.build);
                    pass.set_bind_group(2, &b.build_group, &[]);
                    frame.draw_chunks(&mut pass);
                }
                {
                    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                        label: Some("abuffer_resolve"),
                        color_attachments: &[load_attachment(frame.target)],
                        depth_stencil_attachment: None,
                        timestamp_writes: frame.timestamps("composite"),
                        occlusion_query_set: None,
                        multiview_mask: None,
                    });
                    pass.set_scissor_rect(x, y, w, h);
                    pass.set_pipeline(&self.resolve);
                    pass.set_bind_group(0, &b.resolve_group, &[]);
                    pass.draw(0..3, 0..1);
                }
                encoder.copy_buffer_to_buffer(
                    &self.counters,
                    0,
                    &self.counters_readback,
                    8 * u64::from(k),
                    8,
                );
                k += 1;
            }
        }
        k
    }
}

impl TranslucentTechnique for Reference {
    fn resize(&mut self, _ctx: &GpuContext, width: u32, height: u32) {
        self.width = width;
        self.height = height;
        self.buffers = None;
        self.tiles = 1;
    }

    fn render(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        frame: &mut TranslucentFrame<'_>,
    ) {
        let max = Self::max_capacity(ctx);
        if self.buffers.is_none() {
            let pixels = u64::from(self.width) * u64::from(self.height);
            self.allocate(
                ctx,
                frame,
                (pixels * INITIAL_NODES_PER_PIXEL).clamp(1024, max) as u32,
            );
        }
        let Some(backup) = self.buffers.as_ref().map(|b| b.backup.clone()) else {
            return;
        };
        // Keep the opaque image, in case the frame has to be redone.
        encoder.copy_texture_to_texture(
            frame.target_texture.as_image_copy(),
            backup.as_image_copy(),
            backup.size(),
        );
        let mut attempts = 0;
        loop {
            attempts += 1;
            self.report.attempts = Some(attempts);
            let tiles_recorded = self.record(encoder, frame);

            pipelines::flush(ctx, encoder);
            let counts = readback::map_read(ctx, &self.counters_readback).unwrap_or_default();
            let words: &[u32] = bytemuck::cast_slice(&counts);
            let capacity = self.buffers.as_ref().map_or(0, |b| b.capacity);
            let mut lost = 0u64;
            let mut truncated = 0u64;
            let mut needed = 0u64;
            for t in 0..tiles_recorded as usize {
                let (nodes, trunc) = (u64::from(words[2 * t]), u64::from(words[2 * t + 1]));
                needed = needed.max(nodes);
                lost += nodes.saturating_sub(u64::from(capacity));
                truncated += trunc;
            }
            if lost == 0 {
                self.report.overflow = Some(truncated);
                self.report.layers = None;
                return;
            }
            // Redo the frame from the opaque image with more room.
            encoder.copy_texture_to_texture(
                backup.as_image_copy(),
                frame.target_texture.as_image_copy(),
                backup.size(),
            );
            if u64::from(capacity) < max {
                self.allocate(ctx, frame, needed.next_power_of_two().min(max) as u32);
            } else if self.tiles < MAX_TILES {
                self.tiles *= 2;
            } else {
                self.report.overflow = Some(lost + truncated);
                log::warn!(
                    "A-buffer overflow: {lost} fragments lost even with {0}x{0} tiles",
                    self.tiles
                );
                let _ = self.record(encoder, frame);
                return;
            }
        }
    }

    fn report(&self) -> TechniqueReport {
        self.report
    }
}
