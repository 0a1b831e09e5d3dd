//! The renderer a game embeds: chunks on the GPU and the passes of a frame in seed 000's
//! order: opaque (optional 4× MSAA, resolved), cutout, translucent (the selected technique,
//! depth-tested read-only against the opaque depth), composite over the opaque colour,
//! tonemap to the output format.

use std::collections::HashMap;
use std::time::Instant;

use voxel_core::{BlockRegistry, ChunkPos};
use voxel_mesh::ChunkMeshes;
use wgpu::util::DeviceExt;

use crate::chunks::{ChunkStore, Frustum, MeshKind};
use crate::gpu_types::{FrameUniforms, OPTICAL_DEPTH_VEC4S};
use crate::layers;
use crate::oit::{OitConfig, OitManager, Technique, TranslucentFrame, WeightFit, WeightFunction};
use crate::pipelines::{
    self, COMMON_WGSL, DepthMode, SharedLayouts, load_attachment, texture_entry,
};
use crate::textures::BlockTextures;
use crate::timing::GpuTimer;
use crate::{Camera, DEPTH_FORMAT, GpuContext, Result, SCENE_FORMAT};

/// Settings of a [`Renderer`]. Every field has a reasoned default.
#[derive(Clone, Debug, PartialEq)]
pub struct RendererConfig {
    /// Output width in pixels. Zero is raised to 1 (a renderer always has targets).
    pub width: u32,
    /// Output height in pixels. Zero is raised to 1.
    pub height: u32,
    /// Format of the textures `render` draws into. Default `Rgba8UnormSrgb`, what
    /// offscreen readback and PNG files want; a window passes its surface format.
    pub output_format: wgpu::TextureFormat,
    /// 4× MSAA for the opaque and cutout passes. Default off: the translucent pass is
    /// single-sampled anyway (seed 000) and lavapipe pays 4× for it.
    pub msaa: bool,
    /// Transparency settings (technique, weight, ...). Its size follows `width`/`height`.
    pub oit: OitConfig,
    /// Direction towards the sun (normalised on use). Default: high in the south-east, so
    /// that every face direction gets a different brightness.
    pub sun_dir: [f32; 3],
    /// Ambient share of the lighting. Default 0.45: faces away from the sun stay readable.
    pub ambient: f32,
    /// Sky colour (linear). Default a light blue.
    pub sky: [f32; 3],
    /// Frames over which a newly uploaded chunk fades in (screen-door dissolve of its
    /// opaque and cutout faces, alpha ramp of its translucent ones). Default 0: off, so
    /// that a picture depends only on the scene; the interactive demo turns it on.
    pub fade_in_frames: u32,
}

impl Default for RendererConfig {
    fn default() -> Self {
        Self {
            width: 1280,
            height: 720,
            output_format: wgpu::TextureFormat::Rgba8UnormSrgb,
            msaa: false,
            oit: OitConfig::default(),
            sun_dir: [0.35, 0.85, 0.4],
            ambient: 0.45,
            sky: [0.45, 0.65, 0.9],
            fade_in_frames: 0,
        }
    }
}

/// What a frame drew.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrameStats {
    /// Chunk meshes drawn: opaque, cutout, translucent.
    pub meshes_drawn: [usize; 3],
    /// Translucent quads drawn.
    pub translucent_quads: usize,
    /// CPU time spent recording the frame, milliseconds (sorting included).
    pub cpu_ms: f64,
    /// CPU time spent sorting translucent quads (sorted-quads), milliseconds.
    pub sort_ms: f64,
    /// Chunks whose translucent quads were re-sorted this frame.
    pub chunks_resorted: usize,
    /// Technique-specific facts (peeled layers, reference overflow).
    pub technique: crate::oit::TechniqueReport,
    /// What the fitted WBOIT weight was fitted to: the view depths the visible translucent
    /// meshes span and, per screen tile, the optical depth in front of depths across them
    /// (no table when the frame does not use the fitted weight).
    pub weight_fit: WeightFit,
}

#[derive(Debug)]
struct SceneTargets {
    width: u32,
    height: u32,
    color: wgpu::Texture,
    color_view: wgpu::TextureView,
    depth: wgpu::Texture,
    depth_view: wgpu::TextureView,
    msaa: Option<(wgpu::TextureView, wgpu::TextureView)>,
    tonemap_group: wgpu::BindGroup,
    depth_resolve_group: Option<wgpu::BindGroup>,
}

const MSAA_SAMPLES: u32 = 4;

/// Draws a voxel world. See the module docs for the passes.
#[derive(Debug)]
pub struct Renderer {
    ctx: GpuContext,
    config: RendererConfig,
    layouts: SharedLayouts,
    frame_buffer: wgpu::Buffer,
    scene_group: wgpu::BindGroup,
    chunks: ChunkStore,
    opaque: wgpu::RenderPipeline,
    cutout: wgpu::RenderPipeline,
    tonemap_layout: wgpu::BindGroupLayout,
    tonemap: HashMap<wgpu::TextureFormat, wgpu::RenderPipeline>,
    depth_resolve: (wgpu::BindGroupLayout, wgpu::RenderPipeline),
    targets: SceneTargets,
    oit: OitManager,
    timer: Option<GpuTimer>,
    frame_index: u32,
    /// Chunks fading in, with the frame they appeared.
    fading: HashMap<ChunkPos, u32>,
    /// Sorted-quads: the eye each chunk's translucent quads were last sorted for.
    sorted_for: HashMap<ChunkPos, glam::DVec3>,
}

/// Most timed passes in a frame: peeling to convergence can take many.
const MAX_TIMED_PASSES: u32 = 160;

impl Renderer {
    /// A renderer for the blocks of `registry`. Falls back (with a log line) where the
    /// adapter lacks something: MSAA off without 4× support.
    pub fn new(
        ctx: &GpuContext,
        registry: &BlockRegistry,
        mut config: RendererConfig,
    ) -> Result<Self> {
        config.width = config.width.max(1);
        config.height = config.height.max(1);
        if config.msaa && !ctx.caps.msaa4 {
            log::warn!("4x MSAA is not supported for the scene formats: rendering without MSAA");
            config.msaa = false;
        }
        let device = &ctx.device;
        let layouts = SharedLayouts::new(device);
        let textures = BlockTextures::new(ctx, registry)?;
        let frame_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("frame_uniforms"),
            contents: bytemuck::bytes_of(&<FrameUniforms as bytemuck::Zeroable>::zeroed()),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        let bayer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("bayer_levels"),
            contents: bytemuck::cast_slice(&crate::oit::stipple::bayer::bayer_levels()),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let scene_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("scene"),
            layout: &layouts.scene,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: frame_buffer.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&textures.view),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::Sampler(&textures.sampler),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: bayer.as_entire_binding(),
                },
            ],
        });

        let (opaque, cutout) = Self::opaque_pipelines(ctx, &layouts, config.msaa);
        let tonemap_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("tonemap_layout"),
            entries: &[texture_entry(
                0,
                wgpu::TextureSampleType::Float { filterable: false },
            )],
        });
        let depth_resolve_layout =
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("depth_resolve_layout"),
                entries: &[wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Depth,
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: true,
                    },
                    count: None,
                }],
            });
        let depth_resolve = pipelines::fullscreen_pipeline(
            device,
            "depth_resolve",
            include_str!("shaders/depth_resolve.wgsl"),
            "fs_depth_resolve",
            &[Some(&depth_resolve_layout)],
            &[],
            true,
            &[],
        );
        let mut oit_config = config.oit.clone();
        oit_config.width = config.width;
        oit_config.height = config.height;
        let oit = OitManager::new(ctx, &layouts, oit_config);
        let targets = Self::targets(
            ctx,
            &tonemap_layout,
            &depth_resolve_layout,
            config.width,
            config.height,
            config.msaa,
        );
        Ok(Self {
            ctx: ctx.clone(),
            chunks: ChunkStore::new(
                layouts.chunk.clone(),
                registry.iter().map(|(_, def)| def.opacity).collect(),
            ),
            layouts,
            frame_buffer,
            scene_group,
            opaque,
            cutout,
            tonemap_layout,
            tonemap: HashMap::new(),
            depth_resolve: (depth_resolve_layout, depth_resolve),
            targets,
            oit,
            timer: GpuTimer::new(ctx, MAX_TIMED_PASSES),
            frame_index: 0,
            fading: HashMap::new(),
            sorted_for: HashMap::new(),
            config,
        })
    }

    fn opaque_pipelines(
        ctx: &GpuContext,
        layouts: &SharedLayouts,
        msaa: bool,
    ) -> (wgpu::RenderPipeline, wgpu::RenderPipeline) {
        let module = pipelines::shader(
            &ctx.device,
            "opaque",
            &[
                COMMON_WGSL,
                crate::oit::stipple::DITHER_WGSL,
                include_str!("shaders/opaque.wgsl"),
            ],
        );

        let samples = if msaa { MSAA_SAMPLES } else { 1 };
        let groups = [Some(&layouts.scene), Some(&layouts.chunk)];
        let make = |label, entry| {
            pipelines::chunk_pipeline(
                &ctx.device,
                label,
                &module,
                entry,
                &groups,
                &[pipelines::scene_target(None)],
                DepthMode::Write,
                samples,
            )
        };
        (make("opaque", "fs_opaque"), make("cutout", "fs_cutout"))
    }

    fn targets(
        ctx: &GpuContext,
        tonemap_layout: &wgpu::BindGroupLayout,
        depth_resolve_layout: &wgpu::BindGroupLayout,
        width: u32,
        height: u32,
        msaa: bool,
    ) -> SceneTargets {
        use wgpu::TextureUsages as U;
        let target = |label, format, samples, usage| {
            pipelines::multisampled_target(
                &ctx.device,
                label,
                format,
                usage,
                width,
                height,
                samples,
            )
        };
        let (color, color_view) = target(
            "scene_color",
            SCENE_FORMAT,
            1,
            U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC | U::COPY_DST,
        );
        let (depth, depth_view) = target(
            "scene_depth",
            DEPTH_FORMAT,
            1,
            U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC,
        );
        let msaa_views = msaa.then(|| {
            let (_, c) = target(
                "scene_color_msaa",
                SCENE_FORMAT,
                MSAA_SAMPLES,
                U::RENDER_ATTACHMENT,
            );
            let (_, d) = target(
                "scene_depth_msaa",
                DEPTH_FORMAT,
                MSAA_SAMPLES,
                U::RENDER_ATTACHMENT | U::TEXTURE_BINDING,
            );
            (c, d)
        });
        let tonemap_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("tonemap"),
            layout: tonemap_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(&color_view),
            }],
        });
        let depth_resolve_group = msaa_views.as_ref().map(|(_, d)| {
            ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("depth_resolve"),
                layout: depth_resolve_layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(d),
                }],
            })
        });
        SceneTargets {
            width,
            height,
            color,
            color_view,
            depth,
            depth_view,
            msaa: msaa_views,
            tonemap_group,
            depth_resolve_group,
        }
    }

    /// The GPU context.
    pub fn context(&self) -> &GpuContext {
        &self.ctx
    }

    /// The configuration in force (after fallbacks).
    pub fn config(&self) -> &RendererConfig {
        &self.config
    }

    /// Output size in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.targets.width, self.targets.height)
    }

    /// Uploads or replaces a chunk's meshes; empty meshes remove it. A chunk that was not
    /// on the GPU fades in when [`RendererConfig::fade_in_frames`] is set.
    pub fn upload_chunk(&mut self, pos: ChunkPos, meshes: &ChunkMeshes) {
        let new = self.chunks.get(pos).is_none();
        self.chunks.upload(&self.ctx, pos, meshes);
        self.sorted_for.remove(&pos);
        if new && self.config.fade_in_frames > 0 && self.chunks.get(pos).is_some() {
            self.fading.insert(pos, self.frame_index);
            self.chunks.set_alpha(&self.ctx, pos, 0.0);
        }
    }

    /// Removes a chunk from the GPU.
    pub fn remove_chunk(&mut self, pos: ChunkPos) {
        self.chunks.remove(pos);
        self.fading.remove(&pos);
        self.sorted_for.remove(&pos);
    }

    /// Removes every chunk.
    pub fn clear_chunks(&mut self) {
        self.chunks.clear();
        self.fading.clear();
        self.sorted_for.clear();
    }

    /// Changes the transparency settings (technique, weight, Bayer size, peel layers, ...).
    pub fn set_oit_config(&mut self, config: OitConfig) {
        self.oit.set_config(config);
    }

    /// Changes how many frames new chunks take to fade in (0: no fade).
    pub fn set_fade_in_frames(&mut self, frames: u32) {
        self.config.fade_in_frames = frames;
        if frames == 0 {
            for (pos, _) in self.fading.drain() {
                self.chunks.set_alpha(&self.ctx, pos, 1.0);
            }
        }
    }

    /// The chunks on the GPU.
    pub fn chunks(&self) -> &ChunkStore {
        &self.chunks
    }

    /// The transparency manager.
    pub fn oit(&self) -> &OitManager {
        &self.oit
    }

    /// Switches the transparency technique.
    pub fn set_technique(&mut self, technique: Technique) {
        self.oit.set_technique(technique);
    }

    /// Changes the WBOIT weight function.
    pub fn set_weight(&mut self, weight: WeightFunction) {
        self.oit.set_weight(weight);
    }

    /// Turns 4× MSAA on or off (rebuilds the opaque pipelines and targets).
    pub fn set_msaa(&mut self, msaa: bool) {
        let msaa = msaa && self.ctx.caps.msaa4;
        if msaa == self.config.msaa {
            return;
        }
        self.config.msaa = msaa;
        (self.opaque, self.cutout) = Self::opaque_pipelines(&self.ctx, &self.layouts, msaa);
        self.targets = Self::targets(
            &self.ctx,
            &self.tonemap_layout,
            &self.depth_resolve.0,
            self.targets.width,
            self.targets.height,
            msaa,
        );
    }

    /// Resizes every target. The same size does nothing; a zero width or height (a
    /// minimised window) does nothing either and keeps the old targets.
    pub fn resize(&mut self, width: u32, height: u32) {
        if width == 0 || height == 0 || (width, height) == self.size() {
            return;
        }
        self.config.width = width;
        self.config.height = height;
        self.targets = Self::targets(
            &self.ctx,
            &self.tonemap_layout,
            &self.depth_resolve.0,
            width,
            height,
            self.config.msaa,
        );
        self.oit.resize(width, height);
    }

    /// GPU milliseconds per pass label of the latest timed frame, if timestamps work.
    pub fn gpu_times(&mut self) -> Vec<(&'static str, f64)> {
        self.timer
            .as_mut()
            .map(|t| t.poll().to_vec())
            .unwrap_or_default()
    }

    /// Like [`Renderer::gpu_times`], but waits for the last submitted frame's results.
    pub fn gpu_times_blocking(&mut self) -> Vec<(&'static str, f64)> {
        let ctx = self.ctx.clone();
        self.timer
            .as_mut()
            .map(|t| t.read_blocking(&ctx))
            .unwrap_or_default()
    }

    /// Call after submitting a frame's encoder: starts reading its GPU timings (and the
    /// technique's own counters) back.
    pub fn after_submit(&mut self) {
        if let Some(t) = &mut self.timer {
            t.after_submit();
        }
        self.oit.after_submit();
    }

    /// Advances chunk fade-ins by one frame.
    fn update_fades(&mut self) {
        let frames = self.config.fade_in_frames.max(1);
        let now = self.frame_index;
        let mut done = Vec::new();
        for (&pos, &start) in &self.fading {
            let t = now.wrapping_sub(start) as f32 / frames as f32;
            self.chunks.set_alpha(&self.ctx, pos, t.min(1.0));
            if t >= 1.0 {
                done.push(pos);
            }
        }
        for pos in done {
            self.fading.remove(&pos);
        }
    }

    /// Sorted-quads: re-sorts the translucent quads of the visible chunks whose last sort
    /// was for an eye farther than [`OitConfig::resort_distance`] away. Returns (ms, chunks).
    fn sort_quads(&mut self, positions: &[ChunkPos], eye: glam::DVec3) -> (f64, usize) {
        let start = Instant::now();
        let threshold = self.oit.config().resort_distance;
        let mut n = 0;
        for &pos in positions {
            if self
                .sorted_for
                .get(&pos)
                .is_some_and(|e| e.distance(eye) <= threshold)
            {
                continue;
            }
            let Some(chunk) = self.chunks.get(pos) else {
                continue;
            };
            let mut quads = chunk.translucent_quads().to_vec();
            let o = pos.origin();
            let local = eye - glam::DVec3::new(o[0] as f64, o[1] as f64, o[2] as f64);
            voxel_mesh::sort::quads_back_to_front(&mut quads, local.as_vec3().to_array());
            self.chunks.reorder_translucent(&self.ctx, pos, quads);
            self.sorted_for.insert(pos, eye);
            n += 1;
        }
        (start.elapsed().as_secs_f64() * 1e3, n)
    }

    /// The HDR scene colour (after the composite, before tonemapping).
    pub fn scene_color(&self) -> &wgpu::Texture {
        &self.targets.color
    }

    /// The single-sample scene depth (reverse-Z).
    pub fn scene_depth(&self) -> &wgpu::Texture {
        &self.targets.depth
    }

    fn tonemap_pipeline(&mut self, format: wgpu::TextureFormat) -> &wgpu::RenderPipeline {
        let (ctx, layout) = (&self.ctx, &self.tonemap_layout);
        self.tonemap.entry(format).or_insert_with(|| {
            let encode = if format.is_srgb() { 0.0 } else { 1.0 };
            pipelines::fullscreen_pipeline(
                &ctx.device,
                "tonemap",
                include_str!("shaders/tonemap.wgsl"),
                "fs_tonemap",
                &[Some(layout)],
                &[Some(wgpu::ColorTargetState {
                    format,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
                false,
                &[("SRGB_ENCODE", encode)],
            )
        })
    }

    /// Records a frame into `encoder`, ending with the tonemap into `output` (a view of a
    /// texture of [`RendererConfig::output_format`] and of the renderer's size). Fails on
    /// an invalid camera (NaN, zero direction, bad planes) without recording anything.
    pub fn render(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        output: &wgpu::TextureView,
        camera: &Camera,
    ) -> Result<FrameStats> {
        camera.validate()?;
        let start = Instant::now();
        let format = self.config.output_format;
        self.tonemap_pipeline(format);
        self.update_fades();
        let (w, h) = self.size();
        let view_proj = camera.view_proj(f64::from(w) / f64::from(h));
        let frustum = Frustum::new(view_proj, camera.eye);
        let (sort_ms, chunks_resorted) = if self.oit.technique() == Technique::SortedQuads {
            let positions: Vec<ChunkPos> = self
                .chunks
                .visible(MeshKind::Translucent, &frustum)
                .iter()
                .map(|v| v.pos)
                .collect();
            self.sort_quads(&positions, camera.eye)
        } else {
            (0.0, 0)
        };
        let opaque = self.chunks.visible(MeshKind::Opaque, &frustum);
        let cutout = self.chunks.visible(MeshKind::Cutout, &frustum);
        let mut translucent = self.chunks.visible(MeshKind::Translucent, &frustum);
        translucent.reverse();
        // Only the fitted WBOIT weight needs the estimate of the layers in view.
        let (near, far) = (camera.near as f32, camera.far as f32);
        let fitted = matches!(
            self.oit.technique(),
            Technique::WboitMrt | Technique::WboitTwoPass
        ) && self.oit.config().weight == WeightFunction::Fitted;
        let weight_fit = if fitted {
            layers::fit(
                translucent.iter().map(|v| v.mesh.layers()),
                view_proj,
                camera.eye,
                near,
                far,
            )
        } else {
            WeightFit {
                range: [near, far],
                optical_depth: Vec::new(),
            }
        };
        let depth_range = weight_fit.range;
        let mut optical_depth = [[0.0; 4]; OPTICAL_DEPTH_VEC4S];
        let flat: &mut [f32] = bytemuck::cast_slice_mut(&mut optical_depth);
        let n = weight_fit.optical_depth.len().min(flat.len());
        flat[..n].copy_from_slice(&weight_fit.optical_depth[..n]);
        let stats = FrameStats {
            meshes_drawn: [opaque.len(), cutout.len(), translucent.len()],
            translucent_quads: translucent.iter().map(|v| v.mesh.quads() as usize).sum(),
            sort_ms,
            chunks_resorted,
            weight_fit,
            ..FrameStats::default()
        };

        let (eye_int, eye_frac) = camera.eye_split();
        let sun = glam::Vec3::from(self.config.sun_dir).normalize_or(glam::Vec3::Y);

        let oit_config = self.oit.config();
        let uniforms = FrameUniforms {
            view_proj: view_proj.to_cols_array_2d(),
            eye_int: eye_int.map(|v| v.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32),
            fov_y: camera.fov_y_deg.to_radians() as f32,
            eye_frac: eye_frac.to_array(),
            near: camera.near as f32,
            sun_dir: sun.to_array(),
            ambient: self.config.ambient,
            sky: self.config.sky,
            far: camera.far as f32,
            viewport: [w as f32, h as f32],
            weight_fn: oit_config.weight as u32,
            accum_scale: self.oit.accum_scale(),
            shading_state: oit_config.shading_state().pack(),
            frame_index: self.frame_index,
            depth_range,
            optical_depth,
        };
        self.frame_index = self.frame_index.wrapping_add(1);
        self.ctx
            .queue
            .write_buffer(&self.frame_buffer, 0, bytemuck::bytes_of(&uniforms));
        if let Some(t) = &mut self.timer {
            t.begin_frame();
        }

        let t = &self.targets;
        let sky = self.config.sky.map(f64::from);
        let sky = wgpu::Color {
            r: sky[0],
            g: sky[1],
            b: sky[2],
            a: 1.0,
        };
        let (color_view, depth_view, resolve) = match &t.msaa {
            Some((c, d)) => (c, d, Some(&t.color_view)),
            None => (&t.color_view, &t.depth_view, None),
        };
        // Opaque, then cutout; with MSAA the colour resolves at the end of the last one.
        for (kind, pipeline, list) in [
            (MeshKind::Opaque, &self.opaque, &opaque),
            (MeshKind::Cutout, &self.cutout, &cutout),
        ] {
            let first = kind == MeshKind::Opaque;
            if !first && list.is_empty() {
                continue;
            }
            let last = !first || cutout.is_empty();
            let label = if first { "opaque" } else { "cutout" };
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some(label),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: color_view,
                    depth_slice: None,
                    resolve_target: if last { resolve } else { None },
                    ops: wgpu::Operations {
                        load: if first {
                            wgpu::LoadOp::Clear(sky)
                        } else {
                            wgpu::LoadOp::Load
                        },
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: depth_view,
                    depth_ops: Some(wgpu::Operations {
                        // Reverse-Z: clear to 0, the far plane.
                        load: if first {
                            wgpu::LoadOp::Clear(0.0)
                        } else {
                            wgpu::LoadOp::Load
                        },
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: self.timer.as_mut().and_then(|t| t.pass(label)),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &self.scene_group, &[]);
            for v in list {
                v.mesh.draw(&mut pass);
            }
        }
        if let Some(group) = &t.depth_resolve_group {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("depth_resolve"),
                color_attachments: &[],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &t.depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(0.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: self.timer.as_mut().and_then(|t| t.pass("opaque")),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.depth_resolve.1);
            pass.set_bind_group(0, group, &[]);
            pass.draw(0..3, 0..1);
        }

        let mut frame = TranslucentFrame {
            target: &t.color_view,
            target_texture: &t.color,
            depth: &t.depth_view,
            depth_texture: &t.depth,
            scene: &self.scene_group,
            chunks: &translucent,
            timer: self.timer.as_mut(),
        };
        self.oit.render(encoder, &mut frame);

        let pipeline = &self.tonemap[&format];
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("tonemap"),
            color_attachments: &[load_attachment(output)],
            depth_stencil_attachment: None,
            timestamp_writes: self.timer.as_mut().and_then(|t| t.pass("tonemap")),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &t.tonemap_group, &[]);
        pass.draw(0..3, 0..1);
        drop(pass);
        if let Some(t) = &mut self.timer {
            t.end_frame(encoder);
        }
        Ok(FrameStats {
            cpu_ms: start.elapsed().as_secs_f64() * 1e3,
            technique: self.oit.report(),
            ..stats
        })
    }

    /// Renders one frame into `output` and submits it (for tools and tests).
    pub fn render_and_submit(
        &mut self,
        output: &wgpu::TextureView,
        camera: &Camera,
    ) -> Result<FrameStats> {
        let mut encoder = self
            .ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("frame"),
            });
        let stats = self.render(&mut encoder, output, camera)?;
        self.ctx.queue.submit([encoder.finish()]);
        self.after_submit();
        Ok(stats)
    }
}
