//! Order-independent transparency behind one API: [`OitManager`] (seed 002's OITManager in
//! Rust form) records the translucent pass and its composite for the selected
//! [`Technique`]. One folder per technique; each implements [`TranslucentTechnique`].

pub mod peeling;
pub mod reference;
pub mod sorted;
pub mod stipple;
pub mod wboit;

use crate::chunks::Visible;
use crate::pipelines::SharedLayouts;
use crate::timing::GpuTimer;
use crate::{Error, GpuContext, Result};

pub use stipple::{BayerSize, ShadingState, TransparencyMode};
pub use wboit::weights::{WeightFit, WeightFunction};

/// A way to draw the translucent meshes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Technique {
    /// Translucent meshes are not drawn at all.
    OpaqueOnly,
    /// Weighted blended OIT, one pass into two targets (MRT) with independent blend states.
    WboitMrt,
    /// Weighted blended OIT, two passes (seed 002): one per target. For adapters without
    /// independent blend.
    WboitTwoPass,
    /// Screen-door transparency with a Bayer pattern (seed 001): the low-end mode.
    Stipple,
    /// Alpha blending of chunks sorted back to front (seed 003): the baseline.
    Sorted,
    /// Like `Sorted`, with the quads inside each chunk sorted back to front too.
    SortedQuads,
    /// Dual depth peeling of [`OitConfig::peel_layers`] layers (seed 004).
    DepthPeeling,
    /// The exact reference: per-pixel sorted fragment lists (A-buffer). Stalls the GPU.
    Reference,
    /// The second exact method: front-to-back depth peeling until a pass writes nothing.
    /// Stalls the GPU once per layer.
    PeelReference,
}

impl Technique {
    /// Every technique, in the order menus and reports list them.
    pub const ALL: [Technique; 9] = [
        Technique::OpaqueOnly,
        Technique::WboitMrt,
        Technique::WboitTwoPass,
        Technique::Stipple,
        Technique::Sorted,
        Technique::SortedQuads,
        Technique::DepthPeeling,
        Technique::Reference,
        Technique::PeelReference,
    ];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Technique::OpaqueOnly => "opaque-only",
            Technique::WboitMrt => "wboit-mrt",
            Technique::WboitTwoPass => "wboit-two-pass",
            Technique::Stipple => "stipple",
            Technique::Sorted => "sorted",
            Technique::SortedQuads => "sorted-quads",
            Technique::DepthPeeling => "depth-peeling",
            Technique::Reference => "reference",
            Technique::PeelReference => "peel-reference",
        }
    }

    /// Whether the technique computes the exact blend (up to rounding).
    pub fn is_exact(self) -> bool {
        matches!(self, Technique::Reference | Technique::PeelReference)
    }

    /// Parses a command-line name; the error lists the known names.
    pub fn from_name(name: &str) -> Result<Self> {
        Self::ALL
            .into_iter()
            .find(|t| t.name() == name)
            .ok_or_else(|| {
                Error::UnknownName(format!(
                    "technique {name:?}; known: {}",
                    Self::ALL.map(Technique::name).join(", ")
                ))
            })
    }
}

impl std::fmt::Display for Technique {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Settings of the transparency techniques. Every field has a reasoned default.
#[derive(Clone, Debug, PartialEq)]
pub struct OitConfig {
    /// The technique to draw translucent meshes with. Default: WBOIT in one MRT pass, the
    /// fastest method that looks right on any adapter with independent blend.
    pub technique: Technique,
    /// Render target width in pixels.
    pub width: u32,
    /// Render target height in pixels.
    pub height: u32,
    /// WBOIT weight function. Default: ours, the transmittance in front of the fragment
    /// estimated from the translucent layers in view, which had the lowest error of all
    /// on the scene suite (`results/`).
    pub weight: WeightFunction,

    /// Accumulate WBOIT in RGBA8 even when RGBA16F works (to test the fallback).
    /// Default false: RGBA8 loses most of the weighted sum's precision.
    pub force_rgba8_accum: bool,
    /// Scale WBOIT accumulation by 1/64 so that fp16 sums stay finite up to ~1390 layers of
    /// the maximum weight (without it, 22 such layers reach 65504). Default true; turn off
    /// only to test the composite's guard against non-finite sums.
    pub wboit_headroom: bool,
    /// Stipple pattern. Default 4×4, seed 001's default ("era-authentic").
    pub bayer: BayerSize,
    /// Whether kept stipple pixels write depth. Default true, seed 001's behaviour ("writes
    /// to depth buffer normally"): nearer kept pixels then hide what is behind them.
    pub stipple_depth_write: bool,
    /// Uniform alpha of the stipple shading state, multiplying every translucent alpha.
    /// Default 255 (1.0): surfaces keep their own opacity.
    pub stipple_alpha: u8,
    /// Layers dual depth peeling captures at most (even; presets 4, 6, 8). Default 8: the
    /// depth complexity of glass-over-water views in our terrain stays below it.
    pub peel_layers: u32,
    /// Sorted-quads: how far (blocks) the eye may move before a chunk's quads are
    /// re-sorted. Default 0.25: a quarter block changes the order of few quads, and a
    /// sort of a chunk's translucent quads takes microseconds.
    pub resort_distance: f64,
}

impl Default for OitConfig {
    fn default() -> Self {
        Self {
            technique: Technique::WboitMrt,
            width: 1280,
            height: 720,
            weight: WeightFunction::Fitted,

            force_rgba8_accum: false,
            wboit_headroom: true,
            bayer: BayerSize::B4,
            stipple_depth_write: true,
            stipple_alpha: 255,
            peel_layers: 8,
            resort_distance: 0.25,
        }
    }
}

impl OitConfig {
    /// Seed 001's packed shading state for the frame uniforms (stipple mode, pattern, alpha).
    pub fn shading_state(&self) -> ShadingState {
        ShadingState {
            alpha: self.stipple_alpha,
            mode: TransparencyMode::Stipple,
            pattern: self.bayer,
        }
    }
}

/// Technique-specific facts about the last frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TechniqueReport {
    /// Layers found (depth peeling).
    pub layers: Option<u32>,
    /// Peeling iterations run this frame (each a front and, in dual mode, a back peel).
    pub iterations: Option<u32>,

    /// Fragments that did not fit (reference): should be zero; never hidden.
    pub overflow: Option<u64>,
    /// Attempts the reference needed this frame (more than 1 after growing its pool).
    pub attempts: Option<u32>,
}

/// What a technique draws with and into, for one frame.
#[derive(Debug)]
pub struct TranslucentFrame<'a> {
    /// The HDR scene colour holding the opaque image; the composite blends into it.
    pub target: &'a wgpu::TextureView,
    /// The texture of `target` (for copies).
    pub target_texture: &'a wgpu::Texture,
    /// The opaque depth (single-sample): read-only attachment, or sampled by peeling.
    pub depth: &'a wgpu::TextureView,
    /// The texture of `depth` (for copies).
    pub depth_texture: &'a wgpu::Texture,
    /// Group 0: frame uniforms and block textures.
    pub scene: &'a wgpu::BindGroup,
    /// The visible translucent meshes, farthest first.
    pub chunks: &'a [Visible<'a>],
    /// Pass timing, when available.
    pub timer: Option<&'a mut GpuTimer>,
}

impl TranslucentFrame<'_> {
    /// Timestamp writes for the next pass under `label`.
    pub fn timestamps(
        &mut self,
        label: &'static str,
    ) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
        self.timer.as_deref_mut().and_then(|t| t.pass(label))
    }

    /// Records the draws of every visible translucent mesh.
    pub fn draw_chunks(&self, pass: &mut wgpu::RenderPass<'_>) {
        pass.set_bind_group(0, self.scene, &[]);
        for c in self.chunks {
            c.mesh.draw(pass);
        }
    }
}

/// One transparency technique: its pipelines and targets, created when it becomes active
/// and dropped when another one does.
pub trait TranslucentTechnique: std::fmt::Debug {
    /// Rebuilds size-dependent targets; called only when the size really changed.
    fn resize(&mut self, ctx: &GpuContext, width: u32, height: u32);
    /// Records the translucent pass(es) and the composite into `frame.target`.
    fn render(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        frame: &mut TranslucentFrame<'_>,
    );
    /// Called after the frame's commands were submitted (to start reading results back).
    fn after_submit(&mut self) {}
    /// Technique-specific facts about the last frame.
    fn report(&self) -> TechniqueReport {
        TechniqueReport::default()
    }
    /// The WBOIT accumulation target, for techniques that have one.
    fn accumulation(&self) -> Option<&wgpu::Texture> {
        None
    }
    /// The WBOIT revealage target, for techniques that have one.
    fn revealage(&self) -> Option<&wgpu::Texture> {
        None
    }
}

/// Owns the active technique and records its passes (seed 002's OITManager API: created
/// with the device and a config; `resize`; the accumulation and revealage targets;
/// `render` records the translucent pass and composite; resources freed on drop).
#[derive(Debug)]
pub struct OitManager {
    ctx: GpuContext,
    layouts: SharedLayouts,
    config: OitConfig,
    /// Created on the first frame that has translucent meshes in view.
    active: Option<Box<dyn TranslucentTechnique>>,
}

impl OitManager {
    /// A manager for `config`. No GPU resource is created until a frame needs one. A
    /// technique the adapter cannot run falls back (logged): two-pass WBOIT without
    /// independent blend.
    pub fn new(ctx: &GpuContext, layouts: &SharedLayouts, config: OitConfig) -> Self {
        let mut m = Self {
            ctx: ctx.clone(),
            layouts: layouts.clone(),
            config,
            active: None,
        };
        m.config.technique = m.supported(m.config.technique);
        m.config.width = m.config.width.max(1);
        m.config.height = m.config.height.max(1);
        m
    }

    /// `technique`, or what replaces it on this adapter.
    fn supported(&self, technique: Technique) -> Technique {
        let caps = &self.ctx.caps;
        if technique == Technique::WboitMrt && !caps.independent_blend() {
            log::warn!("adapter lacks independent blend: using two-pass WBOIT instead of MRT");
            return Technique::WboitTwoPass;
        }
        if technique == Technique::Reference && !caps.fragment_storage() {
            log::warn!(
                "adapter lacks fragment storage writes: using peel-to-convergence as the reference"
            );
            return Technique::PeelReference;
        }
        technique
    }

    /// The configuration in force (after any fallback).
    pub fn config(&self) -> &OitConfig {
        &self.config
    }

    /// The active technique.
    pub fn technique(&self) -> Technique {
        self.config.technique
    }

    /// Switches technique at run time; the old one's resources are freed at once.
    pub fn set_technique(&mut self, technique: Technique) {
        let technique = self.supported(technique);
        if technique != self.config.technique {
            self.config.technique = technique;
            self.active = None;
        }
    }

    /// Changes the WBOIT weight function (a uniform: no pipeline is rebuilt).
    pub fn set_weight(&mut self, weight: WeightFunction) {
        self.config.weight = weight;
    }

    /// Changes settings other than the size; resources are rebuilt only if a setting the
    /// active technique's pipelines or targets depend on changed.
    pub fn set_config(&mut self, config: OitConfig) {
        let old = &self.config;
        let rebuild = config.technique != old.technique
            || config.force_rgba8_accum != old.force_rgba8_accum
            || config.stipple_depth_write != old.stipple_depth_write
            || config.peel_layers != old.peel_layers;
        self.config = OitConfig {
            width: old.width,
            height: old.height,
            ..config
        };
        self.config.technique = self.supported(self.config.technique);
        if rebuild {
            self.active = None;
        }
    }

    /// Technique-specific facts about the last frame.
    pub fn report(&self) -> TechniqueReport {
        self.active.as_ref().map(|t| t.report()).unwrap_or_default()
    }

    /// Call after the frame's commands were submitted.
    pub fn after_submit(&mut self) {
        if let Some(t) = &mut self.active {
            t.after_submit();
        }
    }

    /// Resizes the targets. Same size: nothing happens. Zero width or height (a minimised
    /// window): nothing happens either, and the old targets stay until a real size comes.
    pub fn resize(&mut self, width: u32, height: u32) {
        if width == 0 || height == 0 || (width, height) == (self.config.width, self.config.height) {
            return;
        }
        self.config.width = width;
        self.config.height = height;
        if let Some(t) = &mut self.active {
            t.resize(&self.ctx, width, height);
        }
    }

    /// The WBOIT accumulation target, when WBOIT is active and has drawn.
    pub fn accumulation_target(&self) -> Option<&wgpu::Texture> {
        self.active.as_ref().and_then(|t| t.accumulation())
    }

    /// The WBOIT revealage target, when WBOIT is active and has drawn.
    pub fn revealage_target(&self) -> Option<&wgpu::Texture> {
        self.active.as_ref().and_then(|t| t.revealage())
    }

    /// Whether the active technique's GPU resources exist.
    pub fn has_resources(&self) -> bool {
        self.active.is_some()
    }

    /// Multiplier of WBOIT accumulation outputs for the frame uniforms.
    pub fn accum_scale(&self) -> f32 {
        wboit::accum_scale(&self.ctx, &self.config)
    }

    fn create(&self) -> Option<Box<dyn TranslucentTechnique>> {
        let c = &self.config;
        match c.technique {
            Technique::OpaqueOnly => None,
            Technique::WboitMrt | Technique::WboitTwoPass => {
                Some(Box::new(wboit::Wboit::new(&self.ctx, &self.layouts, c)))
            }
            Technique::Sorted | Technique::SortedQuads => {
                Some(Box::new(sorted::Sorted::new(&self.ctx, &self.layouts)))
            }
            Technique::Stipple => {
                Some(Box::new(stipple::Stipple::new(&self.ctx, &self.layouts, c)))
            }
            Technique::DepthPeeling => Some(Box::new(peeling::Peeling::new(
                &self.ctx,
                &self.layouts,
                c,
                peeling::PeelMode::Dual {
                    layers: c.peel_layers,
                },
            ))),
            Technique::PeelReference => Some(Box::new(peeling::Peeling::new(
                &self.ctx,
                &self.layouts,
                c,
                peeling::PeelMode::Converge,
            ))),
            Technique::Reference => Some(Box::new(reference::Reference::new(
                &self.ctx,
                &self.layouts,
                c,
            ))),
        }
    }

    /// Records the translucent pass(es) and the composite into `frame.target`. With no
    /// visible translucent mesh (or `OpaqueOnly`) nothing is recorded and no resource is
    /// created.
    pub fn render(&mut self, encoder: &mut wgpu::CommandEncoder, frame: &mut TranslucentFrame<'_>) {
        if frame.chunks.is_empty() || self.config.technique == Technique::OpaqueOnly {
            return;
        }
        if self.active.is_none() {
            self.active = self.create();
        }
        if let Some(t) = &mut self.active {
            t.render(&self.ctx, encoder, frame);
        }
    }
}
