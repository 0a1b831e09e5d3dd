//! Order-independent transparency behind one API: [`OitManager`] prepares and records the translucent passes and their composite for the
//! selected [`Technique`].
//!
//! One folder per technique. Its type implements [`TranslucentTechnique`] (the hooks of a
//! frame: prepare on the CPU, record, read back, report) and [`TechniqueKind`] (how to
//! build it, and the key that decides when it must be rebuilt); it owns its pipelines,
//! targets, uniforms, bind groups (from group 2 on) and per-chunk caches. Adding a technique
//! is its folder plus one line in the list below (and, if it has settings of its own, their
//! struct as a field of [`OitConfig`]).

pub(crate) mod moments;
pub(crate) mod opaque_only;
pub(crate) mod peeling;
pub(crate) mod reference;
pub(crate) mod sorted;
pub(crate) mod stipple;
mod sums;
pub(crate) mod wboit;

use std::fmt;
use std::sync::Arc;

use glam::Mat4;
use voxel_core::ChunkPos;

use crate::bindings::SharedLayouts;
use crate::chunks::{ChunkStore, DrawList, FrameDraws};
use crate::context::Capabilities;
use crate::fetch::QuadFetch;
use crate::gpu::Target;
use crate::ladder::{self, Need};
use crate::layers::VisibleLayers;
use crate::stages::{GameDraw, TranslucentContract, TranslucentObject, TranslucentVariant};
use crate::timing::Timer;
use crate::{Camera, Error, GpuContext, Result};

pub(crate) use moments::{MboitReport, MboitSettings};
pub(crate) use peeling::{PeelReport, PeelingSettings};
pub(crate) use reference::ReferenceReport;
pub(crate) use sorted::SortReport;
pub(crate) use stipple::StippleSettings;
pub(crate) use wboit::{WboitReport, WboitSettings};

/// Declares [`Technique`] from the list of techniques: variant, command-line name, and the
/// type (implementing [`TechniqueKind`]) that draws it.
macro_rules! techniques {
    ($( $(#[doc = $doc:literal])* $variant:ident = $name:literal => $kind:ty $([$stalls:ident])?, )*) => {
        /// A way to draw the translucent meshes.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum Technique {
            $( $(#[doc = $doc])* $variant, )*
        }

        /// The pipeline key of the active technique, by technique.
        #[derive(Clone, Debug, PartialEq)]
        enum Key {
            $( $variant(<$kind as TechniqueKind>::Key), )*
        }

        impl Key {
            /// The technique this key builds.
            fn technique(&self) -> Technique {
                match self { $( Key::$variant(_) => Technique::$variant, )* }
            }
        }

        impl Technique {
            /// Number of techniques.
            pub(crate) const COUNT: usize = [$( stringify!($variant) ),*].len();

            /// Every technique, in the order menus and reports list them.
            pub const ALL: [Technique; Self::COUNT] = [$( Technique::$variant ),*];

            /// Whether the technique waits for GPU results inside `Renderer::render`
            /// (the exact references: hundreds of milliseconds a frame), so that it has no
            /// place in a game's frame loop.
            pub const fn stalls(self) -> bool {
                match self { $( Technique::$variant => stall_flag!($($stalls)?), )* }
            }

            /// The command-line name.
            pub fn name(self) -> &'static str {
                match self { $( Technique::$variant => $name, )* }
            }

            /// Whether the technique computes the exact blend (up to rounding).
            pub fn is_exact(self) -> bool {
                match self { $( Technique::$variant => <$kind as TechniqueKind>::is_exact(self), )* }
            }

            /// Whether the technique draws the translucent meshes at all.
            pub fn draws(self) -> bool {
                match self { $( Technique::$variant => <$kind as TechniqueKind>::DRAWS, )* }
            }

            /// Whether the technique draws translucent things back to front (so that a
            /// game's objects are ordered with the chunks, [`crate::stages::TranslucentObject`]).
            pub fn sorts(self) -> bool {
                match self { $( Technique::$variant => <$kind as TechniqueKind>::SORTS, )* }
            }

            /// Whether the technique with `config` reads [`FrameView::layers`].
            fn reads_layers(self, config: &OitConfig) -> bool {
                match self { $( Technique::$variant => <$kind as TechniqueKind>::reads_layers(config), )* }
            }

            /// What replaces the technique on an adapter that cannot run it.
            fn fallback(self, caps: &Capabilities) -> Option<Technique> {
                match self { $( Technique::$variant => <$kind as TechniqueKind>::fallback(self, caps), )* }
            }

            /// What the technique with `config` needs of a device beyond the world's own
            /// passes ([`crate::ladder::world_needs`], and the way quads are fetched).
            pub(crate) fn needs(self, config: &OitConfig, caps: &Capabilities) -> Vec<Need> {
                match self { $( Technique::$variant => <$kind as TechniqueKind>::needs(self, config, caps), )* }
            }

            fn key(self, config: &OitConfig, caps: &Capabilities) -> Key {
                match self {
                    $( Technique::$variant => Key::$variant(<$kind as TechniqueKind>::key(self, config, caps)), )*
                }
            }

            fn create(self, setup: &Setup, config: &OitConfig) -> Result<Box<dyn TranslucentTechnique>> {
                match self {
                    $( Technique::$variant => Ok(Box::new(<$kind as TechniqueKind>::create(setup, self, config)?)), )*
                }
            }
        }
    };
}

/// `true` for a technique marked `[stalls]` in the list below.
macro_rules! stall_flag {
    () => {
        false
    };
    (stalls) => {
        true
    };
}

techniques! {
    /// Translucent meshes are not drawn at all.
    OpaqueOnly = "opaque-only" => opaque_only::OpaqueOnly,
    /// Weighted blended OIT, one pass into two targets (MRT) with independent blend states.
    WboitMrt = "wboit-mrt" => wboit::Wboit,
    /// Weighted blended OIT, two passes: one per target. For adapters without
    /// independent blend.
    WboitTwoPass = "wboit-two-pass" => wboit::Wboit,
    /// Moment-based OIT with 4 power moments of log-warped depth (Münstermann et al. 2018):
    /// the transmittance in front of each fragment reconstructed from per-pixel moments.
    Mboit = "mboit" => moments::Mboit,
    /// Screen-door transparency with a Bayer pattern (Mulder, Groen & van Wijk 1998): the
    /// low-end mode.
    Stipple = "stipple" => stipple::Stipple,
    /// Alpha blending of chunks sorted back to front (the painter's order): the baseline.
    Sorted = "sorted" => sorted::Sorted,
    /// Like `Sorted`, with the quads inside each chunk sorted back to front too.
    SortedQuads = "sorted-quads" => sorted::Sorted,
    /// Dual depth peeling of [`PeelingSettings::layers`] layers (Bavoil & Myers 2008).
    DepthPeeling = "depth-peeling" => peeling::Peeling,
    /// The exact reference: per-pixel sorted fragment lists (A-buffer). Stalls the GPU.
    Reference = "reference" => reference::Reference [stalls],
    /// The second exact method: front-to-back depth peeling until a pass writes nothing.
    /// Stalls the GPU once per layer.
    PeelReference = "peel-reference" => peeling::Peeling [stalls],
}

/// How many techniques never stall.
const REAL_TIME_COUNT: usize = {
    let mut n = 0;
    let mut i = 0;
    while i < Technique::COUNT {
        if !Technique::ALL[i].stalls() {
            n += 1;
        }
        i += 1;
    }
    n
};

impl Technique {
    /// Every technique that never waits for the GPU inside a frame ([`Technique::stalls`]
    /// is false), in [`Technique::ALL`]'s order: the ones a game offers its players.
    pub const REAL_TIME: [Technique; REAL_TIME_COUNT] = {
        let mut out = [Technique::OpaqueOnly; REAL_TIME_COUNT];
        let (mut i, mut n) = (0, 0);
        while i < Technique::COUNT {
            if !Technique::ALL[i].stalls() {
                out[n] = Technique::ALL[i];
                n += 1;
            }
            i += 1;
        }
        out
    };
}

impl Technique {
    /// The ladder a game climbs down to the best technique a device runs
    /// ([`Technique::best_available`]), best first by the lab's measurements: the sorted
    /// techniques (the default, see [`OitConfig::technique`]; they blend into the scene
    /// colour and need nothing more), WBOIT in one pass and in two (float accumulation
    /// targets, independent blend for one pass), and stipple, the low-end mode, which
    /// needs nothing but the world's own passes (no blending at all).
    pub const LADDER: [Technique; 5] = [
        Technique::SortedQuads,
        Technique::Sorted,
        Technique::WboitMrt,
        Technique::WboitTwoPass,
        Technique::Stipple,
    ];

    /// The low-end mode: stipple, the last rung of [`Technique::LADDER`].
    pub const LOW_END: Technique = Technique::Stipple;

    /// `Ok` when a device of `caps` draws the world and the technique with `config` as
    /// itself; else [`Error::Unsupported`] naming each capability it lacks.
    pub fn check(self, config: &OitConfig, caps: &Capabilities) -> Result<()> {
        QuadFetch::choose(caps, None)?;
        ladder::check("drawing the world", &ladder::world_needs(), caps)?;
        ladder::check(self.name(), &self.needs(config, caps), caps)
    }

    /// What draws when the technique is asked for with `config` on a device of `caps`:
    /// itself, or what replaces it where it cannot run (two-pass WBOIT without independent
    /// blend, peel-to-convergence as the reference without fragment storage), or
    /// [`Error::Unsupported`] naming what the device lacks.
    pub fn resolve(self, config: &OitConfig, caps: &Capabilities) -> Result<Technique> {
        match self.fallback(caps) {
            None => self.check(config, caps).map(|()| self),
            Some(other) => other.check(config, caps).map(|()| other).map_err(|e| {
                let lacking = ladder::missing(&self.needs(config, caps), caps).unwrap_or_default();
                Error::Unsupported(format!(
                    "{self} needs {lacking}, and its replacement {other} cannot run either: {e}"
                ))
            }),
        }
    }

    /// The techniques a device of `caps` runs as themselves with default settings, in
    /// [`Technique::ALL`]'s order (one it lacks something for may still be asked for and
    /// draw as its replacement, [`Technique::resolve`]).
    pub fn supported(caps: &Capabilities) -> Vec<Technique> {
        let config = OitConfig::default();
        Self::ALL
            .into_iter()
            .filter(|t| t.fallback(caps).is_none() && t.check(&config, caps).is_ok())
            .collect()
    }

    /// The highest rung of [`Technique::LADDER`] a device of `caps` runs as itself; an
    /// [`Error::Unsupported`] naming what stipple, the last rung, lacks when it runs none.
    pub fn best_available(caps: &Capabilities) -> Result<Technique> {
        let config = OitConfig::default();
        match Self::LADDER
            .into_iter()
            .find(|t| t.fallback(caps).is_none() && t.check(&config, caps).is_ok())
        {
            Some(t) => Ok(t),
            None => Self::LOW_END.check(&config, caps).map(|()| Self::LOW_END),
        }
    }
}

impl fmt::Display for Technique {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// How a technique's type is built; see the module docs.
pub(crate) trait TechniqueKind: TranslucentTechnique + Sized + 'static {
    /// What its pipelines and targets are built from: the manager rebuilds the technique
    /// when the key changes. Settings outside the key are read every frame.
    type Key: Clone + PartialEq + fmt::Debug;

    /// Whether it draws translucent meshes at all (`false`: no resource, no pass).
    const DRAWS: bool = true;

    /// Whether it draws back to front (a game's objects are then ordered with the chunks).
    const SORTS: bool = false;

    /// Whether `technique` (one this type draws) computes the exact blend.
    fn is_exact(_technique: Technique) -> bool {
        false
    }

    /// Whether it reads the visible translucent meshes' planes ([`FrameView::layers`])
    /// with `config`: the culling copies them only then.
    fn reads_layers(_config: &OitConfig) -> bool {
        false
    }

    /// What replaces `technique` on an adapter that lacks something it needs.
    fn fallback(_technique: Technique, _caps: &Capabilities) -> Option<Technique> {
        None
    }

    /// What `technique` with `config` needs of the device beyond the world's own passes
    /// (features, downlevel flags, limits, formats beyond what WebGPU guarantees), checked
    /// before it is built. Default: nothing more.
    fn needs(_technique: Technique, _config: &OitConfig, _caps: &Capabilities) -> Vec<Need> {
        Vec::new()
    }

    /// The key of `technique` with `config` on this adapter.
    fn key(technique: Technique, config: &OitConfig, caps: &Capabilities) -> Self::Key;

    /// Creates the pipelines and targets of `technique`.
    fn create(setup: &Setup, technique: Technique, config: &OitConfig) -> Result<Self>;
}

/// What a technique is created with.
#[derive(Debug, Clone)]
pub(crate) struct Setup {
    /// The device.
    pub ctx: GpuContext,
    /// Groups 0 and 1 of every chunk pipeline.
    pub layouts: SharedLayouts,
    /// Render target size in pixels.
    pub size: (u32, u32),
    /// Opacity of each block type, by block id.
    pub block_opacity: Arc<[f32]>,
}

/// Settings of the transparency techniques: which one draws, and each one's own settings.
/// Every field has a reasoned default.
#[derive(Clone, Debug, PartialEq)]
pub struct OitConfig {
    /// The technique that draws translucent meshes. Default: `sorted-quads`, the one the
    /// measurements of game frames (terrain with water and glass, a game's particles and
    /// entities) show best: exact on block scenes, within 1/255 of the reference on all
    /// but a few pixels of the game frames, and no dearer on the GPU than chunk sorting.
    pub technique: Technique,
    /// Weighted blended OIT (both variants).
    pub wboit: WboitSettings,
    /// Moment-based OIT.
    pub mboit: MboitSettings,
    /// Stipple.
    pub stipple: StippleSettings,
    /// Depth peeling.
    pub peeling: PeelingSettings,
}

impl Default for OitConfig {
    fn default() -> Self {
        Self {
            // Sorted quads: on the lab's game frames and block suite the most accurate
            // real-time technique at the GPU cost of chunk sorting (README, "What the
            // measurements say"); it needs no optional feature.
            technique: Technique::SortedQuads,
            // Each technique's settings carry their own reasoned defaults.
            wboit: WboitSettings::default(),
            mboit: MboitSettings::default(),
            stipple: StippleSettings::default(),
            peeling: PeelingSettings::default(),
        }
    }
}

impl OitConfig {
    /// A default configuration drawing with `technique`.
    pub fn with(technique: Technique) -> Self {
        Self {
            technique,
            ..Self::default()
        }
    }

    /// Checks every setting against what the renderer supports.
    pub fn validate(&self) -> Result<()> {
        self.stipple.validate()?;
        self.mboit.validate()?;
        self.peeling.validate()
    }
}

/// Technique-specific facts about the last frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TechniqueReport {
    /// CPU milliseconds the technique spent preparing the frame (sorting, fitting).
    pub prepare_ms: f64,
    /// Weighted blended OIT: what the fitted weight was fitted to.
    pub wboit: Option<WboitReport>,
    /// Moment-based OIT: the moments' format and the warp's depth range.
    pub mboit: Option<MboitReport>,
    /// Sorted quads: what was re-sorted.
    pub sort: Option<SortReport>,
    /// Depth peeling: layers found and iterations run.
    pub peeling: Option<PeelReport>,
    /// The A-buffer: attempts, tiles and what did not fit.
    pub reference: Option<ReferenceReport>,
}

/// The CPU side of a frame, for [`TranslucentTechnique::prepare`].
#[derive(Debug)]
pub(crate) struct FrameView<'a> {
    /// The camera.
    pub camera: &'a Camera,
    /// Its camera-relative view-projection for the render target's aspect.
    pub view_proj: Mat4,
    /// The visible chunks with translucent meshes, farthest first.
    pub translucent: &'a [ChunkPos],
    /// Their planes, when the technique asked for them (`OitManager::wants_layers`;
    /// else empty).
    pub layers: VisibleLayers<'a>,
    /// The game's translucent objects when it draws translucent geometry this frame
    /// (`None` when it does not; an empty slice when it draws without declaring them).
    pub game_objects: Option<&'a [TranslucentObject]>,
    /// Where a technique writes its uniforms for the frame: copies in the frame's encoder,
    /// so that a frame recorded before it (and not yet submitted) keeps its own.
    pub writes: &'a std::sync::Mutex<crate::submission::FrameWrites>,
}

impl FrameView<'_> {
    /// Writes `data` into `target` at `offset` in the frame being recorded.
    pub(crate) fn write(&self, target: &wgpu::Buffer, offset: u64, data: &[u8]) {
        self.writes
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .write(target, offset, data);
    }
}

/// What a technique draws with and into, for one frame.
#[derive(Debug)]
pub(crate) struct TranslucentFrame<'a> {
    /// The HDR scene colour holding the opaque image; the composite blends into it.
    pub target: &'a Target,
    /// The opaque depth (single-sample): read-only attachment, or sampled by peeling.
    pub depth: &'a Target,
    /// Group 0: frame uniforms and block textures.
    pub scene: &'a wgpu::BindGroup,
    /// The frame's draw commands.
    pub draws: &'a FrameDraws<'a>,
    /// The visible translucent meshes, farthest first.
    pub chunks: &'a DrawList,
    /// Pass timing, when available.
    pub timer: Option<&'a Timer>,
    /// The eye is inside a translucent volume: draw both sides of translucent faces
    /// (the `two_sided` variant of each [`crate::gpu::SidedPipeline`]).
    pub two_sided: bool,
    /// The exact references walk media along their fragments (a volume in view, or the
    /// eye in one): group 0's volume depth holds the opaque depth, and they draw both
    /// sides (where a ray leaves a volume).
    pub volumes: bool,
    /// The game's translucent geometry, drawn in every pass of the technique.
    pub game: Option<&'a GameDraw<'a>>,
}

impl TranslucentFrame<'_> {
    /// Records the draws of every visible translucent mesh (group 0 and each chunk's
    /// group 1 set here; the pipeline and groups from 2 on set by the caller).
    pub(crate) fn draw_chunks(&self, pass: &mut crate::gpu::CountedPass<'_, '_>) {
        pass.set_bind_group(0, self.scene, &[]);
        self.draws.draw(self.chunks, pass);
    }
}

/// One transparency technique: its pipelines, targets and caches, created when it becomes
/// active and dropped when another one does.
pub(crate) trait TranslucentTechnique: fmt::Debug + Send + Sync {
    /// Rebuilds size-dependent targets; called only when the size really changed.
    fn resize(&mut self, ctx: &GpuContext, width: u32, height: u32) -> Result<()>;

    /// CPU work before the frame is recorded (sorting quads, fitting the weight, writing
    /// the technique's uniforms); may rewrite the order of chunks' translucent quads.
    fn prepare(
        &mut self,
        _ctx: &GpuContext,
        _config: &OitConfig,
        _chunks: &mut ChunkStore,
        _view: &FrameView<'_>,
    ) -> Result<()> {
        Ok(())
    }

    /// Records the translucent pass(es) and the composite into `frame.target`.
    fn render(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        frame: &TranslucentFrame<'_>,
    ) -> Result<()>;

    /// The passes a game's translucent pipelines must match (see [`crate::stages`]).
    fn variants(&self) -> Vec<TranslucentVariant>;

    /// Built ahead of a switch ([`OitManager::prebuild`]): prepares what its first frame
    /// would otherwise build for the chunks on the GPU now (sorted-quads: each chunk's
    /// order structure), so that the switch's first frame costs what a frame costs.
    fn warm(&mut self, _chunks: &ChunkStore) {}

    /// Technique-specific facts about the last frame.
    fn report(&self) -> TechniqueReport {
        TechniqueReport::default()
    }

    /// The WBOIT accumulation target, for techniques that have one.
    fn accumulation(&self) -> Option<&wgpu::Texture> {
        None
    }
}

/// Owns the active technique and records its passes (the life cycle of an engine's OIT
/// manager: created with the device and a config; `resize`; the accumulation and revealage targets;
/// `render` records the translucent pass and composite; resources freed on drop).
#[derive(Debug)]
pub struct OitManager {
    setup: Setup,
    config: OitConfig,
    /// Created on the first frame that has translucent meshes in view (or taken from
    /// `kept`), with its key.
    active: Option<(Key, Box<dyn TranslucentTechnique>)>,
    /// Techniques built ahead of a switch ([`OitManager::prebuild`]), with their keys.
    kept: Vec<(Key, Box<dyn TranslucentTechnique>)>,
    /// The techniques asked for with [`OitManager::prebuild`]: kept built while another
    /// one is active.
    prebuilt: Vec<Technique>,
    /// Techniques built so far.
    builds: usize,
    prepare_ms: f64,
    /// The game's contract for the active technique, made when first asked for.
    contract: Option<Arc<TranslucentContract>>,
    /// The key and id of every contract made so far, so the same technique with the same
    /// settings always has the same id on this renderer and a game's pipelines built for
    /// it stay valid across switches away and back. Ids come from [`NEXT_CONTRACT_ID`], so
    /// no two renderers share one: pipelines built for another renderer's contract (whose
    /// group layouts are that renderer's) are refused, never taken for this one's.
    contract_keys: Vec<(Key, u64)>,
}

/// The next [`TranslucentContract::id`] given out, by any renderer of the process (ids
/// start at 1).
static NEXT_CONTRACT_ID: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

impl OitManager {
    /// A manager for `config`. No GPU resource is created until a frame needs one. A
    /// technique the adapter cannot run falls back (logged): two-pass WBOIT without
    /// independent blend, peel-to-convergence as the reference without fragment storage;
    /// one without a replacement it can run is an [`Error::Unsupported`] naming what the
    /// device lacks ([`Technique::resolve`]).
    pub(crate) fn new(setup: Setup, config: OitConfig) -> Result<Self> {
        config.validate()?;
        let technique = Self::resolve_with(&setup, &config, config.technique)?;
        let mut m = Self {
            setup,
            config,
            active: None,
            kept: Vec::new(),
            prebuilt: Vec::new(),
            builds: 0,
            prepare_ms: 0.0,
            contract: None,
            contract_keys: Vec::new(),
        };
        m.config.technique = technique;
        Ok(m)
    }

    /// `technique`, or what replaces it on this adapter (logged), with `config`'s
    /// settings; [`Error::Unsupported`] when neither can run.
    fn resolve_with(setup: &Setup, config: &OitConfig, technique: Technique) -> Result<Technique> {
        let caps = &setup.ctx.caps;
        let t = technique.resolve(config, caps)?;
        if t != technique {
            let lacking = ladder::missing(&technique.needs(config, caps), caps)
                .unwrap_or_else(|| "what it needs".into());
            log::warn!(
                "technique {technique} needs {lacking}, which this device ({}) lacks: drawing \
                 with {t} instead",
                caps.adapter_name
            );
        }
        Ok(t)
    }

    /// [`OitManager::resolve_with`] with the settings in force.
    fn resolve(&self, technique: Technique) -> Result<Technique> {
        Self::resolve_with(&self.setup, &self.config, technique)
    }

    /// The configuration in force (after any fallback).
    pub fn config(&self) -> &OitConfig {
        &self.config
    }

    /// The active technique.
    pub(crate) fn technique(&self) -> Technique {
        self.config.technique
    }

    /// Whether the technique in force reads the planes of the visible translucent meshes
    /// ([`FrameView::layers`]; WBOIT with the fitted weight, MBOIT). The renderer's culling copies
    /// them only then.
    pub(crate) fn wants_layers(&self) -> bool {
        self.config.technique.reads_layers(&self.config)
    }

    /// Switches technique at run time; the old one's resources are freed at once. Returns
    /// the technique in force (`technique`, or what replaces it on this adapter); one the
    /// adapter cannot run is an [`Error::Unsupported`] and changes nothing.
    pub(crate) fn set_technique(&mut self, technique: Technique) -> Result<Technique> {
        let config = OitConfig {
            technique,
            ..self.config.clone()
        };
        self.set_config(config)?;
        Ok(self.config.technique)
    }

    /// Changes the settings. Resources are rebuilt only when the technique's key (what
    /// its pipelines and targets are built from) changes; other settings apply from the
    /// next frame. An invalid setting, or a technique the adapter cannot run
    /// ([`Error::Unsupported`]), is an error and changes nothing.
    pub(crate) fn set_config(&mut self, config: OitConfig) -> Result<()> {
        config.validate()?;
        let technique = Self::resolve_with(&self.setup, &config, config.technique)?;
        self.config = config;
        self.config.technique = technique;
        let key = self
            .config
            .technique
            .key(&self.config, &self.setup.ctx.caps);
        if self.active.as_ref().is_some_and(|(k, _)| *k != key)
            && let Some(old) = self.active.take()
            && self.prebuilt.contains(&old.0.technique())
        {
            // A prebuilt technique waits for the next switch back to it.
            self.kept.push(old);
        }
        // Prebuilt techniques whose settings changed are rebuilt now, not at the switch.
        for (k, t) in &mut self.kept {
            let technique = k.technique();
            let new = technique.key(&self.config, &self.setup.ctx.caps);
            if new != *k {
                *t = technique.create(&self.setup, &self.config)?;
                self.builds += 1;
                *k = new;
            }
        }
        if self.active.is_none() {
            self.contract = None;
        }
        Ok(())
    }

    /// What a game's translucent pipelines must match for the technique in force (creating
    /// its resources if needed: a game builds its pipelines before the frame that needs
    /// them). Its `id` changes when a switch (or a setting the technique's pipelines depend
    /// on) needs new pipelines.
    pub(crate) fn contract(&mut self) -> Result<Arc<TranslucentContract>> {
        if let Some(c) = &self.contract {
            return Ok(c.clone());
        }
        let technique = self.config.technique;
        let variants = match self.active(true)? {
            Some(t) => t.variants(),
            None => Vec::new(),
        };
        let key = technique.key(&self.config, &self.setup.ctx.caps);
        let c = Arc::new(TranslucentContract {
            id: self.contract_id(key),
            technique: technique.name(),
            variants,
        });
        self.contract = Some(c.clone());
        Ok(c)
    }

    /// The id of the contract of the technique of `key`: the one it got when first seen
    /// on this renderer, else a new one, unique in the process.
    fn contract_id(&mut self, key: Key) -> u64 {
        if let Some((_, id)) = self.contract_keys.iter().find(|(k, _)| *k == key) {
            return *id;
        }
        let id = NEXT_CONTRACT_ID.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        self.contract_keys.push((key, id));
        id
    }

    /// What a game's translucent pipelines must match for `technique` (or what replaces
    /// it on this device) with the current settings, before switching to it: the same
    /// contract, id included, that [`OitManager::contract`] gives once it is in force, so
    /// that a game builds its pipelines ahead as [`OitManager::prebuild`] builds the
    /// technique's (which this does too: the technique stays built). An
    /// [`Error::Unsupported`] for a technique the device cannot run.
    pub(crate) fn contract_for(
        &mut self,
        technique: Technique,
    ) -> Result<Arc<TranslucentContract>> {
        let technique = self.resolve(technique)?;
        if technique == self.config.technique {
            return self.contract();
        }
        self.prebuild(technique)?;
        let key = technique.key(&self.config, &self.setup.ctx.caps);
        let variants = self
            .kept
            .iter()
            .find(|(k, _)| *k == key)
            .map(|(_, t)| t.variants())
            .unwrap_or_default();
        Ok(Arc::new(TranslucentContract {
            id: self.contract_id(key),
            technique: technique.name(),
            variants,
        }))
    }

    /// Builds `technique`'s pipelines and targets now (with the current settings; after
    /// its fallback on this adapter), so that switching to it later builds nothing and the
    /// first frame after the switch costs what any frame costs. It stays built while other
    /// techniques draw, is resized with the others and rebuilt when a setting it is built
    /// from changes, until [`OitManager::release`]. Returns the technique built; one the
    /// adapter cannot run (nor its replacement) is an [`Error::Unsupported`].
    pub(crate) fn prebuild(&mut self, technique: Technique) -> Result<Technique> {
        let technique = self.resolve(technique)?;
        if !self.prebuilt.contains(&technique) {
            self.prebuilt.push(technique);
        }
        if !technique.draws() {
            return Ok(technique);
        }
        let key = technique.key(&self.config, &self.setup.ctx.caps);
        let built = self.active.iter().chain(&self.kept).any(|(k, _)| *k == key);
        if !built {
            let t = technique.create(&self.setup, &self.config)?;
            self.builds += 1;
            self.kept.push((key, t));
        }
        Ok(technique)
    }

    /// What [`TranslucentTechnique::warm`] prepares for `technique` (built ahead), for the
    /// chunks on the GPU now.
    pub(crate) fn warm(&mut self, technique: Technique, chunks: &ChunkStore) {
        let Ok(technique) = self.resolve(technique) else {
            return;
        };
        let key = technique.key(&self.config, &self.setup.ctx.caps);
        for (k, t) in self.active.iter_mut().chain(&mut self.kept) {
            if *k == key {
                t.warm(chunks);
            }
        }
    }

    /// Forgets a [`OitManager::prebuild`]: its resources are freed unless it is active.
    pub(crate) fn release(&mut self, technique: Technique) {
        // A technique that cannot run was never built.
        let Ok(technique) = technique.resolve(&self.config, &self.setup.ctx.caps) else {
            return;
        };
        self.prebuilt.retain(|t| *t != technique);
        self.kept.retain(|(k, _)| k.technique() != technique);
    }

    /// How many times a technique's pipelines and targets were built: a switch to a
    /// prebuilt technique adds nothing.
    pub fn builds(&self) -> usize {
        self.builds
    }

    /// Technique-specific facts about the last frame.
    pub(crate) fn report(&self) -> TechniqueReport {
        let mut r = self
            .active
            .as_ref()
            .map(|(_, t)| t.report())
            .unwrap_or_default();
        r.prepare_ms = self.prepare_ms;
        r
    }

    /// Resizes the targets (the caller checks that the size is valid and new).
    pub(crate) fn resize(&mut self, width: u32, height: u32) -> Result<()> {
        self.setup.size = (width, height);
        for (_, t) in self.active.iter_mut().chain(&mut self.kept) {
            t.resize(&self.setup.ctx, width, height)?;
        }
        Ok(())
    }

    /// The WBOIT accumulation target, when WBOIT is active and has drawn.
    pub fn accumulation_target(&self) -> Option<&wgpu::Texture> {
        self.active.as_ref().and_then(|(_, t)| t.accumulation())
    }

    /// Whether the active technique's GPU resources exist.
    pub fn has_resources(&self) -> bool {
        self.active.is_some()
    }

    /// The active technique, created if translucent meshes are in view and it draws.
    fn active(&mut self, in_view: bool) -> Result<Option<&mut Box<dyn TranslucentTechnique>>> {
        let technique = self.config.technique;
        if !in_view || !technique.draws() {
            return Ok(None);
        }
        if self.active.is_none() {
            let key = technique.key(&self.config, &self.setup.ctx.caps);
            let t = match self.kept.iter().position(|(k, _)| *k == key) {
                Some(i) => self.kept.swap_remove(i).1,
                None => {
                    self.builds += 1;
                    technique.create(&self.setup, &self.config)?
                }
            };
            self.active = Some((key, t));
        }
        Ok(self.active.as_mut().map(|(_, t)| t))
    }

    /// The technique's CPU work for the frame (see [`TranslucentTechnique::prepare`]). With
    /// no visible translucent mesh and no game geometry nothing happens and no resource is
    /// created.
    pub(crate) fn prepare(
        &mut self,
        chunks: &mut ChunkStore,
        view: &FrameView<'_>,
        game: bool,
    ) -> Result<()> {
        let start = web_time::Instant::now();
        let (ctx, config) = (self.setup.ctx.clone(), self.config.clone());
        if let Some(t) = self.active(!view.translucent.is_empty() || game)? {
            t.prepare(&ctx, &config, chunks, view)?;
        }
        self.prepare_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(())
    }

    /// Records the translucent pass(es) and the composite into `frame.target`. With no
    /// visible translucent mesh (or a technique that draws nothing) nothing is recorded.
    pub(crate) fn render(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        frame: &TranslucentFrame<'_>,
    ) -> Result<()> {
        let ctx = self.setup.ctx.clone();
        match self.active(!frame.chunks.is_empty() || frame.game.is_some())? {
            Some(t) => t.render(&ctx, encoder, frame),
            None => Ok(()),
        }
    }
}

/// Where a composite draws: the screen rectangle (0 to 1, y down) that translucent things
/// may cover, grown as more are added; `None` stands for the whole screen. A full-screen
/// composite discards every pixel no translucent fragment reached, so a scissor around the
/// rest leaves the picture as it is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ScreenCover(pub Option<[glam::Vec2; 2]>);

impl ScreenCover {
    /// Nothing covered yet.
    pub(crate) fn none() -> Self {
        Self(Some([glam::Vec2::INFINITY, glam::Vec2::NEG_INFINITY]))
    }

    /// The rectangle `min`–`max` added.
    pub(crate) fn add_rect(&mut self, [min, max]: [glam::Vec2; 2]) {
        if let Some([lo, hi]) = &mut self.0 {
            *lo = lo.min(min);
            *hi = hi.max(max);
        }
    }

    /// The box `lo`–`hi` (world blocks) seen through `view_proj` (camera-relative, from
    /// `eye`) added: the rectangle around its corners' projections; the whole screen when
    /// a corner lies at or behind the eye's plane, or is not finite.
    pub(crate) fn add_box(
        &mut self,
        (lo, hi): (glam::DVec3, glam::DVec3),
        view_proj: Mat4,
        eye: glam::DVec3,
    ) {
        if self.0.is_none() {
            return;
        }
        let (mut min, mut max) = (glam::Vec2::INFINITY, glam::Vec2::NEG_INFINITY);
        for i in 0..8 {
            let corner = glam::DVec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            );
            let clip = view_proj * (corner - eye).as_vec3().extend(1.0);
            // Clip w is the view depth; a corner at or behind the eye's plane reaches
            // everywhere on screen.
            if clip.w.partial_cmp(&1e-3) != Some(std::cmp::Ordering::Greater) || !clip.is_finite() {
                self.0 = None;
                return;
            }
            let p = glam::Vec2::new((clip.x / clip.w + 1.0) * 0.5, (1.0 - clip.y / clip.w) * 0.5);
            min = min.min(p);
            max = max.max(p);
        }
        self.add_rect([min, max]);
    }

    /// A game's objects added (`None`: it draws translucent geometry it does not declare,
    /// which may lie anywhere): the box around all of them (each object's box, or its
    /// ball's).
    pub(crate) fn add_objects(
        &mut self,
        objects: Option<&[TranslucentObject]>,
        view_proj: Mat4,
        eye: glam::DVec3,
    ) {
        let Some(objects) = objects.filter(|o| !o.is_empty()) else {
            if objects.is_some() {
                // Drawn but not declared.
                self.0 = None;
            }
            return;
        };
        let (mut lo, mut hi) = (glam::DVec3::INFINITY, glam::DVec3::NEG_INFINITY);
        for o in objects {
            let half = o.half_extents.unwrap_or(glam::DVec3::splat(o.radius)).abs();
            lo = lo.min(o.center - half);
            hi = hi.max(o.center + half);
        }
        self.add_box((lo, hi), view_proj, eye);
    }

    /// The pixels `[x, y, width, height]` of a `size` target it covers, grown by a pixel
    /// (the rasteriser's vertex snapping, and a projection on the CPU in f32 against the
    /// shader's); zero size when nothing is covered, `None` for the whole screen.
    pub(crate) fn pixels(&self, size: (u32, u32)) -> Option<[u32; 4]> {
        self.0.map(|[min, max]| pixel_rect(min, max, size))
    }
}

/// The pixels `[x, y, width, height]` of a `size` target around the screen rectangle
/// `min`–`max` (0 to 1, y down), grown by a pixel (the rasteriser's vertex snapping, and
/// a projection on the CPU in f32 against the shader's); zero size when it is empty or
/// off screen.
pub(crate) fn pixel_rect(
    min: glam::Vec2,
    max: glam::Vec2,
    (width, height): (u32, u32),
) -> [u32; 4] {
    let size = glam::Vec2::new(width as f32, height as f32);
    let lo = (min * size - 1.0).floor().clamp(glam::Vec2::ZERO, size);
    let hi = (max * size + 1.0).ceil().clamp(glam::Vec2::ZERO, size);
    if !(lo.x < hi.x && lo.y < hi.y) {
        return [0; 4];
    }
    [
        lo.x as u32,
        lo.y as u32,
        (hi.x - lo.x) as u32,
        (hi.y - lo.y) as u32,
    ]
}

/// Parses a command-line name (what `name` gives); the error lists the known names.
impl std::str::FromStr for Technique {
    type Err = Error;

    fn from_str(name: &str) -> Result<Self> {
        crate::error::parse_name("technique", name, &Self::ALL, Self::name)
    }
}
