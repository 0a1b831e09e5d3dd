//! Weighted blended OIT (McGuire & Bavoil 2013), single-pass MRT and two-pass variants.
//!
//! Seeds 000 and 002 disagree, and each is wrong somewhere:
//! - Seed 000's accumulation (ONE, ONE on all four channels, output `(C·α·w, α·w)`) and its
//!   composite (`avg = accum.rgb / max(accum.a, 1e-5)`, then `mix(avg, opaque, reveal)`) are
//!   the paper's. Its revealage blend (ZERO, ONE_MINUS_SRC_ALPHA) only works if the shader's
//!   revealage output carries α in its alpha channel; a scalar `out float` has alpha 1, which
//!   zeroes the revealage at the first fragment. We write α to every channel and blend with
//!   ONE_MINUS_SRC (colour), which is right whatever the alpha channel holds.
//! - Seed 002's first pass blends the accumulation's alpha channel with (ZERO,
//!   ONE_MINUS_SRC_ALPHA), so `accum.a` holds Π(1 − α) instead of Σ(α·w), and its composite
//!   divides by that: colours come out scaled by Σ(α·w)/Π(1 − α), wrong for every stack
//!   (the "very transparent surfaces may appear darker" it reports). We keep its two-pass
//!   structure (one target per pass, for adapters without independent blend) with seed
//!   000's blend states, so both variants compute the same thing.
//!
//! fp16 overflow: with weights up to 3000·α, 22 near layers of α = 1 exceed 65504 and the
//! sums become infinite (then NaN in the ratio). Outputs are scaled by 1/64, which cancels
//! in the ratio and keeps sums finite up to ~1390 such layers; the composite also replaces
//! a non-finite average (black, coverage kept) so the scene never holds NaN or inf.
//!
//! RGBA8 fallback (seed 000): when `Rgba16Float` cannot be blended, the accumulation is
//! RGBA8 with outputs scaled so that eight maximum-weight layers fit; the average then has
//! eight bits of precision at best. Logged when chosen.

pub mod weights;

use crate::GpuContext;
use crate::oit::{OitConfig, Technique, TranslucentFrame, TranslucentTechnique};
use crate::pipelines::{
    self, COMMON_WGSL, DepthMode, SharedLayouts, clear_attachment, load_attachment,
    read_only_depth, texture_entry,
};

/// Revealage format (seed 000): one byte of Π(1 − α).
pub const REVEALAGE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R8Unorm;
/// Output scale with RGBA16F accumulation and headroom on.
pub const HEADROOM_SCALE: f32 = 1.0 / 64.0;
/// Output scale with RGBA8 accumulation: eight layers of the largest weight (3000) fit in 1.
pub const RGBA8_SCALE: f32 = 1.0 / (3000.0 * 8.0);

/// The accumulation format for `config` on this adapter (RGBA16F, or the RGBA8 fallback).
pub fn accumulation_format(ctx: &GpuContext, config: &OitConfig) -> wgpu::TextureFormat {
    if config.force_rgba8_accum || !ctx.caps.rgba16f_blendable {
        wgpu::TextureFormat::Rgba8Unorm
    } else {
        wgpu::TextureFormat::Rgba16Float
    }
}

/// The accumulation output scale for `config` on this adapter.
pub fn accum_scale(ctx: &GpuContext, config: &OitConfig) -> f32 {
    if accumulation_format(ctx, config) == wgpu::TextureFormat::Rgba8Unorm {
        RGBA8_SCALE
    } else if config.wboit_headroom {
        HEADROOM_SCALE
    } else {
        1.0
    }
}

const ADDITIVE: wgpu::BlendState = wgpu::BlendState {
    color: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    },
    alpha: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    },
};

const MULTIPLY_ONE_MINUS_SRC: wgpu::BlendState = wgpu::BlendState {
    color: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::Zero,
        dst_factor: wgpu::BlendFactor::OneMinusSrc,
        operation: wgpu::BlendOperation::Add,
    },
    alpha: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::Zero,
        dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha,
        operation: wgpu::BlendOperation::Add,
    },
};

#[derive(Debug)]
enum Accumulate {
    Mrt(wgpu::RenderPipeline),
    TwoPass {
        accumulate: wgpu::RenderPipeline,
        revealage: wgpu::RenderPipeline,
    },
}

#[derive(Debug)]
struct Targets {
    accumulation: wgpu::Texture,
    accumulation_view: wgpu::TextureView,
    revealage: wgpu::Texture,
    revealage_view: wgpu::TextureView,
    composite_group: wgpu::BindGroup,
}

/// WBOIT resources: pipelines and the two size-dependent targets.
#[derive(Debug)]
pub struct Wboit {
    accumulate: Accumulate,
    composite: wgpu::RenderPipeline,
    composite_layout: wgpu::BindGroupLayout,
    accum_format: wgpu::TextureFormat,
    targets: Targets,
}

impl Wboit {
    /// Creates the pipelines for `config.technique` (MRT or two-pass) and the targets.
    pub fn new(ctx: &GpuContext, layouts: &SharedLayouts, config: &OitConfig) -> Self {
        let device = &ctx.device;
        let accum_format = accumulation_format(ctx, config);
        if accum_format != wgpu::TextureFormat::Rgba16Float {
            log::warn!("WBOIT accumulates in RGBA8: RGBA16F blending unavailable or disabled");
        }
        let module = pipelines::shader(
            device,
            "wboit_accumulate",
            &[COMMON_WGSL, include_str!("accumulate.wgsl")],
        );
        let groups = [Some(&layouts.scene), Some(&layouts.chunk)];
        let target = |format, blend| {
            Some(wgpu::ColorTargetState {
                format,
                blend: Some(blend),
                write_mask: wgpu::ColorWrites::ALL,
            })
        };
        let accum_target = target(accum_format, ADDITIVE);
        let reveal_target = target(REVEALAGE_FORMAT, MULTIPLY_ONE_MINUS_SRC);
        let chunk = |label, entry, targets: &[Option<wgpu::ColorTargetState>]| {
            pipelines::chunk_pipeline(
                device,
                label,
                &module,
                entry,
                &groups,
                targets,
                DepthMode::ReadOnly,
                1,
            )
        };
        let accumulate = if config.technique == Technique::WboitTwoPass {
            Accumulate::TwoPass {
                accumulate: chunk("wboit_accumulate", "fs_accumulate", &[accum_target]),
                revealage: chunk("wboit_revealage", "fs_revealage", &[reveal_target]),
            }
        } else {
            Accumulate::Mrt(chunk(
                "wboit_accumulate_mrt",
                "fs_accumulate_mrt",
                &[accum_target, reveal_target],
            ))
        };
        let composite_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("wboit_composite_layout"),
            entries: &[
                texture_entry(0, wgpu::TextureSampleType::Float { filterable: false }),
                texture_entry(1, wgpu::TextureSampleType::Float { filterable: false }),
            ],
        });
        let composite = pipelines::fullscreen_pipeline(
            device,
            "wboit_composite",
            include_str!("composite.wgsl"),
            "fs_composite",
            &[Some(&composite_layout)],
            &[pipelines::scene_target(Some(
                wgpu::BlendState::ALPHA_BLENDING,
            ))],
            false,
            &[],
        );
        let targets = Self::targets(
            ctx,
            &composite_layout,
            accum_format,
            config.width,
            config.height,
        );
        Self {
            accumulate,
            composite,
            composite_layout,
            accum_format,
            targets,
        }
    }

    fn targets(
        ctx: &GpuContext,
        layout: &wgpu::BindGroupLayout,
        accum_format: wgpu::TextureFormat,
        width: u32,
        height: u32,
    ) -> Targets {
        use wgpu::TextureUsages as U;
        let usage = U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC;
        let make =
            |label, format| pipelines::target(&ctx.device, label, format, usage, width, height);
        let (accumulation, accumulation_view) = make("wboit_accumulation", accum_format);
        let (revealage, revealage_view) = make("wboit_revealage", REVEALAGE_FORMAT);
        let composite_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("wboit_composite"),
            layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&accumulation_view),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&revealage_view),
                },
            ],
        });
        Targets {
            accumulation,
            accumulation_view,
            revealage,
            revealage_view,
            composite_group,
        }
    }
}

const REVEAL_CLEAR: wgpu::Color = wgpu::Color {
    r: 1.0,
    g: 1.0,
    b: 1.0,
    a: 1.0,
};

impl TranslucentTechnique for Wboit {
    fn resize(&mut self, ctx: &GpuContext, width: u32, height: u32) {
        self.targets = Self::targets(
            ctx,
            &self.composite_layout,
            self.accum_format,
            width,
            height,
        );
    }

    fn render(
        &mut self,
        _ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        frame: &mut TranslucentFrame<'_>,
    ) {
        let t = &self.targets;
        match &self.accumulate {
            Accumulate::Mrt(pipeline) => {
                let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("wboit_accumulate_mrt"),
                    color_attachments: &[
                        clear_attachment(&t.accumulation_view, wgpu::Color::TRANSPARENT),
                        clear_attachment(&t.revealage_view, REVEAL_CLEAR),
                    ],
                    depth_stencil_attachment: read_only_depth(frame.depth),
                    timestamp_writes: frame.timestamps("translucent"),
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_pipeline(pipeline);
                frame.draw_chunks(&mut pass);
            }
            Accumulate::TwoPass {
                accumulate,
                revealage,
            } => {
                for (label, pipeline, view, clear) in [
                    (
                        "wboit_accumulate",
                        accumulate,
                        &t.accumulation_view,
                        wgpu::Color::TRANSPARENT,
                    ),
                    (
                        "wboit_revealage",
                        revealage,
                        &t.revealage_view,
                        REVEAL_CLEAR,
                    ),
                ] {
                    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                        label: Some(label),
                        color_attachments: &[clear_attachment(view, clear)],
                        depth_stencil_attachment: read_only_depth(frame.depth),
                        timestamp_writes: frame.timestamps("translucent"),
                        occlusion_query_set: None,
                        multiview_mask: None,
                    });
                    pass.set_pipeline(pipeline);
                    frame.draw_chunks(&mut pass);
                }
            }
        }
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("wboit_composite"),
            color_attachments: &[load_attachment(frame.target)],
            depth_stencil_attachment: None,
            timestamp_writes: frame.timestamps("composite"),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.composite);
        pass.set_bind_group(0, &t.composite_group, &[]);
        pass.draw(0..3, 0..1);
    }

    fn accumulation(&self) -> Option<&wgpu::Texture> {
        Some(&self.targets.accumulation)
    }

    fn revealage(&self) -> Option<&wgpu::Texture> {
        Some(&self.targets.revealage)
    }
}
