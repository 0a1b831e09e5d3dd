//! Stipple (screen-door) transparency, the low-end mode (seed 001): a translucent fragment
//! is kept or discarded by comparing its alpha (texture alpha × uniform alpha × chunk
//! alpha) with a Bayer threshold at its screen position. No targets, no blending, no
//! sorting; kept pixels write depth unless configured not to (seed 001's open question:
//! writing depth makes nearer stippled layers hide farther ones where they are kept, which
//! is what a screen door does; not writing lets farther layers show through the gaps of
//! nearer ones even where a nearer pixel was kept, which is wrong but softer).
//!
//! The shimmer when the camera moves is the technique's nature (seed 001: intentional).

pub mod bayer;

use crate::GpuContext;
use crate::oit::{OitConfig, TranslucentFrame, TranslucentTechnique};
use crate::pipelines::{self, COMMON_WGSL, DepthMode, SharedLayouts, load_attachment};

pub use bayer::{BayerSize, ShadingState, TransparencyMode};

/// WGSL of the dithering helpers (they read the Bayer levels from group 0, binding 3).
pub const DITHER_WGSL: &str = include_str!("dither.wgsl");

/// The stipple pipeline.
#[derive(Debug)]
pub struct Stipple {
    pipeline: wgpu::RenderPipeline,
    depth_write: bool,
}

impl Stipple {
    /// Creates the pipeline (depth write per `config.stipple_depth_write`).
    pub fn new(ctx: &GpuContext, layouts: &SharedLayouts, config: &OitConfig) -> Self {
        let module = pipelines::shader(
            &ctx.device,
            "stipple",
            &[COMMON_WGSL, DITHER_WGSL, include_str!("stipple.wgsl")],
        );

        let depth_write = config.stipple_depth_write;
        let pipeline = pipelines::chunk_pipeline(
            &ctx.device,
            "stipple",
            &module,
            "fs_stipple",
            &[Some(&layouts.scene), Some(&layouts.chunk)],
            &[pipelines::scene_target(None)],
            if depth_write {
                DepthMode::Write
            } else {
                DepthMode::ReadOnly
            },
            1,
        );
        Self {
            pipeline,
            depth_write,
        }
    }
}

impl TranslucentTechnique for Stipple {
    fn resize(&mut self, _ctx: &GpuContext, _width: u32, _height: u32) {}

    fn render(
        &mut self,
        _ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        frame: &mut TranslucentFrame<'_>,
    ) {
        let depth = if self.depth_write {
            Some(wgpu::RenderPassDepthStencilAttachment {
                view: frame.depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            })
        } else {
            pipelines::read_only_depth(frame.depth)
        };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("stipple"),
            color_attachments: &[load_attachment(frame.target)],
            depth_stencil_attachment: depth,
            timestamp_writes: frame.timestamps("translucent"),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        frame.draw_chunks(&mut pass);
    }
}
