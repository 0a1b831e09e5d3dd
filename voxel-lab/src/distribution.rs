//! The lab over random scenes ([`crate::random`]): per technique the distribution of its
//! error over the scenes (percentiles of mean FLIP and of the largest channel error, the
//! share of scenes it gets exact, NaN pixels), a histogram of its largest error, and
//! **where it fails**: which scene features are over-represented among its worst scenes.
//!
//! Only scenes whose reference is exact are scored (the others are counted and named).
//! Percentiles are nearest-rank: `pP` is the smallest value that at least P % of the
//! scenes do not exceed. A technique's worst scene is the one with the highest mean FLIP,
//! ties broken by the largest channel error.

use crate::{Error, Result};

use serde::Serialize;

use crate::random::{Features, RandomSet};
use crate::summary::{EvalOptions, Record, Summary, is_real_time};

/// Percentiles of a set of values.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Percentiles {
    /// 10th percentile.
    pub p10: f64,
    /// Median.
    pub p50: f64,
    /// 90th percentile.
    pub p90: f64,
    /// 99th percentile.
    pub p99: f64,
    /// Largest value.
    pub max: f64,
}

/// The nearest-rank `p`-th percentile of sorted, non-empty `sorted`.
pub fn percentile(sorted: &[f64], p: f64) -> f64 {
    let n = sorted.len();
    let rank = ((p / 100.0) * n as f64).ceil().max(1.0) as usize;
    sorted[rank.min(n) - 1]
}

impl Percentiles {
    /// The percentiles of `values`; `None` when there are none.
    pub fn of(values: &[f64]) -> Option<Self> {
        if values.is_empty() {
            return None;
        }
        let mut v = values.to_vec();
        v.sort_by(f64::total_cmp);
        Some(Self {
            p10: percentile(&v, 10.0),
            p50: percentile(&v, 50.0),
            p90: percentile(&v, 90.0),
            p99: percentile(&v, 99.0),
            max: v[v.len() - 1],
        })
    }
}

/// Bins of the largest-error histogram, in 1/255 steps, inclusive.
pub const ERROR_BINS: [(u32, u32); 9] = [
    (0, 0),
    (1, 1),
    (2, 3),
    (4, 7),
    (8, 15),
    (16, 31),
    (32, 63),
    (64, 127),
    (128, 255),
];

/// Label of error bin `i` (`"2–3"`).
pub fn bin_label(i: usize) -> String {
    let (lo, hi) = ERROR_BINS[i];
    if lo == hi {
        lo.to_string()
    } else {
        format!("{lo}–{hi}")
    }
}

/// One technique (or weight run) over the scored scenes.
#[derive(Clone, Debug, Serialize)]
pub struct TechniqueDistribution {
    /// Run name (`wboit-mrt/fitted` for a weight run).
    pub technique: String,
    /// Scenes scored (reference exact).
    pub n: usize,
    /// Mean FLIP per scene.
    pub flip_mean: Percentiles,
    /// Largest channel error per scene, in 1/255.
    pub max_abs_err: Percentiles,
    /// Share of scored scenes within 1/255 everywhere.
    pub exact_share: f64,
    /// `sorted-quads`: share of scored scenes within 1/255 off the quad edges
    /// ([`crate::edges`]).
    pub exact_off_edges_share: Option<f64>,
    /// NaN/inf pixels over all scenes (scored or not).
    pub nan_px: usize,
    /// GPU ms of the translucent work, over the scored scenes where it drew something
    /// (`None` without timestamps, or where it never did).
    pub gpu_ms: Option<Percentiles>,
    /// CPU ms per frame.
    pub cpu_ms: Percentiles,
    /// Scenes per bin of [`ERROR_BINS`].
    pub histogram: Vec<usize>,
    /// Its worst scene (largest error, then highest FLIP).
    pub worst_scene: String,
    /// That scene's mean FLIP.
    pub worst_flip: f64,
    /// That scene's largest error.
    pub worst_max_abs_err: u32,
}

/// What one random scene holds and what was measured of it as a whole.
#[derive(Clone, Debug, Serialize)]
pub struct SceneRow {
    /// `random-SEED-INDEX`.
    pub scene: String,
    /// What the generator put in it.
    pub features: Features,
    /// Whether its reference is exact (it is scored).
    pub reference_exact: bool,
    /// The exact methods' largest disagreement, in 1/255.
    pub reference_disagreement: u32,
    /// Layers peel-to-convergence found.
    pub depth_complexity: u32,
    /// Whether the reference differs from `opaque-only` (something translucent is in
    /// view); `None` when `opaque-only` was not run.
    pub translucent_in_view: Option<bool>,
    /// Quad-order cycles `sorted-quads` met; `None` when it was not run.
    pub sort_cycles: Option<u32>,
}

impl SceneRow {
    /// The generator's features and the measured ones, in plain words.
    pub fn flags(&self) -> Vec<(&'static str, bool)> {
        let mut v = self.features.flags();
        v.push(("a depth complexity over 8", self.depth_complexity > 8));
        v.push((
            "cycles in the quad order",
            self.sort_cycles.is_some_and(|c| c > 0),
        ));
        v
    }
}

/// How many scenes have a feature.
#[derive(Clone, Debug, Serialize)]
pub struct FeatureShare {
    /// The feature, in plain words.
    pub feature: String,
    /// Scenes with it.
    pub scenes: usize,
    /// Their share of all scenes.
    pub share: f64,
}

/// A feature more common among a technique's worst scenes than among all.
#[derive(Clone, Debug, Serialize)]
pub struct OverRepresented {
    /// The feature.
    pub feature: String,
    /// Worst scenes with it.
    pub worst: usize,
    /// Their share of the worst scenes.
    pub worst_share: f64,
    /// Its share of all scored scenes.
    pub all_share: f64,
}

/// Where a technique fails: its worst decile and the features over-represented in it.
#[derive(Clone, Debug, Serialize)]
pub struct WhereItFails {
    /// The technique.
    pub technique: String,
    /// Scored scenes where it is off by more than 1/255 somewhere.
    pub failing: usize,
    /// Scored scenes.
    pub scored: usize,
    /// Its worst decile (largest error first, then highest FLIP), only scenes where it
    /// fails.
    pub worst: Vec<String>,
    /// Lowest and highest mean FLIP among them.
    pub worst_flip: (f64, f64),
    /// Largest error among them.
    pub worst_max_abs_err: u32,
    /// Features at least 1.5 times as common among the worst as among all scored
    /// scenes (and in at least 30 % and 2 of them), most over-represented first.
    pub over: Vec<OverRepresented>,
}

/// Everything `distribution.json` holds (and `scenes.json`, the rows).
#[derive(Clone, Debug, Serialize)]
pub struct Distribution {
    /// Seed of the scenes.
    pub seed: u64,
    /// Scenes drawn.
    pub count: usize,
    /// Picture size.
    pub width: u32,
    /// Picture height.
    pub height: u32,
    /// Scenes scored (reference exact).
    pub scored: usize,
    /// Scenes not scored: the exact methods disagree by more than 2/255, or the A-buffer
    /// capped pixels visibly.
    pub not_scored: Vec<String>,
    /// Scenes whose reference equals `opaque-only` (nothing translucent in view).
    pub translucent_not_in_view: usize,
    /// Their share of all scenes.
    pub translucent_not_in_view_share: f64,
    /// Share of scenes with each feature.
    pub features: Vec<FeatureShare>,
    /// Per run: the distribution of its error.
    pub techniques: Vec<TechniqueDistribution>,
    /// Per real-time technique: where it fails.
    pub where_it_fails: Vec<WhereItFails>,
    /// Per scene: what it holds (written to `scenes.json`, not `distribution.json`).
    #[serde(skip)]
    pub scenes: Vec<SceneRow>,
}

/// Smallest share of the worst scenes a feature needs to count as over-represented.
pub const MIN_WORST_SHARE: f64 = 0.3;
/// Smallest ratio of its share among the worst scenes to its share among all.
pub const MIN_LIFT: f64 = 1.5;

/// A record's rank for "worst": the largest error, then FLIP. (FLIP first would call a
/// scene off by 1/255 on many pixels worse than one off by 88/255 on a few: the first is
/// rounding, the second a wrong picture.)
fn worse(a: &Record, b: &Record) -> std::cmp::Ordering {
    a.max_abs_err
        .cmp(&b.max_abs_err)
        .then(a.flip_mean.total_cmp(&b.flip_mean))
}

/// The distribution of every run of `summary`, an evaluation of the random scenes `set`.
pub fn compute(summary: &Summary, set: RandomSet) -> Distribution {
    let (width, height) = summary
        .records
        .first()
        .map_or((0, 0), |r| (r.width, r.height));
    let scenes: Vec<SceneRow> = summary
        .features
        .iter()
        .map(|f| {
            let check = summary.reference_checks.iter().find(|c| c.scene == f.scene);
            let of = |t: &str| {
                summary
                    .records
                    .iter()
                    .find(|r| r.scene == f.scene && r.technique == t)
            };
            SceneRow {
                scene: f.scene.clone(),
                features: f.features.clone(),
                reference_exact: check.is_some_and(|c| c.exact),
                reference_disagreement: check.map_or(0, |c| c.max_abs_err),
                depth_complexity: check.map_or(0, |c| c.depth_complexity),
                translucent_in_view: of("opaque-only").map(|r| r.max_abs_err > 0),
                sort_cycles: of("sorted-quads").and_then(|r| r.sort_cycles),
            }
        })
        .collect();
    let not_scored: Vec<String> = scenes
        .iter()
        .filter(|s| !s.reference_exact)
        .map(|s| s.scene.clone())
        .collect();
    let scored = scenes.len() - not_scored.len();
    let translucent_not_in_view = scenes
        .iter()
        .filter(|s| s.translucent_in_view == Some(false))
        .count();

    let mut features: Vec<FeatureShare> = Vec::new();
    for s in &scenes {
        for (name, on) in s.flags() {
            match features.iter_mut().find(|f| f.feature == name) {
                Some(f) => f.scenes += usize::from(on),
                None => features.push(FeatureShare {
                    feature: name.to_owned(),
                    scenes: usize::from(on),
                    share: 0.0,
                }),
            }
        }
    }
    for f in &mut features {
        f.share = f.scenes as f64 / scenes.len().max(1) as f64;
    }

    let mut runs = summary.main_techniques();
    runs.extend(summary.weight_runs());
    let techniques: Vec<TechniqueDistribution> =
        runs.iter().filter_map(|t| technique(summary, t)).collect();
    let where_it_fails = summary
        .main_techniques()
        .iter()
        .filter(|t| is_real_time(t))
        .map(|t| where_it_fails(summary, &scenes, t))
        .collect();
    Distribution {
        seed: set.seed,
        count: scenes.len(),
        width,
        height,
        scored,
        not_scored,
        translucent_not_in_view,
        translucent_not_in_view_share: translucent_not_in_view as f64 / scenes.len().max(1) as f64,
        features,
        techniques,
        where_it_fails,
        scenes,
    }
}

fn technique(summary: &Summary, t: &str) -> Option<TechniqueDistribution> {
    let rs: Vec<&Record> = summary.scored(t).collect();
    let worst = rs.iter().copied().max_by(|a, b| worse(a, b))?;
    let flip: Vec<f64> = rs.iter().map(|r| r.flip_mean).collect();
    let err: Vec<f64> = rs.iter().map(|r| f64::from(r.max_abs_err)).collect();
    let gpu: Vec<f64> = rs
        .iter()
        .filter_map(|r| r.gpu_ms)
        .filter(|g| *g > 0.0)
        .collect();
    let cpu: Vec<f64> = rs.iter().map(|r| r.cpu_ms).collect();
    let histogram = ERROR_BINS
        .iter()
        .map(|(lo, hi)| {
            rs.iter()
                .filter(|r| (*lo..=*hi).contains(&r.max_abs_err.min(255)))
                .count()
        })
        .collect();
    Some(TechniqueDistribution {
        technique: t.to_owned(),
        n: rs.len(),
        flip_mean: Percentiles::of(&flip)?,
        max_abs_err: Percentiles::of(&err)?,
        exact_share: rs.iter().filter(|r| r.max_abs_err <= 1).count() as f64 / rs.len() as f64,
        exact_off_edges_share: rs
            .iter()
            .map(|r| r.max_abs_err_off_edges.map(|e| e <= 1))
            .collect::<Option<Vec<bool>>>()
            .map(|e| e.iter().filter(|x| **x).count() as f64 / rs.len() as f64),
        nan_px: summary
            .records
            .iter()
            .filter(|r| r.technique == t)
            .map(|r| r.nan_px)
            .sum(),
        gpu_ms: Percentiles::of(&gpu),
        cpu_ms: Percentiles::of(&cpu)?,
        histogram,
        worst_scene: worst.scene.clone(),
        worst_flip: worst.flip_mean,
        worst_max_abs_err: worst.max_abs_err,
    })
}

fn where_it_fails(summary: &Summary, scenes: &[SceneRow], t: &str) -> WhereItFails {
    let mut rs: Vec<&Record> = summary.scored(t).collect();
    rs.sort_by(|a, b| worse(b, a));
    let decile = rs.len().div_ceil(10).max(1);
    let worst: Vec<&Record> = rs
        .iter()
        .copied()
        .take(decile)
        .filter(|r| r.max_abs_err > 1)
        .collect();
    let row = |name: &str| scenes.iter().find(|s| s.scene == name);
    let flags_of = |r: &Record| row(&r.scene).map(SceneRow::flags).unwrap_or_default();
    let mut over = Vec::new();
    if !worst.is_empty() {
        let all: Vec<Vec<(&str, bool)>> = rs.iter().map(|r| flags_of(r)).collect();
        let bad: Vec<Vec<(&str, bool)>> = worst.iter().map(|r| flags_of(r)).collect();
        let names: Vec<&str> = all.first().map_or(Vec::new(), |f| {
            f.iter().map(|(n, _)| *n).collect::<Vec<&str>>()
        });
        let count = |set: &[Vec<(&str, bool)>], name: &str| {
            set.iter()
                .filter(|f| f.iter().any(|(n, on)| *n == name && *on))
                .count()
        };
        for name in names {
            let w = count(&bad, name);
            let worst_share = w as f64 / bad.len() as f64;
            let all_share = count(&all, name) as f64 / all.len() as f64;
            if w >= 2.min(bad.len())
                && worst_share >= MIN_WORST_SHARE
                && worst_share >= MIN_LIFT * all_share
            {
                over.push(OverRepresented {
                    feature: name.to_owned(),
                    worst: w,
                    worst_share,
                    all_share,
                });
            }
        }
        over.sort_by(|a, b| {
            (b.worst_share / b.all_share.max(1e-9))
                .total_cmp(&(a.worst_share / a.all_share.max(1e-9)))
                .then(b.worst.cmp(&a.worst))
        });
    }
    WhereItFails {
        technique: t.to_owned(),
        failing: rs.iter().filter(|r| r.max_abs_err > 1).count(),
        scored: rs.len(),
        worst: worst.iter().map(|r| r.scene.clone()).collect(),
        worst_flip: (
            worst
                .iter()
                .map(|r| r.flip_mean)
                .fold(f64::INFINITY, f64::min)
                .min(1.0),
            worst.iter().map(|r| r.flip_mean).fold(0.0, f64::max),
        ),
        worst_max_abs_err: worst.iter().map(|r| r.max_abs_err).max().unwrap_or(0),
        over,
    }
}

/// `where` in plain words: one paragraph.
pub fn describe(w: &WhereItFails) -> String {
    if w.worst.is_empty() {
        return format!(
            "**{}** is within 1/255 of the reference on every one of the {} scored scenes: no failure to explain.",
            w.technique, w.scored
        );
    }
    let mut s = format!(
        "**{}** is off by more than 1/255 on {} of {} scenes. Its worst {} (up to {}/255, mean FLIP {:.4} to {:.4})",
        w.technique,
        w.failing,
        w.scored,
        if w.worst.len() == 1 {
            "scene".to_owned()
        } else {
            format!("{} scenes", w.worst.len())
        },
        w.worst_max_abs_err,
        w.worst_flip.0,
        w.worst_flip.1,
    );
    let one = w.worst.len() == 1;
    if w.over.is_empty() {
        s += if one {
            " looks like the rest: none of its features is rarer elsewhere."
        } else {
            " look like the rest: no feature is over-represented among them."
        };
        return s;
    }
    let parts: Vec<String> = w
        .over
        .iter()
        .map(|o| {
            format!(
                "{} ({} of {}, against {:.0} % of all scenes)",
                o.feature,
                o.worst,
                w.worst.len(),
                o.all_share * 100.0
            )
        })
        .collect();
    s += if one {
        " has these features, each rarer among the other scenes: "
    } else {
        " have more often than the rest: "
    };
    s += &parts.join("; ");
    s += ".";
    s
}

/// The file of `technique`'s worst scene, relative to the output folder
/// (`worst/wboit-mrt_fitted.toml` for `wboit-mrt/fitted`).
pub fn worst_file(technique: &str) -> String {
    format!("worst/{}.toml", technique.replace('/', "_"))
}

/// Most scenes with an inexact reference written to `worst/not-exact/`.
pub const MAX_NOT_EXACT_FILES: usize = 50;

/// Writes into `out/worst/` the scene file of every run's worst scene (but the
/// reference's, which is exact by definition), and into `out/worst/not-exact/` those of
/// the first [`MAX_NOT_EXACT_FILES`] scenes whose reference is not exact. Each is the
/// generator's text of that scene, which is what the evaluation parsed, with a comment
/// saying how to replay it.
pub fn write_worst(
    out: &std::path::Path,
    set: RandomSet,
    d: &Distribution,
    opts: &EvalOptions,
) -> Result<()> {
    let size = (d.width, d.height);
    let index = |name: &str| d.scenes.iter().position(|s| s.scene == name);
    let write = |rel: &str, index: usize, comment: &str| -> Result<()> {
        let path = out.join(rel);
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir).map_err(Error::io(dir))?;
        }
        let text = format!(
            "# {comment}\n# Replay: demo eval --scenes {rel} --frames {} --warmup {}\n{}",
            opts.frames,
            opts.warmup,
            set.scene(index, size).text
        );
        crate::files::write_file(&path, text.as_bytes())
    };
    for t in &d.techniques {
        if t.technique == "reference" {
            continue;
        }
        let Some(i) = index(&t.worst_scene) else {
            continue;
        };
        write(
            &worst_file(&t.technique),
            i,
            &format!(
                "Worst of {} among {} random scenes of seed {} at {}x{}: mean FLIP {:.4}, largest error {}/255.",
                t.technique, d.count, d.seed, d.width, d.height, t.worst_flip, t.worst_max_abs_err
            ),
        )?;
    }
    for name in d.not_scored.iter().take(MAX_NOT_EXACT_FILES) {
        let Some(i) = index(name) else { continue };
        let row = &d.scenes[i];
        write(
            &format!("worst/not-exact/{name}.toml"),
            i,
            &format!(
                "Reference not exact: the A-buffer and peel-to-convergence differ by {}/255 (depth complexity {}).",
                row.reference_disagreement, row.depth_complexity
            ),
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_rank_percentiles() {
        let v: Vec<f64> = (1..=10).map(f64::from).collect();
        let p = Percentiles::of(&v).unwrap_or_default();
        assert_eq!(
            (p.p10, p.p50, p.p90, p.p99, p.max),
            (1.0, 5.0, 9.0, 10.0, 10.0)
        );
        let p = Percentiles::of(&[3.0]).unwrap_or_default();
        assert_eq!((p.p10, p.p50, p.max), (3.0, 3.0, 3.0));
        assert!(Percentiles::of(&[]).is_none());
    }

    #[test]
    fn error_bins_cover_every_level_once() {
        for e in 0..=255u32 {
            let n = ERROR_BINS
                .iter()
                .filter(|(lo, hi)| (*lo..=*hi).contains(&e))
                .count();
            assert_eq!(n, 1, "{e}");
        }
        assert_eq!(bin_label(2), "2–3");
        assert_eq!(bin_label(1), "1");
    }
}
