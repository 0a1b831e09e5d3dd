//! Weighted blended OIT (McGuire & Bavoil 2013), single-pass MRT and two-pass variants.
//!
//! Two common ways of writing it are each wrong somewhere:
//! - The one-pass form's accumulation (ONE, ONE on all four channels, output `(C·α·w, α·w)`) and its
//!   composite (`avg = accum.rgb / max(accum.a, 1e-5)`, then `mix(avg, opaque, reveal)`) are
//!   the paper's. Its revealage blend (ZERO, ONE_MINUS_SRC_ALPHA) only works if the shader's
//!   revealage output carries α in its alpha channel; a scalar `out float` has alpha 1, which
//!   zeroes the revealage at the first fragment. We write α to every channel and blend with
//!   ONE_MINUS_SRC (colour), which is right whatever the alpha channel holds.
//! - A common two-pass form's first pass blends the accumulation's alpha channel with (ZERO,
//!   ONE_MINUS_SRC_ALPHA), so `accum.a` holds Π(1 − α) instead of Σ(α·w), and its composite
//!   divides by that: colours come out scaled by Σ(α·w)/Π(1 − α), wrong for every stack
//!   ("very transparent surfaces may appear darker", as such code reports). We keep the
//!   two-pass structure (one target per pass, for adapters without independent blend)
//!   with the one-pass form's blend states, so both variants compute the same thing.
//!
//! fp16 overflow: with weights up to 3000·α, 22 near layers of α = 1 exceed 65504 and the
//! sums become infinite (then NaN in the ratio). Outputs are scaled by 1/64, which cancels
//! in the ratio and keeps sums finite up to ~1390 such layers; the composite also replaces
//! a non-finite average (black, coverage kept) so the scene never holds NaN or inf.
//!
//! RGBA8 fallback: when `Rgba16Float` cannot be blended, the accumulation is
//! RGBA8 with outputs scaled so that eight maximum-weight layers fit; the average then has
//! eight bits of precision at best. Logged when chosen.
//!
//! The weight's parameters (the fitted weight's table, [`fit`]) are the technique's own
//! uniform, group 2, written each frame by `Wboit::prepare`.
//! The chunk pipelines are built per weight (the weight a shader constant, so that no
//! fragment pays for the other weights' code), the first time a frame draws with it, and
//! kept; games' pipelines read the weight from the uniform.
//!
//! With the fitted weight the composite covers only the screen rectangle of the visible
//! translucent planes ([`WboitSettings::composite_scissor`]); the accumulation targets are
//! cleared by the accumulation pass's load ops (no clear pass).

pub(crate) mod fit;
pub(crate) mod weights;

use bytemuck::{Pod, Zeroable};

use crate::chunks::ChunkStore;
use crate::context::Capabilities;
use crate::gpu::{self, Depth, Pass, SidedPipeline, Target};
use crate::ladder::Need;
use crate::oit::sums;
use crate::oit::{
    FrameView, OitConfig, ScreenCover, Setup, Technique, TechniqueKind, TechniqueReport,
    TranslucentFrame, TranslucentTechnique,
};
use crate::stages::{TranslucentVariant, game_group, game_layout, game_prelude};
use crate::timing::GpuPass;
use crate::{GpuContext, Result};

use fit::{PROFILE_LEN, TILES};
use weights::{MAX_FITTED_DEPTH, WeightFit, WeightFunction};

/// What the one-pass variant needs besides the two-pass one: both targets in one pass,
/// each with its own blend state.
const MRT_NEEDS: [Need; 2] = [
    Need::Downlevel(wgpu::DownlevelFlags::INDEPENDENT_BLEND),
    Need::Limit(crate::ladder::Limit::ColorAttachments, 2),
];

/// Revealage format: one byte of Π(1 − α).
pub const REVEALAGE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R8Unorm;
/// Output scale with RGBA16F accumulation and headroom on.
pub const HEADROOM_SCALE: f32 = 1.0 / 64.0;
/// Output scale with RGBA8 accumulation: eight layers of the largest weight (3000) fit in 1.
pub const RGBA8_SCALE: f32 = 1.0 / (3000.0 * 8.0);
/// `vec4`s of the fitted weight's optical-depth table.
pub(crate) const TABLE_VEC4S: usize = TILES * TILES * PROFILE_LEN / 4;

/// Settings of weighted blended OIT. Every field has a reasoned default.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WboitSettings {
    /// The weight function.
    pub weight: WeightFunction,
    /// Accumulate in RGBA8 even when RGBA16F works (to test the fallback).
    pub force_rgba8_accum: bool,
    /// Scale accumulation by 1/64 so that fp16 sums stay finite up to ~1390 layers of the
    /// maximum weight (without it, 22 such layers reach 65504).
    pub headroom: bool,
    /// With the fitted weight, composite only within the screen rectangle of the
    /// translucent planes facing the eye (the fit projects them anyway) and the box around
    /// the game's declared translucent objects, and not at all when it is empty; the
    /// whole screen when a game draws translucent geometry it does not declare (whose
    /// extent the renderer does not know) or the eye is inside a medium (back faces are
    /// drawn). Outside it the composite would discard every pixel (revealage 1), so the
    /// picture is the same.
    pub composite_scissor: bool,
}

impl Default for WboitSettings {
    fn default() -> Self {
        Self {
            // Ours, the transmittance in front of the fragment estimated from the layers in
            // view: the lowest error of all weights on the scene suite (`results/`).
            weight: WeightFunction::Fitted,
            // RGBA8 loses most of the weighted sum's precision: only as a fallback.
            force_rgba8_accum: false,
            // On: turn off only to test the composite's guard against non-finite sums.
            headroom: true,
            // On: the same picture for fewer composited pixels; off only to test that.
            composite_scissor: true,
        }
    }
}

/// What WBOIT drew with in the last frame.
#[derive(Clone, Debug, PartialEq)]
pub struct WboitReport {
    /// The weight in force.
    pub weight: WeightFunction,
    /// The accumulation format (RGBA16F, or the RGBA8 fallback).
    pub accumulation: wgpu::TextureFormat,
    /// What the fitted weight was fitted to (`None` with another weight).
    pub fit: Option<WeightFit>,
    /// The pixels the composite covered, `[x, y, width, height]` (zero size: it was
    /// skipped); `None`: the whole screen.
    pub composite_rect: Option<[u32; 4]>,
}

/// The technique's uniform (`WboitParams` in `accumulate.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub(crate) struct WboitParams {
    /// [`WeightFunction::id`] of the weight.
    pub weight_fn: u32,
    /// Scale of accumulation outputs (keeps fp16 sums finite).
    pub accum_scale: f32,
    /// Nearest and farthest view depth of the visible translucent chunks (fitted weight).
    pub depth_range: [f32; 2],
    /// Optical depth of one layer of the eye's medium (fitted weight; 0 in air): it dims
    /// every fragment behind the medium's surface at its pixel.
    pub medium_depth: f32,
    /// `ln` of the near end of `depth_range` and `(PROFILE_LEN − 1) / ln(far / near)`
    /// ([`WeightFit::log_mapping`]): the table index of view depth `d` is
    /// `(ln d − log_near) · log_scale`, one log per fragment instead of two and a divide.
    pub log_near: f32,
    /// See `log_near`.
    pub log_scale: f32,
    /// Padding (the table is 16-byte aligned).
    pub _pad: f32,
    /// Per screen tile, the optical depth in front of log-spaced depths (fitted weight).
    pub optical_depth: [[f32; 4]; TABLE_VEC4S],
}

/// The accumulation format for `settings` on this adapter (RGBA16F, or the RGBA8 fallback).
pub(crate) fn accumulation_format(
    caps: &Capabilities,
    settings: &WboitSettings,
) -> wgpu::TextureFormat {
    if settings.force_rgba8_accum || !caps.rgba16f_blendable {
        wgpu::TextureFormat::Rgba8Unorm
    } else {
        wgpu::TextureFormat::Rgba16Float
    }
}

/// The accumulation output scale for `settings` on this adapter.
pub(crate) fn accum_scale(caps: &Capabilities, settings: &WboitSettings) -> f32 {
    if accumulation_format(caps, settings) == wgpu::TextureFormat::Rgba8Unorm {
        RGBA8_SCALE
    } else if settings.headroom {
        HEADROOM_SCALE
    } else {
        1.0
    }
}

/// The accumulation shader for chunk pipelines drawing with `weight` (`None`: any, read
/// from the uniform): constants from Rust, the shared code, the weights, the chunk entries.
pub(crate) fn accumulate_wgsl(weight: Option<WeightFunction>) -> String {
    [
        weight_consts(weight).as_str(),
        &crate::bindings::common_wgsl(),
        include_str!("accumulate.wgsl"),
        include_str!("chunks.wgsl"),
    ]
    .concat()
}

/// `WEIGHT_SPECIALISED` when a pipeline serves any weight (games' pipelines).
const WEIGHT_ANY: u32 = u32::MAX;

/// The shader's constants; `WEIGHT_SPECIALISED` is `weight`'s id, or [`WEIGHT_ANY`].
fn weight_consts(weight: Option<WeightFunction>) -> String {
    WeightFunction::wgsl_ids()
        .u32("WEIGHT_ANY", WEIGHT_ANY)
        .u32(
            "WEIGHT_SPECIALISED",
            weight.map_or(WEIGHT_ANY, WeightFunction::id),
        )
        .u32("TILES", TILES as u32)
        .u32("PROFILE_LEN", PROFILE_LEN as u32)
        .u32("TABLE_VEC4S", TABLE_VEC4S as u32)
        .f32("MAX_FITTED_DEPTH", MAX_FITTED_DEPTH)
        .finish()
}

/// The group-2 entries of the accumulation pipelines: the uniform.
fn params_entries() -> [wgpu::BindGroupLayoutEntry; 1] {
    [gpu::buffer_entry(
        0,
        wgpu::ShaderStages::FRAGMENT,
        wgpu::BufferBindingType::Uniform,
    )]
}

/// A game's output for a pass writing the accumulation, the revealage or both.
fn game_output(accumulation: bool, revealage: bool) -> String {
    let mut fields = String::new();
    let mut body = String::new();
    let mut location = 0;
    if accumulation {
        fields += &format!("    @location({location}) accumulation: vec4<f32>,\n");
        body += "    out.accumulation = wboit_accumulation(position, oit_view_depth(position), fogged(position.xy, position.z, color));\n";
        location += 1;
    }
    if revealage {
        fields += &format!("    @location({location}) revealage: vec4<f32>,\n");
        body += "    out.revealage = vec4<f32>(color.a);\n";
    }
    format!(
        "struct OitOutput {{\n{fields}}};\n\n\
         // Weighted sums: accumulation += (C·α, α)·w, revealage *= 1 − α.\n\
         fn oit_output(position: vec4<f32>, color: vec4<f32>) -> OitOutput {{\n    \
         var out: OitOutput;\n{body}    return out;\n}}\n"
    )
}

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

const REVEAL_CLEAR: wgpu::Color = wgpu::Color {
    r: 1.0,
    g: 1.0,
    b: 1.0,
    a: 1.0,
};

#[derive(Debug)]
enum Accumulate {
    Mrt(SidedPipeline),
    TwoPass {
        accumulate: SidedPipeline,
        revealage: SidedPipeline,
    },
}

/// What the chunk pipelines of a weight are built from.
#[derive(Debug)]
struct AccumulateBuilder {
    two_pass: bool,
    layouts: crate::bindings::SharedLayouts,
    params_layout: wgpu::BindGroupLayout,
    /// The accumulation and revealage target states.
    targets: [Option<wgpu::ColorTargetState>; 2],
}

impl AccumulateBuilder {
    /// The chunk pipelines for `weight`, whose shader has the weight as a constant: a
    /// driver drops the other weights' code, where a switch on the uniform leaves it in
    /// every fragment of a CPU rasteriser (lavapipe runs every case of a switch, masked:
    /// `results/wboit-passes/report.md`).
    fn build(&self, device: &wgpu::Device, weight: WeightFunction) -> Accumulate {
        let module = gpu::shader(
            device,
            "wboit_accumulate",
            &[&accumulate_wgsl(Some(weight))],
        );
        let groups = self.layouts.with(&[&self.params_layout]);
        let chunk = |label, fragment_entry, targets: &[Option<wgpu::ColorTargetState>]| {
            sums::chunk_pass(device, label, &module, fragment_entry, &groups, targets)
        };
        let [accum, reveal] = &self.targets;
        if self.two_pass {
            Accumulate::TwoPass {
                accumulate: chunk(
                    "wboit_accumulate",
                    "fs_accumulate",
                    std::slice::from_ref(accum),
                ),
                revealage: chunk(
                    "wboit_revealage",
                    "fs_revealage",
                    std::slice::from_ref(reveal),
                ),
            }
        } else {
            Accumulate::Mrt(chunk(
                "wboit_accumulate_mrt",
                "fs_accumulate_mrt",
                &[accum.clone(), reveal.clone()],
            ))
        }
    }
}

#[derive(Debug)]
struct Targets {
    accumulation: Target,
    revealage: Target,
    composite_group: wgpu::BindGroup,
}

/// WBOIT resources: pipelines, the two size-dependent targets, the uniform, and the fitted
/// weight's summary of each translucent mesh.
#[derive(Debug)]
pub(crate) struct Wboit {
    /// The chunk pipelines of each weight drawn with so far (built when first needed; a
    /// frame draws with the last one `prepare` asked for).
    accumulate: Vec<(WeightFunction, Accumulate)>,
    /// What a weight's pipelines are built from.
    builder: AccumulateBuilder,
    composite: wgpu::RenderPipeline,
    composite_layout: wgpu::BindGroupLayout,
    accum_format: wgpu::TextureFormat,
    targets: Targets,
    params: wgpu::Buffer,
    params_group: wgpu::BindGroup,
    game_layout: wgpu::BindGroupLayout,
    /// The accumulation and revealage target states (for games' pipelines).
    target_states: [Option<wgpu::ColorTargetState>; 2],
    block_opacity: std::sync::Arc<[f32]>,
    /// The weight of this frame's chunk pipelines.
    weight: WeightFunction,
    /// The fitted weight's estimate (and the room it reuses each frame).
    fitter: fit::Fitter,
    /// The composite's scissor rectangle for this frame's chunks (`[x, y, w, h]`), `None`
    /// for the whole screen ([`WboitSettings::composite_scissor`]).
    composite_rect: Option<[u32; 4]>,
    report: Option<WboitReport>,
}

impl TechniqueKind for Wboit {
    /// MRT or two passes, and the accumulation format.
    type Key = (Technique, wgpu::TextureFormat);

    /// The fitted weight is estimated from the visible planes.
    fn reads_layers(config: &OitConfig) -> bool {
        config.wboit.weight == WeightFunction::Fitted
    }

    fn fallback(technique: Technique, caps: &Capabilities) -> Option<Technique> {
        (technique == Technique::WboitMrt && crate::ladder::missing(&MRT_NEEDS, caps).is_some())
            .then_some(Technique::WboitTwoPass)
    }

    /// Additive and multiplicative blending into its two targets; MRT: both in one pass,
    /// with a blend state each.
    fn needs(technique: Technique, config: &OitConfig, caps: &Capabilities) -> Vec<Need> {
        let mut needs = vec![
            Need::BlendableTarget(accumulation_format(caps, &config.wboit)),
            Need::BlendableTarget(REVEALAGE_FORMAT),
        ];
        if technique == Technique::WboitMrt {
            needs.extend(MRT_NEEDS);
        }
        needs
    }

    fn key(technique: Technique, config: &OitConfig, caps: &Capabilities) -> Self::Key {
        (technique, accumulation_format(caps, &config.wboit))
    }

    fn create(setup: &Setup, technique: Technique, config: &OitConfig) -> Result<Self> {
        let device = &setup.ctx.device;
        let accum_format = accumulation_format(&setup.ctx.caps, &config.wboit);
        if accum_format != wgpu::TextureFormat::Rgba16Float {
            log::warn!("WBOIT accumulates in RGBA8: RGBA16F blending unavailable or disabled");
        }
        let params_layout = gpu::layout(device, "wboit_params_layout", &params_entries());
        let (params, params_group) = gpu::zeroed_uniform::<WboitParams>(
            device,
            ("wboit_params", "wboit_params"),
            &params_layout,
        );
        let accum_target = sums::blended(accum_format, sums::ADDITIVE);
        let reveal_target = sums::blended(REVEALAGE_FORMAT, MULTIPLY_ONE_MINUS_SRC);
        let builder = AccumulateBuilder {
            two_pass: technique == Technique::WboitTwoPass,
            layouts: setup.layouts.clone(),
            params_layout: params_layout.clone(),
            targets: [accum_target.clone(), reveal_target.clone()],
        };
        let weight = config.wboit.weight;
        let accumulate = vec![(weight, builder.build(device, weight))];
        let (composite_layout, composite) =
            gpu::composite_pipeline(device, "wboit_composite", include_str!("composite.wgsl"));
        let targets = Self::targets(device, &composite_layout, accum_format, setup.size);
        Ok(Self {
            accumulate,
            builder,
            weight,
            composite,
            composite_layout,
            accum_format,
            targets,
            params,
            params_group,
            game_layout: game_layout(device, "wboit_game", &params_entries()),
            target_states: [accum_target, reveal_target],
            block_opacity: setup.block_opacity.clone(),
            fitter: fit::Fitter::default(),
            composite_rect: None,
            report: None,
        })
    }
}

impl Wboit {
    fn targets(
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        accum_format: wgpu::TextureFormat,
        size: (u32, u32),
    ) -> Targets {
        let [accumulation, revealage] = sums::targets(
            device,
            [
                ("wboit_accumulation", accum_format),
                ("wboit_revealage", REVEALAGE_FORMAT),
            ],
            size,
        );
        let composite_group = gpu::texture_group(
            device,
            "wboit_composite",
            layout,
            &[&accumulation.view, &revealage.view],
        );
        Targets {
            accumulation,
            revealage,
            composite_group,
        }
    }

    /// Fits the weight to the visible translucent meshes' planes.
    fn fit(&mut self, view: &FrameView<'_>) -> WeightFit {
        let cam = view.camera;
        self.fitter.fit(
            view.layers.iter(),
            view.view_proj,
            cam.eye,
            cam.near as f32,
            cam.far as f32,
        )
    }
}

impl TranslucentTechnique for Wboit {
    fn resize(&mut self, ctx: &GpuContext, width: u32, height: u32) -> Result<()> {
        self.targets = Self::targets(
            &ctx.device,
            &self.composite_layout,
            self.accum_format,
            (width, height),
        );
        Ok(())
    }

    fn prepare(
        &mut self,
        ctx: &GpuContext,
        config: &OitConfig,
        _chunks: &mut ChunkStore,
        view: &FrameView<'_>,
    ) -> Result<()> {
        let settings = &config.wboit;
        self.weight = settings.weight;
        if !self.accumulate.iter().any(|(w, _)| *w == settings.weight) {
            let built = self.builder.build(&ctx.device, settings.weight);
            self.accumulate.push((settings.weight, built));
        }
        if let Some(WboitReport { fit: Some(old), .. }) = self.report.take() {
            self.fitter.recycle(old);
        }
        let fit = (settings.weight == WeightFunction::Fitted).then(|| self.fit(view));
        let mut params = WboitParams {
            weight_fn: settings.weight.id(),
            accum_scale: accum_scale(&ctx.caps, settings),
            depth_range: [view.camera.near as f32, view.camera.far as f32],
            medium_depth: view
                .camera
                .medium
                .and_then(|b| self.block_opacity.get(b.index()))
                .map_or(0.0, |&a| fit::layer_depth(a) as f32),
            log_near: 0.0,
            log_scale: 0.0,
            _pad: 0.0,
            optical_depth: [[0.0; 4]; TABLE_VEC4S],
        };
        if let Some(fit) = &fit {
            params.depth_range = fit.range;
            [params.log_near, params.log_scale] = fit.log_mapping();
            let flat: &mut [f32] = bytemuck::cast_slice_mut(&mut params.optical_depth);
            let n = fit.optical_depth.len().min(flat.len());
            flat[..n].copy_from_slice(&fit.optical_depth[..n]);
        }
        view.write(&self.params, 0, bytemuck::bytes_of(&params));
        let size = self.targets.accumulation.texture.size();
        let size = (size.width, size.height);
        // The fit projected every plane drawn (front faces, with the eye in air) already;
        // other weights, and frames in a medium, composite the whole screen (projecting
        // every chunk's box again cost more CPU time than the composite it saved). A
        // game's objects add the box around them (the whole screen where it draws
        // translucent geometry it does not declare).
        self.composite_rect = fit
            .as_ref()
            .filter(|_| settings.composite_scissor && view.camera.medium.is_none())
            .and_then(|fit| {
                let mut cover = ScreenCover::none();
                cover.add_rect(fit.covered);
                cover.add_objects(view.game_objects, view.view_proj, view.camera.eye);
                cover.pixels(size)
            });
        self.report = Some(WboitReport {
            weight: settings.weight,
            accumulation: self.accum_format,
            fit,
            composite_rect: self.composite_rect,
        });
        Ok(())
    }

    fn render(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        frame: &TranslucentFrame<'_>,
    ) -> Result<()> {
        let t = &self.targets;
        let (accum, reveal) = (&t.accumulation.view, &t.revealage.view);
        let depth = Depth::ReadOnly(&frame.depth.view);
        let game = frame.game.map(|g| {
            let own = [self.params.as_entire_binding()];
            (
                g,
                game_group(&ctx.device, "wboit_game", &self.game_layout, g, &own),
            )
        });
        // Chunks, then the game's geometry in its pipeline for this pass.
        let draw = |pass: &mut crate::gpu::CountedPass<'_, '_>,
                    pipeline: &SidedPipeline,
                    variant: usize| {
            pass.set_pipeline(pipeline.get(frame.two_sided));
            pass.set_bind_group(2, &self.params_group, &[]);
            frame.draw_chunks(pass);
            if let Some((g, group)) = &game {
                g.draw_all(pass, variant, group);
            }
        };
        let Some((_, accumulate)) = self.accumulate.iter().find(|(w, _)| *w == self.weight) else {
            // `prepare` builds the weight's pipelines before every frame.
            return Ok(());
        };
        match accumulate {
            Accumulate::Mrt(pipeline) => {
                let colors = [
                    gpu::clear(accum, wgpu::Color::TRANSPARENT),
                    gpu::clear(reveal, REVEAL_CLEAR),
                ];
                Pass::new("wboit_accumulate_mrt", GpuPass::Translucent, &colors)
                    .depth(depth)
                    .record(encoder, frame.timer, |pass| draw(pass, pipeline, 0));
            }
            Accumulate::TwoPass {
                accumulate,
                revealage,
            } => {
                for (variant, (label, pipeline, view, clear)) in [
                    (
                        "wboit_accumulate",
                        accumulate,
                        accum,
                        wgpu::Color::TRANSPARENT,
                    ),
                    ("wboit_revealage", revealage, reveal, REVEAL_CLEAR),
                ]
                .into_iter()
                .enumerate()
                {
                    let colors = [gpu::clear(view, clear)];
                    Pass::new(label, GpuPass::Translucent, &colors)
                        .depth(depth)
                        .record(encoder, frame.timer, |pass| draw(pass, pipeline, variant));
                }
            }
        }
        let rect = self.composite_rect;
        if let Some(report) = &mut self.report {
            report.composite_rect = rect;
        }
        if rect.is_some_and(|[_, _, w, h]| w == 0 || h == 0) {
            // No translucent box on screen: every pixel would be discarded.
            return Ok(());
        }
        let colors = [gpu::load(&frame.target.view)];
        Pass::new("wboit_composite", GpuPass::Composite, &colors)
            .reads(&[accum, reveal])
            .record(encoder, frame.timer, |pass| {
                pass.set_pipeline(&self.composite);
                pass.set_bind_group(0, &t.composite_group, &[]);
                if let Some([x, y, w, h]) = rect {
                    pass.set_scissor_rect(x, y, w, h);
                }
                pass.draw_full_screen();
            });
        Ok(())
    }

    fn report(&self) -> TechniqueReport {
        TechniqueReport {
            wboit: self.report.clone(),
            ..TechniqueReport::default()
        }
    }

    fn accumulation(&self) -> Option<&wgpu::Texture> {
        Some(&self.targets.accumulation.texture)
    }

    fn variants(&self) -> Vec<TranslucentVariant> {
        // Games' pipelines serve every weight: theirs reads it from the uniform.
        let own = weight_consts(None) + include_str!("accumulate.wgsl");
        let [accum, reveal] = self.target_states.clone();
        let variant = |name, accumulation, revealage, targets| TranslucentVariant {
            name,
            wgsl: game_prelude(&own, &game_output(accumulation, revealage)),
            targets,
            depth_stencil: gpu::depth_state(gpu::DepthMode::ReadOnly),
            layout: self.game_layout.clone(),
        };
        if self.builder.two_pass {
            vec![
                variant("wboit_accumulate", true, false, vec![accum]),
                variant("wboit_revealage", false, true, vec![reveal]),
            ]
        } else {
            vec![variant(
                "wboit_accumulate_mrt",
                true,
                true,
                vec![accum, reveal],
            )]
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wgsl_layout::{assert_layout, field, parse};

    #[test]
    fn params_match_their_wgsl() {
        assert_layout::<WboitParams>(
            &parse(&accumulate_wgsl(None)),
            "WboitParams",
            &[
                field!(WboitParams, weight_fn),
                field!(WboitParams, accum_scale),
                field!(WboitParams, depth_range),
                field!(WboitParams, medium_depth),
                field!(WboitParams, log_near),
                field!(WboitParams, log_scale),
                field!(WboitParams, optical_depth),
            ],
        );
    }
}
