//! The renderer a game embeds: chunks on the GPU and the passes of a frame in the usual
//! forward order: opaque (optional 4× MSAA, resolved), cutout, translucent (the selected technique,
//! depth-tested read-only against the opaque depth), composite over the opaque colour,
//! tonemap to the output format.

pub(crate) mod config;
mod frame;
mod targets;
#[cfg(test)]
mod tests;

use std::sync::Arc;

use voxel_core::{BlockRegistry, ChunkPos, World, WorldPos};
use voxel_mesh::ChunkMeshes;
use wgpu::util::DeviceExt;

use crate::bindings::{FrameUniforms, SharedLayouts, common_wgsl};
use crate::chunks::{ChunkStore, Culled, DrawBuilder, DrawMode, PosMap};
use crate::cost::{CostQueries, FrameCost};
use crate::error::scoped;
use crate::fetch::{QuadFetch, TableTexture};
use crate::gpu::{self, ChunkPipeline, DepthMode};
use crate::ladder;
use crate::light_volume::{ChunkLight, LightVolume};
use crate::medium::{self, MediumLook, MediumPass};
use crate::oit::sorted::interleave::Interleaver;
use crate::oit::{OitConfig, OitManager, Setup, Technique, TechniqueReport};
use crate::submission::{FrameWrites, Outcome, Submissions};
use crate::sun::{SunRegion, SunVolume};
use crate::textures::BlockTextures;
use crate::timing::{GpuTimes, Timer};
use crate::{Error, GpuContext, Result};

pub(crate) use config::{Lighting, OUTPUT_FORMATS, RendererConfig};
use config::{check_ao_strength, check_lighting, check_output_format, check_size};
use targets::{MSAA_SAMPLES, Post, SceneResources, SceneTargets};

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
    /// Bytes of the chunk records (32 per slot, with room to grow).
    pub record_bytes: u64,
    /// Bytes of the indirect draw commands (16 per mesh drawn, with room to grow).
    pub indirect_bytes: u64,
    /// Pages of the arena.
    pub pages: usize,
    /// Free ranges over all pages.
    pub free_ranges: usize,
    /// Bytes of the chunks' light: the arena's light pages (as large as its pages, once a
    /// lit chunk was uploaded) and the palettes (`docs/light.md`); 0 in a world drawn unlit.
    pub light_bytes: u64,
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
    /// Whether chunks of odd levels of detail are drawn darker ([`Renderer::set_level_bands`]).
    level_bands: bool,
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
    /// The frame's buffer writes (kept between frames for their room).
    writes: FrameWrites,
    /// The encoder the last frame ended in (`frame::encoder_key`).
    last_encoder: Option<u64>,
    /// What the next frame's cost is counted with ([`crate::cost`]), once asked for.
    cost: CostCounting,
}

/// Counting what frames ask of the GPU ([`crate::cost`]): armed for one frame at a time.
#[derive(Debug, Default)]
pub(crate) struct CostCounting {
    /// The next frame is counted.
    armed: bool,
    /// The query sets, made the first time a frame is counted.
    queries: Option<CostQueries>,
    /// The last counted frame: what was counted, each pass's query slot, slots used.
    counted: Option<(FrameCost, Vec<Option<u32>>, u32)>,
    /// The submission signal of its encoder (`submission::Submissions::attach`).
    signal: u64,
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
        let sun = SunVolume::new(device, registry);
        // Each block's look as a medium, then the sun filters (`sun.rs`).
        let media_data: Vec<[f32; 4]> = looks
            .iter()
            .map(|l| {
                l.map_or([0.0; 4], |l| {
                    [l.color[0], l.color[1], l.color[2], l.absorption]
                })
            })
            .chain(sun.filters().iter().copied())
            .collect();
        let media = TableTexture::new(
            device,
            "block_media",
            wgpu::TextureFormat::Rgba32Float,
            media_data.len(),
        );
        media.write(&ctx.queue, 0, bytemuck::cast_slice(&media_data));
        let scene = SceneResources {
            frame_buffer: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("frame_uniforms"),
                contents: bytemuck::bytes_of(&<FrameUniforms as bytemuck::Zeroable>::zeroed()),
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            }),
            textures,
            layer_table,
            media,
            sun_table: looks.len() as u32,
            sun,
            light: LightVolume::new(device, registry),
            depth_sampler: gpu::depth_sampler(device),
        };
        let (opaque, cutout) = Self::opaque_pipelines(ctx, &layouts, config.msaa);
        let mut post = Post::new(device, ctx.caps.msaa4);
        post.make_tonemap(ctx, config.output_format);
        let medium = MediumPass::new(ctx, &layouts);
        let size = (config.width, config.height);
        let targets = SceneTargets::new(ctx, &post, &layouts, &scene, size, (config.msaa, false));
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
            level_bands: false,
            fading: PosMap::default(),
            culled: Culled::default(),
            builder: DrawBuilder::default(),
            checked_view: None,
            writes: FrameWrites::default(),
            last_encoder: None,
            cost: CostCounting::default(),
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
            &[&common_wgsl(), include_str!("../shaders/opaque.wgsl")],
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

    /// Turns sun shadows on over `region` (see [`SunRegion::around`]), its cells read from
    /// `world` now: the sun's light on the lit chunks' faces in the region is dimmed and
    /// tinted by the blocks along its ray, per fragment, in every technique
    /// (`docs/light.md`, "Sun shadows"). Faces outside the region, and chunks drawn unlit,
    /// keep the sky light for the sun's. A region the adapter cannot hold (more than
    /// [`MAX_SUN_CHUNKS`] chunks an axis, or its largest 3D texture) or a world over another
    /// registry is an [`Error::InvalidSetting`] that changes nothing. Edits reach the
    /// shadows through [`Renderer::update_sun_shadows`].
    pub fn set_sun_shadows(&mut self, world: &World, region: SunRegion) -> Result<()> {
        self.ctx.check_device()?;
        let ctx = &self.ctx;
        let sun = &mut self.scene.sun;
        scoped(&ctx.device, "sun shadows", || {
            sun.set(&ctx.device, &ctx.queue, world, region)
        })??;
        self.targets = self.targets_for(self.size(), self.config.msaa, self.targets.volumes);
        Ok(())
    }

    /// Reads chunks `chunks` of `world` again into the sun shadows (the chunks an edit
    /// changed: [`World::take_dirty`]'s, before meshing); chunks outside the region, or
    /// without sun shadows, are skipped. An unloaded chunk reads as air.
    pub fn update_sun_shadows(&mut self, world: &World, chunks: &[ChunkPos]) {
        self.scene.sun.update(&self.ctx.queue, world, chunks);
    }

    /// Moves the sun shadows' region so that its x and z centre on the chunk of `eye` (a
    /// player's position, each frame or when it changes chunk), its size and heights kept,
    /// and reads only the chunks that come into it from `world` (32 KiB each; the volume
    /// is a torus, the chunks that stay are not touched). Returns how many chunks were
    /// read: 0 while the eye stays in its chunk, or without sun shadows. Chunks loaded
    /// later into the region reach it through [`Renderer::update_sun_shadows`].
    pub fn follow_sun_shadows(&mut self, world: &World, eye: WorldPos) -> usize {
        let (centre, _) = eye.split();
        self.scene.sun.follow(&self.ctx.queue, world, centre)
    }

    /// Turns sun shadows off (frees the volume).
    pub fn clear_sun_shadows(&mut self) {
        self.scene.sun.clear(&self.ctx.device);
        self.targets = self.targets_for(self.size(), self.config.msaa, self.targets.volumes);
    }

    /// The region the sun shadows cover, if on.
    pub fn sun_region(&self) -> Option<SunRegion> {
        self.scene.sun.region()
    }

    /// Turns the light volume on over `region` (see [`SunRegion::around`]; at most
    /// [`MAX_LIGHT_CHUNKS`](crate::MAX_LIGHT_CHUNKS) chunks an axis), the light of its chunks read now through
    /// `light` ([`voxel_core::LightField::shared`], or a lit streamer's
    /// `ChunkStreamer::light_chunk`) with `world`'s blocks: a game's content and its own
    /// shaders are lit by the light field there ([`light_wgsl`](crate::light_volume::light_wgsl),
    /// `docs/light.md`, "Light for a game's things"). A region the adapter cannot hold or
    /// a world over another registry is an [`Error::InvalidSetting`] that changes nothing.
    /// Edits reach it through [`Renderer::update_light_volume`].
    pub fn set_light_volume(
        &mut self,
        world: &World,
        light: ChunkLight<'_>,
        region: SunRegion,
    ) -> Result<()> {
        self.ctx.check_device()?;
        let ctx = &self.ctx;
        let volume = &mut self.scene.light;
        scoped(&ctx.device, "light volume", || {
            volume.set(&ctx.device, &ctx.queue, world, light, region)
        })?
    }

    /// Reads chunks `chunks` again into the light volume (those whose light an edit
    /// changed: [`voxel_core::LightField::take_changed`]'s); chunks outside the region, or
    /// without a volume, are skipped. A chunk without blocks or light reads as unlit.
    pub fn update_light_volume(
        &mut self,
        world: &World,
        light: ChunkLight<'_>,
        chunks: &[ChunkPos],
    ) {
        self.scene
            .light
            .update(&self.ctx.queue, world, light, chunks);
    }

    /// Moves the light volume's region so that its x and z centre on the chunk of `eye`,
    /// as [`Renderer::follow_sun_shadows`] does the sun's; returns how many chunks were
    /// read (256 KiB each).
    pub fn follow_light_volume(
        &mut self,
        world: &World,
        light: ChunkLight<'_>,
        eye: WorldPos,
    ) -> usize {
        let (centre, _) = eye.split();
        self.scene
            .light
            .follow(&self.ctx.queue, world, light, centre)
    }

    /// Turns the light volume off (frees it): a game's things are lit as before light
    /// existed.
    pub fn clear_light_volume(&mut self) {
        self.scene.light.clear(&self.ctx.device);
    }

    /// The region the light volume covers, if on.
    pub fn light_region(&self) -> Option<SunRegion> {
        self.scene.light.region()
    }

    /// The layout of the group a game binds the light volume with (the frame's
    /// [`crate::stages::GameFrame::light`]), for its pipelines: a uniform and two 3D
    /// textures and a sampler, visible to the vertex and fragment stages, as
    /// [`light_wgsl`](crate::light_volume::light_wgsl) declares them.
    pub fn light_layout(&self) -> &wgpu::BindGroupLayout {
        &self.scene.light.layout
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
        self.upload_keyed(pos, 0, meshes)
    }

    /// Uploads or replaces chunk `pos` of level of detail `level` (1 to
    /// [`voxel_core::MAX_LEVEL`]): the meshes of a [`voxel_core::TerrainGenerator::generate_level_chunk`]
    /// chunk (or any chunk of cells `2^level` blocks wide in x and z and one block high),
    /// meshed as any chunk is. It is drawn by every technique as a chunk is, and fades in as
    /// one does. Level 0 is [`Renderer::upload_chunk`].
    ///
    /// It is kept under the full-detail chunk where it starts, [`level_key`]`(level, pos)`,
    /// and replaces whatever chunk was kept there; [`Renderer::remove_chunk`] of that key
    /// removes it. Levels are meant to lie in rings around the eye, each a square (in
    /// chunks, x and z) holding the finer ones: the order of translucent meshes across
    /// levels is exact then (coarser first), and overlapping levels draw both. A position
    /// whose key lies outside the `i32` world is an error.
    pub fn upload_level_chunk(
        &mut self,
        level: u8,
        pos: ChunkPos,
        meshes: &ChunkMeshes,
    ) -> Result<()> {
        self.ctx.check_device()?;
        let key = level_key(level, pos).ok_or_else(|| {
            Error::InvalidSetting(format!(
                "level {level} chunk {pos:?}: levels go from 0 to {}, and the chunk must \
                 start inside the i32 world",
                voxel_core::MAX_LEVEL
            ))
        })?;
        self.upload_keyed(key, level, meshes)
    }

    fn upload_keyed(&mut self, pos: ChunkPos, level: u8, meshes: &ChunkMeshes) -> Result<()> {
        let new = self.chunks.get(pos).is_none();
        self.chunks.upload(&self.ctx, pos, level, meshes)?;
        if new && self.config.fade_in_frames > 0 && self.chunks.get(pos).is_some() {
            self.fading.insert(pos, self.frame_index);
            self.chunks.set_alpha(&self.ctx, pos, 0.0, false);
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
    /// `OitManager::prebuild`. Returns the technique built (after its fallback on this
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
        let (arena, records, palettes) = self.chunks.memory();
        ChunkMemory {
            arena_bytes: arena.bytes,
            quad_bytes: arena.used_bytes,
            record_bytes: records,
            indirect_bytes: self.chunks.indirect_bytes(),
            pages: arena.pages,
            free_ranges: arena.fragments,
            light_bytes: arena.light_bytes + palettes,
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

    /// The sun direction, ambient share, brightness and sky in force.
    pub fn lighting(&self) -> Lighting {
        Lighting {
            sun_dir: self.config.sun_dir,
            ambient: self.config.ambient,
            brightness: self.config.brightness,
            sky: self.config.sky,
        }
    }

    /// Changes the sun direction, ambient share, brightness and sky from the next frame on: they are
    /// frame uniforms and the clear colour, so nothing is rebuilt and no chunk is uploaded
    /// again. Invalid values ([`Lighting::validate`]) are an error and change nothing.
    pub fn set_lighting(&mut self, lighting: Lighting) -> Result<()> {
        lighting.validate()?;
        self.config.sun_dir = lighting.sun_dir;
        self.config.ambient = lighting.ambient;
        self.config.brightness = lighting.brightness;
        self.config.sky = lighting.sky;
        Ok(())
    }

    /// Shows where the levels of detail lie (a debugging view): with `on`, every technique
    /// draws the chunks of odd levels ([`Renderer::upload_level_chunk`]; cells 2, 8, 32
    /// blocks wide) a quarter darker, so the rings show as bands. Applied at the next frame.
    pub fn set_level_bands(&mut self, on: bool) {
        self.level_bands = on;
    }

    /// Changes how many frames new chunks take to fade in (0: no fade).
    pub fn set_fade_in_frames(&mut self, frames: u32) {
        self.config.fade_in_frames = frames;
        if frames == 0 {
            for (pos, _) in self.fading.drain() {
                self.chunks.set_alpha(&self.ctx, pos, 1.0, false);
            }
        }
    }

    /// The chunks on the GPU ([`crate::low_level::chunks`]).
    pub(crate) fn chunks(&self) -> &ChunkStore {
        &self.chunks
    }

    /// The transparency manager ([`crate::low_level::oit`]).
    pub(crate) fn oit(&self) -> &OitManager {
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

    /// Counts what the next frame asks of the GPU ([`crate::cost`]): its passes' draws,
    /// state changes and clears, and, where the device has the queries and the technique
    /// never submits inside its frame, their fragments and samples. Read with
    /// [`Renderer::frame_cost`] once that frame is submitted.
    pub(crate) fn count_next_frame(&mut self) {
        self.cost.armed = true;
    }

    /// What the last counted frame asked of the GPU ([`Renderer::count_next_frame`]),
    /// waiting for its query results once its encoder is submitted; `None` when no frame
    /// was counted since the last call, or when the counted frame's encoder was dropped
    /// unsubmitted (nothing of it ran; it is forgotten). While that encoder is neither
    /// submitted nor dropped: `Error::FrameOrder`, and the frame is kept for a call after
    /// the submit.
    pub(crate) fn frame_cost(&mut self) -> Result<Option<FrameCost>> {
        if self.cost.counted.is_none() {
            return Ok(None);
        }
        match self.submissions.outcome_of(&self.ctx, self.cost.signal) {
            Outcome::Pending => {
                return Err(Error::FrameOrder(
                    "the counted frame's encoder is not submitted yet: its cost is known once \
                     the encoder is submitted (frame_cost returns it then)"
                        .into(),
                ));
            }
            Outcome::Dropped => {
                self.cost.counted = None;
                return Ok(None);
            }
            Outcome::Submitted | Outcome::Nothing => {}
        }
        let Some((mut cost, slots, used)) = self.cost.counted.take() else {
            return Ok(None);
        };
        if let Some(queries) = &self.cost.queries
            && cost.measured
        {
            self.ctx.check_device()?;
            let results = queries.read(&self.ctx, used)?;
            crate::cost::fill(&mut cost, &slots, &results);
        }
        Ok(Some(cost))
    }

    /// Starts counting the frame about to be recorded when one is armed.
    pub(crate) fn begin_cost(&mut self) {
        if !std::mem::take(&mut self.cost.armed) {
            return;
        }
        // The exact techniques submit inside their frame and record hundreds of passes:
        // their commands are counted, not measured; nor is anything on a device whose
        // occlusion queries do not count samples (GL's say only whether any passed).
        let measure = !self.oit.technique().stalls() && self.ctx.caps.counts_samples();
        if measure && self.cost.queries.is_none() {
            let statistics = self
                .ctx
                .caps
                .features
                .contains(wgpu::Features::PIPELINE_STATISTICS_QUERY);
            self.cost.queries = Some(CostQueries::new(&self.ctx.device, statistics));
        }
        let slots = self
            .cost
            .queries
            .as_ref()
            .filter(|_| measure)
            .map(CostQueries::slots);
        let (w, h) = self.size();
        crate::cost::begin_frame(u64::from(w) * u64::from(h), slots);
    }

    /// Ends the counted frame, if one is: resolves its queries at the end of `encoder`.
    /// Whether one was.
    pub(crate) fn end_cost(&mut self, encoder: &mut wgpu::CommandEncoder) -> bool {
        let Some((cost, slots, used)) = crate::cost::end_frame() else {
            return false;
        };
        if let Some(q) = &self.cost.queries
            && cost.measured
        {
            q.resolve(encoder, used);
        }
        self.cost.counted = Some((cost, slots, used));
        true
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
}

/// Copies what the manager holds (technique after fallback) into a renderer's config.
fn config_with(mine: &mut OitConfig, manager: &OitConfig) {
    mine.clone_from(manager);
}

/// The key of chunk `pos` of level of detail `level` on the GPU: the full-detail chunk
/// where it starts (`pos` times `2^level` in x and z). `None` past
/// [`voxel_core::MAX_LEVEL`] or outside the `i32` world.
pub fn level_key(level: u8, pos: ChunkPos) -> Option<ChunkPos> {
    if level > voxel_core::MAX_LEVEL {
        return None;
    }
    let s = voxel_core::level_scale(level);
    let wide = |v: i32| i32::try_from(i64::from(v) * s).ok();
    let key = ChunkPos::new(wide(pos.x)?, pos.y, wide(pos.z)?);
    key.is_valid().then_some(key)
}
