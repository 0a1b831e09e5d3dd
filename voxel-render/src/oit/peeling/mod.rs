//! Depth peeling: dual depth peeling (Bavoil & Myers 2008) with N layers, and
//! front-to-back peeling (Everitt 2001) to convergence as a second exact reference.
//!
//! Dual (N even; presets 4, 6, 8): each iteration peels the nearest remaining layer (front
//! peel) and the farthest remaining layer strictly behind it (back peel), in two
//! renders per iteration (the paper does both in one pass with MAX blending). Back layers are blended over the opaque image as they come (farthest
//! first); front layers are under-accumulated (nearest first) and composited over the
//! result at the end, so all 2·(N/2) layers are blended in depth order. Layers beyond N
//! (between the innermost front and back layers) are lost: the method's failure mode.
//!
//! Limits between passes are depth textures (ping-pong): a fragment is a candidate only
//! strictly between the previous front and back layers at its pixel; see `peel.wgsl` for
//! why no depth epsilon is needed. They are the technique's group 2.
//!
//! Early exit and adaptive layer count: an occlusion query counts the samples each front
//! peel wrote. Results come back a frame later without stalling; the next frame runs only
//! as many iterations as were non-empty, plus one that probes for more (never more than
//! N/2). A frame with no translucent chunk in view records nothing at all. In a browser's
//! WebGPU (no occlusion queries there through wgpu) every frame runs all N/2.
//!
//! Peel to convergence (exact): front peels only, each followed by reading its occlusion
//! count (a stall per layer), until a pass writes nothing, at most [`MAX_PEEL_LAYERS`]
//! layers (reported when reached). For measurement, not games.

use crate::context::Capabilities;
use crate::gpu::{
    self, ChunkPipeline, Depth, DepthMode, FullscreenPipeline, Pass, SidedPipeline, Target,
};
use crate::ladder::Need;
use crate::oit::{
    OitConfig, Setup, Technique, TechniqueKind, TechniqueReport, TranslucentFrame,
    TranslucentTechnique,
};
use crate::readback::QueryReadback;
use crate::stages::{TranslucentVariant, game_group, game_layout, game_prelude};
use crate::timing::GpuPass;
use crate::{DEPTH_FORMAT, Error, GpuContext, Result, SCENE_FORMAT};

/// Most layers either kind of peeling captures: dual peeling's setting may not exceed it,
/// and peeling to convergence stops there (reporting that it did). Each layer costs a
/// pass over every translucent mesh; 512 is past any depth complexity the lab uses (its
/// densest scene has 200 sheets) and keeps a frame bounded.
pub const MAX_PEEL_LAYERS: u32 = 512;

/// Settings of dual depth peeling. Every field has a reasoned default.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PeelingSettings {
    /// Layers dual depth peeling captures at most (even, 2 to [`MAX_PEEL_LAYERS`]).
    pub layers: u32,
}

impl Default for PeelingSettings {
    fn default() -> Self {
        Self {
            // The depth complexity of glass-over-water views in our terrain stays below 8.
            layers: 8,
        }
    }
}

impl PeelingSettings {
    /// The layer count must be even and within 2 to [`MAX_PEEL_LAYERS`].
    pub fn validate(&self) -> Result<()> {
        if (2..=MAX_PEEL_LAYERS).contains(&self.layers) && self.layers.is_multiple_of(2) {
            Ok(())
        } else {
            Err(Error::InvalidSetting(format!(
                "peeling.layers {}: dual depth peeling takes an even number of layers from 2 to {MAX_PEEL_LAYERS}",
                self.layers
            )))
        }
    }
}

/// What peeling found in the last frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PeelReport {
    /// Layers found (dual: from the last counts read back; converge: this frame's).
    pub layers: Option<u32>,
    /// Peeling iterations run this frame (each a front and, in dual mode, a back peel).
    pub iterations: u32,
    /// Converge mode: the frame stopped at [`MAX_PEEL_LAYERS`] with layers left.
    pub truncated: bool,
}

/// Which peeling.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum PeelMode {
    /// Dual depth peeling of `layers` layers (even).
    Dual {
        /// Layers captured at most: front and back, two per iteration.
        layers: u32,
    },
    /// Front-to-back peeling until a pass writes nothing.
    Converge,
}

impl PeelMode {
    /// Iterations a frame runs at most.
    fn max_iterations(self) -> u32 {
        match self {
            PeelMode::Dual { layers } => layers.max(2) / 2,
            PeelMode::Converge => MAX_PEEL_LAYERS,
        }
    }
}

/// The two depth limits of a peel pass and the medium state: the group the chunk
/// pipelines bind, and the views (a game's group holds them too).
#[derive(Debug)]
struct Limits {
    group: wgpu::BindGroup,
    views: [wgpu::TextureView; 3],
}

#[derive(Debug)]
struct Targets {
    front: [Target; 2],
    back: [Target; 2],
    front_layer: Target,
    back_layer: Target,
    front_acc: Target,
    /// Converge mode: the medium state after the layers so far (`peel_state` in
    /// `limits.wgsl`), read from [0] and written into [1] (copied back after each peel:
    /// where a pass writes nothing the state stays). 1×1 in dual mode.
    state: [Target; 2],
    /// The group of the volume after the last layer: `state[1]`.
    last_group: wgpu::BindGroup,
    /// Limits for the front peel of an iteration writing slot `i`: (front[1-i], back[1-i]).
    front_limits: [Limits; 2],
    /// Limits for the back peel writing slot `i`: (front[i], back[1-i]).
    back_limits: [Limits; 2],
    /// Converge mode: (front[1-i], back[1]) with back[1] the opaque depth.
    converge_limits: [Limits; 2],
    front_layer_group: wgpu::BindGroup,
    back_layer_group: wgpu::BindGroup,
    front_acc_group: wgpu::BindGroup,
}

/// The group-2 entries of the peel pipelines: the front and back limits, the medium state.
fn limit_entries() -> [wgpu::BindGroupLayoutEntry; 3] {
    [
        gpu::texture_entry(0, gpu::DEPTH_READ),
        gpu::texture_entry(1, gpu::DEPTH_READ),
        gpu::texture_entry(2, wgpu::TextureSampleType::Uint),
    ]
}

/// The medium state's format (`peel_state` in `limits.wgsl`).
const STATE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Uint;

/// The peel pass's own WGSL (after the shared chunk code or a game's prelude).
fn peel_own_wgsl() -> String {
    [include_str!("limits.wgsl"), include_str!("state.wgsl")].concat()
}

/// Depth peeling resources.
#[derive(Debug)]
pub(crate) struct Peeling {
    device: wgpu::Device,
    mode: PeelMode,
    peel_front: SidedPipeline,
    peel_back: SidedPipeline,
    under: wgpu::RenderPipeline,
    over: wgpu::RenderPipeline,
    front_composite: wgpu::RenderPipeline,
    /// Converge mode: the volume after each pixel's last layer.
    last_volume: wgpu::RenderPipeline,
    last_layout: wgpu::BindGroupLayout,
    limits_layout: wgpu::BindGroupLayout,
    layer_layout: wgpu::BindGroupLayout,
    game_layout: wgpu::BindGroupLayout,
    targets: Targets,
    /// Samples each front peel wrote (occlusion queries).
    counts: QueryReadback,
    /// Dual mode: iterations to run this frame (adaptive).
    iterations: u32,
    /// Whether the device counts samples for the adaptation (not in a browser's WebGPU,
    /// [`Capabilities::occlusion_queries`]): without, every frame runs all iterations.
    adaptive: bool,
    report: PeelReport,
    /// Copies the opaque depth into the limits.
    depth_copy: gpu::DepthCopy,
}

const UNDER: wgpu::BlendState = wgpu::BlendState {
    color: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::OneMinusDstAlpha,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    },
    alpha: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::OneMinusDstAlpha,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    },
};

impl TechniqueKind for Peeling {
    type Key = PeelMode;

    fn is_exact(technique: Technique) -> bool {
        technique == Technique::PeelReference
    }

    /// Peeling to convergence waits for each layer's occlusion count before the next.
    fn needs(technique: Technique, _: &OitConfig, _: &Capabilities) -> Vec<Need> {
        match technique {
            Technique::PeelReference => vec![Need::WaitForGpu],
            _ => Vec::new(),
        }
    }

    fn key(technique: Technique, config: &OitConfig, _: &Capabilities) -> PeelMode {
        match technique {
            Technique::PeelReference => PeelMode::Converge,
            _ => PeelMode::Dual {
                layers: config.peeling.layers,
            },
        }
    }

    fn create(setup: &Setup, technique: Technique, config: &OitConfig) -> Result<Self> {
        let mode = Self::key(technique, config, &setup.ctx.caps);
        let device = &setup.ctx.device;
        let limits_layout = gpu::layout(device, "peel_limits_layout", &limit_entries());
        let layer_layout = gpu::textures_layout(
            device,
            "peel_layer_layout",
            wgpu::TextureSampleType::Float { filterable: false },
            1,
        );
        let module = gpu::shader(
            device,
            "peel",
            &[
                &crate::bindings::common_wgsl(),
                &peel_own_wgsl(),
                include_str!("peel.wgsl"),
            ],
        );
        let groups = setup.layouts.with(&[&limits_layout]);
        // Peeling to convergence passes the medium on from layer to layer.
        let converge = mode == PeelMode::Converge;
        let (entry, targets) = if converge {
            ("fs_peel_state", peel_targets(true))
        } else {
            ("fs_peel", peel_targets(false))
        };
        let peel = |label, depth| {
            ChunkPipeline {
                label,
                module: &module,
                fragment_entry: entry,
                groups: &groups,
                targets: &targets,
                depth,
                samples: 1,
            }
            .build_sided(device)
        };
        let blend = |label, fragment_entry, state| {
            FullscreenPipeline {
                label,
                source: include_str!("blend.wgsl"),
                fragment_entry,
                groups: &[Some(&layer_layout)],
                targets: &[gpu::scene_target(Some(state))],
                writes_depth: false,
                constants: &[],
            }
            .build(device)
        };
        let last_layout =
            gpu::textures_layout(device, "peel_last_layout", wgpu::TextureSampleType::Uint, 1);
        let last_volume = FullscreenPipeline {
            label: "peel_last_volume",
            source: &(crate::bindings::scene_volume_wgsl(1) + include_str!("last.wgsl")),
            fragment_entry: "fs_last_volume",
            groups: &[Some(&last_layout), Some(&setup.layouts.scene)],
            targets: &[gpu::scene_target(Some(UNDER))],
            writes_depth: false,
            constants: &[],
        }
        .build(device);
        let layouts = (&limits_layout, &layer_layout, &last_layout);
        let targets = Self::targets(device, layouts, setup.size, mode);
        let max_iterations = mode.max_iterations();
        Ok(Self {
            device: device.clone(),
            mode,
            peel_front: peel("peel_front", DepthMode::Write),
            peel_back: peel("peel_back", DepthMode::WriteFarthest),
            under: blend("peel_under", "fs_under", UNDER),
            over: blend("peel_over", "fs_over", wgpu::BlendState::ALPHA_BLENDING),
            front_composite: blend(
                "peel_front_composite",
                "fs_front",
                wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING,
            ),
            game_layout: game_layout(device, "peel_game", &limit_entries()),
            last_volume,
            last_layout,
            limits_layout,
            layer_layout,
            targets,
            counts: QueryReadback::new(
                &setup.ctx,
                "peel_counts",
                wgpu::QueryType::Occlusion,
                max_iterations,
            ),
            iterations: max_iterations,
            adaptive: setup.ctx.caps.occlusion_queries(),
            report: PeelReport::default(),
            depth_copy: gpu::DepthCopy::new(&setup.ctx),
        })
    }
}

impl Peeling {
    /// The targets for `size`; `layouts` are the limits', the layers' and the last
    /// volume's.
    fn targets(
        d: &wgpu::Device,
        layouts: (
            &wgpu::BindGroupLayout,
            &wgpu::BindGroupLayout,
            &wgpu::BindGroupLayout,
        ),
        size: (u32, u32),
        mode: PeelMode,
    ) -> Targets {
        let (limits_layout, layer_layout, last_layout) = layouts;
        use wgpu::TextureUsages as U;
        let depth = |label| {
            let usage = U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_DST;
            gpu::target(d, label, DEPTH_FORMAT, usage, size)
        };
        let color = |label| {
            let usage = U::RENDER_ATTACHMENT | U::TEXTURE_BINDING;
            gpu::target(d, label, SCENE_FORMAT, usage, size)
        };
        let front = [depth("peel_front_depth_0"), depth("peel_front_depth_1")];
        let back = [depth("peel_back_depth_0"), depth("peel_back_depth_1")];
        let state_size = if mode == PeelMode::Converge {
            size
        } else {
            (1, 1)
        };
        let state = ["peel_state_0", "peel_state_1"].map(|label| {
            let usage = U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC | U::COPY_DST;
            gpu::target(d, label, STATE_FORMAT, usage, state_size)
        });
        let limits = |label, a: &Target, b: &Target| Limits {
            group: gpu::texture_group(d, label, limits_layout, &[&a.view, &b.view, &state[0].view]),
            views: [a.view.clone(), b.view.clone(), state[0].view.clone()],
        };
        let front_limits = [
            limits("peel_front_limits_0", &front[1], &back[1]),
            limits("peel_front_limits_1", &front[0], &back[0]),
        ];
        let back_limits = [
            limits("peel_back_limits_0", &front[0], &back[1]),
            limits("peel_back_limits_1", &front[1], &back[0]),
        ];
        let converge_limits = [
            limits("peel_converge_limits_0", &front[1], &back[1]),
            limits("peel_converge_limits_1", &front[0], &back[1]),
        ];
        let front_layer = color("peel_front_layer");
        let back_layer = color("peel_back_layer");
        let front_acc = color("peel_front_accumulation");
        let layer = |label, t: &Target| gpu::texture_group(d, label, layer_layout, &[&t.view]);
        let last_group = gpu::texture_group(d, "peel_last", last_layout, &[&state[1].view]);
        Targets {
            state,
            last_group,
            front_layer_group: layer("peel_front_layer", &front_layer),
            back_layer_group: layer("peel_back_layer", &back_layer),
            front_acc_group: layer("peel_front_accumulation", &front_acc),
            front_limits,
            back_limits,
            converge_limits,
            front,
            back,
            front_layer,
            back_layer,
            front_acc,
        }
    }

    /// One geometry peel into `layer` with `depth` as attachment and `limits` as group 2,
    /// counting the samples it writes into occlusion query `query` when given.
    fn peel_pass(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        frame: &TranslucentFrame<'_>,
        back: bool,
        depth: Depth<'_>,
        limits: &Limits,
        query: Option<u32>,
    ) {
        let game = frame.game.map(|g| {
            let own = limits
                .views
                .each_ref()
                .map(wgpu::BindingResource::TextureView);
            (
                g,
                game_group(&self.device, "peel_game", &self.game_layout, g, &own),
            )
        });
        let (label, pipeline, layer) = if back {
            ("peel_back", &self.peel_back, &self.targets.back_layer)
        } else {
            ("peel_front", &self.peel_front, &self.targets.front_layer)
        };
        let converge = self.mode == PeelMode::Converge;
        let state = &self.targets.state;
        let mut colors = vec![gpu::clear(&layer.view, wgpu::Color::TRANSPARENT)];
        if converge {
            colors.push(gpu::load(&state[1].view));
        }
        let pass = Pass {
            occlusion: query.map(|_| self.counts.set()),
            ..Pass::new(label, GpuPass::Translucent, &colors).depth(depth)
        };
        // With volumes in view, peeling to convergence needs the faces where rays leave
        // them (seen from behind) too.
        let two_sided = frame.two_sided || (converge && frame.volumes);
        pass.record(encoder, frame.timer, |pass| {
            pass.set_pipeline(pipeline.get(two_sided));
            pass.set_bind_group(2, &limits.group, &[]);
            if let Some(i) = query {
                pass.begin_occlusion_query(i);
            }
            frame.draw_chunks(pass);
            if let Some((g, group)) = &game {
                g.draw_all(pass, usize::from(back), group);
            }
            if query.is_some() {
                pass.end_occlusion_query();
            }
        });
        if converge {
            // Where the pass wrote nothing, the state stays what it was.
            encoder.copy_texture_to_texture(
                state[1].texture.as_image_copy(),
                state[0].texture.as_image_copy(),
                state[1].texture.size(),
            );
        }
    }

    /// Blends `group`'s layer into `target` with `pipeline`.
    fn blend_pass(
        encoder: &mut wgpu::CommandEncoder,
        frame: &TranslucentFrame<'_>,
        pipeline: &wgpu::RenderPipeline,
        target: &wgpu::TextureView,
        group: &wgpu::BindGroup,
    ) {
        let colors = [gpu::load(target)];
        Pass::new("peel_blend", GpuPass::Composite, &colors).record(encoder, frame.timer, |pass| {
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, group, &[]);
            pass.draw_full_screen();
        });
    }

    /// Clears the front accumulation, sets the first limits: front[1] at the near plane,
    /// back[1] a copy of the opaque depth.
    fn begin(&self, encoder: &mut wgpu::CommandEncoder, frame: &TranslucentFrame<'_>) {
        let t = &self.targets;
        let mut colors = vec![gpu::clear(&t.front_acc.view, wgpu::Color::TRANSPARENT)];
        let converge = self.mode == PeelMode::Converge;
        if converge {
            // No medium before the first layer.
            colors.push(gpu::clear(&t.state[1].view, wgpu::Color::TRANSPARENT));
        }
        Pass {
            timing: None,
            ..Pass::new("peel_clear", GpuPass::Translucent, &colors)
                .depth(Depth::Clear(&t.front[1].view, 1.0))
        }
        .record(encoder, None, |_| {});
        if converge {
            encoder.copy_texture_to_texture(
                t.state[1].texture.as_image_copy(),
                t.state[0].texture.as_image_copy(),
                t.state[1].texture.size(),
            );
        }
        let timing = GpuPass::Translucent;
        self.depth_copy
            .record(encoder, frame.depth, &t.back[1], timing, frame.timer);
    }

    /// Front peel of iteration `i` into slot `i % 2`, with `limits` (its samples counted
    /// into query `i` when `count`), then under-blends it.
    fn front_iteration(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        frame: &TranslucentFrame<'_>,
        (i, count): (u32, bool),
        limits: &Limits,
    ) {
        let t = &self.targets;
        let cur = (i % 2) as usize;
        // The candidates must also lie in front of the opaque surfaces: start from them.
        let timing = GpuPass::Translucent;
        self.depth_copy
            .record(encoder, frame.depth, &t.front[cur], timing, frame.timer);
        self.peel_pass(
            encoder,
            frame,
            false,
            Depth::Load(&t.front[cur].view),
            limits,
            count.then_some(i),
        );
        Self::blend_pass(
            encoder,
            frame,
            &self.under,
            &t.front_acc.view,
            &t.front_layer_group,
        );
    }

    fn render_dual(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        frame: &TranslucentFrame<'_>,
    ) -> Result<()> {
        let max_iterations = self.mode.max_iterations();
        // Adapt to the last counts that came back: non-empty iterations plus one probe.
        // A failed readback keeps the last count (logged): peeling stays correct, only
        // the adaptation waits.
        match self.counts.take() {
            Ok(Some(counts)) => {
                let ran = counts.len() as u32;
                let non_empty = counts.iter().take_while(|&&c| c > 0).count() as u32;
                self.iterations = if non_empty == ran {
                    ran + 1
                } else {
                    non_empty + 1
                };
                self.report.layers = Some(2 * non_empty);
            }
            Ok(None) => {}
            Err(e) => log::warn!("depth peeling keeps its layer count: {e}"),
        }
        self.iterations = self.iterations.clamp(1, max_iterations);
        self.report.iterations = self.iterations;
        self.begin(encoder, frame);

        let t = &self.targets;
        for i in 0..self.iterations {
            let cur = (i % 2) as usize;
            self.front_iteration(encoder, frame, (i, self.adaptive), &t.front_limits[cur]);
            self.peel_pass(
                encoder,
                frame,
                true,
                Depth::Clear(&t.back[cur].view, 1.0),
                &t.back_limits[cur],
                None,
            );
            Self::blend_pass(
                encoder,
                frame,
                &self.over,
                &frame.target.view,
                &t.back_layer_group,
            );
        }
        Self::blend_pass(
            encoder,
            frame,
            &self.front_composite,
            &frame.target.view,
            &t.front_acc_group,
        );
        if self.adaptive {
            self.counts.copy(encoder, 0..self.iterations);
        }
        Ok(())
    }

    fn render_converge(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        frame: &TranslucentFrame<'_>,
    ) -> Result<()> {
        self.begin(encoder, frame);
        let mut layers = 0;
        let mut truncated = true;
        for i in 0..MAX_PEEL_LAYERS {
            let cur = (i % 2) as usize;
            let limits = &self.targets.converge_limits[cur];
            self.front_iteration(encoder, frame, (i, true), limits);
            // Wait for this pass's count: zero means every layer has been peeled.
            self.counts.copy(encoder, i..i + 1);
            gpu::flush(ctx, encoder)?;
            let written =
                self.counts.wait(ctx)?.first().copied().ok_or_else(|| {
                    Error::ReadbackData("an occlusion count came back empty".into())
                })?;
            if written == 0 {
                truncated = false;
                break;
            }
            layers += 1;
        }
        if truncated {
            log::warn!("peel-to-convergence stopped at {MAX_PEEL_LAYERS} layers with more left");
        }
        self.report = PeelReport {
            layers: Some(layers),
            iterations: layers + u32::from(!truncated),
            truncated,
        };
        if frame.volumes {
            let colors = [gpu::load(&self.targets.front_acc.view)];
            Pass::new("peel_last_volume", GpuPass::Composite, &colors).record(
                encoder,
                frame.timer,
                |pass| {
                    pass.set_pipeline(&self.last_volume);
                    pass.set_bind_group(0, &self.targets.last_group, &[]);
                    pass.set_bind_group(1, frame.scene, &[]);
                    pass.draw_full_screen();
                },
            );
        }
        Self::blend_pass(
            encoder,
            frame,
            &self.front_composite,
            &frame.target.view,
            &self.targets.front_acc_group,
        );
        Ok(())
    }
}

impl TranslucentTechnique for Peeling {
    fn resize(&mut self, ctx: &GpuContext, width: u32, height: u32) -> Result<()> {
        let layouts = (&self.limits_layout, &self.layer_layout, &self.last_layout);
        self.targets = Self::targets(&ctx.device, layouts, (width, height), self.mode);
        Ok(())
    }

    fn render(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        frame: &TranslucentFrame<'_>,
    ) -> Result<()> {
        match self.mode {
            PeelMode::Dual { .. } => self.render_dual(encoder, frame),
            PeelMode::Converge => self.render_converge(ctx, encoder, frame),
        }
    }

    fn variants(&self) -> Vec<TranslucentVariant> {
        let output = "struct OitOutput {\n    @location(0) color: vec4<f32>,\n    \
            @builtin(frag_depth) depth: f32,\n};\n\n\
            // The fragment, at the depth the exact methods give an object, is a layer\n\
            // candidate strictly between the limits, or dropped.\n\
            fn oit_output(position: vec4<f32>, color: vec4<f32>) -> OitOutput {\n    \
            let p = oit_object_position(position);\n    \
            if !peel_candidate(p) || color.a <= 0.0 {\n        discard;\n    }\n    \
            return OitOutput(fogged(p.xy, p.z, color), p.z);\n}\n";
        let variant = |name, depth| TranslucentVariant {
            name,
            wgsl: game_prelude(&peel_own_wgsl(), output),
            targets: peel_targets(false),
            depth_stencil: gpu::depth_state(depth),
            layout: self.game_layout.clone(),
        };
        match self.mode {
            PeelMode::Dual { .. } => vec![
                variant("peel_front", DepthMode::Write),
                variant("peel_back", DepthMode::WriteFarthest),
            ],
            // The layer holds the volume in front of the object; the medium goes on.
            PeelMode::Converge => vec![TranslucentVariant {
                name: "peel_front",
                wgsl: game_prelude(&peel_own_wgsl(), CONVERGE_OUTPUT),
                targets: peel_targets(true),
                depth_stencil: gpu::depth_state(DepthMode::Write),
                layout: self.game_layout.clone(),
            }],
        }
    }

    fn report(&self) -> TechniqueReport {
        TechniqueReport {
            peeling: Some(self.report),
            ..TechniqueReport::default()
        }
    }
}

/// The colour targets of a peel pass: the layer, and in peeling to convergence the medium
/// state after it.
fn peel_targets(converge: bool) -> Vec<Option<wgpu::ColorTargetState>> {
    let mut targets = vec![gpu::scene_target(None)];
    if converge {
        targets.push(Some(wgpu::ColorTargetState {
            format: STATE_FORMAT,
            blend: None,
            write_mask: wgpu::ColorWrites::ALL,
        }));
    }
    targets
}

/// A game's `oit_output` in peeling to convergence (after `state.wgsl`).
const CONVERGE_OUTPUT: &str = "struct OitOutput {\n    @location(0) color: vec4<f32>,\n    \
    @location(1) state: vec4<u32>,\n    @builtin(frag_depth) depth: f32,\n};\n\n\
    // The fragment, at the depth the exact methods give an object, is a layer candidate\n\
    // strictly between the limits, or dropped; its layer holds the volume in front of it.\n\
    fn oit_output(position: vec4<f32>, color: vec4<f32>) -> OitOutput {\n    \
    let p = oit_object_position(position);\n    \
    if !peel_candidate(p) || color.a <= 0.0 {\n        discard;\n    }\n    \
    let layer = peel_layer(p, color, vec4<f32>(0.0), OBJECT_BLOCK);\n    \
    return OitOutput(layer.color, layer.state, p.z);\n}\n";
