//! The lab's results: what was asked ([`EvalOptions`]), one [`Record`] per scene ×
//! technique, the exact methods' agreement per scene ([`ReferenceCheck`]), and the
//! questions the charts and the report ask of them.

use crate::Result;

use std::path::{Path, PathBuf};

use serde::Serialize;
use voxel_render::{Technique, WeightFunction};

use crate::random::{Features, RandomSet};

/// What to run.
#[derive(Clone, Debug)]
pub struct EvalOptions {
    /// Scene files, in order.
    pub scenes: Vec<PathBuf>,
    /// Techniques to measure (the exact reference is always rendered too).
    pub techniques: Vec<Technique>,
    /// WBOIT weights compared in extra `wboit-mrt` runs (empty: none).
    pub weights: Vec<WeightFunction>,
    /// Output size; `None`: each scene's own, else 640×360.
    pub size: Option<(u32, u32)>,
    /// Timed frames per picture (the median is reported).
    pub frames: usize,
    /// Untimed frames first (pipelines, targets, adaptive peeling settle).
    pub warmup: usize,
    /// Output folder.
    pub out: PathBuf,
    /// Run the stability sweeps too.
    pub stability: bool,
    /// Frames of the flicker camera path.
    pub flicker_frames: usize,
    /// Points per sweep (the parameter lists are cut to this many, spread over their range).
    pub sweep_points: usize,
    /// The command line, for the report.
    pub command: String,
    /// Width of the saved heat maps and reference pictures (downscaled, to keep results
    /// small); `None`: full size.
    pub heatmap_width: Option<u32>,
    /// Random scenes instead of `scenes` (`demo eval --random N --seed S`): no heat maps
    /// per scene; `distribution.json`, `scenes.json`, `worst/` and the distribution
    /// charts besides the usual files.
    pub random: Option<RandomSet>,
    /// What a run spends its time on besides the techniques' frames: FLIP, heat maps, the
    /// ray march.
    pub checks: Checks,
}

/// The lab's own work per scene and per run, which a quick check can cut: each is on by
/// default.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Checks {
    /// Mean FLIP per run (NVIDIA's perceptual difference, on the CPU: the lab's dearest
    /// step per run at large sizes). Off: `flip_mean` is `null` (NaN) and no heat map is
    /// made.
    pub flip: bool,
    /// FLIP heat maps and the reference pictures saved per scene.
    pub heatmaps: bool,
    /// Width of the CPU ray march that checks each scene's reference (`None`: the run's
    /// size; `Some(0)`: no ray march, the reference counts as exact where the two GPU
    /// methods agree within 2/255 and the A-buffer capped nothing visibly). The ray
    /// march is the dearest step per scene.
    pub raymarch_width: Option<u32>,
    /// Wall-clock seconds after which no further scene is started (`None`: no limit): a
    /// check on a machine lent for minutes ends with the scenes done written out, those
    /// left named in the report.
    pub time_budget: Option<f64>,
}

impl Default for Checks {
    fn default() -> Self {
        Self {
            flip: true,
            heatmaps: true,
            raymarch_width: None,
            time_budget: None,
        }
    }
}

/// One scene × technique measurement (the keys of `summary.json`).
#[derive(Clone, Debug, Serialize)]
pub struct Record {
    /// Scene file stem.
    pub scene: String,
    /// Technique name (with `/weight` for the weight comparison runs).
    pub technique: String,
    /// WBOIT weight in force, for WBOIT techniques.
    pub weight: Option<String>,
    /// Picture width.
    pub width: u32,
    /// Picture height.
    pub height: u32,
    /// Median GPU ms of the translucent work per frame (the technique's passes and
    /// composites); `null` without timestamp queries.
    pub gpu_ms: Option<f64>,
    /// Median CPU ms to record a frame (quad sorting and the exact methods' waits included).
    pub cpu_ms: f64,
    /// Median CPU ms of it spent ordering the game's translucent objects with the chunks
    /// (sorted techniques in scenes with particles or entities; `null` otherwise).
    #[serde(default)]
    pub game_sort_ms: Option<f64>,
    /// Root mean square error, [0, 1] units.
    pub rmse: f64,
    /// PSNR in dB (100: identical).
    pub psnr: f64,
    /// Mean FLIP.
    pub flip_mean: f64,
    /// Largest channel error in 1/255 steps.
    pub max_abs_err: u32,
    /// Share of pixels off by more than 1/255.
    pub frac_bad_px: f64,
    /// Pixels of the HDR scene colour holding NaN or inf.
    pub nan_px: usize,
    /// Depth peeling: layers found.
    pub layers: Option<u32>,
    /// The A-buffer: fragments that did not fit its pool (should be 0).
    pub lost_fragments: Option<u64>,
    /// The A-buffer: pixels with more fragments than it blends.
    pub capped_pixels: Option<u64>,
    /// Whether the scene's reference is exact ([`ReferenceCheck::exact`]); the errors of
    /// a scene whose reference is not are not scored in means and charts.
    pub reference_exact: bool,
    /// `sorted-quads`: cycles in the visible chunks' quad orders (groups of quads no
    /// order draws exactly); 0 means its order is exact.
    pub sort_cycles: Option<u32>,
    /// `sorted-quads`: quads in those cycles.
    pub quads_in_cycles: Option<u32>,
    /// The sorted techniques: the largest channel error over the pixels off translucent
    /// quad edges ([`crate::edges`]) and off a game's objects that interpenetrate or nearly
    /// touch ([`crate::overlaps`]), where the order of quads and planes decides the colour.
    pub max_abs_err_off_edges: Option<u32>,
    /// The sorted techniques: pixels off by more than 1/255 that lie on a quad edge.
    pub edge_px: Option<u32>,
    /// The sorted techniques: pixels off by more than 1/255 that show two of a game's
    /// objects that interpenetrate (no order of whole objects is right there).
    pub overlap_px: Option<u32>,
    /// The sorted techniques: pixels off by more than 1/255 that show two of a game's
    /// objects near each other (bounding balls meeting, solids apart), whose centres order
    /// them.
    pub near_px: Option<u32>,
    /// The FLIP heat map, relative to the output folder (empty when not saved: random
    /// scenes save none).
    pub heatmap: String,
    /// What the technique's frame asked of the GPU, counted in one frame after the timed
    /// ones (`null` where the frame could not be counted).
    pub cost: Option<CostRecord>,
}

/// What one frame asked of the GPU ([`voxel_render::low_level::FrameCost`]): sums over
/// the translucent work, the media passes and the whole frame, and each pass.
#[derive(Clone, Debug, Serialize)]
pub struct CostRecord {
    /// The technique's passes and composites (what `gpu_ms` times).
    pub translucent: CostSums,
    /// The passes of the media (the eye's medium and volumes in view), before the
    /// technique draws.
    pub media: CostSums,
    /// Every pass of the frame.
    pub frame: CostSums,
    /// Buffer copies of the frame's own writes (uniforms, draw commands, re-sorted quads).
    pub uploads: u32,
    /// Their bytes.
    pub upload_bytes: u64,
    /// Buffers created while the frame was recorded.
    pub buffers_created: u32,
    /// Bind groups created while the frame was recorded.
    pub bind_groups_created: u32,
    /// Every pass, in order.
    pub passes: Vec<PassRecord>,
}

/// Sums over a set of passes ([`voxel_render::low_level::CostTotals`]).
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct CostSums {
    /// Render passes.
    pub passes: u32,
    /// Texture copies.
    pub copies: u32,
    /// Passes that drew a full-screen triangle.
    pub full_screen_passes: u32,
    /// Draw commands recorded.
    pub draw_calls: u32,
    /// Draws issued (each command of a multi-draw).
    pub draws: u32,
    /// Pipeline changes.
    pub pipelines: u32,
    /// Bind group and vertex buffer changes.
    pub bind_groups: u32,
    /// Calls into the game's own drawing.
    pub game_calls: u32,
    /// Bytes of targets cleared.
    pub clear_bytes: u64,
    /// Fragments shaded (`null`: not measured).
    pub fragments: Option<u64>,
    /// Samples written or blended.
    pub samples: Option<u64>,
    /// Bytes written into targets, clears and copies included.
    pub bytes_written: Option<u64>,
    /// Bytes read from targets and the textures the passes declare.
    pub bytes_read: Option<u64>,
    /// Fragments shaded per pixel of the frame.
    pub fragments_per_pixel: Option<f64>,
}

impl CostSums {
    fn of(t: &voxel_render::low_level::CostTotals, pixels: u64) -> Self {
        Self {
            passes: t.passes,
            copies: t.copies,
            full_screen_passes: t.full_screen_passes,
            draw_calls: t.draw_calls,
            draws: t.draws,
            pipelines: t.pipelines,
            bind_groups: t.bind_groups,
            game_calls: t.game_calls,
            clear_bytes: t.clear_bytes,
            fragments: t.fragments,
            samples: t.samples,
            bytes_written: t.bytes_written,
            bytes_read: t.bytes_read,
            fragments_per_pixel: t.fragments.map(|f| f as f64 / pixels.max(1) as f64),
        }
    }

    /// Bytes written and read together (`None`: not measured).
    pub fn bytes(&self) -> Option<u64> {
        Some(self.bytes_written? + self.bytes_read?)
    }
}

/// One pass of a counted frame ([`voxel_render::low_level::PassCost`]).
#[derive(Clone, Debug, Serialize)]
pub struct PassRecord {
    /// Its label.
    pub label: String,
    /// The kind of GPU work it counts as (`untimed` for none).
    pub kind: String,
    /// Draw commands recorded.
    pub draw_calls: u32,
    /// Draws issued.
    pub draws: u32,
    /// Pipeline changes.
    pub pipelines: u32,
    /// Bind group and vertex buffer changes.
    pub bind_groups: u32,
    /// Calls into the game's own drawing.
    pub game_calls: u32,
    /// Full-screen triangles drawn.
    pub full_screen_draws: u32,
    /// Bytes of attachments cleared.
    pub clear_bytes: u64,
    /// Bytes a texture copy moved (0: a render pass).
    pub copy_bytes: u64,
    /// Fragments shaded.
    pub fragments: Option<u64>,
    /// Samples written or blended.
    pub samples: Option<u64>,
    /// Bytes written.
    pub bytes_written: Option<u64>,
    /// Bytes read.
    pub bytes_read: Option<u64>,
}

impl CostRecord {
    /// The record of `cost`.
    pub fn of(cost: &voxel_render::low_level::FrameCost) -> Self {
        let px = cost.pixels;
        Self {
            translucent: CostSums::of(&cost.translucent(), px),
            media: CostSums::of(&cost.of_kind(voxel_render::GpuPass::Medium), px),
            frame: CostSums::of(&cost.all(), px),
            uploads: cost.uploads,
            upload_bytes: cost.upload_bytes,
            buffers_created: cost.buffers_created,
            bind_groups_created: cost.bind_groups_created,
            passes: cost
                .passes
                .iter()
                .map(|p| PassRecord {
                    label: p.label.clone(),
                    kind: p
                        .kind
                        .map_or("untimed", voxel_render::GpuPass::name)
                        .to_owned(),
                    draw_calls: p.draw_calls,
                    draws: p.draws,
                    pipelines: p.pipelines,
                    bind_groups: p.bind_groups,
                    game_calls: p.game_calls,
                    full_screen_draws: p.full_screen_draws,
                    clear_bytes: p.clear_bytes,
                    copy_bytes: p.copy_bytes,
                    fragments: p.fragments,
                    samples: p.samples,
                    bytes_written: p.bytes_written(),
                    bytes_read: p.bytes_read(),
                })
                .collect(),
        }
    }
}

/// The exact methods against each other, per scene.
#[derive(Clone, Debug, Serialize)]
pub struct ReferenceCheck {
    /// Scene file stem.
    pub scene: String,
    /// Largest channel difference between the A-buffer and peel-to-convergence pictures.
    pub max_abs_err: u32,
    /// Pixels where the two GPU methods differ by more than 2/255 (`eval::GPU_AGREEMENT`)
    /// and the ray march does not side with the A-buffer (`eval::unsettled_pixels`, which
    /// lies above this module).
    pub unsettled: usize,
    /// Whether the reference counts as exact: the A-buffer lost nothing and capped no
    /// pixel visibly, the CPU ray march ([`crate::raymarch`]), which shares no mesh and
    /// no rasteriser with it, agrees with it (flat textures) on every pixel off geometric
    /// edges and finds no crack, and wherever the two GPU methods differ by more than
    /// 2/255 the ray march sides with the A-buffer (`unsettled` is 0). The ray march
    /// decides where the GPU methods disagree (peeling keeps one of two fragments of equal
    /// depth); a disagreement it cannot decide (on an edge or a seam) leaves the scene
    /// unscored.
    pub exact: bool,
    /// The ray march against the A-buffer, both with flat textures.
    pub raymarch: RayMarchSummary,
    /// A-buffer fragments that did not fit (must be 0).
    pub lost_fragments: u64,
    /// A-buffer pixels with more fragments than it blends.
    pub capped_pixels: u64,
    /// Of those, pixels where the fragments it dropped could change the colour.
    pub capped_visible_pixels: u64,
    /// Layers peel-to-convergence found (the scene's depth complexity).
    pub depth_complexity: u32,
}

/// What the ray march found against the A-buffer on one scene (flat textures).
#[derive(Clone, Debug, Default, Serialize)]
pub struct RayMarchSummary {
    /// Pixels off geometric edges and seams whose colours differ by more than 1/255.
    pub differing: usize,
    /// The largest channel difference off edges and seams (1/255).
    pub max_abs_err_off_edges: u8,
    /// Differing pixels with an edge within `raymarch::EDGE_RADIUS_PX` of the centre.
    pub differing_on_edges: usize,
    /// Differing pixels on a seam of two merged translucent quads (a T-junction can drop a
    /// layer at a sub-pixel sliver).
    pub translucent_seams: usize,
    /// Pixels where the GPU drew no opaque surface inside closed geometry.
    pub cracks: usize,
    /// Where the first differing pixels are: pixel, colours, and the chunk, block and face
    /// the ray ended on.
    pub worst: Vec<String>,
    /// Seconds the ray march of the picture took.
    pub seconds: f64,
}

/// Everything an evaluation produced.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    /// Adapter the pictures were rendered on.
    pub adapter: String,
    /// One record per scene × technique.
    pub records: Vec<Record>,
    /// The exact methods' agreement per scene.
    pub reference_checks: Vec<ReferenceCheck>,
    /// Random scenes: what each holds, in scene order (empty for scene files).
    pub features: Vec<SceneFeatures>,
    /// Scenes left out because the run's time budget was spent
    /// ([`Checks::time_budget`]).
    pub skipped: Vec<String>,
}

/// What a random scene holds.
#[derive(Clone, Debug, Serialize)]
pub struct SceneFeatures {
    /// Scene name (`random-SEED-INDEX`).
    pub scene: String,
    /// Its features.
    pub features: Features,
}

/// A technique's means over the scenes whose reference is exact.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SuiteMean {
    /// Mean GPU ms, if every scene has a GPU time.
    pub gpu_ms: Option<f64>,
    /// Mean CPU ms.
    pub cpu_ms: f64,
    /// Mean FLIP.
    pub flip: f64,
    /// Mean RMSE.
    pub rmse: f64,
    /// Scenes counted.
    pub scenes: usize,
}

impl Summary {
    /// The techniques of the main chart and tables, in order: the runs without a weight
    /// suffix.
    pub fn main_techniques(&self) -> Vec<String> {
        let mut names: Vec<String> = Vec::new();
        for r in &self.records {
            if !r.technique.contains('/') && !names.contains(&r.technique) {
                names.push(r.technique.clone());
            }
        }
        names
    }

    /// The weight comparison runs (`wboit-mrt/<weight>`), in order.
    pub fn weight_runs(&self) -> Vec<String> {
        let mut names: Vec<String> = Vec::new();
        for r in &self.records {
            if r.technique.contains('/') && !names.contains(&r.technique) {
                names.push(r.technique.clone());
            }
        }
        names
    }

    /// The records of `technique` on scenes whose reference is exact.
    pub fn scored<'a>(&'a self, technique: &'a str) -> impl Iterator<Item = &'a Record> + 'a {
        self.records
            .iter()
            .filter(move |r| r.technique == technique && r.reference_exact)
    }

    /// Means of `technique` over the scored scenes.
    pub fn suite_mean(&self, technique: &str) -> SuiteMean {
        let rs: Vec<&Record> = self.scored(technique).collect();
        let n = rs.len().max(1) as f64;
        SuiteMean {
            gpu_ms: rs
                .iter()
                .map(|r| r.gpu_ms)
                .collect::<Option<Vec<f64>>>()
                .map(|v| v.iter().sum::<f64>() / n),
            cpu_ms: rs.iter().map(|r| r.cpu_ms).sum::<f64>() / n,
            flip: rs.iter().map(|r| r.flip_mean).sum::<f64>() / n,
            rmse: rs.iter().map(|r| r.rmse).sum::<f64>() / n,
            scenes: rs.len(),
        }
    }

    /// The largest disagreement of the exact methods over all scenes.
    pub fn worst_reference_disagreement(&self) -> u32 {
        self.reference_checks
            .iter()
            .map(|c| c.max_abs_err)
            .max()
            .unwrap_or(0)
    }
}

/// Whether a run name (`wboit-mrt/fitted` counts as `wboit-mrt`) is one of the real-time
/// techniques that draw: not an exact method, not `opaque-only`.
pub fn is_real_time(run: &str) -> bool {
    let name = run.split('/').next().unwrap_or(run);
    name.parse::<Technique>()
        .is_ok_and(|t| t.draws() && !t.is_exact())
}

/// Writes `value` as pretty JSON.
pub fn write_json(path: &Path, value: &impl Serialize) -> Result<()> {
    let text = serde_json::to_string_pretty(value)?;
    crate::files::write_file(path, (text + "\n").as_bytes())
}
