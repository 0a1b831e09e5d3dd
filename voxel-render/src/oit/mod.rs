//! Order-independent transparency behind one API: [`OitManager`] (seed 002's OITManager in
//! Rust form) records the translucent pass and its composite for the selected
//! [`Technique`]. One folder per technique; each implements [`TranslucentTechnique`].

pub mod sorted;
pub mod wboit;

use crate::chunks::Visible;
use crate::pipelines::SharedLayouts;
use crate::timing::GpuTimer;
use crate::{Error, GpuContext, Result};

pub use wboit::weights::WeightFunction;

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
    /// Alpha blending of chunks sorted back to front (seed 003): the baseline.
    Sorted,
}

impl Technique {
    /// Every technique, in the order menus and reports list them.
    pub const ALL: [Technique; 4] = [
        Technique::OpaqueOnly,
        Technique::WboitMrt,
        Technique::WboitTwoPass,
        Technique::Sorted,
    ];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Technique::OpaqueOnly => "opaque-only",
            Technique::WboitMrt => "wboit-mrt",
            Technique::WboitTwoPass => "wboit-two-pass",
            Technique::Sorted => "sorted",
        }
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
    /// fastest exact-enough method on any adapter with independent blend.
    pub technique: Technique,
    /// Render target width in pixels.
    pub width: u32,
    /// Render target height in pixels.
    pub height: u32,
    /// WBOIT weight function. Default: McGuire & Bavoil 2013 eq. 10, the depth-buffer
    /// weight that needs no knowledge of the scene's scale.
    pub weight: WeightFunction,
    /// Accumulate WBOIT in RGBA8 even when RGBA16F works (to test the fallback).
    /// Default false: RGBA8 loses most of the weighted sum's precision.
    pub force_rgba8_accum: bool,
    /// Scale WBOIT accumulation by 1/64 so that fp16 sums stay finite up to ~1390 layers of
    /// the maximum weight (without it, 22 such layers reach 65504). Default true; turn off
    /// only to test the composite's guard against non-finite sums.
    pub wboit_headroom: bool,
}

impl Default for OitConfig {
    fn default() -> Self {
        Self {
            technique: Technique::WboitMrt,
            width: 1280,
            height: 720,
            weight: WeightFunction::McGuire10,
            force_rgba8_accum: false,
            wboit_headroom: true,
        }
    }
}

/// What a technique draws with and into, for one frame.
#[derive(Debug)]
pub struct TranslucentFrame<'a> {
    /// The HDR scene colour holding the opaque image; the composite blends into it.
    pub target: &'a wgpu::TextureView,
    /// The opaque depth (single-sample): read-only attachment, or sampled by peeling.
    pub depth: &'a wgpu::TextureView,
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
        if technique == Technique::WboitMrt && !self.ctx.caps.independent_blend() {
            log::warn!("adapter lacks independent blend: using two-pass WBOIT instead of MRT");
            return Technique::WboitTwoPass;
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
            Technique::Sorted => Some(Box::new(sorted::Sorted::new(&self.ctx, &self.layouts))),
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
