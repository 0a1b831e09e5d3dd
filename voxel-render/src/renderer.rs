//! The renderer a game embeds: chunks on the GPU and the passes of a frame in the usual
//! forward order: opaque (optional 4× MSAA, resolved), cutout, translucent (the selected technique,
//! depth-tested read-only against the opaque depth), composite over the opaque colour,
//! tonemap to the output format.

use std::collections::HashMap;
use std::sync::Arc;
use std::time::Instant;

use glam::Mat4;
use voxel_core::{BlockId, BlockRegistry, ChunkPos};
use voxel_mesh::ChunkMeshes;
use wgpu::util::DeviceExt;

use crate::bindings::{FrameUniforms, NO_MEDIUM, SharedLayouts, common_wgsl};
use crate::chunks::{
    ChunkStore, Culled, DrawBuilder, DrawList, DrawMode, FrameDraws, Frustum, GpuChunk, MeshKind,
    PosMap,
};
use crate::error::scoped;
use crate::fetch::{QuadFetch, TableTexture};
use crate::gpu::{self, ChunkPipeline, Depth, DepthMode, FullscreenPipeline, Pass, Target};
use crate::ladder;
use crate::medium::{self, MediumLook, MediumPass};
use crate::oit::sorted::interleave::{ChunkSequence, Interleaver};
use crate::oit::{
    FrameView, OitConfig, OitManager, Setup, Technique, TechniqueReport, TranslucentFrame,
    WeightFunction,
};
use crate::stages::{GameDraw, GameFrame, GameStages, NoGame, Split, TranslucentContract};
use crate::submission::{Outcome, Submissions};
use crate::textures::BlockTextures;
use crate::timing::{GpuPass, GpuTimes, Timer};
use crate::{Camera, DEPTH_FORMAT, Error, GpuContext, Result, SCENE_FORMAT};

/// Settings of a [`Renderer`]. Every field has a reasoned default.
#[derive(Clone, Debug, PartialEq)]
pub struct RendererConfig {
    /// Output width in pixels. Zero is raised to 1 (a renderer always has targets); more
    /// than the adapter's `max_texture_dimension_2d` is an error.
    pub width: u32,
    /// Output height in pixels, like `width`.
    pub height: u32,
    /// Format of the textures `render` draws into first (its tonemap pipeline is built
    /// with the renderer). Default `Rgba8UnormSrgb`, what offscreen readback and PNG files
    /// want. Any of [`OUTPUT_FORMATS`] works without changing this: an output of another
    /// format gets its tonemap pipeline at its first frame (once per format, about a
    /// millisecond), and this field follows the format drawn last.
    pub output_format: wgpu::TextureFormat,
    /// The format of the views `render` is given, where they differ from their texture's:
    /// the sRGB or linear twin of the texture's format (a surface configured with
    /// `view_formats`). Default `None`: every view has its texture's format, which is
    /// what wgpu gives unless asked otherwise. A view format the texture cannot have is
    /// ignored.
    pub output_view_format: Option<wgpu::TextureFormat>,
    /// 4× MSAA for the opaque and cutout passes. Default off: the translucent pass is
    /// single-sampled anyway and lavapipe pays 4× for it.
    pub msaa: bool,
    /// Transparency settings (technique and each technique's own settings).
    pub oit: OitConfig,
    /// Direction towards the sun (normalised on use; a zero vector means straight up).
    /// Default: high in the south-east, so that every face direction gets a different
    /// brightness. NaN or infinite components are an error at [`Renderer::new`].
    pub sun_dir: [f32; 3],
    /// Ambient share of the lighting, 0 to 1 (outside, NaN or infinite: an error at
    /// [`Renderer::new`]). Default 0.45: faces away from the sun stay readable.
    pub ambient: f32,
    /// Sky colour (linear), each channel finite and at least 0 (else an error at
    /// [`Renderer::new`]). Default a light blue.
    pub sky: [f32; 3],
    /// How chunk meshes are drawn. Default: indirect (`multi_draw_indirect` per page and
    /// pass), which costs the CPU next to nothing per chunk; adapters without indirect
    /// first-instance draws, and [`QuadFetch::Instanced`], draw one mesh per draw (logged).
    pub draw: DrawMode,
    /// Frames over which a newly uploaded chunk fades in (screen-door dissolve of its
    /// opaque and cutout faces, alpha ramp of its translucent ones). Default 0: off, so
    /// that a picture depends only on the scene; the interactive demo turns it on.
    pub fade_in_frames: u32,
    /// How strongly the mesher's per-vertex ambient occlusion darkens, 0 to 1. Default 1:
    /// one-block steps of terrain read as steps. 0 draws every face with its Lambert light
    /// alone (the pictures before ambient occlusion).
    pub ao_strength: f32,
    /// Every block drawn in one flat colour (its base colour and opacity; cutout blocks
    /// solid), no texture pattern. Default off. For comparisons with references that
    /// cannot filter textures as a GPU does (the lab's CPU ray march).
    pub flat_textures: bool,
    /// How the chunk pipelines fetch quads. Default `None`: the first of
    /// [`QuadFetch::ALL`] the device can (storage buffers where the vertex stage has them,
    /// else instance attributes). A way the device cannot is an [`Error::Unsupported`].
    pub quad_fetch: Option<QuadFetch>,
}

impl Default for RendererConfig {
    fn default() -> Self {
        Self {
            width: 1280,
            height: 720,
            output_format: wgpu::TextureFormat::Rgba8UnormSrgb,
            output_view_format: None,
            msaa: false,
            oit: OitConfig::default(),
            sun_dir: [0.35, 0.85, 0.4],
            ambient: 0.45,
            sky: [0.45, 0.65, 0.9],
            draw: DrawMode::Indirect,
            fade_in_frames: 0,
            ao_strength: 1.0,
            flat_textures: false,
            // The device decides: both draw the same picture.
            quad_fetch: None,
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
    /// Draw calls recorded for the chunks of the opaque, cutout and translucent lists (once
    /// each: a technique's extra passes repeat them).
    pub draw_calls: usize,
    /// CPU time spent recording the frame, milliseconds (the technique's preparation
    /// included).
    pub cpu_ms: f64,
    /// What the technique did (its CPU time, sorting, layers, overflow, weight fit).
    pub technique: TechniqueReport,
    /// The game's translucent objects ordered this frame ([`crate::stages`]; 0 when the
    /// technique does not sort).
    pub game_objects_sorted: usize,
    /// CPU milliseconds ordering them.
    pub game_sort_ms: f64,
}

/// GPU memory of the chunks ([`Renderer::chunk_memory`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ChunkMemory {
    /// Bytes of the quad arena's pages.
    pub arena_bytes: u64,
    /// Of those, bytes holding quads (the rest is free room and fragmentation).
    pub quad_bytes: u64,
    /// Bytes of the chunk records (16 per slot, with room to grow).
    pub record_bytes: u64,
    /// Bytes of the indirect draw commands (16 per mesh drawn, with room to grow).
    pub indirect_bytes: u64,
    /// Pages of the arena.
    pub pages: usize,
    /// Free ranges over all pages.
    pub free_ranges: usize,
}

/// What group 0 binds, apart from the per-size medium boundary.
#[derive(Debug)]
struct SceneResources {
    frame_buffer: wgpu::Buffer,
    textures: BlockTextures,
    /// The block layers as a texture ([`QuadFetch::Instanced`]).
    layer_table: Option<TableTexture>,
    /// Per block id, its look as a medium (`block_media` in `common.wgsl`): linear colour
    /// and absorption.
    media: TableTexture,
    /// The nearest sampler every depth texture is read with (`gpu::DEPTH_READ`).
    depth_sampler: wgpu::Sampler,
}

/// The HDR scene colour and depth, the medium boundary, and what reads them.
#[derive(Debug)]
struct SceneTargets {
    size: (u32, u32),
    color: Target,
    depth: Target,
    /// Inside a medium: the depth of its first surface per pixel ([`crate::medium`]).
    boundary: Target,
    /// With a volume in view: a copy of the opaque depth, which the translucent passes
    /// read (their depth attachment is that depth, read-only).
    volume_depth: Target,
    /// Whether `volume_depth` is at full size (1×1 until a volume is in view).
    volumes: bool,
    /// Group 0 of the chunk passes (the boundary readable).
    scene_group: wgpu::BindGroup,
    /// Group 0 of the pass that writes the boundary.
    boundary_scene_group: wgpu::BindGroup,
    /// The scene group of the pass writing `volume_depth` (the opaque depth in its place).
    exit_scene_group: wgpu::BindGroup,
    /// The scene group of the pass writing `volume_entry` and `entry_look`.
    entry_scene_group: wgpu::BindGroup,
    /// The nearest front face of a volume (`shaders/inside_volume.wgsl`).
    volume_entry: Target,
    /// Its medium's look.
    entry_look: Target,
    fog_group: wgpu::BindGroup,
    /// MSAA colour and depth, resolved into `color` and `depth`.
    msaa: Option<(Target, Target)>,
    tonemap_group: wgpu::BindGroup,
    depth_resolve_group: Option<wgpu::BindGroup>,
}

/// The passes after the technique's: tonemap (per output format) and the MSAA depth
/// resolve.
#[derive(Debug)]
struct Post {
    tonemap_layout: wgpu::BindGroupLayout,
    /// Per output format: the tonemap, and the same with a depth target, which
    /// [`Renderer::check_output`] sets in a pass beside the scene depth.
    tonemap: HashMap<wgpu::TextureFormat, (wgpu::RenderPipeline, wgpu::RenderPipeline)>,
    depth_resolve_layout: wgpu::BindGroupLayout,
    depth_resolve: wgpu::RenderPipeline,
}

const MSAA_SAMPLES: u32 = 4;

/// The formats [`Renderer::render`] draws into: what surfaces offer (BGRA and RGBA, sRGB or
/// not; 10-bit; half float, written linear) and what offscreen targets use. An sRGB format
/// is encoded by the GPU, the 8- and 10-bit linear ones by the tonemap shader, so every
/// one shows the same picture.
pub const OUTPUT_FORMATS: [wgpu::TextureFormat; 6] = [
    wgpu::TextureFormat::Rgba8UnormSrgb,
    wgpu::TextureFormat::Rgba8Unorm,
    wgpu::TextureFormat::Bgra8UnormSrgb,
    wgpu::TextureFormat::Bgra8Unorm,
    wgpu::TextureFormat::Rgb10a2Unorm,
    wgpu::TextureFormat::Rgba16Float,
];

/// The format to draw an output texture of `format` with: `view` when it is given and is
/// the texture's sRGB / linear twin ([`RendererConfig::output_view_format`]), else the
/// texture's own.
fn output_format(
    view: Option<wgpu::TextureFormat>,
    format: wgpu::TextureFormat,
) -> wgpu::TextureFormat {
    match view {
        Some(v) if v.remove_srgb_suffix() == format.remove_srgb_suffix() => v,
        _ => format,
    }
}

/// Lighting a renderer draws with ([`Renderer::set_lighting`]); its fields are those of
/// [`RendererConfig`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lighting {
    /// Direction towards the sun (normalised on use).
    pub sun_dir: [f32; 3],
    /// Ambient share of the lighting, 0 to 1.
    pub ambient: f32,
    /// Sky colour (linear), what the background is cleared to.
    pub sky: [f32; 3],
}

impl Lighting {
    /// The first hour [`Lighting::daytime`] draws: sunrise.
    pub const SUNRISE: f32 = 6.0;
    /// The last hour [`Lighting::daytime`] draws: sunset.
    pub const SUNSET: f32 = 18.0;

    /// The lighting of [`RendererConfig::default`].
    pub fn default_day() -> Self {
        let c = RendererConfig::default();
        Self {
            sun_dir: c.sun_dir,
            ambient: c.ambient,
            sky: c.sky,
        }
    }

    /// Daylight at `hour` (clamped to [`Lighting::SUNRISE`]..=[`Lighting::SUNSET`]): the
    /// sun rises in the east (+x), stands highest in the south (+z) at noon and sets in
    /// the west; the ambient share falls from 0.45 at noon to 0.2 at the horizon, and the
    /// sky turns from light blue to a dusk orange. A model for a time-of-day control, not
    /// an atmosphere.
    pub fn daytime(hour: f32) -> Self {
        let hour = if hour.is_finite() { hour } else { 12.0 };
        let h = hour.clamp(Self::SUNRISE, Self::SUNSET);
        // 0 at sunrise, pi at sunset.
        let a = (h - Self::SUNRISE) / (Self::SUNSET - Self::SUNRISE) * std::f32::consts::PI;
        // A path leaning toward the south (z = 0.47 y: at 10:30 this is the default
        // lighting's sun within a few degrees), a few degrees above the horizon at either
        // end so that the sides facing the sun keep some light.
        let elevation = 0.08 + 0.92 * a.sin();
        let sun = glam::Vec3::new(a.cos(), elevation, 0.47 * elevation).normalize_or(glam::Vec3::Y);
        let day = glam::Vec3::from([0.45, 0.65, 0.9]);
        let dusk = glam::Vec3::from([0.85, 0.45, 0.25]);
        let t = a.sin().clamp(0.0, 1.0).sqrt();
        Self {
            sun_dir: sun.to_array(),
            ambient: 0.2 + 0.25 * t,
            sky: dusk.lerp(day, t).to_array(),
        }
    }

    /// Checks the values: a finite non-zero sun direction, an ambient share from 0 to 1,
    /// a finite sky colour of non-negative channels.
    pub fn validate(&self) -> Result<()> {
        let bad = |what: String| Err(Error::InvalidSetting(what));
        if let Err(why) = voxel_core::unit_direction(self.sun_dir.map(f64::from)) {
            return bad(format!("sun direction {:?}: {why}", self.sun_dir));
        }
        if !(0.0..=1.0).contains(&self.ambient) {
            return bad(format!("ambient {}: it must be from 0 to 1", self.ambient));
        }
        if !self.sky.iter().all(|c| c.is_finite() && *c >= 0.0) {
            return bad(format!(
                "sky colour {:?}: every channel must be finite and not negative",
                self.sky
            ));
        }
        Ok(())
    }
}

/// Draws a voxel world. See the module docs for the passes.
#[derive(Debug)]
pub struct Renderer {
    ctx: GpuContext,
    config: RendererConfig,
    layouts: SharedLayouts,
    scene: SceneResources,
    chunks: ChunkStore,
    opaque: wgpu::RenderPipeline,
    cutout: wgpu::RenderPipeline,
    post: Post,
    medium: MediumPass,
    /// Per block id: its look as a medium (translucent blocks only).
    looks: Vec<Option<MediumLook>>,
    targets: SceneTargets,
    oit: OitManager,
    timer: Option<Timer>,
    /// What became of each frame's encoder (timings, and flushing a dropped frame's
    /// queue writes).
    submissions: Submissions,
    /// Orders a game's translucent objects among the chunks (sorted techniques), its
    /// buffers kept between frames.
    interleaver: Interleaver,
    frame_index: u32,
    /// Chunks fading in, with the frame they appeared.
    fading: PosMap<ChunkPos, u32>,
    /// The last frame's visible meshes (kept for the room of its lists).
    culled: Culled,
    /// The last frame's draw commands (likewise).
    builder: DrawBuilder,
    /// The last output view that passed [`Renderer::check_output`]'s recorded check, so
    /// that drawing into the same view again skips it (a window's views are new each
    /// frame and pay it: about 0.08 ms on this project's 2-core machine).
    checked_view: Option<wgpu::TextureView>,
}

impl Renderer {
    /// A renderer for the blocks of `registry`. Falls back (with a log line) where the
    /// adapter lacks something: MSAA off without 4× support, a technique it cannot run.
    /// A size beyond the adapter's limits or an invalid setting is an error.
    pub fn new(ctx: &GpuContext, registry: &BlockRegistry, config: RendererConfig) -> Result<Self> {
        ctx.check_device()?;
        let mut config = config;
        config.width = config.width.max(1);
        config.height = config.height.max(1);
        check_size(ctx, config.width, config.height)?;
        check_output_format(ctx, config.output_format)?;
        check_lighting(&config)?;
        config.oit.validate()?;
        check_ao_strength(config.ao_strength)?;
        ladder::check("drawing the world", &ladder::world_needs(), &ctx.caps)?;
        if !OUTPUT_FORMATS.contains(&config.output_format) {
            return Err(Error::InvalidSetting(format!(
                "output format {:?}: the renderer draws into {}",
                config.output_format,
                OUTPUT_FORMATS.map(|f| format!("{f:?}")).join(", ")
            )));
        }
        if config.msaa && !ctx.caps.msaa4 {
            log::warn!("4x MSAA is not supported for the scene formats: rendering without MSAA");
            config.msaa = false;
        }
        let fetch = QuadFetch::choose(&ctx.caps, config.quad_fetch)?;
        if config.draw == DrawMode::Indirect && !ctx.caps.indirect_draws() {
            log::warn!(
                "no indirect draws with a first instance on this adapter: one draw per chunk mesh"
            );
            config.draw = DrawMode::PerChunk;
        }
        if config.draw == DrawMode::Indirect && !fetch.indirect() {
            log::info!("{} quad fetch: one draw per chunk mesh", fetch.name());
            config.draw = DrawMode::PerChunk;
        }
        if fetch != QuadFetch::ALL[0] {
            log::info!("drawing the world with {} quad fetch", fetch.name());
        }
        config.quad_fetch = Some(fetch);
        scoped(&ctx.device, "creating the renderer", || {
            Self::create(ctx, registry, config, fetch)
        })?
    }

    fn create(
        ctx: &GpuContext,
        registry: &BlockRegistry,
        mut config: RendererConfig,
        fetch: QuadFetch,
    ) -> Result<Self> {
        let device = &ctx.device;
        let layouts = SharedLayouts::new(device, fetch);
        let textures = BlockTextures::new(ctx, registry, config.flat_textures)?;
        let layer_table = (fetch == QuadFetch::Instanced).then(|| {
            let t = TableTexture::new(
                device,
                "block_layer_table",
                wgpu::TextureFormat::R32Uint,
                textures.table.len(),
            );
            t.write(&ctx.queue, 0, bytemuck::cast_slice(&textures.table));
            t
        });
        let looks = medium::looks(registry);
        let media = TableTexture::new(
            device,
            "block_media",
            wgpu::TextureFormat::Rgba32Float,
            looks.len(),
        );
        let media_data: Vec<[f32; 4]> = looks
            .iter()
            .map(|l| {
                l.map_or([0.0; 4], |l| {
                    [l.color[0], l.color[1], l.color[2], l.absorption]
                })
            })
            .collect();
        media.write(&ctx.queue, 0, bytemuck::cast_slice(&media_data));
        let scene = SceneResources {
            frame_buffer: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("frame_uniforms"),
                contents: bytemuck::bytes_of(&FrameUniforms::default()),
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            }),
            textures,
            layer_table,
            media,
            depth_sampler: gpu::depth_sampler(device),
        };
        let (opaque, cutout) = Self::opaque_pipelines(ctx, &layouts, config.msaa);
        let mut post = Post::new(device);
        post.make_tonemap(ctx, config.output_format);
        let medium = MediumPass::new(ctx, &layouts);
        let size = (config.width, config.height);
        let targets = SceneTargets::new(
            ctx,
            &post,
            &layouts,
            &scene,
            &medium,
            size,
            (config.msaa, false),
        );
        let block_opacity = registry
            .iter()
            .map(|(_, def)| def.opacity)
            .collect::<Arc<[f32]>>();
        let setup = Setup {
            ctx: ctx.clone(),
            layouts: layouts.clone(),
            size,
            block_opacity: block_opacity.clone(),
        };
        let oit = OitManager::new(setup, config.oit.clone())?;
        config_with(&mut config.oit, oit.config());
        Ok(Self {
            ctx: ctx.clone(),
            chunks: ChunkStore::new(
                ctx,
                layouts.chunk.clone(),
                fetch,
                block_opacity,
                looks
                    .iter()
                    .map(|l| l.is_some_and(|l| l.absorption > 0.0))
                    .collect(),
            ),
            layouts,
            scene,
            opaque,
            cutout,
            post,
            medium,
            looks,
            targets,
            oit,
            timer: Timer::new(ctx),
            submissions: Submissions::default(),
            interleaver: Interleaver::default(),
            frame_index: 0,
            fading: PosMap::default(),
            culled: Culled::default(),
            builder: DrawBuilder::default(),
            checked_view: None,
            config,
        })
    }

    fn opaque_pipelines(
        ctx: &GpuContext,
        layouts: &SharedLayouts,
        msaa: bool,
    ) -> (wgpu::RenderPipeline, wgpu::RenderPipeline) {
        let module = gpu::shader(
            &ctx.device,
            "opaque",
            &[&common_wgsl(), include_str!("shaders/opaque.wgsl")],
        );
        let groups = layouts.with(&[]);
        // Opaque quads grow against T-junction cracks; cutout quads do not: leaves keep
        // their faces toward other leaves, and a grown inner face would poke out along the
        // seams of the faces in front of it.
        let make = |label, fragment_entry, grow: bool| {
            let pipeline = ChunkPipeline {
                label,
                module: &module,
                fragment_entry,
                groups: &groups,
                targets: &[gpu::scene_target(None)],
                depth: DepthMode::Write,
                samples: if msaa { MSAA_SAMPLES } else { 1 },
            };
            if grow {
                pipeline.build_solid(&ctx.device)
            } else {
                pipeline.build(&ctx.device)
            }
        };
        (
            make("opaque", "fs_opaque", true),
            make("cutout", "fs_cutout", false),
        )
    }

    /// The scene targets for `size`, with or without MSAA, and the volume depth at full
    /// size once a volume has been in view.
    fn targets_for(&self, size: (u32, u32), msaa: bool, volumes: bool) -> SceneTargets {
        SceneTargets::new(
            &self.ctx,
            &self.post,
            &self.layouts,
            &self.scene,
            &self.medium,
            size,
            (msaa, volumes),
        )
    }

    /// The GPU context.
    pub fn context(&self) -> &GpuContext {
        &self.ctx
    }

    /// The configuration in force: after fallbacks, and after every `set_*` call.
    pub fn config(&self) -> &RendererConfig {
        &self.config
    }

    /// Output size in pixels.
    pub fn size(&self) -> (u32, u32) {
        self.targets.size
    }

    /// Uploads or replaces a chunk's meshes; empty meshes remove it. A chunk that was not
    /// on the GPU fades in when [`RendererConfig::fade_in_frames`] is set. A position
    /// outside the `i32` world ([`ChunkPos::is_valid`]) is an error.
    pub fn upload_chunk(&mut self, pos: ChunkPos, meshes: &ChunkMeshes) -> Result<()> {
        self.ctx.check_device()?;
        if !pos.is_valid() {
            return Err(Error::InvalidSetting(format!(
                "chunk position {pos:?} lies outside the i32 world (coordinates {} to {})",
                ChunkPos::MIN,
                ChunkPos::MAX
            )));
        }
        let new = self.chunks.get(pos).is_none();
        self.chunks.upload(&self.ctx, pos, meshes)?;
        if new && self.config.fade_in_frames > 0 && self.chunks.get(pos).is_some() {
            self.fading.insert(pos, self.frame_index);
            self.chunks.set_alpha(&self.ctx, pos, 0.0);
        }
        Ok(())
    }

    /// Removes a chunk from the GPU.
    pub fn remove_chunk(&mut self, pos: ChunkPos) {
        self.chunks.remove(&self.ctx, pos);
        self.fading.remove(&pos);
    }

    /// Removes every chunk.
    pub fn clear_chunks(&mut self) {
        self.chunks.clear(&self.ctx);
        self.fading.clear();
    }

    /// Changes the transparency settings. Resources are rebuilt only where the active
    /// technique's pipelines depend on what changed. An invalid setting is an error and
    /// changes nothing.
    pub fn set_oit_config(&mut self, config: OitConfig) -> Result<()> {
        self.ctx.check_device()?;
        self.oit.set_config(config)?;
        config_with(&mut self.config.oit, self.oit.config());
        Ok(())
    }

    /// Switches the transparency technique (or what replaces it on this adapter) and
    /// returns the one in force. A technique the device cannot run (nor a replacement) is
    /// an [`Error::Unsupported`] naming what it lacks, and changes nothing
    /// ([`Technique::supported`] lists what a device runs).
    pub fn set_technique(&mut self, technique: Technique) -> Result<Technique> {
        self.ctx.check_device()?;
        let t = self.oit.set_technique(technique)?;
        config_with(&mut self.config.oit, self.oit.config());
        Ok(t)
    }

    /// Builds `technique`'s pipelines and targets now, so that a later
    /// [`Renderer::set_technique`] to it builds nothing and its first frame costs what any
    /// frame costs (a game prepares the techniques its settings menu offers at loading
    /// time). It stays built until [`Renderer::release_technique`]; see
    /// [`OitManager::prebuild`]. Returns the technique built (after its fallback on this
    /// adapter); one the device cannot run is an [`Error::Unsupported`].
    pub fn prebuild_technique(&mut self, technique: Technique) -> Result<Technique> {
        self.ctx.check_device()?;
        let oit = &mut self.oit;
        let built = scoped(&self.ctx.device, "building a technique ahead", || {
            oit.prebuild(technique)
        })??;
        self.oit.warm(built, &self.chunks);
        Ok(built)
    }

    /// Frees what [`Renderer::prebuild_technique`] built for `technique`, unless it is
    /// drawing.
    pub fn release_technique(&mut self, technique: Technique) {
        self.oit.release(technique);
    }

    /// Changes the WBOIT weight function (a uniform: no pipeline is rebuilt).
    pub fn set_weight(&mut self, weight: WeightFunction) {
        let mut config = self.oit.config().clone();
        config.wboit.weight = weight;
        // Only the weight changed: the configuration stays valid.
        let _ = self.set_oit_config(config);
    }

    /// Changes how chunk meshes are drawn; indirect draws stay off on an adapter without
    /// them (logged at creation) and with [`QuadFetch::Instanced`].
    pub fn set_draw_mode(&mut self, mode: DrawMode) {
        let indirect = self.ctx.caps.indirect_draws() && self.layouts.fetch.indirect();
        self.config.draw = if mode == DrawMode::Indirect && !indirect {
            DrawMode::PerChunk
        } else {
            mode
        };
    }

    /// GPU bytes the chunks take: the quad arena (all pages, and the part holding quads)
    /// and the chunk records.
    pub fn chunk_memory(&self) -> ChunkMemory {
        let (arena, records) = self.chunks.memory();
        ChunkMemory {
            arena_bytes: arena.bytes,
            quad_bytes: arena.used_bytes,
            record_bytes: records,
            indirect_bytes: self.chunks.indirect_bytes(),
            pages: arena.pages,
            free_ranges: arena.fragments,
        }
    }

    /// Changes the ambient-occlusion strength (0 to 1; see
    /// [`RendererConfig::ao_strength`]) from the next frame on: a uniform, nothing is
    /// rebuilt or uploaded again. A value outside 0..=1 or not finite is an error.
    pub fn set_ao_strength(&mut self, strength: f32) -> Result<()> {
        self.ctx.check_device()?;
        check_ao_strength(strength)?;
        self.config.ao_strength = strength;
        Ok(())
    }

    /// The sun direction, ambient share and sky in force.
    pub fn lighting(&self) -> Lighting {
        Lighting {
            sun_dir: self.config.sun_dir,
            ambient: self.config.ambient,
            sky: self.config.sky,
        }
    }

    /// Changes the sun direction, ambient share and sky from the next frame on: they are
    /// frame uniforms and the clear colour, so nothing is rebuilt and no chunk is uploaded
    /// again. Invalid values ([`Lighting::validate`]) are an error and change nothing.
    pub fn set_lighting(&mut self, lighting: Lighting) -> Result<()> {
        lighting.validate()?;
        self.config.sun_dir = lighting.sun_dir;
        self.config.ambient = lighting.ambient;
        self.config.sky = lighting.sky;
        Ok(())
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

    /// Turns 4× MSAA on or off (rebuilds the opaque pipelines and targets). Without 4×
    /// support it stays off (logged at creation).
    pub fn set_msaa(&mut self, msaa: bool) -> Result<()> {
        self.ctx.check_device()?;
        let msaa = msaa && self.ctx.caps.msaa4;
        if msaa == self.config.msaa {
            return Ok(());
        }
        let (ctx, size) = (&self.ctx, self.size());
        let (pipelines, targets) = scoped(&ctx.device, "switching MSAA", || {
            (
                Self::opaque_pipelines(ctx, &self.layouts, msaa),
                self.targets_for(size, msaa, self.targets.volumes),
            )
        })?;
        (self.opaque, self.cutout) = pipelines;
        self.targets = targets;
        self.config.msaa = msaa;
        Ok(())
    }

    /// Resizes every target. The same size does nothing; a zero width or height (a
    /// minimised window) does nothing either and keeps the old targets until a real size
    /// comes. A size beyond the adapter's limit is an error and changes nothing.
    pub fn resize(&mut self, width: u32, height: u32) -> Result<()> {
        self.ctx.check_device()?;
        if width == 0 || height == 0 || (width, height) == self.size() {
            return Ok(());
        }
        check_size(&self.ctx, width, height)?;
        let ctx = &self.ctx;
        let targets = scoped(&ctx.device, "resizing", || {
            self.targets_for((width, height), self.config.msaa, self.targets.volumes)
        })?;
        self.targets = targets;
        self.checked_view = None;
        self.config.width = width;
        self.config.height = height;
        let oit = &mut self.oit;
        scoped(&self.ctx.device, "resizing", || oit.resize(width, height))?
    }

    /// GPU milliseconds per pass of the latest timed frame whose results have arrived
    /// (empty without timestamps, and once the device is lost). Results arrive a frame or
    /// more after submission, once wgpu is polled (each `queue.submit` polls).
    pub fn gpu_times(&mut self) -> GpuTimes {
        if self.ctx.check_device().is_err() {
            return GpuTimes::default();
        }
        let last = self.settle_submission();
        let ctx = &self.ctx;
        self.timer
            .as_mut()
            .map(|t| t.poll(ctx, last))
            .unwrap_or_default()
    }

    /// Like [`Renderer::gpu_times`], but waits for the last submitted frame's results
    /// (empty once the device is lost: nothing will come).
    pub fn gpu_times_blocking(&mut self) -> GpuTimes {
        if self.ctx.check_device().is_err() {
            return GpuTimes::default();
        }
        let ctx = self.ctx.clone();
        let Some(mut timer) = self.timer.take() else {
            return GpuTimes::default();
        };
        let times = timer.read_blocking(&ctx, || self.settle_submission());
        self.timer = Some(timer);
        times
    }

    /// What became of the last frame's encoder; a dropped one's queue writes are flushed
    /// by an empty submit (wgpu keeps them, and their staging memory, until a submit).
    fn settle_submission(&mut self) -> Outcome {
        let last = self.submissions.settle(&self.ctx);
        if last == Outcome::Dropped && self.ctx.check_device().is_ok() {
            self.ctx.queue.submit([]);
        }
        last
    }

    /// Optional, after submitting a frame's encoder: frees for reuse now the arena places
    /// the frame drew that were freed meanwhile (the next `render` frees them otherwise).
    /// GPU timings and a technique's counters need no call: they are read back once a
    /// frame's commands are submitted.
    pub fn after_submit(&mut self) {
        self.chunks.frame_submitted(&self.ctx);
    }

    /// The HDR scene colour (after the composite, before tonemapping).
    pub fn scene_color(&self) -> &wgpu::Texture {
        &self.targets.color.texture
    }

    /// The single-sample scene depth (reverse-Z).
    pub fn scene_depth(&self) -> &wgpu::Texture {
        &self.targets.depth.texture
    }

    /// A view of [`Renderer::scene_depth`], for a game's pass that draws over the frame
    /// tested against it (attached read-only, [`gpu::Depth::ReadOnly`], with
    /// [`gpu::overlay_depth`]). Valid until the next resize.
    pub fn scene_depth_view(&self) -> &wgpu::TextureView {
        &self.targets.depth.view
    }

    /// Records a frame into `encoder`, ending with the tonemap into `output`: a view of
    /// mip level 0 of a single-layer, single-sample 2D texture of the renderer's size,
    /// of one of [`OUTPUT_FORMATS`], with `RENDER_ATTACHMENT` usage. The view has its
    /// texture's format, or [`RendererConfig::output_view_format`] when that is the
    /// texture's twin. Anything else is an [`Error::Output`] before anything is recorded.
    ///
    /// Nothing needs calling after the frame's commands are submitted: GPU timings and
    /// a technique's counters (depth peeling's layers) are read back once they are.
    ///
    /// Fails without recording anything on an invalid camera (NaN, zero direction, bad
    /// planes), a mismatched output ([`Error::Output`]) or a lost device
    /// ([`Error::DeviceLost`]).
    ///
    /// Submit each frame before recording the next: what changes between `render` and
    /// the submit (chunks uploaded or removed) never changes what this frame draws, and
    /// the arena places it draws are reused only after [`Renderer::after_submit`] or the
    /// next `render`.
    ///
    /// The exact techniques (`Reference`, `PeelReference`) wait for GPU results in the
    /// middle of the frame: they submit what `encoder` holds so far and go on in a fresh
    /// encoder that replaces it (the order of commands is kept). Real-time techniques never
    /// submit.
    pub fn render(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        output: &wgpu::TextureView,
        camera: &Camera,
    ) -> Result<FrameStats> {
        self.render_with(encoder, output, camera, &mut NoGame)
    }

    /// What a game's translucent pipelines must match for the technique in force, made
    /// (with the technique's resources) when first asked for; its `id` changes when a
    /// technique switch or a setting needs new pipelines ([`crate::stages`]).
    pub fn translucent_contract(&mut self) -> Result<Arc<TranslucentContract>> {
        self.ctx.check_device()?;
        self.oit.contract()
    }

    /// [`Renderer::translucent_contract`] of `technique` (or what replaces it on this
    /// device), before switching to it: a game builds its translucent pipelines for every
    /// technique its settings offer at loading time, as [`Renderer::prebuild_technique`]
    /// builds the renderer's (which this does too), so that a switch compiles nothing.
    /// The id is the one the contract has once the technique is in force.
    pub fn translucent_contract_for(
        &mut self,
        technique: Technique,
    ) -> Result<Arc<TranslucentContract>> {
        self.ctx.check_device()?;
        let oit = &mut self.oit;
        scoped(&self.ctx.device, "building a technique ahead", || {
            oit.contract_for(technique)
        })?
    }

    /// [`Renderer::render`] with a game's stages: its opaque geometry after the world's,
    /// its translucent geometry composed by the technique with the chunks, its overlays
    /// before and after tonemapping (see [`crate::stages`]). A stage the game does not
    /// declare costs nothing.
    pub fn render_with(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        output: &wgpu::TextureView,
        camera: &Camera,
        game: &mut dyn GameStages,
    ) -> Result<FrameStats> {
        self.ctx.check_device()?;
        camera.validate()?;
        // The output's format (its tonemap pipeline made the first time), checked with it.
        let format = output_format(self.config.output_view_format, output.texture().format());
        if OUTPUT_FORMATS.contains(&format) {
            self.post.make_tonemap(&self.ctx, format);
        }
        self.check_output(output, format)?;
        let stages = game.stages();
        if stages.translucent {
            let current = self.oit.contract()?.id;
            let built_for = game.translucent_contract_id();
            if built_for != Some(current) {
                return Err(Error::StaleContract {
                    built_for,
                    current,
                    technique: self.oit.technique().name(),
                });
            }
        }
        if format != self.config.output_format {
            log::info!(
                "drawing into {format:?} from now on (was {:?})",
                self.config.output_format
            );
            self.config.output_format = format;
        }
        let start = Instant::now();
        // Ends the last timed frame if it was submitted since; this one is timed unless
        // it is not.
        let last = self.settle_submission();
        let ctx = &self.ctx;
        let timed = self
            .timer
            .as_mut()
            .is_some_and(|t| t.begin_frame(ctx, last));
        self.update_fades();
        // The previous frame is submitted (the contract above): what it drew may be reused.
        self.chunks.frame_submitted(&self.ctx);
        // Before any list of this frame takes the meshes' places.
        self.chunks.compact(&self.ctx);
        let (w, h) = self.size();
        let aspect = f64::from(w) / f64::from(h);
        let camera = &self.drawn_camera(camera);
        let medium = camera
            .medium
            .and_then(|b| Some((b, self.looks.get(b.index()).copied().flatten()?)));
        let view_proj = camera.view_proj(aspect);
        let frustum = Frustum::new(view_proj, camera.eye);

        // One pass over the chunks finds the visible meshes of every kind, in draw order:
        // translucent chunks farthest first, by the integer key that is exact for a grid of
        // equal cubes (`voxel_mesh::order`); opaque and cutout meshes grouped by page, front
        // to back (early depth rejection).
        let layers = self.oit.wants_layers();
        self.chunks.cull(&frustum, layers, &mut self.culled);
        self.chunks.lists_built();
        // A volume in view: its faces read the opaque depth (a copy, made below), whose
        // target is made the first time.
        let volumes = self
            .culled
            .translucent_slots()
            .any(|slot| self.chunks.by_slot(slot).is_some_and(GpuChunk::has_volume));
        if volumes && !self.targets.volumes {
            let (size, msaa) = (self.size(), self.config.msaa);
            let targets = scoped(&self.ctx.device, "making the volume depth", || {
                self.targets_for(size, msaa, true)
            })?;
            self.targets = targets;
        }
        // The technique's CPU work (it may reorder quads within their places).
        let view = FrameView {
            camera,
            view_proj,
            translucent: self.culled.translucent_positions(),
            layers: self.culled.translucent_layers(),
            game_objects: stages.translucent.then(|| game.translucent_objects()),
        };
        self.oit
            .prepare(&mut self.chunks, &view, stages.translucent)?;
        // A sorting technique orders the game's objects with the chunks (after `prepare`:
        // sorted-quads splits a chunk's quads in their new order).
        let sort_start = Instant::now();
        let sorts = stages.translucent && self.oit.technique().sorts();
        if sorts {
            // Each visible translucent chunk's surfaces, in draw order.
            let chunks: Vec<_> = self
                .culled
                .translucent_slots()
                .map(|slot| {
                    self.chunks
                        .by_slot(slot)
                        .and_then(|c| c.translucent_surfaces())
                })
                .collect();
            let split_quads = self.oit.technique() == Technique::SortedQuads;
            let sequence = ChunkSequence {
                surfaces: &chunks,
                keys: self.culled.translucent_keys(),
                positions: self.culled.translucent_positions(),
            };
            self.interleaver.order(
                game.translucent_objects(),
                camera.eye,
                &sequence,
                medium.is_some(),
                split_quads,
            );
        }
        let (order, splits): (&[u32], &[Split]) = if sorts {
            self.interleaver.result()
        } else {
            (&[], &[])
        };
        let game_sort_ms = sort_start.elapsed().as_secs_f64() * 1e3;
        let objects = if sorts {
            order.len()
        } else {
            game.translucent_objects().len()
        };
        // The sorted techniques (drawn in order, one blend per fragment) compose a fragment
        // inside a volume against the volume's entry (`inside_volume.wgsl`).
        let ordered = matches!(
            self.oit.technique(),
            Technique::Sorted | Technique::SortedQuads | Technique::DepthPeeling
        );
        let volume_mode = match (volumes, ordered) {
            (false, _) => 0,
            (true, false) => 1,
            (true, true) => 2,
        };
        self.write_frame_uniforms(
            camera,
            view_proj,
            medium.as_ref().map(|(b, look)| (*b, look)),
            volume_mode,
        );
        let (eye_int, eye_frac) = camera.eye_split();
        let game_frame = GameFrame {
            camera,
            view_proj,
            eye_int,
            eye_frac,
            size: (w, h),
            opaque_samples: if self.config.msaa { MSAA_SAMPLES } else { 1 },
            output_format: self.config.output_format,
            order: sorts.then_some(order),
        };
        if stages != crate::stages::Stages::default() {
            game.prepare(&self.ctx, &game_frame);
            // A device lost now (a reset can land in the game's code) makes nothing valid:
            // nothing more is recorded.
            self.ctx.check_device()?;
        }
        let game = &*game;

        let builder = &mut self.builder;
        builder.clear();
        let lists = [MeshKind::Opaque, MeshKind::Cutout, MeshKind::Translucent]
            .map(|kind| builder.list(self.culled.meshes(kind)));
        // Per-chunk draws read the commands on the CPU.
        if self.config.draw == DrawMode::Indirect {
            self.chunks.upload_draws(&self.ctx, self.builder.commands());
        }
        let draws = FrameDraws {
            store: &self.chunks,
            commands: self.builder.commands(),
            mode: self.config.draw,
        };
        let [opaque, cutout, translucent] = &lists;

        let timer = self.timer.as_ref().filter(|_| timed);
        let t = &self.targets;
        let game_opaque = stages.opaque.then_some((game, &game_frame));
        self.draw_opaque(encoder, &draws, opaque, cutout, game_opaque, timer);
        if stages.opaque {
            self.ctx.check_device()?;
        }
        if medium.is_some() {
            let scene = &t.boundary_scene_group;
            self.medium.boundary_pass(
                encoder,
                &t.depth,
                &t.boundary,
                scene,
                &draws,
                translucent,
                timer,
            );
        }
        if volumes {
            let exits = (!self.oit.technique().is_exact()).then_some((
                &t.exit_scene_group,
                &draws,
                translucent,
            ));
            self.medium
                .volume_depth_pass(encoder, &t.depth, &t.volume_depth, exits, timer);
            if volume_mode == 2 {
                self.medium.volume_entry_pass(
                    encoder,
                    &t.depth,
                    (&t.volume_entry, &t.entry_look),
                    &t.entry_scene_group,
                    &draws,
                    translucent,
                    timer,
                );
            }
        }
        let game_draw = stages.translucent.then(|| GameDraw {
            stages: game,
            frame: &game_frame,
            objects,
            splits,
            frame_buffer: &self.scene.frame_buffer,
            boundary: &t.boundary.view,
            depth_sampler: &self.scene.depth_sampler,
            volume_depth: &t.volume_depth.view,
            volume_entry: &t.volume_entry.view,
            entry_look: &t.entry_look.view,
        });
        self.oit.render(
            encoder,
            &TranslucentFrame {
                target: &t.color,
                depth: &t.depth,
                scene: &t.scene_group,
                draws: &draws,
                chunks: translucent,
                timer,
                two_sided: medium.is_some(),
                volumes,
                game: game_draw.as_ref(),
            },
        )?;
        if stages.translucent {
            self.ctx.check_device()?;
        }
        if let Some((_, look)) = &medium {
            let sun = sun_unit(self.config.sun_dir);
            let light = self.config.ambient + (1.0 - self.config.ambient) * sun.y.max(0.0);
            let params = medium::fog_params(look, camera, aspect, [w as f32, h as f32], light);
            self.ctx
                .queue
                .write_buffer(&self.medium.fog_params, 0, bytemuck::bytes_of(&params));
            self.medium.fog_pass(encoder, &t.color, &t.fog_group, timer);
        }
        if stages.hdr_overlay {
            let colors = [gpu::load(&t.color.view)];
            Pass::new("game_hdr_overlay", GpuPass::Game, &colors)
                .depth(Depth::ReadOnly(&t.depth.view))
                .record(encoder, timer, |pass| game.hdr_overlay(pass, &game_frame));
            self.ctx.check_device()?;
        }
        self.tonemap(encoder, output, timer);
        if stages.overlay {
            let colors = [gpu::load(output)];
            Pass::new("game_overlay", GpuPass::Game, &colors)
                .record(encoder, timer, |pass| game.overlay(pass, &game_frame));
            self.ctx.check_device()?;
        }
        let stats = FrameStats {
            meshes_drawn: lists.each_ref().map(DrawList::meshes),
            translucent_quads: translucent.quads() as usize,
            draw_calls: lists.iter().map(|l| l.calls(self.config.draw)).sum(),
            cpu_ms: 0.0,
            technique: TechniqueReport::default(),
            game_objects_sorted: order.len(),
            game_sort_ms,
        };
        if timed && let Some(t) = &mut self.timer {
            t.end_frame(&self.ctx, encoder);
        }
        self.submissions.attach(&self.ctx, encoder);
        Ok(FrameStats {
            cpu_ms: start.elapsed().as_secs_f64() * 1e3,
            technique: self.oit.report(),
            ..stats
        })
    }

    /// The camera a frame of `camera` is drawn with: no translucent face closer than the
    /// near plane's corners (the near plane shrinks for the frame), and an eye within
    /// [`crate::MIN_NEAR`] of a translucent face moved off it to its medium's side
    /// ([`medium::guard`]). Tools that reason about the picture's geometry (the lab's quad
    /// edges) use this one.
    pub fn drawn_camera(&self, camera: &Camera) -> Camera {
        let (w, h) = self.size();
        medium::guard(
            &camera.normalized(),
            f64::from(w) / f64::from(h),
            &self.chunks,
        )
    }

    /// Renders one frame into `output` and submits it (for tools and tests).
    pub fn render_and_submit(
        &mut self,
        output: &wgpu::TextureView,
        camera: &Camera,
    ) -> Result<FrameStats> {
        self.render_and_submit_with(output, camera, &mut NoGame)
    }

    /// [`Renderer::render_and_submit`] with a game's stages ([`Renderer::render_with`]).
    pub fn render_and_submit_with(
        &mut self,
        output: &wgpu::TextureView,
        camera: &Camera,
        game: &mut dyn GameStages,
    ) -> Result<FrameStats> {
        let mut encoder = self
            .ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("frame"),
            });
        let stats = self.render_with(&mut encoder, output, camera, game)?;
        self.ctx.check_device()?;
        self.ctx.queue.submit([encoder.finish()]);
        // A loss during the submission is this frame's too.
        self.ctx.check_device()?;
        Ok(stats)
    }

    /// The output must match what the tonemap pipeline and the targets are made for: the
    /// texture's size, format, usage, samples, dimension and layers here; what only the
    /// view knows (its mip level, dimension and format; wgpu does not expose them) by
    /// recording the tonemap's pass into a throwaway encoder inside an error scope, beside
    /// the scene depth (the renderer's size, so that a view of another level fails).
    fn check_output(
        &mut self,
        output: &wgpu::TextureView,
        want: wgpu::TextureFormat,
    ) -> Result<()> {
        let t = output.texture();
        let (w, h) = self.size();
        if (t.width(), t.height()) != (w, h) {
            return Err(Error::Output(format!(
                "{}x{} pixels, but the renderer draws {w}x{h} (call resize first)",
                t.width(),
                t.height()
            )));
        }
        if !OUTPUT_FORMATS.contains(&t.format()) {
            return Err(Error::Output(format!(
                "format {:?}: the renderer draws into {} (last {want:?})",
                t.format(),
                OUTPUT_FORMATS.map(|f| format!("{f:?}")).join(", ")
            )));
        }
        if !t.usage().contains(wgpu::TextureUsages::RENDER_ATTACHMENT)
            || t.sample_count() != 1
            || t.dimension() != wgpu::TextureDimension::D2
            || t.depth_or_array_layers() != 1
        {
            return Err(Error::Output(format!(
                "must be a single-sample, single-layer 2D texture with RENDER_ATTACHMENT usage \
                 (this one: {:?}, {} samples, {} layers, {:?})",
                t.dimension(),
                t.sample_count(),
                t.depth_or_array_layers(),
                t.usage()
            )));
        }
        if self.checked_view.as_ref() == Some(output) {
            return Ok(());
        }
        let Some((_, check)) = self.post.tonemap.get(&want) else {
            return Err(Error::Output(format!("no tonemap pipeline for {want:?}")));
        };
        let device = &self.ctx.device;
        let checked = scoped(device, "checking the output view", || {
            let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("output_view_check"),
            });
            let color = [gpu::load(output)];
            // One pass (about 10 µs on lavapipe): the scene depth beside the output fails
            // on another size, the pipeline on another view format.
            Pass::new("output_view_check", GpuPass::Tonemap, &color)
                .depth(Depth::Load(&self.targets.depth.view))
                .record(&mut encoder, None, |pass| pass.set_pipeline(check));
            // Never submitted: recording and finishing are what validate.
            drop(encoder.finish());
        });
        if checked.is_ok() {
            self.checked_view = Some(output.clone());
        }
        checked.map_err(|e| {
            let why = match &e {
                Error::Gpu { error, .. } => error.to_string(),
                other => other.to_string(),
            };
            Error::Output(format!(
                "the view must be a 2D view of mip level 0 ({w}x{h}) viewed as {want:?}: {}",
                why.lines()
                    .map(str::trim)
                    .filter(|l| !l.is_empty())
                    .collect::<Vec<_>>()
                    .join(" ")
            ))
        })
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
        self.frame_index = self.frame_index.wrapping_add(1);
    }

    fn write_frame_uniforms(
        &self,
        camera: &Camera,
        view_proj: Mat4,
        medium: Option<(BlockId, &MediumLook)>,
        volumes: u32,
    ) {
        let (eye_int, eye_frac) = camera.eye_split();
        let sun = sun_unit(self.config.sun_dir);
        let (w, h) = self.size();
        let tan_y = (camera.fov_y_deg.to_radians() / 2.0).tan();
        let tan_x = tan_y * f64::from(w) / f64::from(h);
        let uniforms = FrameUniforms {
            view_proj: view_proj.to_cols_array_2d(),
            eye_int: eye_int.map(|v| v.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32),
            near: camera.near as f32,
            eye_frac: eye_frac.to_array(),
            far: camera.far as f32,
            sun_dir: sun.to_array(),
            ambient: self.config.ambient,
            sky: self.config.sky,
            viewport: [w as f32, h as f32],
            medium: medium.map_or(NO_MEDIUM, |(b, _)| u32::from(b.0)),
            ao_strength: self.config.ao_strength,
            tan_half: [tan_x as f32, tan_y as f32],
            volumes,
            medium_look: medium.map_or([0.0; 4], |(_, look)| {
                let [r, g, b] = look.color;
                [r, g, b, look.absorption]
            }),
            ..FrameUniforms::default()
        };
        self.ctx
            .queue
            .write_buffer(&self.scene.frame_buffer, 0, bytemuck::bytes_of(&uniforms));
    }

    /// The opaque pass, the cutout pass, then the game's opaque stage; with MSAA the
    /// colour resolves at the end of the last one and the depth in a pass of its own.
    fn draw_opaque(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        draws: &FrameDraws<'_>,
        opaque: &DrawList,
        cutout: &DrawList,
        game: Option<(&dyn GameStages, &GameFrame<'_>)>,
        timer: Option<&Timer>,
    ) {
        let t = &self.targets;
        let [r, g, b] = self.config.sky.map(f64::from);
        let sky = wgpu::Color { r, g, b, a: 1.0 };
        let (color, depth, resolve) = match &t.msaa {
            Some((c, d)) => (&c.view, &d.view, Some(&t.color.view)),
            None => (&t.color.view, &t.depth.view, None),
        };
        // The passes that run, in order: the opaque pass always (it clears), the others
        // when they have something to draw. The last one resolves MSAA colour.
        let runs = [
            (GpuPass::Opaque, true),
            (GpuPass::Cutout, !cutout.is_empty()),
            (GpuPass::Game, game.is_some()),
        ];
        let last = runs.iter().rposition(|r| r.1).unwrap_or(0);
        for (i, &(kind, run)) in runs.iter().enumerate() {
            if !run {
                continue;
            }
            let first = i == 0;
            let colors = [gpu::attachment(
                color,
                if first {
                    wgpu::LoadOp::Clear(sky)
                } else {
                    wgpu::LoadOp::Load
                },
                if i == last { resolve } else { None },
            )];
            // Reverse-Z: clear to 0, the far plane.
            let depth = if first {
                Depth::Clear(depth, 0.0)
            } else {
                Depth::Load(depth)
            };
            let label = if kind == GpuPass::Game {
                "game_opaque"
            } else {
                kind.name()
            };
            Pass::new(label, kind, &colors)
                .depth(depth)
                .record(encoder, timer, |pass| match (kind, game) {
                    (GpuPass::Game, Some((game, frame))) => game.opaque(pass, frame),
                    _ => {
                        let (pipeline, list) = if first {
                            (&self.opaque, opaque)
                        } else {
                            (&self.cutout, cutout)
                        };
                        pass.set_pipeline(pipeline);
                        pass.set_bind_group(0, &t.scene_group, &[]);
                        draws.draw(list, pass);
                    }
                });
        }
        if let Some(group) = &t.depth_resolve_group {
            Pass::new("depth_resolve", GpuPass::Opaque, &[])
                .depth(Depth::Clear(&t.depth.view, 0.0))
                .record(encoder, timer, |pass| {
                    pass.set_pipeline(&self.post.depth_resolve);
                    pass.set_bind_group(0, group, &[]);
                    pass.draw(0..3, 0..1);
                });
        }
    }

    fn tonemap(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        output: &wgpu::TextureView,
        timer: Option<&Timer>,
    ) {
        let Some((pipeline, _)) = self.post.tonemap.get(&self.config.output_format) else {
            return;
        };
        let colors = [gpu::load(output)];
        Pass::new("tonemap", GpuPass::Tonemap, &colors).record(encoder, timer, |pass| {
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &self.targets.tonemap_group, &[]);
            pass.draw(0..3, 0..1);
        });
    }
}

/// Copies what the manager holds (technique after fallback) into a renderer's config.
fn config_with(mine: &mut OitConfig, manager: &OitConfig) {
    mine.clone_from(manager);
}

/// The output format must be one the tonemap writes: a colour format sampled as float
/// (the shader writes `vec4<f32>`) that every adapter can render to.
fn check_output_format(ctx: &GpuContext, format: wgpu::TextureFormat) -> Result<()> {
    let float = matches!(
        format.sample_type(None, Some(ctx.caps.features)),
        Some(wgpu::TextureSampleType::Float { .. })
    );
    let renderable = format
        .guaranteed_format_features(ctx.caps.features)
        .allowed_usages
        .contains(wgpu::TextureUsages::RENDER_ATTACHMENT);
    if !format.has_color_aspect() || format.has_depth_aspect() || !float || !renderable {
        return Err(Error::InvalidSetting(format!(
            "output_format {format:?}: the tonemap writes float colour, so it must be a \
             renderable float colour format (e.g. Rgba8UnormSrgb, Bgra8UnormSrgb, Rgba16Float)"
        )));
    }
    Ok(())
}

/// The sun direction at length 1, normalised in f64 so that any finite non-zero
/// direction (`[1e38; 3]`, `[f32::MAX, 0, 0]`) is the same direction at length 1; a zero
/// one (accepted by `Renderer::new`, refused by `set_lighting`) is straight up.
fn sun_unit(sun: [f32; 3]) -> glam::Vec3 {
    voxel_core::unit_direction(sun.map(f64::from))
        .map_or(glam::Vec3::Y, |d| glam::DVec3::from(d).as_vec3())
}

/// Lighting values must be numbers the shaders can use: NaN or infinity would reach
/// every pixel.
fn check_lighting(config: &RendererConfig) -> Result<()> {
    let bad = |m: String| Err(Error::InvalidSetting(m));
    // A zero sun direction is the documented fallback here: straight up.
    if !config.sun_dir.iter().all(|v| v.is_finite()) {
        return bad(format!(
            "sun_dir {:?}: every component must be finite",
            config.sun_dir
        ));
    }
    if !(0.0..=1.0).contains(&config.ambient) {
        return bad(format!(
            "ambient {}: it must be a share from 0 to 1",
            config.ambient
        ));
    }
    if !config.sky.iter().all(|v| v.is_finite() && *v >= 0.0) {
        return bad(format!(
            "sky {:?}: every channel must be finite and at least 0",
            config.sky
        ));
    }
    Ok(())
}

/// An ambient-occlusion strength must be a number from 0 to 1.
fn check_ao_strength(strength: f32) -> Result<()> {
    if (0.0..=1.0).contains(&strength) {
        Ok(())
    } else {
        Err(Error::InvalidSetting(format!(
            "ambient-occlusion strength {strength}: it must be from 0 to 1"
        )))
    }
}

/// A render size must fit the adapter's 2D textures.
fn check_size(ctx: &GpuContext, width: u32, height: u32) -> Result<()> {
    let limit = ctx.caps.limits.max_texture_dimension_2d;
    for (what, value) in [("render width", width), ("render height", height)] {
        if value > limit {
            return Err(Error::TooLarge {
                what: what.into(),
                value: u64::from(value),
                limit_name: "max_texture_dimension_2d",
                limit: u64::from(limit),
            });
        }
    }
    Ok(())
}

impl Post {
    fn new(device: &wgpu::Device) -> Self {
        let float = wgpu::TextureSampleType::Float { filterable: false };
        let tonemap_layout = gpu::layout(device, "tonemap_layout", &[gpu::texture_entry(0, float)]);
        let depth_resolve_layout = gpu::layout(
            device,
            "depth_resolve_layout",
            &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: gpu::DEPTH_READ,
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: true,
                },
                count: None,
            }],
        );
        let depth_resolve = FullscreenPipeline {
            label: "depth_resolve",
            source: include_str!("shaders/depth_resolve.wgsl"),
            fragment_entry: "fs_depth_resolve",
            groups: &[Some(&depth_resolve_layout)],
            targets: &[],
            writes_depth: true,
            constants: &[],
        }
        .build(device);
        Self {
            tonemap_layout,
            tonemap: HashMap::new(),
            depth_resolve_layout,
            depth_resolve,
        }
    }

    /// Creates the tonemap pipeline for `format` if it does not exist yet.
    fn make_tonemap(&mut self, ctx: &GpuContext, format: wgpu::TextureFormat) {
        let layout = &self.tonemap_layout;
        self.tonemap.entry(format).or_insert_with(|| {
            // sRGB formats are encoded by the GPU, a float one is written linear.
            let encode = !(format.is_srgb() || format == wgpu::TextureFormat::Rgba16Float);
            let make = |label, writes_depth| {
                FullscreenPipeline {
                    label,
                    source: include_str!("shaders/tonemap.wgsl"),
                    fragment_entry: "fs_tonemap",
                    groups: &[Some(layout)],
                    targets: &[Some(wgpu::ColorTargetState {
                        format,
                        blend: None,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                    writes_depth,
                    constants: &[("SRGB_ENCODE", if encode { 1.0 } else { 0.0 })],
                }
                .build(&ctx.device)
            };
            (make("tonemap", false), make("tonemap_output_check", true))
        });
    }
}

impl SceneTargets {
    /// The targets for `size`; `(msaa, volumes)`: with MSAA targets, and with the volume
    /// depth at full size (else 1×1: no volume has been in view).
    fn new(
        ctx: &GpuContext,
        post: &Post,
        layouts: &SharedLayouts,
        scene: &SceneResources,
        medium: &MediumPass,
        size: (u32, u32),
        (msaa, volumes): (bool, bool),
    ) -> Self {
        use wgpu::TextureUsages as U;
        let device = &ctx.device;
        let target = |label, format, samples, usage| {
            gpu::TargetDesc {
                label,
                format,
                usage,
                size,
                samples,
            }
            .create(device)
        };
        let color = target(
            "scene_color",
            SCENE_FORMAT,
            1,
            U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC | U::COPY_DST,
        );
        let depth = target(
            "scene_depth",
            DEPTH_FORMAT,
            1,
            U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC,
        );
        let msaa = msaa.then(|| {
            (
                target(
                    "scene_color_msaa",
                    SCENE_FORMAT,
                    MSAA_SAMPLES,
                    U::RENDER_ATTACHMENT,
                ),
                target(
                    "scene_depth_msaa",
                    DEPTH_FORMAT,
                    MSAA_SAMPLES,
                    U::RENDER_ATTACHMENT | U::TEXTURE_BINDING,
                ),
            )
        });
        let boundary = target(
            "medium_boundary",
            DEPTH_FORMAT,
            1,
            U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_DST,
        );
        // The volumes' depths and the nearest entry's look: 1×1 until a volume is in view.
        let volume_target = |label, format| {
            gpu::TargetDesc {
                label,
                format,
                usage: U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_DST,
                size: if volumes { size } else { (1, 1) },
                samples: 1,
            }
            .create(device)
        };
        let volume_depth = volume_target("volume_depth", DEPTH_FORMAT);
        let volume_entry = volume_target("volume_entry", DEPTH_FORMAT);
        let entry_look = volume_target("entry_look", medium::ENTRY_LOOK_FORMAT);
        // The block layers: binding 4 (a storage buffer) or 5 (a table texture),
        // `shaders/common.wgsl`.
        let layers = match &scene.layer_table {
            Some(table) => (5, wgpu::BindingResource::TextureView(&table.view)),
            None => (4, scene.textures.layers.as_entire_binding()),
        };
        let group = |label,
                     boundary: &Target,
                     volume_depth: &Target,
                     entry: (&Target, &wgpu::TextureView)| {
            let resources = [
                (0, scene.frame_buffer.as_entire_binding()),
                (1, wgpu::BindingResource::TextureView(&scene.textures.view)),
                (2, wgpu::BindingResource::Sampler(&scene.textures.sampler)),
                (3, wgpu::BindingResource::TextureView(&boundary.view)),
                layers.clone(),
                (6, wgpu::BindingResource::Sampler(&scene.depth_sampler)),
                (7, wgpu::BindingResource::TextureView(&volume_depth.view)),
                (8, wgpu::BindingResource::TextureView(&scene.media.view)),
                (9, wgpu::BindingResource::TextureView(&entry.0.view)),
                (10, wgpu::BindingResource::TextureView(entry.1)),
            ];
            let entries =
                resources.map(|(binding, resource)| wgpu::BindGroupEntry { binding, resource });
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(label),
                layout: &layouts.scene,
                entries: &entries,
            })
        };
        let entry = (&volume_entry, &entry_look.view);
        let scene_group = group("scene", &boundary, &volume_depth, entry);
        // The pass writing the boundary reads the opaque depth in its place (ties with
        // cutout faces, `shaders/medium_boundary.wgsl`), and so do the passes writing the
        // volume depth and the volume entry (which reads the media table for the look).
        let boundary_scene_group = group("scene_writing_boundary", &depth, &volume_depth, entry);
        let exit_scene_group = group("scene_writing_volume_depth", &boundary, &depth, entry);
        let entry_scene_group = group(
            "scene_writing_volume_entry",
            &boundary,
            &volume_depth,
            (&depth, &scene.media.view),
        );
        let fog_group = medium.fog_group(device, &boundary);
        let tonemap_group =
            gpu::texture_group(device, "tonemap", &post.tonemap_layout, &[&color.view]);
        let depth_resolve_group = msaa.as_ref().map(|(_, d)| {
            gpu::texture_group(
                device,
                "depth_resolve",
                &post.depth_resolve_layout,
                &[&d.view],
            )
        });
        Self {
            size,
            color,
            depth,
            boundary,
            volume_depth,
            volumes,
            scene_group,
            boundary_scene_group,
            exit_scene_group,
            entry_scene_group,
            volume_entry,
            entry_look,
            fog_group,
            msaa,
            tonemap_group,
            depth_resolve_group,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use wgpu::TextureFormat as F;

    /// A game moves the renderer to a render thread or keeps it in an ECS resource: it must
    /// be `Send` (this fails to compile otherwise).
    #[test]
    fn renderer_is_send() {
        fn send<T: Send>() {}
        send::<super::Renderer>();
        send::<crate::ChunkStreamer>();
    }

    #[test]
    fn a_view_has_its_texture_format_unless_a_twin_is_declared() {
        assert_eq!(output_format(None, F::Bgra8Unorm), F::Bgra8Unorm);
        assert_eq!(output_format(None, F::Rgba8UnormSrgb), F::Rgba8UnormSrgb);
        let srgb = Some(F::Bgra8UnormSrgb);
        assert_eq!(output_format(srgb, F::Bgra8Unorm), F::Bgra8UnormSrgb);
        assert_eq!(
            output_format(srgb, F::Rgba8Unorm),
            F::Rgba8Unorm,
            "not its twin"
        );
    }

    #[test]
    fn daytime_lighting_is_valid_and_follows_the_sun() {
        let noon = Lighting::daytime(12.0);
        let dusk = Lighting::daytime(Lighting::SUNSET);
        for hour in [f32::NAN, -5.0, 6.0, 9.0, 12.0, 15.0, 18.0, 30.0] {
            Lighting::daytime(hour).validate().unwrap();
        }
        assert!(noon.sun_dir[1] > 0.9 && dusk.sun_dir[1] < 0.2 && dusk.sun_dir[1] > 0.0);
        assert!(
            Lighting::daytime(8.0).sun_dir[0] > 0.0,
            "morning sun in the east"
        );
        assert!(
            Lighting::daytime(16.0).sun_dir[0] < 0.0,
            "afternoon sun in the west"
        );
        assert!(noon.ambient > dusk.ambient);
        assert!(dusk.sky[0] > dusk.sky[2] && noon.sky[2] > noon.sky[0]);
        Lighting::default_day().validate().unwrap();
    }
}
