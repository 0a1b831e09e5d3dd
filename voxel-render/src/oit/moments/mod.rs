//! Moment-based order-independent transparency (Münstermann, Krumpen, Klein & Peters
//! 2018) with 4 power moments of logarithmically warped depth; Sharpe's MBOIT in vkQuake
//! as a practical reference.
//!
//! Three passes:
//! 1. **Moments**: every translucent fragment adds its absorbance `a = −ln(1 − α)` to `b0`
//!    (R32Float) and `a·(z, z², z³, z⁴)` to the moments (Rgba32Float), additive blend, `z`
//!    its view depth warped logarithmically to [−1, 1] across the frame's translucent
//!    depth range (`depth_range`).
//! 2. **Resolve**: the translucent geometry again; each fragment reconstructs the
//!    transmittance in front of it from the moments (the paper's Hamburger 4-moment bound,
//!    `transmittance`) and adds `(C·α, α)·T` to an Rgba16Float accumulation.
//! 3. **Composite**: `accum.rgb / accum.a` with coverage `1 − e^(−b0)` over the opaque
//!    image, like WBOIT's composite: the total transmittance is exact, only the weights
//!    of the average are estimated.
//!
//! Fallbacks: 32-bit moments need `FLOAT32_BLENDABLE`; without it (or with
//! [`MboitSettings::half_precision`]) the moments are Rgba16Float and R16Float with a
//! larger bias (`BIAS_F16`), logged. Without blendable Rgba16Float the technique is
//! replaced by `wboit-two-pass` (which then accumulates in RGBA8), logged by the manager.

use bytemuck::{Pod, Zeroable};
use glam::DVec3;

use crate::chunks::ChunkStore;
use crate::context::Capabilities;
use crate::gpu::{self, Depth, Pass, SidedPipeline};
use crate::ladder::Need;
use crate::oit::sums;
use crate::oit::{
    FrameView, OitConfig, ScreenCover, Setup, Technique, TechniqueKind, TechniqueReport,
    TranslucentFrame, TranslucentTechnique,
};
use crate::stages::{TranslucentObject, TranslucentVariant, game_group, game_layout, game_prelude};
use crate::timing::GpuPass;
use crate::{Error, GpuContext, Result};

/// The largest absorbance one fragment adds (α = 1 would add infinity): e^−10 ≈ 4.5·10⁻⁵
/// of the light passes, below what an 8-bit output shows.
pub(crate) const ABSORBANCE_MAX: f32 = 10.0;
/// The moment bias with 32-bit moments: the value of the paper's code for 4 power moments
/// in single precision.
pub(crate) const BIAS_F32: f32 = 5e-7;
/// The moment bias with 16-bit moments: about their rounding step (2⁻¹¹ ≈ 4.9·10⁻⁴
/// relative), not tuned further (suite mean FLIP 0.0240 with it against 0.0190 with 32-bit
/// moments, results/mboit/report.md). The paper's 16-bit setting goes with its
/// quantisation transform, which additive blending into half floats cannot apply.
pub(crate) const BIAS_F16: f32 = 5e-4;
#[cfg(test)]
/// The moments' depth-warp vector the bias pulls toward (the paper's, for [−1, 1]).
pub(crate) const BIAS_VECTOR: [f32; 4] = [0.0, 0.375, 0.0, 0.375];
/// The colour accumulation format of the resolve.
pub(crate) const ACCUMULATION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// Settings of moment-based OIT. Every field has a reasoned default.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MboitSettings {
    /// Store the moments in 16-bit floats even when 32-bit ones can be blended (to test
    /// the fallback, or to halve the moments' bandwidth).
    pub half_precision: bool,
    /// The share of a fragment's own layer counted as in front of it, in [0, 1]: the
    /// reconstruction is a lower bound of the absorbance in front, and this pays it back.
    pub overestimation: f32,
}

impl Default for MboitSettings {
    fn default() -> Self {
        Self {
            // 32-bit moments where the adapter blends them: more accurate than 16-bit ones
            // on the suite (mean FLIP 0.0190 against 0.0240 at 320×180) and no slower on
            // lavapipe.
            half_precision: false,
            // The paper's 0.25; 0.1 and 0.4 gave a higher suite mean FLIP (0.0243 and
            // 0.0259 against 0.0190, results/mboit/report.md).
            overestimation: 0.25,
        }
    }
}

impl MboitSettings {
    /// Checks the overestimation factor.
    pub fn validate(&self) -> Result<()> {
        if (0.0..=1.0).contains(&self.overestimation) {
            Ok(())
        } else {
            Err(Error::InvalidSetting(format!(
                "mboit.overestimation {}: must lie in [0, 1]",
                self.overestimation
            )))
        }
    }
}

/// What moment-based OIT drew with in the last frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MboitReport {
    /// The moments' format (Rgba32Float, or the Rgba16Float fallback).
    pub moments: wgpu::TextureFormat,
    /// The view depths the warp spans.
    pub depth_range: [f32; 2],
    /// The pixels the composite covered, `[x, y, width, height]` (zero size: it was
    /// skipped): the rectangle around the visible translucent meshes' boxes and the
    /// game's objects; `None`: the whole screen.
    pub composite_rect: Option<[u32; 4]>,
}

/// The technique's uniform (`MboitParams` in `moments.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub(crate) struct MboitParams {
    /// ln of the nearest view depth of the warp.
    pub ln_near: f32,
    /// 1 / (ln far − ln near).
    pub inv_ln_range: f32,
    /// The moment bias.
    pub bias: f32,
    /// [`MboitSettings::overestimation`].
    pub overestimation: f32,
}

impl MboitParams {
    /// The parameters for a warp across `range` (view depths) with `bias`.
    pub(crate) fn new(range: [f32; 2], bias: f32, overestimation: f32) -> Self {
        let ln_near = range[0].max(1e-6).ln();
        let ln_far = range[1].max(range[0] * 1.001).max(1e-6).ln();
        Self {
            ln_near,
            inv_ln_range: 1.0 / (ln_far - ln_near).max(1e-6),
            bias,
            overestimation,
        }
    }

    #[cfg(test)]
    /// The warped depth of `view_depth` (`mboit_warp` in WGSL).
    pub(crate) fn warp(&self, view_depth: f32) -> f32 {
        let t = (view_depth.max(1e-6).ln() - self.ln_near) * self.inv_ln_range;
        t.clamp(0.0, 1.0) * 2.0 - 1.0
    }
}

/// Whether the moments are stored in 32-bit floats for `settings` on this adapter.
pub fn single_precision(caps: &Capabilities, settings: &MboitSettings) -> bool {
    caps.float32_blendable() && !settings.half_precision
}

/// The formats of `b0` and of the four moments.
fn moment_formats(single: bool) -> (wgpu::TextureFormat, wgpu::TextureFormat) {
    use wgpu::TextureFormat as F;
    if single {
        (F::R32Float, F::Rgba32Float)
    } else {
        (F::R16Float, F::Rgba16Float)
    }
}

/// Absorbance of one fragment of opacity `alpha` (`mboit_absorbance` in WGSL).
#[cfg(test)]
fn absorbance(alpha: f32) -> f32 {
    -(1.0 - alpha).max((-ABSORBANCE_MAX).exp()).ln()
}

#[cfg(test)]
/// The transmittance in front of warped depth `z` from the total absorbance `b0` and the
/// sums `m` of the absorbance-weighted power moments (`mboit_transmittance` in WGSL, the
/// paper's `computeTransmittanceAtDepthFrom4PowerMoments`), in f64 for the tests' sake.
pub(crate) fn transmittance(b0: f64, m: [f64; 4], z: f64, bias: f64, overestimation: f64) -> f64 {
    if b0 <= 0.0 {
        return 1.0;
    }
    let b: [f64; 4] =
        std::array::from_fn(|i| m[i] / b0 + (f64::from(BIAS_VECTOR[i]) - m[i] / b0) * bias);
    let l21d11 = b[2] - b[0] * b[1];
    let d11 = b[1] - b[0] * b[0];
    let l21 = l21d11 / d11;
    let d22 = b[3] - b[1] * b[1] - l21d11 * l21;
    let mut c = [1.0, z, z * z];
    c[1] -= b[0];
    c[2] -= b[1] + l21 * c[1];
    c[1] /= d11;
    c[2] /= d22;
    c[1] -= l21 * c[2];
    c[0] -= c[1] * b[0] + c[2] * b[1];
    let (p, q) = (c[1] / c[2], c[0] / c[2]);
    let r = (p * p * 0.25 - q).max(0.0).sqrt();
    let (z1, z2) = (-p * 0.5 - r, -p * 0.5 + r);
    let f0 = overestimation;
    let f1 = if z1 < z { 1.0 } else { 0.0 };
    let f2 = if z2 < z { 1.0 } else { 0.0 };
    let f01 = (f1 - f0) / (z1 - z);
    let f12 = (f2 - f1) / (z2 - z1);
    let f012 = (f12 - f01) / (z2 - z);
    let p2 = f012;
    let p1 = f01 - f012 * z1;
    let p0 = f0 - p1 * z;
    let p1 = p1 - p2 * z;
    let mut a = p0 + b[0] * p1 + b[1] * p2;
    if !a.is_finite() {
        a = overestimation;
    }
    (-b0 * a.clamp(0.0, 1.0)).exp()
}

/// The view depths the warp spans: from the nearest to the farthest point (along the
/// view direction) of `boxes` (world-space boxes around the visible translucent meshes) and
/// of `game_objects`' balls, within the camera's near and far planes. A game that draws
/// translucent geometry without declaring its objects gets the whole near-to-far range.
pub(crate) fn depth_range(
    camera: &crate::Camera,
    boxes: impl IntoIterator<Item = (DVec3, DVec3)>,
    game_objects: Option<&[TranslucentObject]>,
) -> [f32; 2] {
    let (near, far) = (camera.near, camera.far);
    if game_objects.is_some_and(<[_]>::is_empty) {
        return [near as f32, far as f32];
    }
    let forward = camera.forward;
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for (min, max) in boxes {
        let (min, max) = (min - camera.eye, max - camera.eye);
        // The box's extreme depths along `forward`: per axis the end that lowers (raises)
        // the dot product.
        let (mut a, mut b) = (0.0, 0.0);
        for k in 0..3 {
            let (p, q) = (min[k] * forward[k], max[k] * forward[k]);
            a += p.min(q);
            b += p.max(q);
        }
        lo = lo.min(a);
        hi = hi.max(b);
    }
    for o in game_objects.unwrap_or(&[]) {
        let d = (o.center - camera.eye).dot(forward);
        let r = if o.radius.is_finite() {
            o.radius.max(0.0)
        } else {
            far
        };
        lo = lo.min(d - r);
        hi = hi.max(d + r);
    }
    let lo = lo.clamp(near, far);
    let hi = hi.clamp(near, far);
    if hi > lo {
        [lo as f32, hi as f32]
    } else {
        [near as f32, far as f32]
    }
}

/// The shader of pass 1 (`resolve` false) or pass 2: constants from Rust, the shared
/// code, the moments' maths, the chunk entries.
pub(crate) fn mboit_wgsl(resolve: bool) -> String {
    let mut s = consts() + &crate::bindings::common_wgsl() + include_str!("moments.wgsl");
    if resolve {
        s += include_str!("resolve.wgsl");
        s += include_str!("resolve_chunks.wgsl");
    } else {
        s += include_str!("chunks.wgsl");
    }
    s
}

fn consts() -> String {
    gpu::WgslConsts::default()
        .f32("ABSORBANCE_MAX", ABSORBANCE_MAX)
        .finish()
}

/// Group 2 of pass 1 (the uniform) or of pass 2 (the uniform and pass 1's two targets).
fn group_entries(resolve: bool) -> Vec<wgpu::BindGroupLayoutEntry> {
    let mut entries = vec![gpu::buffer_entry(
        0,
        wgpu::ShaderStages::FRAGMENT,
        wgpu::BufferBindingType::Uniform,
    )];
    if resolve {
        let float = wgpu::TextureSampleType::Float { filterable: false };
        entries.push(gpu::texture_entry(1, float));
        entries.push(gpu::texture_entry(2, float));
    }
    entries
}

fn additive_target(format: wgpu::TextureFormat) -> Option<wgpu::ColorTargetState> {
    sums::blended(format, sums::ADDITIVE)
}

/// The size-dependent targets and the groups that read them.
#[derive(Debug)]
struct Targets {
    b0: gpu::Target,
    moments: gpu::Target,
    accumulation: gpu::Target,
    /// Group 2 of the resolve: the uniform, `b0` and the moments.
    resolve_group: wgpu::BindGroup,
    composite_group: wgpu::BindGroup,
}

/// Moment-based OIT's pipelines, targets and uniform.
#[derive(Debug)]
pub(crate) struct Mboit {
    moments: SidedPipeline,
    resolve: SidedPipeline,
    composite: wgpu::RenderPipeline,
    resolve_layout: wgpu::BindGroupLayout,
    composite_layout: wgpu::BindGroupLayout,
    single: bool,
    targets: Targets,
    params: wgpu::Buffer,
    moments_group: wgpu::BindGroup,
    /// The game's group layouts of pass 1 and pass 2.
    game_layouts: [wgpu::BindGroupLayout; 2],
    report: Option<MboitReport>,
}

impl TechniqueKind for Mboit {
    /// Whether the moments are 32-bit.
    type Key = bool;

    fn fallback(_: Technique, caps: &Capabilities) -> Option<Technique> {
        (!caps.rgba16f_blendable).then_some(Technique::WboitTwoPass)
    }

    /// Additive blending into the moments' targets (both in one pass) and the colour
    /// accumulation.
    fn needs(_: Technique, config: &OitConfig, caps: &Capabilities) -> Vec<Need> {
        let (b0, moments) = moment_formats(single_precision(caps, &config.mboit));
        let mut needs = [b0, moments, ACCUMULATION_FORMAT]
            .map(Need::BlendableTarget)
            .to_vec();
        needs.push(Need::Limit(crate::ladder::Limit::ColorAttachments, 2));
        needs
    }

    fn key(_: Technique, config: &OitConfig, caps: &Capabilities) -> bool {
        single_precision(caps, &config.mboit)
    }

    /// The warp's depth range comes from the boxes of the visible translucent meshes.
    fn reads_layers(_: &OitConfig) -> bool {
        true
    }

    fn create(setup: &Setup, _: Technique, config: &OitConfig) -> Result<Self> {
        let device = &setup.ctx.device;
        let single = single_precision(&setup.ctx.caps, &config.mboit);
        if !single && !config.mboit.half_precision {
            log::warn!(
                "MBOIT stores its moments in 16-bit floats: this device cannot blend 32-bit float targets (FLOAT32_BLENDABLE)"
            );
        }
        let (b0_format, moments_format) = moment_formats(single);
        let moments_layout = gpu::layout(device, "mboit_moments_layout", &group_entries(false));
        let resolve_layout = gpu::layout(device, "mboit_resolve_layout", &group_entries(true));
        let (params, moments_group) = gpu::zeroed_uniform::<MboitParams>(
            device,
            ("mboit_params", "mboit_moments"),
            &moments_layout,
        );
        let chunk = |label, resolve: bool, layout: &wgpu::BindGroupLayout, targets: &[_]| {
            let module = gpu::shader(device, label, &[&mboit_wgsl(resolve)]);
            let entry = if resolve { "fs_resolve" } else { "fs_moments" };
            let groups = setup.layouts.with(&[layout]);
            sums::chunk_pass(device, label, &module, entry, &groups, targets)
        };
        let moments = chunk(
            "mboit_moments",
            false,
            &moments_layout,
            &[additive_target(b0_format), additive_target(moments_format)],
        );
        let resolve = chunk(
            "mboit_resolve",
            true,
            &resolve_layout,
            &[additive_target(ACCUMULATION_FORMAT)],
        );
        let (composite_layout, composite) =
            gpu::composite_pipeline(device, "mboit_composite", include_str!("composite.wgsl"));
        let targets = Self::targets(
            device,
            [&resolve_layout, &composite_layout],
            &params,
            single,
            setup.size,
        );
        Ok(Self {
            moments,
            resolve,
            composite,
            resolve_layout,
            composite_layout,
            single,
            targets,
            params,
            moments_group,
            game_layouts: [
                game_layout(device, "mboit_moments_game", &group_entries(false)),
                game_layout(device, "mboit_resolve_game", &group_entries(true)),
            ],
            report: None,
        })
    }
}

impl Mboit {
    fn targets(
        device: &wgpu::Device,
        [resolve_layout, composite_layout]: [&wgpu::BindGroupLayout; 2],
        params: &wgpu::Buffer,
        single: bool,
        size: (u32, u32),
    ) -> Targets {
        let (b0_format, moments_format) = moment_formats(single);
        let [b0, moments, accumulation] = sums::targets(
            device,
            [
                ("mboit_b0", b0_format),
                ("mboit_moments", moments_format),
                ("mboit_accumulation", ACCUMULATION_FORMAT),
            ],
            size,
        );
        let resolve_group = gpu::bind_group(
            device,
            "mboit_resolve",
            resolve_layout,
            &[
                params.as_entire_binding(),
                wgpu::BindingResource::TextureView(&b0.view),
                wgpu::BindingResource::TextureView(&moments.view),
            ],
        );
        let composite_group = gpu::texture_group(
            device,
            "mboit_composite",
            composite_layout,
            &[&accumulation.view, &b0.view],
        );
        Targets {
            b0,
            moments,
            accumulation,
            resolve_group,
            composite_group,
        }
    }

    fn bias(&self) -> f32 {
        if self.single { BIAS_F32 } else { BIAS_F16 }
    }

    /// A game's output for pass 1 (`resolve` false) or pass 2.
    fn game_output(resolve: bool) -> &'static str {
        if resolve {
            "struct OitOutput {\n    @location(0) accumulation: vec4<f32>,\n};\n\n\
             // accumulation += (C·α, α)·T, T the transmittance in front from the moments.\n\
             fn oit_output(position: vec4<f32>, color: vec4<f32>) -> OitOutput {\n    \
             return OitOutput(mboit_resolve(position, oit_view_depth(position), fogged(position.xy, position.z, color)));\n}\n"
        } else {
            "struct OitOutput {\n    @location(0) b0: vec4<f32>,\n    @location(1) moments: vec4<f32>,\n};\n\n\
             // b0 += −ln(1 − α), moments += that times (z, z², z³, z⁴) of the warped depth.\n\
             fn oit_output(position: vec4<f32>, color: vec4<f32>) -> OitOutput {\n    \
             let m = mboit_moments(oit_view_depth(position), color.a);\n    \
             return OitOutput(m.b0, m.moments);\n}\n"
        }
    }
}

impl TranslucentTechnique for Mboit {
    fn resize(&mut self, ctx: &GpuContext, width: u32, height: u32) -> Result<()> {
        self.targets = Self::targets(
            &ctx.device,
            [&self.resolve_layout, &self.composite_layout],
            &self.params,
            self.single,
            (width, height),
        );
        Ok(())
    }

    fn prepare(
        &mut self,
        _ctx: &GpuContext,
        config: &OitConfig,
        _chunks: &mut ChunkStore,
        view: &FrameView<'_>,
    ) -> Result<()> {
        let range = depth_range(view.camera, view.layers.boxes(), view.game_objects);
        let params = MboitParams::new(range, self.bias(), config.mboit.overestimation);
        view.write(&self.params, 0, bytemuck::bytes_of(&params));
        // The composite discards every pixel no translucent fragment reached: only the
        // rectangle around the meshes' boxes and the game's objects is drawn.
        let mut cover = ScreenCover::none();
        for b in view.layers.boxes() {
            cover.add_box(b, view.view_proj, view.camera.eye);
        }
        cover.add_objects(view.game_objects, view.view_proj, view.camera.eye);
        let size = self.targets.accumulation.texture.size();
        self.report = Some(MboitReport {
            moments: self.targets.moments.texture.format(),
            depth_range: range,
            composite_rect: cover.pixels((size.width, size.height)),
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
        let depth = Depth::ReadOnly(&frame.depth.view);
        // The game's groups for the two passes (its bindings moved up by two).
        let game = frame.game.map(|g| {
            let params = self.params.as_entire_binding();
            let moments = game_group(
                &ctx.device,
                "mboit_moments_game",
                &self.game_layouts[0],
                g,
                std::slice::from_ref(&params),
            );
            let resolve = game_group(
                &ctx.device,
                "mboit_resolve_game",
                &self.game_layouts[1],
                g,
                &[
                    params.clone(),
                    wgpu::BindingResource::TextureView(&t.b0.view),
                    wgpu::BindingResource::TextureView(&t.moments.view),
                ],
            );
            (g, [moments, resolve])
        });
        let draw = |pass: &mut crate::gpu::CountedPass<'_, '_>,
                    pipeline: &SidedPipeline,
                    group: &wgpu::BindGroup,
                    variant: usize| {
            pass.set_pipeline(pipeline.get(frame.two_sided));
            pass.set_bind_group(2, group, &[]);
            frame.draw_chunks(pass);
            if let Some((g, groups)) = &game {
                g.draw_all(pass, variant, &groups[variant]);
            }
        };
        let colors = [
            gpu::clear(&t.b0.view, wgpu::Color::TRANSPARENT),
            gpu::clear(&t.moments.view, wgpu::Color::TRANSPARENT),
        ];
        Pass::new("mboit_moments", GpuPass::Translucent, &colors)
            .depth(depth)
            .record(encoder, frame.timer, |pass| {
                draw(pass, &self.moments, &self.moments_group, 0);
            });
        let colors = [gpu::clear(&t.accumulation.view, wgpu::Color::TRANSPARENT)];
        Pass::new("mboit_resolve", GpuPass::Translucent, &colors)
            .depth(depth)
            .reads(&[&t.b0.view, &t.moments.view])
            .record(encoder, frame.timer, |pass| {
                draw(pass, &self.resolve, &t.resolve_group, 1);
            });
        let rect = self.report.and_then(|r| r.composite_rect);
        if rect.is_some_and(|[_, _, w, h]| w == 0 || h == 0) {
            // Nothing translucent on screen: every pixel would be discarded.
            return Ok(());
        }
        let colors = [gpu::load(&frame.target.view)];
        Pass::new("mboit_composite", GpuPass::Composite, &colors)
            .reads(&[&t.accumulation.view, &t.b0.view])
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

    fn variants(&self) -> Vec<TranslucentVariant> {
        let (b0_format, moments_format) = moment_formats(self.single);
        let variant = |name, resolve: bool, targets| {
            let mut own = consts() + include_str!("moments.wgsl");
            if resolve {
                own += include_str!("resolve.wgsl");
            }
            TranslucentVariant {
                name,
                wgsl: game_prelude(&own, Self::game_output(resolve)),
                targets,
                depth_stencil: gpu::depth_state(gpu::DepthMode::ReadOnly),
                layout: self.game_layouts[usize::from(resolve)].clone(),
            }
        };
        vec![
            variant(
                "mboit_moments",
                false,
                vec![additive_target(b0_format), additive_target(moments_format)],
            ),
            variant(
                "mboit_resolve",
                true,
                vec![additive_target(ACCUMULATION_FORMAT)],
            ),
        ]
    }

    fn report(&self) -> TechniqueReport {
        TechniqueReport {
            mboit: self.report,
            ..TechniqueReport::default()
        }
    }

    fn accumulation(&self) -> Option<&wgpu::Texture> {
        Some(&self.targets.accumulation.texture)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wgsl_layout::{assert_layout, field, parse};

    #[test]
    fn params_match_their_wgsl() {
        for resolve in [false, true] {
            assert_layout::<MboitParams>(
                &parse(&mboit_wgsl(resolve)),
                "MboitParams",
                &[
                    field!(MboitParams, ln_near),
                    field!(MboitParams, inv_ln_range),
                    field!(MboitParams, bias),
                    field!(MboitParams, overestimation),
                ],
            );
        }
    }

    /// Moments of fragments `(alpha, z)`: b0 and the four sums, as pass 1 adds them.
    fn sums(layers: &[(f32, f64)]) -> (f64, [f64; 4]) {
        let mut b0 = 0.0;
        let mut m = [0.0; 4];
        for &(alpha, z) in layers {
            let a = f64::from(absorbance(alpha));
            b0 += a;
            for (k, s) in m.iter_mut().enumerate() {
                *s += a * z.powi(k as i32 + 1);
            }
        }
        (b0, m)
    }

    #[test]
    fn one_layer_counts_the_overestimated_share_of_itself() {
        let (b0, m) = sums(&[(0.6, 0.2)]);
        let t = transmittance(b0, m, 0.2, f64::from(BIAS_F32), 0.25);
        // Its own layer: a quarter of its absorbance, to within what the bias moves.
        let want = (-0.25 * b0).exp();
        assert!((t - want).abs() < 1e-3, "{t} vs {want}");
        // In front of it, nothing; behind it, all of it.
        let front = transmittance(b0, m, -0.5, f64::from(BIAS_F32), 0.25);
        let back = transmittance(b0, m, 0.8, f64::from(BIAS_F32), 0.25);
        assert!((front - 1.0).abs() < 1e-3, "{front}");
        assert!((back - 0.4).abs() < 1e-3, "{back}");
    }

    #[test]
    fn layers_apart_are_resolved_in_order() {
        // Three sheets: the transmittance in front of each is (nearly) the product of the
        // ones in front, at the warp's resolution (0.3 apart).
        let layers = [(0.5, -0.6), (0.7, -0.3), (0.4, 0.0)];
        let (b0, m) = sums(&layers);
        let exact = [1.0, 0.5, 0.5 * 0.3];
        for (&(alpha, z), want) in layers.iter().zip(exact) {
            let own = (-0.25 * f64::from(absorbance(alpha))).exp();
            let t = transmittance(b0, m, z, f64::from(BIAS_F32), 0.25);
            // The reconstruction is a bound, not exact: within 0.1 of the product with
            // the layer's own quarter share.
            assert!((t - want * own).abs() < 0.1, "z {z}: {t} vs {}", want * own);
        }
        // Monotonic: nothing in front of a fragment comes back behind it.
        let mut last = 1.0;
        for i in 0..=40 {
            let z = -1.0 + f64::from(i) * 0.05;
            let t = transmittance(b0, m, z, f64::from(BIAS_F32), 0.25);
            assert!(t <= last + 1e-9, "z {z}: {t} after {last}");
            last = t;
        }
    }

    #[test]
    fn degenerate_moments_give_finite_transmittance() {
        // Empty, a single layer at the ends of the range, and an opaque one.
        for (b0, m, z) in [
            (0.0, [0.0; 4], 0.0),
            (1.0, [1.0, 1.0, 1.0, 1.0], 1.0),
            (1.0, [-1.0, 1.0, -1.0, 1.0], -1.0),
            (10.0, [0.0; 4], 0.0),
        ] {
            for bias in [BIAS_F32, BIAS_F16] {
                let t = transmittance(b0, m, z, f64::from(bias), 0.25);
                assert!((0.0..=1.0).contains(&t), "{b0} {m:?} {z}: {t}");
            }
        }
        assert_eq!(absorbance(1.0), ABSORBANCE_MAX);
        assert_eq!(absorbance(0.0), 0.0);
    }

    #[test]
    fn the_warp_spans_the_range() {
        let p = MboitParams::new([2.0, 200.0], BIAS_F32, 0.25);
        assert!((p.warp(2.0) + 1.0).abs() < 1e-6);
        assert!((p.warp(200.0) - 1.0).abs() < 1e-5);
        assert!(
            p.warp(20.0).abs() < 1e-5,
            "log: the middle is the geometric mean"
        );
        assert_eq!(p.warp(0.5), -1.0);
        assert_eq!(p.warp(1e4), 1.0);
        // A degenerate range stays finite.
        let q = MboitParams::new([5.0, 5.0], BIAS_F32, 0.25);
        assert!(q.inv_ln_range.is_finite() && q.warp(5.0).is_finite());
    }

    #[test]
    fn the_range_spans_the_boxes_and_objects_seen() {
        let cam =
            crate::Camera::look_at(DVec3::new(0.0, 0.0, 10.0), DVec3::ZERO, 60.0, 0.1, 1000.0)
                .unwrap();
        let sheet = (DVec3::new(-5.0, -5.0, 0.0), DVec3::new(5.0, 5.0, 1.0));
        let far = (DVec3::new(-5.0, -5.0, -40.0), DVec3::new(5.0, 5.0, -39.0));
        assert_eq!(depth_range(&cam, [sheet, far], None), [9.0, 50.0]);
        // A box around the eye starts at the near plane.
        let around = (DVec3::splat(-20.0), DVec3::splat(20.0));
        assert_eq!(depth_range(&cam, [around], None), [0.1, 30.0]);
        // A game's particle nearer than every mesh widens the range; undeclared geometry
        // takes the camera's.
        let ball = TranslucentObject::ball(DVec3::new(0.0, 0.0, 7.0), 1.0);
        assert_eq!(depth_range(&cam, [sheet], Some(&[ball])), [2.0, 10.0]);
        assert_eq!(depth_range(&cam, [sheet], Some(&[])), [0.1, 1000.0]);
        // Nothing seen: the camera's range.
        assert_eq!(depth_range(&cam, [], None), [0.1, 1000.0]);
    }

    #[test]
    fn settings_are_checked() {
        assert!(MboitSettings::default().validate().is_ok());
        for bad in [-0.1, 1.5, f32::NAN] {
            let s = MboitSettings {
                overestimation: bad,
                ..MboitSettings::default()
            };
            assert!(s.validate().is_err(), "{bad}");
        }
    }
}
