//! Recording a frame: the camera and output checks, the frame uniforms, and the passes
//! in order (opaque, the game's stages, the technique, tonemap).

use std::sync::{Arc, Mutex, PoisonError};
// std's Instant panics in a browser; web_time's is std's elsewhere.
use web_time::Instant;

use glam::Mat4;
use voxel_core::BlockId;

#[cfg(doc)]
use super::RendererConfig;
use super::config::{OUTPUT_FORMATS, output_format, sun_unit};
use super::targets::MSAA_SAMPLES;

/// How much darker the chunks of odd levels of detail are drawn with
/// [`Renderer::set_level_bands`].
const LEVEL_BAND_DARKENING: f32 = 0.25;
use super::{FrameStats, Renderer};
use crate::bindings::{FrameUniforms, MEDIA_EYE, MEDIA_NONE, MEDIA_VOLUMES, MEDIA_WALK, NO_MEDIUM};
use crate::chunks::{DrawList, DrawMode, FrameDraws, Frustum, GpuChunk, MeshKind};
use crate::error::scoped;
use crate::gpu::{self, Depth, Pass};
use crate::light_volume::Lighting;
use crate::medium::{self, MediumLook};
use crate::oit::sorted::interleave::ChunkSequence;
use crate::oit::{FrameView, Technique, TechniqueReport, TranslucentFrame};
use crate::stages::{
    Clip, GameDraw, GameFrame, GameStages, GameWrites, Split, TranslucentContract,
};
use crate::submission::Outcome;
use crate::timing::{GpuPass, Timer};
use crate::{Camera, Error, Result};

impl Renderer {
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
    /// What changes between `render` and the submit (chunks uploaded or removed) never
    /// changes what this frame draws: the arena places it draws are reused only after
    /// [`Renderer::after_submit`] or the next `render`. Several frames may be recorded
    /// before one submit (in this encoder, or in others submitted in the order recorded):
    /// each frame's buffer writes are copies recorded into its encoder, so each draws with
    /// its own camera, settings and game data (a game writes its own with
    /// [`crate::stages::GameFrame::write_buffer`]); upload or remove chunks only between a
    /// submit and the next frame.
    ///
    /// The exact techniques (`Reference`, `PeelReference`) wait for GPU results in the
    /// middle of the frame: they submit what `encoder` holds so far and go on in a fresh
    /// encoder that replaces it (the order of commands is kept). After a frame recorded
    /// into another encoder that is not yet submitted, they refuse with
    /// [`Error::FrameOrder`] (that frame would run after their first half). Real-time
    /// techniques never submit.
    ///
    /// `encoder` must come from the renderer's device: wgpu offers no way to ask an
    /// encoder's device, and one of another device fails when it is finished.
    ///
    /// `game` draws the game's own geometry in the frame's stages: its opaque geometry
    /// after the world's, its translucent geometry composed by the technique with the
    /// chunks, its overlays before and after tonemapping (see [`crate::stages`]); a stage
    /// the game does not declare costs nothing, and `NoGame` declares none.
    pub fn render(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        output: &wgpu::TextureView,
        camera: &Camera,
        game: &mut dyn GameStages,
    ) -> Result<FrameStats> {
        // Objects of another wgpu instance make wgpu-core panic when it looks their ids up
        // (`context::guard_foreign`): the encoder and the output view are checked first,
        // and a panic of that kind later in the frame (a game's pipeline of another
        // instance, or an id that named an object of this one until then) is an error too,
        // the frame abandoned.
        let frame = crate::context::guard_foreign("an object given to the frame", || {
            self.render_frame(encoder, output, camera, game)
        })
        .and_then(|frame| frame);
        if frame.is_err() {
            // A frame that failed is not counted ([`crate::cost`]).
            drop(crate::cost::end_frame());
        }
        frame
    }

    /// [`Renderer::render`], counted when a frame is armed ([`crate::cost`]).
    fn render_frame(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        output: &wgpu::TextureView,
        camera: &Camera,
        game: &mut dyn GameStages,
    ) -> Result<FrameStats> {
        self.ctx.check_device()?;
        self.ctx.check_encoder(encoder)?;
        camera.validate()?;
        // The output's format (its tonemap pipeline made the first time), checked with it.
        let format = output_format(self.config.output_view_format, output.texture().format());
        if OUTPUT_FORMATS.contains(&format) {
            self.post.make_tonemap(&self.ctx, format);
        }
        self.check_output(output, format)?;
        if let Some(theirs) = game.context()
            && !theirs.same_device(&self.ctx)
        {
            return Err(Error::OtherDevice(format!(
                "the game's stages were made on {}, the renderer draws on {} (a renderer and \
                 the stages it draws share one GpuContext, cloned)",
                theirs.caps.adapter_name, self.ctx.caps.adapter_name
            )));
        }
        let stages = game.stages();
        if stages.translucent {
            let contract = self.oit.contract()?;
            game.follow_contract(&self.ctx, &contract);
            // A device lost in the game's code makes nothing valid.
            self.ctx.check_device()?;
            let current = contract.id;
            let built_for = game.translucent_contract_id();
            if built_for != Some(current) {
                return Err(Error::StaleContract {
                    built_for,
                    current,
                    technique: self.oit.technique().name(),
                });
            }
        }
        // Ends the last timed frame if it was submitted since; this one is timed unless
        // it is not.
        let last = self.frame_order(encoder)?;
        if format != self.config.output_format {
            log::info!(
                "drawing into {format:?} from now on (was {:?})",
                self.config.output_format
            );
            self.config.output_format = format;
        }
        let start = Instant::now();
        // Counting starts after the output's check, whose pass is never submitted.
        self.begin_cost();
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
        // The media fragments are seen through (`bindings::MEDIA_*`): a volume in view (a
        // translucent block with absorption; a technique that draws no translucency sees none)
        // or the eye inside an absorbing medium. Their passes read depths whose targets are
        // made the first time.
        let technique = self.oit.technique();
        let exact = technique.is_exact();
        let volumes = technique != Technique::OpaqueOnly
            && self
                .culled
                .translucent_slots()
                .any(|slot| self.chunks.by_slot(slot).is_some_and(GpuChunk::has_volume));
        let eye_absorbs = medium.is_some_and(|(_, look)| look.fog > 0.0);
        let media = match (exact, volumes, eye_absorbs) {
            (_, false, false) => MEDIA_NONE,
            (true, _, _) => MEDIA_WALK,
            (false, true, _) => MEDIA_VOLUMES,
            (false, false, true) => MEDIA_EYE,
        };
        let volume_targets = media == MEDIA_VOLUMES || media == MEDIA_WALK;
        if volume_targets && !self.targets.volumes {
            let (size, msaa) = (self.size(), self.config.msaa);
            let targets = scoped(&self.ctx.device, "making the volume depth", || {
                self.targets_for(size, msaa, true)
            })?;
            self.targets = targets;
        }
        // The frame's buffer writes land in its encoder, not at the next submit: a frame
        // recorded before this one and not yet submitted keeps its own camera, settings,
        // quad order and draws (see `FrameWrites`).
        let writes = Mutex::new(std::mem::take(&mut self.writes));
        // The technique's CPU work (it may reorder quads within their places).
        let view = FrameView {
            camera,
            view_proj,
            translucent: self.culled.translucent_positions(),
            layers: self.culled.translucent_layers(),
            game_objects: stages.translucent.then(|| game.translucent_objects()),
            writes: &writes,
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
            self.interleaver.look(camera.unit_forward());
            self.interleaver.order(
                game.translucent_objects(),
                camera.eye,
                &sequence,
                medium.is_some(),
                split_quads,
            );
        }
        let (order, splits, clips): (&[u32], &[Split], &[Clip]) = if sorts {
            self.interleaver.result()
        } else {
            (&[], &[], &[])
        };
        let game_sort_ms = sort_start.elapsed().as_secs_f64() * 1e3;
        let objects = if sorts {
            order.len()
        } else {
            game.translucent_objects().len()
        };
        let uniforms = self.frame_uniforms(
            camera,
            view_proj,
            medium.as_ref().map(|(b, look)| (*b, look)),
            media,
        );
        let mut writes = writes.into_inner().unwrap_or_else(PoisonError::into_inner);
        writes.write(&self.scene.frame_buffer, 0, bytemuck::bytes_of(&uniforms));
        let (eye_int, eye_frac) = camera.eye_split();
        let light = self.scene.light.uniforms(
            eye_int,
            eye_frac.to_array(),
            Lighting {
                sun_dir: sun_unit(self.config.sun_dir).to_array(),
                ambient: self.config.ambient,
                brightness: self.config.brightness,
            },
        );
        writes.write(self.scene.light.uniform(), 0, bytemuck::bytes_of(&light));
        let game_writes = GameWrites::open();
        let game_frame = GameFrame {
            camera,
            view_proj,
            eye_int,
            eye_frac,
            size: (w, h),
            opaque_samples: if self.config.msaa { MSAA_SAMPLES } else { 1 },
            output_format: self.config.output_format,
            sun_dir: sun_unit(self.config.sun_dir),
            ambient: self.config.ambient,
            brightness: self.config.brightness,
            order: sorts.then_some(order),
            light: &self.scene.light.group,
            writes: &game_writes,
        };
        if stages != crate::stages::Stages::default() {
            game.prepare(&self.ctx, &game_frame);
            // A device lost now (a reset can land in the game's code) makes nothing valid:
            // nothing more is recorded.
            self.ctx.check_device()?;
        }
        writes.append(&mut game_writes.take());
        let game = &*game;

        let builder = &mut self.builder;
        builder.clear();
        let lists = [MeshKind::Opaque, MeshKind::Cutout, MeshKind::Translucent]
            .map(|kind| builder.list(self.culled.meshes(kind)));
        // Per-chunk draws read the commands on the CPU.
        if self.config.draw == DrawMode::Indirect {
            self.chunks.upload_draws(&self.ctx, self.builder.commands());
        }
        // Every write of the frame, in its encoder before its first pass.
        writes.append(self.chunks.writes());
        let (copies, bytes) = writes.pending();
        if copies > 0 {
            crate::cost::uploaded(copies, bytes);
            crate::cost::created_buffer();
        }
        let recorded = writes.record(&self.ctx.device, encoder);
        self.writes = writes;
        recorded?;
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
        if volume_targets {
            let exits = (!exact).then_some((&t.exit_scene_group, &draws, translucent));
            self.medium
                .volume_depth_pass(encoder, &t.depth, &t.volume_depth, exits, timer);
        }
        if media == MEDIA_WALK {
            // Where a medium still open after the references' last fragment ends: the
            // nearest back face of a volume, quads grown (`walk_end` in `bindings.rs`).
            let exits = Some((&t.far_scene_group, &draws, translucent));
            self.medium
                .volume_depth_pass(encoder, &t.depth, &t.volume_far, exits, timer);
        }
        if media == MEDIA_VOLUMES {
            self.medium.volume_entry_pass(
                encoder,
                &t.depth,
                (&t.volume_entry, &t.entry_look, &t.opaque_copy),
                &t.entry_scene_group,
                &draws,
                translucent,
                timer,
            );
            self.medium.volume_entry2_pass(
                encoder,
                &t.depth,
                (&t.volume_entry2, &t.entry2_look),
                &t.entry2_scene_group,
                &draws,
                translucent,
                timer,
            );
            self.medium.volume_far_pass(
                encoder,
                &t.volume_far,
                &t.far_scene_group,
                &draws,
                translucent,
                timer,
            );
        }
        if media == MEDIA_EYE || media == MEDIA_VOLUMES {
            // The opaque picture seen through the media; each translucent fragment is seen
            // through its own part of the path (`shaders/path.wgsl`).
            self.medium
                .media_pass(encoder, &t.color, &t.scene_group, timer);
        }
        let game_draw = stages.translucent.then_some(GameDraw {
            stages: game,
            frame: &game_frame,
            objects,
            splits,
            clips,
            frame_buffer: &self.scene.frame_buffer,
            depth_sampler: &self.scene.depth_sampler,
            media: [
                &t.boundary.view,
                &t.volume_depth.view,
                &t.volume_entry.view,
                &t.entry_look.view,
                &t.volume_entry2.view,
                &t.entry2_look.view,
                &t.volume_far.view,
                &t.opaque_copy.view,
            ],
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
                volumes: media == MEDIA_WALK,
                game: game_draw.as_ref(),
            },
        )?;
        if stages.translucent {
            self.ctx.check_device()?;
        }
        if stages.hdr_overlay {
            let colors = [gpu::load(&t.color.view)];
            Pass::new("game_hdr_overlay", GpuPass::Game, &colors)
                .depth(Depth::ReadOnly(&t.depth.view))
                .record(encoder, timer, |pass| {
                    pass.game(|raw| game.hdr_overlay(raw, &game_frame))
                });
            self.ctx.check_device()?;
        }
        self.tonemap(encoder, output, timer);
        if stages.overlay {
            let colors = [gpu::load(output)];
            Pass::new("game_overlay", GpuPass::Game, &colors).record(encoder, timer, |pass| {
                pass.game(|raw| game.overlay(raw, &game_frame))
            });
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
        let counted = self.end_cost(encoder);
        let signal = self.submissions.attach(&self.ctx, encoder);
        if counted {
            self.cost.signal = signal;
            self.submissions.watch(signal);
        }
        self.last_encoder = Some(encoder_key(encoder));
        Ok(FrameStats {
            cpu_ms: start.elapsed().as_secs_f64() * 1e3,
            technique: self.oit.report(),
            ..stats
        })
    }

    /// What became of the last frame's encoder; an [`Error::FrameOrder`] when this frame
    /// cannot be recorded into `encoder` now. An exact technique (`Technique::stalls`)
    /// submits inside its frame, so the frame before it must be in the same encoder or
    /// submitted: recorded in another encoder and submitted after, that frame would run
    /// after this one's first half, over the targets both draw in. A frame whose encoder
    /// was submitted but not yet done is waited for (the exact frame waits anyway).
    fn frame_order(&mut self, encoder: &wgpu::CommandEncoder) -> Result<Outcome> {
        let last = self.settle_submission();
        let other = self
            .last_encoder
            .is_some_and(|key| key != encoder_key(encoder));
        if last != Outcome::Pending || !other || !self.oit.technique().stalls() {
            return Ok(last);
        }
        self.ctx.device.poll(wgpu::PollType::wait_indefinitely())?;
        match self.settle_submission() {
            Outcome::Pending => Err(Error::FrameOrder(format!(
                "{} submits inside its frame, but the frame before was recorded into another \
                 encoder that is not submitted yet: submit that encoder first, or record both \
                 frames into one",
                self.oit.technique().name()
            ))),
            settled => Ok(settled),
        }
    }

    /// The camera a frame of `camera` is drawn with: no translucent face closer than the
    /// near plane's corners (the near plane shrinks for the frame), and an eye within
    /// `crate::MIN_NEAR` of a translucent face moved off it to its medium's side
    /// (`medium::guard`). Tools that reason about the picture's geometry (the lab's quad
    /// edges) use this one.
    pub fn drawn_camera(&self, camera: &Camera) -> Camera {
        let (w, h) = self.size();
        medium::guard(
            &camera.normalized(),
            f64::from(w) / f64::from(h),
            &self.chunks,
        )
    }

    /// [`Renderer::render`] into `output`, submitted (for tools and tests).
    pub fn render_and_submit(
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
        let stats = self.render(&mut encoder, output, camera, game)?;
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
        // Before anything compares its ids with the renderer's: ids of another instance can
        // name the renderer's own objects.
        check_texture_device(&self.ctx, t)?;
        if *t == self.targets.color.texture {
            return Err(Error::Output(
                "the renderer's own scene colour texture (Renderer::scene_color): the tonemap \
                 reads it while it writes the output; draw into a texture of your own"
                    .into(),
            ));
        }
        if self.checked_view.as_ref() == Some(output) {
            return Ok(());
        }
        let Some((_, check)) = self.post.tonemap.get(&want) else {
            return Err(Error::Output(format!("no tonemap pipeline for {want:?}")));
        };
        let device = &self.ctx.device;
        let checked = crate::context::guard_foreign("the output view", || {
            scoped(device, "checking the output view", || {
                let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("output_view_check"),
                });
                let color = [gpu::load(output)];
                // One pass (about 10 µs on lavapipe): the scene depth beside the output fails
                // on another size, the pipeline on another view format, the tonemap's group on
                // an output it reads, a view of another device on that.
                Pass::new("output_view_check", GpuPass::Tonemap, &color)
                    .depth(Depth::Load(&self.targets.depth.view))
                    .record(&mut encoder, None, |pass| {
                        pass.set_pipeline(check);
                        pass.set_bind_group(0, &self.targets.tonemap_group, &[]);
                    });
                // Never submitted: recording and finishing are what validate.
                drop(encoder.finish());
            })
        })
        .and_then(|checked| checked);
        if checked.is_ok() {
            self.checked_view = Some(output.clone());
        }
        checked.map_err(|e| {
            let why = match &e {
                Error::Gpu { error, .. } => error.to_string(),
                // Another instance's view (`context::guard_foreign`).
                Error::OtherDevice(_) => return e,
                other => other.to_string(),
            };
            // wgpu's `DeviceMismatch`: "Device with '…' label of TextureView … doesn't
            // match Device …".
            if why.contains("doesn't match Device") {
                return Error::OtherDevice(format!(
                    "the output view: {}",
                    why.lines().map(str::trim).collect::<Vec<_>>().join(" ")
                ));
            }
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
            self.chunks.set_alpha(&self.ctx, pos, t.min(1.0), true);
            if t >= 1.0 {
                done.push(pos);
            }
        }
        for pos in done {
            self.fading.remove(&pos);
        }
        self.frame_index = self.frame_index.wrapping_add(1);
    }

    /// The frame's uniforms (group 0's `frame`).
    fn frame_uniforms(
        &self,
        camera: &Camera,
        view_proj: Mat4,
        medium: Option<(BlockId, &MediumLook)>,
        media: u32,
    ) -> FrameUniforms {
        let (eye_int, eye_frac) = camera.eye_split();
        let sun = sun_unit(self.config.sun_dir);
        let (w, h) = self.size();
        let tan_y = (camera.fov_y_deg.to_radians() / 2.0).tan();
        let tan_x = tan_y * f64::from(w) / f64::from(h);
        let shadows = self.scene.sun.uniforms(eye_int);
        FrameUniforms {
            view_proj: view_proj.to_cols_array_2d(),
            eye_int: eye_int.map(|v| v.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32),
            near: camera.near as f32,
            eye_frac: eye_frac.to_array(),
            far: camera.far as f32,
            sun_dir: sun.to_array(),
            ambient: self.config.ambient,
            brightness: self.config.brightness,
            sky: self.config.sky,
            level_bands: if self.level_bands {
                LEVEL_BAND_DARKENING
            } else {
                0.0
            },
            viewport: [w as f32, h as f32],
            medium: medium.map_or(NO_MEDIUM, |(b, _)| u32::from(b.0)),
            ao_strength: self.config.ao_strength,
            tan_half: [tan_x as f32, tan_y as f32],
            volumes: media,
            medium_look: medium.map_or([0.0; 4], |(_, look)| {
                let [r, g, b] = look.color;
                [r, g, b, look.fog]
            }),
            sun_offset: shadows.offset,
            sun_on: shadows.on,
            sun_size: shadows.size,
            sun_table: self.scene.sun_table,
            sun_wrap: shadows.wrap,
            sun_pad: 0,
            sun_tops: shadows.tops,
        }
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
                .opaque()
                .record(encoder, timer, |pass| match (kind, game) {
                    (GpuPass::Game, Some((game, frame))) => {
                        pass.game(|raw| game.opaque(raw, frame))
                    }
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
        if let (Some(group), Some(resolve)) = (&t.depth_resolve_group, &self.post.depth_resolve) {
            Pass::new("depth_resolve", GpuPass::Opaque, &[])
                .depth(Depth::Clear(&t.depth.view, 0.0))
                .record(encoder, timer, |pass| {
                    pass.set_pipeline(resolve);
                    pass.set_bind_group(0, group, &[]);
                    pass.draw_full_screen();
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
        let reads = [&self.targets.color.view];
        let tonemap = Pass::new("tonemap", GpuPass::Tonemap, &colors)
            .opaque()
            .reads(&reads);
        tonemap.record(encoder, timer, |pass| {
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &self.targets.tonemap_group, &[]);
            pass.draw_full_screen();
        });
    }
}

/// Tells encoders apart while they live (wgpu's id; no two live encoders share one).
/// An `Error::OtherDevice` when `texture` is not of `ctx`'s device. wgpu tells an object's
/// device by no public means, and ids of another `wgpu::Instance` can name the renderer's
/// own objects (wgpu-core then takes them for those), but an error a texture causes goes to
/// its own device: a view of one mip level past its last is asked for, labelled to say why,
/// inside a validation scope of the renderer's device, which catches that error only when
/// the texture is its own, every frame. Another device's error goes to that device's
/// handler: wgpu's default one panics, which is caught here; a game's own handler is told
/// of the view the label names.
#[cfg(not(target_arch = "wasm32"))]
fn check_texture_device(ctx: &crate::GpuContext, texture: &wgpu::Texture) -> Result<()> {
    let scope = ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
    let probed = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        drop(texture.create_view(&wgpu::TextureViewDescriptor {
            label: Some(
                "voxel_render's check of the output's device (a view past the last mip level, \
                 on purpose): the renderer was given a texture of another device or instance",
            ),
            base_mip_level: texture.mip_level_count(),
            mip_level_count: Some(1),
            ..Default::default()
        }));
    }));
    let caught = pollster::block_on(scope.pop());
    match probed {
        Ok(()) if caught.is_some() => Ok(()),
        Err(payload)
            if !payload
                .downcast_ref::<String>()
                .is_some_and(|m| m.contains("wgpu error")) =>
        {
            std::panic::resume_unwind(payload)
        }
        _ => Err(Error::OtherDevice(
            "the output view's texture is of another device than the renderer's, or of \
             another wgpu::Instance (wgpu's error went to that device, not the renderer's); \
             draw into a texture of the renderer's device (Renderer::context), and make every \
             device of a game through one wgpu::Instance"
                .into(),
        )),
    }
}

/// In a browser each object is the browser's own and wgpu validates devices itself.
#[cfg(target_arch = "wasm32")]
fn check_texture_device(_ctx: &crate::GpuContext, _texture: &wgpu::Texture) -> Result<()> {
    Ok(())
}

fn encoder_key(encoder: &wgpu::CommandEncoder) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    encoder.hash(&mut h);
    h.finish()
}
