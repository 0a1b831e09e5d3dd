//! Depth peeling (seed 004): dual depth peeling with N layers, and front-to-back peeling
//! to convergence as a second exact reference.
//!
//! Dual (N even; presets 4, 6, 8): each iteration peels the nearest remaining layer (front
//! peel) and the farthest remaining layer strictly behind it (back peel), seed 004's two
//! renders per pass. Back layers are blended over the opaque image as they come (farthest
//! first); front layers are under-accumulated (nearest first) and composited over the
//! result at the end, so all 2·(N/2) layers are blended in depth order. Layers beyond N
//! (between the innermost front and back layers) are lost: the method's failure mode.
//!
//! Limits between passes are depth textures (ping-pong): a fragment is a candidate only
//! strictly between the previous front and back layers at its pixel; see `peel.wgsl` for
//! why no depth epsilon is needed.
//!
//! Early exit and adaptive layer count: an occlusion query counts the samples each front
//! peel wrote. Results come back a frame later without stalling; the next frame runs only
//! as many iterations as were non-empty, plus one that probes for more (never more than
//! N/2). A frame with no translucent chunk in view records nothing at all.
//!
//! Peel to convergence (exact): front peels only, each followed by reading its occlusion
//! count (a stall per layer), until a pass writes nothing. For measurement, not games.

use crate::oit::{OitConfig, TechniqueReport, TranslucentFrame, TranslucentTechnique};
use crate::pipelines::{
    self, COMMON_WGSL, DepthMode, SharedLayouts, clear_transparent, load_attachment,
};
use crate::readback::QueryReadback;
use crate::{DEPTH_FORMAT, GpuContext, SCENE_FORMAT};

/// Iterations peel-to-convergence runs at most (a safety net: 512 layers).
pub const MAX_CONVERGE_ITERATIONS: u32 = 512;

/// Which peeling.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PeelMode {
    /// Dual depth peeling of `layers` layers (even).
    Dual {
        /// Layers captured at most: front and back, two per iteration.
        layers: u32,
    },
    /// Front-to-back peeling until a pass writes nothing.
    Converge,
}

#[derive(Debug)]
struct Targets {
    front: [(wgpu::Texture, wgpu::TextureView); 2],
    back: [(wgpu::Texture, wgpu::TextureView); 2],
    front_layer: wgpu::TextureView,
    back_layer: wgpu::TextureView,
    front_acc: wgpu::TextureView,
    /// Limits for the front peel of an iteration writing slot `i`: (front[1-i], back[1-i]).
    front_limits: [wgpu::BindGroup; 2],
    /// Limits for the back peel writing slot `i`: (front[i], back[1-i]).
    back_limits: [wgpu::BindGroup; 2],
    /// Converge mode: (front[1-i], back[1]) with back[1] the opaque depth.
    converge_limits: [wgpu::BindGroup; 2],
    front_layer_group: wgpu::BindGroup,
    back_layer_group: wgpu::BindGroup,
    front_acc_group: wgpu::BindGroup,
}

/// Depth peeling resources.
#[derive(Debug)]
pub struct Peeling {
    mode: PeelMode,
    peel_front: wgpu::RenderPipeline,
    peel_back: wgpu::RenderPipeline,
    under: wgpu::RenderPipeline,
    over: wgpu::RenderPipeline,
    front_composite: wgpu::RenderPipeline,
    limits_layout: wgpu::BindGroupLayout,
    layer_layout: wgpu::BindGroupLayout,
    targets: Targets,
    /// Samples each front peel wrote (occlusion queries).
    counts: QueryReadback,
    /// Dual mode: iterations to run this frame (adaptive).
    iterations: u32,
    report: TechniqueReport,
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

impl Peeling {
    /// Creates pipelines and targets for `mode`.
    pub fn new(
        ctx: &GpuContext,
        layouts: &SharedLayouts,
        config: &OitConfig,
        mode: PeelMode,
    ) -> Self {
        let device = &ctx.device;
        let limits_layout = pipelines::textures_layout(
            device,
            "peel_limits_layout",
            wgpu::TextureSampleType::Depth,
            2,
        );
        let layer_layout = pipelines::textures_layout(
            device,
            "peel_layer_layout",
            wgpu::TextureSampleType::Float { filterable: false },
            1,
        );
        let module = pipelines::shader(device, "peel", &[COMMON_WGSL, include_str!("peel.wgsl")]);
        let groups = [
            Some(&layouts.scene),
            Some(&layouts.chunk),
            Some(&limits_layout),
        ];
        let peel = |label, depth| {
            pipelines::chunk_pipeline(
                device,
                label,
                &module,
                "fs_peel",
                &groups,
                &[pipelines::scene_target(None)],
                depth,
                1,
            )
        };
        let peel_front = peel("peel_front", DepthMode::Write);
        let peel_back = peel("peel_back", DepthMode::WriteFarthest);
        let blend = |label, entry, state| {
            pipelines::fullscreen_pipeline(
                device,
                label,
                include_str!("blend.wgsl"),
                entry,
                &[Some(&layer_layout)],
                &[pipelines::scene_target(Some(state))],
                false,
                &[],
            )
        };
        let under = blend("peel_under", "fs_under", UNDER);
        let over = blend("peel_over", "fs_over", wgpu::BlendState::ALPHA_BLENDING);
        let front_composite = blend(
            "peel_front_composite",
            "fs_front",
            wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING,
        );
        let targets = Self::targets(
            ctx,
            &limits_layout,
            &layer_layout,
            config.width,
            config.height,
        );
        let max_iterations = match mode {
            PeelMode::Dual { layers } => layers.max(2) / 2,
            PeelMode::Converge => MAX_CONVERGE_ITERATIONS,
        };
        Self {
            mode,
            peel_front,
            peel_back,
            under,
            over,
            front_composite,
            limits_layout,
            layer_layout,
            targets,
            counts: QueryReadback::new(
                ctx,
                "peel_counts",
                wgpu::QueryType::Occlusion,
                max_iterations,
            ),
            iterations: max_iterations,
            report: TechniqueReport::default(),
        }
    }

    fn targets(
        ctx: &GpuContext,
        limits_layout: &wgpu::BindGroupLayout,
        layer_layout: &wgpu::BindGroupLayout,
        width: u32,
        height: u32,
    ) -> Targets {
        let d = &ctx.device;
        use wgpu::TextureUsages as U;
        let depth = |label| {
            pipelines::target(
                d,
                label,
                DEPTH_FORMAT,
                U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_DST,
                width,
                height,
            )
        };
        let color = |label| {
            pipelines::target(
                d,
                label,
                SCENE_FORMAT,
                U::RENDER_ATTACHMENT | U::TEXTURE_BINDING,
                width,
                height,
            )
            .1
        };
        let front = [depth("peel_front_depth_0"), depth("peel_front_depth_1")];
        let back = [depth("peel_back_depth_0"), depth("peel_back_depth_1")];
        let limits = |label, a: &wgpu::TextureView, b: &wgpu::TextureView| {
            pipelines::texture_group(d, label, limits_layout, &[a, b])
        };
        let front_limits = [
            limits("peel_front_limits_0", &front[1].1, &back[1].1),
            limits("peel_front_limits_1", &front[0].1, &back[0].1),
        ];
        let back_limits = [
            limits("peel_back_limits_0", &front[0].1, &back[1].1),
            limits("peel_back_limits_1", &front[1].1, &back[0].1),
        ];
        let converge_limits = [
            limits("peel_converge_limits_0", &front[1].1, &back[1].1),
            limits("peel_converge_limits_1", &front[0].1, &back[1].1),
        ];
        let front_layer = color("peel_front_layer");
        let back_layer = color("peel_back_layer");
        let front_acc = color("peel_front_accumulation");
        let layer =
            |label, v: &wgpu::TextureView| pipelines::texture_group(d, label, layer_layout, &[v]);
        Targets {
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

    /// One geometry peel into `layer` with `depth` as attachment and `limits` as group 2.
    #[allow(clippy::too_many_arguments)]
    fn peel_pass(
        encoder: &mut wgpu::CommandEncoder,
        frame: &mut TranslucentFrame<'_>,
        pipeline: &wgpu::RenderPipeline,
        label: &'static str,
        layer: &wgpu::TextureView,
        depth: &wgpu::TextureView,
        depth_load: wgpu::LoadOp<f32>,
        limits: &wgpu::BindGroup,
        query: Option<(&wgpu::QuerySet, u32)>,
    ) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(label),
            color_attachments: &[clear_transparent(layer)],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: depth,
                depth_ops: Some(wgpu::Operations {
                    load: depth_load,
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: frame.timestamps("translucent"),
            occlusion_query_set: query.map(|q| q.0),
            multiview_mask: None,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(2, limits, &[]);
        if let Some((_, i)) = query {
            pass.begin_occlusion_query(i);
        }
        frame.draw_chunks(&mut pass);
        if query.is_some() {
            pass.end_occlusion_query();
        }
    }

    fn blend_pass(
        encoder: &mut wgpu::CommandEncoder,
        frame: &mut TranslucentFrame<'_>,
        pipeline: &wgpu::RenderPipeline,
        target: &wgpu::TextureView,
        group: &wgpu::BindGroup,
    ) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("peel_blend"),
            color_attachments: &[load_attachment(target)],
            depth_stencil_attachment: None,
            timestamp_writes: frame.timestamps("composite"),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, group, &[]);
        pass.draw(0..3, 0..1);
    }

    /// Clears the front accumulation, sets the first limits: front[1] at the near plane,
    /// back[1] a copy of the opaque depth.
    fn begin(&self, encoder: &mut wgpu::CommandEncoder, frame: &TranslucentFrame<'_>) {
        let t = &self.targets;
        drop(encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("peel_clear"),
            color_attachments: &[clear_transparent(&t.front_acc)],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &t.front[1].1,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        }));
        encoder.copy_texture_to_texture(
            frame.depth_texture.as_image_copy(),
            t.back[1].0.as_image_copy(),
            frame.depth_texture.size(),
        );
    }

    /// Front peel of iteration `i` into slot `i % 2`, with `limits`, then under-blends it.
    fn front_iteration(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        frame: &mut TranslucentFrame<'_>,
        i: u32,
        limits: &wgpu::BindGroup,
    ) {
        let t = &self.targets;
        let cur = (i % 2) as usize;
        // The candidates must also lie in front of the opaque surfaces: start from them.
        encoder.copy_texture_to_texture(
            frame.depth_texture.as_image_copy(),
            t.front[cur].0.as_image_copy(),
            frame.depth_texture.size(),
        );
        Self::peel_pass(
            encoder,
            frame,
            &self.peel_front,
            "peel_front",
            &t.front_layer,
            &t.front[cur].1,
            wgpu::LoadOp::Load,
            limits,
            Some((self.counts.set(), i)),
        );
        Self::blend_pass(
            encoder,
            frame,
            &self.under,
            &t.front_acc,
            &t.front_layer_group,
        );
    }

    fn render_dual(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        frame: &mut TranslucentFrame<'_>,
        max_iterations: u32,
    ) {
        // Adapt to the last counts that came back: non-empty iterations plus one probe.
        if let Some(counts) = self.counts.take() {
            let ran = counts.len() as u32;
            let non_empty = counts.iter().take_while(|&&c| c > 0).count() as u32;
            self.iterations = if non_empty == ran {
                ran + 1
            } else {
                non_empty + 1
            };
            self.report.layers = Some(2 * non_empty);
        }
        self.iterations = self.iterations.clamp(1, max_iterations);
        self.report.iterations = Some(self.iterations);
        self.begin(encoder, frame);

        for i in 0..self.iterations {
            let cur = (i % 2) as usize;
            let t = &self.targets;
            self.front_iteration(encoder, frame, i, &t.front_limits[cur]);
            Self::peel_pass(
                encoder,
                frame,
                &self.peel_back,
                "peel_back",
                &t.back_layer,
                &t.back[cur].1,
                wgpu::LoadOp::Clear(1.0),
                &t.back_limits[cur],
                None,
            );
            Self::blend_pass(
                encoder,
                frame,
                &self.over,
                frame.target,
                &t.back_layer_group,
            );
        }
        Self::blend_pass(
            encoder,
            frame,
            &self.front_composite,
            frame.target,
            &self.targets.front_acc_group,
        );
        self.counts.copy(encoder, 0..self.iterations);
    }

    fn render_converge(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        frame: &mut TranslucentFrame<'_>,
    ) {
        self.begin(encoder, frame);
        let mut layers = 0;
        for i in 0..MAX_CONVERGE_ITERATIONS {
            let cur = (i % 2) as usize;
            self.front_iteration(encoder, frame, i, &self.targets.converge_limits[cur]);
            // Wait for this pass's count: zero means every layer has been peeled.
            self.counts.copy(encoder, i..i + 1);
            pipelines::flush(ctx, encoder);
            self.counts.map();
            let written = self
                .counts
                .wait(ctx)
                .and_then(|c| c.first().copied())
                .unwrap_or(0);
            if written == 0 {
                break;
            }
            layers += 1;
        }
        self.report.layers = Some(layers);
        self.report.iterations = Some(layers + 1);
        Self::blend_pass(
            encoder,
            frame,
            &self.front_composite,
            frame.target,
            &self.targets.front_acc_group,
        );
    }
}

impl TranslucentTechnique for Peeling {
    fn resize(&mut self, ctx: &GpuContext, width: u32, height: u32) {
        self.targets = Self::targets(ctx, &self.limits_layout, &self.layer_layout, width, height);
    }

    fn render(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        frame: &mut TranslucentFrame<'_>,
    ) {
        match self.mode {
            PeelMode::Dual { layers } => self.render_dual(encoder, frame, layers.max(2) / 2),
            PeelMode::Converge => self.render_converge(ctx, encoder, frame),
        }
    }

    fn after_submit(&mut self) {
        self.counts.map();
    }

    fn report(&self) -> TechniqueReport {
        self.report
    }
}
