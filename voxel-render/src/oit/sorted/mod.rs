//! Sorted alpha blending, the baseline (seed 003's forward pass): translucent chunk meshes
//! drawn back to front by the distance of their centres from the eye, blended
//! `SrcAlpha, OneMinusSrcAlpha` into the HDR scene colour, depth tested (nearer or equal:
//! seed 003's `LessEqual` in our reverse-Z) without depth write.
//!
//! Chunk order is right between chunks that do not overlap in depth, and wrong inside a
//! chunk, whose quads are drawn in mesher order: that is what `sorted-quads` fixes.

use crate::GpuContext;
use crate::oit::{TranslucentFrame, TranslucentTechnique};
use crate::pipelines::{
    self, COMMON_WGSL, DepthMode, SharedLayouts, load_attachment, read_only_depth,
};

/// The sorted baseline's pipeline.
#[derive(Debug)]
pub struct Sorted {
    pipeline: wgpu::RenderPipeline,
}

impl Sorted {
    /// Creates the blending pipeline.
    pub fn new(ctx: &GpuContext, layouts: &SharedLayouts) -> Self {
        let module = pipelines::shader(
            &ctx.device,
            "sorted",
            &[COMMON_WGSL, include_str!("sorted.wgsl")],
        );
        let pipeline = pipelines::chunk_pipeline(
            &ctx.device,
            "sorted",
            &module,
            "fs_sorted",
            &[Some(&layouts.scene), Some(&layouts.chunk)],
            &[pipelines::scene_target(Some(
                wgpu::BlendState::ALPHA_BLENDING,
            ))],
            DepthMode::ReadOnlyOrEqual,
            1,
        );
        Self { pipeline }
    }
}

impl TranslucentTechnique for Sorted {
    fn resize(&mut self, _ctx: &GpuContext, _width: u32, _height: u32) {}

    fn render(
        &mut self,
        _ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        frame: &mut TranslucentFrame<'_>,
    ) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("sorted"),
            color_attachments: &[load_attachment(frame.target)],
            depth_stencil_attachment: read_only_depth(frame.depth),
            timestamp_writes: frame.timestamps("translucent"),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        frame.draw_chunks(&mut pass);
    }
}
