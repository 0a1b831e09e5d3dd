//! `report.md`: every figure of an evaluation in tables, with the charts and heat maps.

use crate::Result;

use std::fmt::Write as _;
use std::path::Path;

use crate::charts::{self, Series, Spread};
use crate::distribution::{self, Distribution, ERROR_BINS, bin_label};
use crate::stability::Stability;
use crate::summary::{EvalOptions, Record, Summary, is_real_time};

fn ms(v: Option<f64>) -> String {
    v.map_or("n/a".into(), |v| format!("{v:.3}"))
}

fn row(r: &Record) -> String {
    // A sorted technique's CPU time ordering the game's objects, where there are any.
    let sort = r
        .game_sort_ms
        .map_or(String::new(), |s| format!(" (objects {s:.3})"));
    // An exact order's error where the order alone decides: off quad edges and off a
    // game's objects that interpenetrate (pixels off by more than 1/255 there, counted).
    let off = match (r.max_abs_err_off_edges, r.edge_px, r.overlap_px, r.near_px) {
        (Some(m), Some(e), Some(o), Some(n)) if e > 0 || o > 0 || n > 0 || m != r.max_abs_err => {
            format!(" ({m} off {e} edge, {o} overlap and {n} near-pair px)")
        }
        _ => String::new(),
    };
    format!(
        "| {} | {} | {:.3}{sort} | {:.4} | {:.4} | {:.1} | {}{off} | {:.4} | {} | [map]({}) |",
        r.technique,
        ms(r.gpu_ms),
        r.cpu_ms,
        r.flip_mean,
        r.rmse,
        r.psnr,
        r.max_abs_err,
        r.frac_bad_px,
        r.nan_px,
        r.heatmap
    )
}

/// The non-exact techniques ranked for one scene: lowest FLIP first.
fn ranking<'a>(summary: &'a Summary, scene: &str) -> Vec<&'a Record> {
    let mut v: Vec<&Record> = summary
        .records
        .iter()
        .filter(|r| r.scene == scene && !r.technique.contains('/'))
        .filter(|r| is_real_time(&r.technique))
        .collect();
    v.sort_by(|a, b| a.flip_mean.total_cmp(&b.flip_mean));
    v
}

/// The speed-against-accuracy chart. `opaque-only` (draws no translucency, costs nothing)
/// stays out of it.
pub fn chart(out: &Path, summary: &Summary, opts: &EvalOptions) -> Result<()> {
    chart_to(&out.join("speed_vs_accuracy"), summary, opts)
}

fn chart_to(path: &Path, summary: &Summary, opts: &EvalOptions) -> Result<()> {
    let names: Vec<String> = summary
        .main_techniques()
        .into_iter()
        .filter(|n| n != "opaque-only")
        .collect();
    // A scene where a technique drew nothing translucent (0 ms: nothing in view to
    // compose) says nothing about it, and would sit at -inf on the log axis.
    let floor = 0.001;
    let per_scene: Vec<Series> = names
        .iter()
        .map(|n| Series {
            name: n.clone(),
            points: summary
                .scored(n)
                .filter_map(|r| r.gpu_ms.filter(|g| *g > 0.0).map(|g| (g, r.flip_mean)))
                .collect(),
        })
        .collect();
    let means: Vec<Series> = names
        .iter()
        .map(|n| {
            let mean = summary.suite_mean(n);
            Series {
                name: n.clone(),
                points: mean
                    .gpu_ms
                    .map(|g| vec![(g.max(floor), mean.flip)])
                    .unwrap_or_default(),
            }
        })
        .collect();
    let (w, h) = opts.size.unwrap_or((640, 360));
    charts::speed_vs_accuracy(
        path,
        &format!(
            "Speed vs accuracy, {} scenes, {w}x{h}, {}",
            summary.reference_checks.len(),
            summary.adapter
        ),
        &per_scene,
        &means,
    )
}

/// The charts of a random evaluation: `speed_vs_accuracy` (per technique the p10–p90
/// range of time and of error around the medians), `speed_vs_accuracy_scenes` (every
/// scene a point) and `max_abs_err_histogram` (small multiples).
pub fn random_charts(
    out: &Path,
    summary: &Summary,
    dist: &Distribution,
    opts: &EvalOptions,
) -> Result<()> {
    let main = summary.main_techniques();
    let spreads: Vec<Spread> = dist
        .techniques
        .iter()
        .filter(|t| main.contains(&t.technique) && t.technique != "opaque-only")
        .filter_map(|t| {
            let g = t.gpu_ms?;
            Some(Spread {
                name: t.technique.clone(),
                x: [g.p10, g.p50, g.p90],
                y: [t.flip_mean.p10, t.flip_mean.p50, t.flip_mean.p90],
            })
        })
        .collect();
    charts::speed_vs_accuracy_spread(
        &out.join("speed_vs_accuracy"),
        &format!(
            "Speed vs accuracy, {} random scenes (seed {}), {}x{}, {}",
            dist.count, dist.seed, dist.width, dist.height, summary.adapter
        ),
        &spreads,
    )?;
    chart_to(&out.join("speed_vs_accuracy_scenes"), summary, opts)?;
    let bins: Vec<String> = (0..ERROR_BINS.len()).map(bin_label).collect();
    let series: Vec<(String, Vec<usize>)> = dist
        .techniques
        .iter()
        .filter(|t| main.contains(&t.technique) && t.technique != "reference")
        .map(|t| (t.technique.clone(), t.histogram.clone()))
        .collect();
    charts::histograms(
        &out.join("max_abs_err_histogram"),
        &format!(
            "Largest channel error per scene, share of the {} scored random scenes",
            dist.scored
        ),
        &bins,
        &series,
    )
}

/// Draws the stability charts into `out/stability/`: one per sweep, one per flicker path.
pub fn stability_charts(out: &Path, st: &Stability) -> Result<()> {
    let dir = out.join("stability");
    for sw in &st.sweeps {
        let series: Vec<Series> = sw
            .flip
            .iter()
            .map(|(t, f)| Series {
                name: t.clone(),
                points: sw.values.iter().copied().zip(f.iter().copied()).collect(),
            })
            .collect();
        charts::sweep(
            &dir.join(&sw.name),
            &format!("Error against {}", sw.parameter),
            &sw.parameter,
            sw.log,
            &series,
        )?;
    }
    for f in &st.flicker {
        charts::bars(
            &dir.join(format!("flicker_{}", f.scene)),
            &format!(
                "Flicker beyond the reference, {}, {} frames",
                f.scene, f.frames
            ),
            "mean excess change per frame (1/255)",
            &f.excess,
        )?;
    }
    Ok(())
}

/// Writes `report.md` into `out`: the figures of `summary` (and `stability`) in tables,
/// with the charts and heat maps.
pub fn write(
    out: &Path,
    summary: &Summary,
    distribution: Option<&Distribution>,
    stability: Option<&Stability>,
    opts: &EvalOptions,
) -> Result<()> {
    let mut s = String::new();
    if let Some(d) = distribution {
        random_report(&mut s, summary, d, opts);
        if let Some(st) = stability {
            stability_section(&mut s, st);
        }
        return write_report(out, s);
    }
    header(&mut s, summary, opts);
    suite_means(&mut s, summary);
    winners(&mut s, summary);
    weights(&mut s, summary);
    costs(&mut s, summary);
    per_scene(&mut s, summary, opts);
    reference_checks(&mut s, summary);
    if let Some(st) = stability {
        stability_section(&mut s, st);
    }
    write_report(out, s)
}

/// Writes `out/report.md`; an error names that file.
fn write_report(out: &Path, text: String) -> Result<()> {
    let path = out.join("report.md");
    crate::files::write_file(&path, text.as_bytes())
}

fn header(s: &mut String, summary: &Summary, opts: &EvalOptions) {
    let size = summary
        .records
        .first()
        .map_or((0, 0), |r| (r.width, r.height));
    let _ = writeln!(s, "# Transparency techniques: speed and accuracy\n");
    if !summary.skipped.is_empty() {
        let _ = writeln!(
            s,
            "**Time budget spent**: {} scenes left out ({}).\n",
            summary.skipped.len(),
            summary.skipped.join(", ")
        );
    }
    let _ = writeln!(
        s,
        "Made by `{}` on **{}**, {}×{} pixels, median of {} timed frames after {} warm-up frames, {} scenes.\n",
        opts.command,
        summary.adapter,
        size.0,
        size.1,
        opts.frames,
        opts.warmup,
        summary.reference_checks.len()
    );
    let inexact: Vec<&str> = summary
        .reference_checks
        .iter()
        .filter(|c| !c.exact)
        .map(|c| c.scene.as_str())
        .collect();
    let _ = writeln!(
        s,
        "Errors are measured against the exact reference (per-pixel sorted fragment lists, an A-buffer), checked on every \
         scene against a CPU ray march that shares no mesh and no rasteriser with it (both with flat textures: every \
         pixel off geometric edges within 1/255, no crack), and against the second GPU method (depth peeling until a \
         pass writes nothing): they agree within {}/255 at worst; where they differ by more than 2/255 the ray march \
         decides, and must side with the A-buffer. {} GPU ms is the translucent work of a frame (the \
         technique's passes and composites), from timestamp queries; on a software rasteriser (lavapipe) only the \
         ratios between techniques mean much. FLIP is NVIDIA's perceptual difference (0 = identical).\n",
        summary.worst_reference_disagreement(),
        if inexact.is_empty() {
            "Every scene's reference is exact.".to_owned()
        } else {
            format!(
                "**Reference not exact** (the ray march differs off edges, finds a crack, or does not side with the \
                 A-buffer where the GPU methods differ by more than 2/255, or the A-buffer capped pixels visibly), so \
                 not scored in means and charts: {}.",
                inexact.join(", ")
            )
        }
    );
    let _ = writeln!(
        s,
        "Where each technique is exact: `sorted-quads` on block scenes wherever an order exists (a cycle of \
         quads has none) and for a game's objects where its tests decide; `depth-peeling` up to its layer count; \
         `wboit-*` and `mboit` for one layer per pixel; `stipple` never. Water is a volume (light kept \
         exp(-absorption d) over d blocks): the exact references split every path through it, `sorted`, \
         `sorted-quads` and `depth-peeling` are exact for one volume along a ray (things inside it included), and \
         a volume behind another is approximate in every real-time technique (docs/techniques.md, Volumes).\n"
    );
    if opts.checks.flip {
        let _ = writeln!(s, "![speed against accuracy](speed_vs_accuracy.png)\n");
    } else {
        let _ = writeln!(
            s,
            "FLIP was not computed (`--no-flip`): its columns read NaN, and there is no chart.\n"
        );
    }
}

fn suite_means(s: &mut String, summary: &Summary) {
    let _ = writeln!(s, "## Suite means\n");
    let _ = writeln!(
        s,
        "| technique | GPU ms | CPU ms | mean FLIP | mean RMSE | worst max err (1/255) | mean share > 1/255 | NaN/inf px |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|");
    for t in summary.main_techniques() {
        let mean = summary.suite_mean(&t);
        let rs: Vec<&Record> = summary.scored(&t).collect();
        let worst = rs.iter().map(|r| r.max_abs_err).max().unwrap_or(0);
        let bad = rs.iter().map(|r| r.frac_bad_px).sum::<f64>() / rs.len().max(1) as f64;
        let nan: usize = summary
            .records
            .iter()
            .filter(|r| r.technique == t)
            .map(|r| r.nan_px)
            .sum();
        let _ = writeln!(
            s,
            "| {t} | {} | {:.3} | {:.4} | {:.4} | {worst} | {bad:.4} | {nan} |",
            ms(mean.gpu_ms),
            mean.cpu_ms,
            mean.flip,
            mean.rmse
        );
    }
}

fn costs(s: &mut String, summary: &Summary) {
    if summary.records.iter().all(|r| r.cost.is_none()) {
        return;
    }
    let _ = writeln!(
        s,
        "## GPU cost (counters)\n\nEvery scene × technique in [costs.md](costs.md).\n"
    );
    crate::costs::section(s, summary, false);
}

fn winners(s: &mut String, summary: &Summary) {
    let _ = writeln!(s, "\n## Which technique wins where\n");
    let _ = writeln!(
        s,
        "Lowest mean FLIP per scene among the real-time techniques (the exact references and opaque-only left out), with the cheapest one that stays under 0.01 FLIP:\n"
    );
    let _ = writeln!(
        s,
        "| scene | most accurate | FLIP | GPU ms | cheapest under 0.01 FLIP | GPU ms | worst | FLIP |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|");
    for c in &summary.reference_checks {
        let rank = ranking(summary, &c.scene);
        let (Some(best), Some(worst)) = (rank.first(), rank.last()) else {
            continue;
        };
        if !c.exact {
            let _ = writeln!(
                s,
                "| {} | reference not exact: not scored | | | | | | |",
                c.scene
            );
            continue;
        }
        if worst.max_abs_err == 0 {
            let _ = writeln!(
                s,
                "| {} | all exact (nothing translucent in view) | 0 | | | | | |",
                c.scene
            );
            continue;
        }
        let cheap = rank.iter().filter(|r| r.flip_mean < 0.01).min_by(|a, b| {
            a.gpu_ms
                .unwrap_or(f64::MAX)
                .total_cmp(&b.gpu_ms.unwrap_or(f64::MAX))
        });
        let (cn, cg) = cheap.map_or(("none".to_owned(), "".to_owned()), |r| {
            (r.technique.clone(), ms(r.gpu_ms))
        });
        let _ = writeln!(
            s,
            "| {} | {} | {:.4} | {} | {cn} | {cg} | {} | {:.4} |",
            c.scene,
            best.technique,
            best.flip_mean,
            ms(best.gpu_ms),
            worst.technique,
            worst.flip_mean
        );
    }
}

fn weights(s: &mut String, summary: &Summary) {
    let weights = summary.weight_runs();
    if weights.is_empty() {
        return;
    }
    let _ = writeln!(s, "\n## WBOIT weight functions\n");
    let _ = writeln!(
        s,
        "The same WBOIT pass (single MRT) with each weight, a constant of its own pipeline: the fitted one reads its table, a log and an exp per fragment, which a CPU rasteriser feels.\n"
    );
    let scenes: Vec<&str> = summary
        .reference_checks
        .iter()
        .map(|c| c.scene.as_str())
        .collect();
    let _ = writeln!(
        s,
        "| weight | mean FLIP | GPU ms | {} |",
        scenes.join(" | ")
    );
    let _ = writeln!(s, "|---|---|---|{}", "---|".repeat(scenes.len()));
    for w in &weights {
        let mean = summary.suite_mean(w);
        let per: Vec<String> = scenes
            .iter()
            .map(|sc| {
                summary
                    .records
                    .iter()
                    .find(|r| &r.technique == w && r.scene == *sc)
                    .map_or("".into(), |r| format!("{:.4}", r.flip_mean))
            })
            .collect();
        let _ = writeln!(
            s,
            "| {} | {:.4} | {} | {} |",
            w.trim_start_matches("wboit-mrt/"),
            mean.flip,
            ms(mean.gpu_ms),
            per.join(" | ")
        );
    }
}

fn per_scene(s: &mut String, summary: &Summary, opts: &EvalOptions) {
    let _ = writeln!(s, "\n## Per scene\n");
    for c in &summary.reference_checks {
        let desc = opts
            .scenes
            .iter()
            .find(|p| {
                p.file_stem()
                    .is_some_and(|f| f.to_string_lossy() == c.scene)
            })
            .and_then(|p| crate::scene::Scene::load(p).ok())
            .map(|sc| format!("**{}**: {}", sc.name, sc.description))
            .unwrap_or_default();
        let _ = writeln!(s, "### {}\n\n{desc}\n", c.scene);
        let _ = writeln!(
            s,
            "Reference picture: [heatmaps/{0}__reference.png](heatmaps/{0}__reference.png). Depth complexity {1}.{2}\n",
            c.scene,
            c.depth_complexity,
            if c.exact {
                ""
            } else {
                " **Reference not exact: errors not scored.**"
            }
        );
        let _ = writeln!(
            s,
            "| technique | GPU ms | CPU ms | FLIP | RMSE | PSNR | max err | share > 1/255 | NaN/inf | heat map |"
        );
        let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|");
        for r in summary.records.iter().filter(|r| r.scene == c.scene) {
            let _ = writeln!(s, "{}", row(r));
        }
        let _ = writeln!(s);
    }
}

fn reference_checks(s: &mut String, summary: &Summary) {
    let _ = writeln!(s, "## Reference cross-check\n");
    let _ = writeln!(
        s,
        "The ray march against the A-buffer, both with flat textures: pixels whose colours differ by more than 1/255 \
         off geometric edges (max error), on an edge (an edge within 1/32 px of the centre: the rasteriser decides), on \
         a seam of merged translucent quads, and cracks (no opaque surface drawn inside closed geometry).\n"
    );
    let _ = writeln!(
        s,
        "| scene | exact | ray march: differing off edges (max err) | on edges | translucent seams | cracks | ray march s | A-buffer vs peel-to-convergence (1/255) | pixels they differ by > 2/255 the ray march does not settle | A-buffer lost fragments | capped pixels (visibly) | depth complexity |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|---|---|");
    for c in &summary.reference_checks {
        let r = &c.raymarch;
        let _ = writeln!(
            s,
            "| {} | {} | {} ({}) | {} | {} | {} | {:.2} | {} | {} | {} | {} ({}) | {} |",
            c.scene,
            if c.exact { "yes" } else { "**no**" },
            r.differing,
            r.max_abs_err_off_edges,
            r.differing_on_edges,
            r.translucent_seams,
            r.cracks,
            r.seconds,
            c.max_abs_err,
            c.unsettled,
            c.lost_fragments,
            c.capped_pixels,
            c.capped_visible_pixels,
            c.depth_complexity
        );
    }
    for c in summary
        .reference_checks
        .iter()
        .filter(|c| !c.raymarch.worst.is_empty())
    {
        let _ = writeln!(
            s,
            "\n{}: where the ray march and the A-buffer differ:\n",
            c.scene
        );
        for w in &c.raymarch.worst {
            let _ = writeln!(s, "- {w}");
        }
    }
}

fn stability_section(s: &mut String, st: &Stability) {
    let _ = writeln!(s, "\n## Stability where methods fail\n");
    for sw in &st.sweeps {
        let _ = writeln!(s, "### {}\n\n![{0}](stability/{0}.png)\n", sw.name);
        let header: Vec<String> = sw.values.iter().map(|v| format!("{v}")).collect();
        let _ = writeln!(s, "| technique | {} |", header.join(" | "));
        let _ = writeln!(s, "|---|{}", "---|".repeat(header.len()));
        for (t, f) in &sw.flip {
            let cells: Vec<String> = f.iter().map(|v| format!("{v:.4}")).collect();
            let _ = writeln!(s, "| {t} | {} |", cells.join(" | "));
        }
        let _ = writeln!(s);
    }
    if !st.flicker.is_empty() {
        flicker_summary(s, &st.flicker);
    }
    for f in &st.flicker {
        let _ = writeln!(
            s,
            "### Flicker along a {}-frame camera path: {}\n\nThe reference itself changes by {:.3}/255 per frame on average; the table gives what each technique changes beyond that: the mean over the path's steps, the largest step, the steps that pop (more than {} % of the pixels more than {}/255 beyond the reference) and the largest share of a step's pixels that far beyond.\n\n![flicker](stability/flicker_{1}.png)\n",
            f.frames,
            f.scene,
            f.reference_change,
            crate::metrics::POP_SHARE * 100.0,
            crate::metrics::POP_LEVEL
        );
        let _ = writeln!(
            s,
            "| technique | excess change per frame (1/255) | largest step (1/255) | pops | worst step's pixels beyond {}/255 (%) |\n|---|---|---|---|---|",
            crate::metrics::POP_LEVEL
        );
        for (i, (t, e)) in f.excess.iter().enumerate() {
            let _ = writeln!(
                s,
                "| {t} | {e:.3} | {:.3} | {} | {:.3} |",
                f.max_step[i].1, f.pops[i].1, f.worst_pop[i].1
            );
        }
        let _ = writeln!(s);
    }
}

/// Every path at once: per technique, the steps that pop over all of them and on how many
/// paths, the largest step, the worst share of pixels and the mean excess.
fn flicker_summary(s: &mut String, flicker: &[crate::stability::Flicker]) {
    let _ = writeln!(
        s,
        "### Pops over every camera path\n\n{} paths in one run. A step pops when more than {} % of its pixels change by more than {}/255 beyond the reference's own change.\n\n| technique | steps that pop | paths with a pop | largest step (1/255) | worst step's pixels beyond (%) | mean excess (1/255) |\n|---|---|---|---|---|---|",
        flicker.len(),
        crate::metrics::POP_SHARE * 100.0,
        crate::metrics::POP_LEVEL
    );
    let Some(first) = flicker.first() else { return };
    for (i, (t, _)) in first.excess.iter().enumerate() {
        let steps: usize = flicker.iter().map(|f| f.pops[i].1).sum();
        let paths = flicker.iter().filter(|f| f.pops[i].1 > 0).count();
        let largest = flicker.iter().map(|f| f.max_step[i].1).fold(0.0, f64::max);
        let worst = flicker.iter().map(|f| f.worst_pop[i].1).fold(0.0, f64::max);
        let mean = flicker.iter().map(|f| f.excess[i].1).sum::<f64>() / flicker.len() as f64;
        let _ = writeln!(
            s,
            "| {t} | {steps} | {paths} | {largest:.3} | {worst:.3} | {mean:.3} |"
        );
    }
    let _ = writeln!(s);
}

/// The report of a random evaluation: the distribution table, the charts, where each
/// technique fails, the scenes' features, the worst scenes and the reference checks.
fn random_report(s: &mut String, summary: &Summary, d: &Distribution, opts: &EvalOptions) {
    let _ = writeln!(
        s,
        "# Transparency techniques on {} random scenes\n",
        d.count
    );
    let _ = writeln!(
        s,
        "Made by `{}` on **{}**, {}×{} pixels, median of {} timed frames after {} warm-up frames: {} scenes drawn \
         from seed {} by the lab's generator (`voxel_lab::random`), each parsed from its own scene file text.\n",
        opts.command, summary.adapter, d.width, d.height, opts.frames, opts.warmup, d.count, d.seed
    );
    let _ = writeln!(
        s,
        "Errors are measured against the exact reference (an A-buffer), checked on every scene against a CPU ray march \
         that shares no mesh and no rasteriser with it (flat textures; every pixel off geometric edges within 1/255, no \
         crack; where the GPU methods differ by more than 2/255 it sides with the A-buffer). **{} of {} scenes are scored**; {}. Something translucent is in view in {} scenes: the reference \
         equals `opaque-only` in {} ({:.1} %).\n",
        d.scored,
        d.count,
        if d.not_scored.is_empty() {
            "every reference is exact".to_owned()
        } else {
            format!(
                "{} {} not (the ray march differs off edges, finds a crack, or does not side with the A-buffer \
                 where the GPU methods differ, or the A-buffer capped pixels visibly): {}{}",
                d.not_scored.len(),
                if d.not_scored.len() == 1 { "is" } else { "are" },
                d.not_scored
                    .iter()
                    .take(20)
                    .cloned()
                    .collect::<Vec<_>>()
                    .join(", "),
                if d.not_scored.len() > 20 { ", …" } else { "" }
            )
        },
        d.count - d.translucent_not_in_view,
        d.translucent_not_in_view,
        d.translucent_not_in_view_share * 100.0
    );
    let _ = writeln!(s, "![speed against accuracy](speed_vs_accuracy.png)\n");
    let _ = writeln!(s, "## Error distribution\n");
    distribution_table(s, d, &summary.main_techniques());
    let weights = summary.weight_runs();
    if !weights.is_empty() {
        let _ = writeln!(s, "\nThe same `wboit-mrt` pass with each WBOIT weight:\n");
        distribution_table(s, d, &weights);
    }
    let _ = writeln!(
        s,
        "\nPercentiles are nearest-rank over the scored scenes; *exact* is the share of scenes within 1/255 on every \
         pixel (for `sorted-quads`, also on every pixel farther than 1/16 pixel from a translucent quad edge: on an \
         edge where three quads meet, sub-pixel snapping, not the order, decides which quads the pixel sees; \
         `voxel_lab::edges`); GPU ms over the scenes where the technique drew something. Every technique's worst \
         scene is in `worst/` ([below](#worst-scenes)).\n"
    );
    let _ = writeln!(s, "![largest error histogram](max_abs_err_histogram.png)\n");
    let _ = writeln!(s, "## Where each technique fails\n");
    let _ = writeln!(
        s,
        "For each technique, its worst decile of scenes (largest error, then highest mean FLIP; only scenes where it is \
         off by more than 1/255) against all scored scenes: a feature is named when at least {:.0} % of the worst scenes have it and it \
         is at least {} times as common among them as among all.\n",
        distribution::MIN_WORST_SHARE * 100.0,
        distribution::MIN_LIFT
    );
    for w in &d.where_it_fails {
        let _ = writeln!(s, "### {}\n\n{}\n", w.technique, distribution::describe(w));
    }
    let _ = writeln!(s, "## The scenes\n");
    let _ = writeln!(
        s,
        "What the {} scenes hold (the generator's design is in `voxel-lab/src/random/mod.rs`; the last two rows are measured):\n",
        d.count
    );
    let _ = writeln!(s, "| feature | scenes | share |\n|---|---|---|");
    for f in &d.features {
        let _ = writeln!(
            s,
            "| {} | {} | {:.1} % |",
            f.feature,
            f.scenes,
            f.share * 100.0
        );
    }
    let _ = writeln!(s, "\n## Worst scenes\n");
    let _ = writeln!(
        s,
        "Each file replays its scene exactly: `demo eval --scenes worst/<technique>.toml --frames {} --warmup {}` \
         renders the same picture with the same error (heat maps included).\n",
        opts.frames, opts.warmup
    );
    let _ = writeln!(
        s,
        "| technique | worst scene | FLIP | max err (1/255) | file |\n|---|---|---|---|---|"
    );
    for t in &d.techniques {
        if t.technique == "reference" {
            continue;
        }
        let file = distribution::worst_file(&t.technique);
        let _ = writeln!(
            s,
            "| {} | {} | {:.4} | {} | [{file}]({file}) |",
            t.technique, t.worst_scene, t.worst_flip, t.worst_max_abs_err
        );
    }
    let _ = writeln!(s, "\n## Reference cross-check\n");
    let worst = summary
        .reference_checks
        .iter()
        .max_by_key(|c| c.max_abs_err)
        .map_or((String::new(), 0), |c| (c.scene.clone(), c.max_abs_err));
    let capped = summary
        .reference_checks
        .iter()
        .filter(|c| c.capped_visible_pixels > 0)
        .count();
    let lost: u64 = summary
        .reference_checks
        .iter()
        .map(|c| c.lost_fragments)
        .sum();
    let checks = &summary.reference_checks;
    let sum = |f: fn(&crate::summary::RayMarchSummary) -> usize| -> usize {
        checks.iter().map(|c| f(&c.raymarch)).sum()
    };
    let ray_max = checks
        .iter()
        .map(|c| c.raymarch.max_abs_err_off_edges)
        .max()
        .unwrap_or(0);
    let mut seconds: Vec<f64> = checks.iter().map(|c| c.raymarch.seconds).collect();
    seconds.sort_by(f64::total_cmp);
    let _ = writeln!(
        s,
        "The ray march against the A-buffer (flat textures) over {} scenes: {} pixels differ by more than 1/255 off \
         geometric edges (largest difference {ray_max}/255), {} on edges, {} on seams of merged translucent quads, {} \
         cracks; ray march {:.2} s per picture (median). The GPU methods differ by {}/255 at most ({}); the A-buffer \
         lost {lost} fragments and capped pixels visibly in {capped} scenes. Depth complexity: up to {} layers.\n",
        checks.len(),
        sum(|r| r.differing),
        sum(|r| r.differing_on_edges),
        sum(|r| r.translucent_seams),
        sum(|r| r.cracks),
        seconds.get(seconds.len() / 2).copied().unwrap_or(0.0),
        worst.1,
        worst.0,
        checks.iter().map(|c| c.depth_complexity).max().unwrap_or(0)
    );
    let bad: Vec<_> = summary
        .reference_checks
        .iter()
        .filter(|c| !c.exact)
        .collect();
    if !bad.is_empty() {
        let _ = writeln!(
            s,
            "| scene (not scored; in `worst/not-exact/`) | ray march: differing off edges (max err) | cracks | A-buffer vs peeling (1/255) | lost fragments | capped (visibly) | depth complexity |\n|---|---|---|---|---|---|---|"
        );
        for c in bad {
            let _ = writeln!(
                s,
                "| {} | {} ({}) | {} | {} | {} | {} ({}) | {} |",
                c.scene,
                c.raymarch.differing,
                c.raymarch.max_abs_err_off_edges,
                c.raymarch.cracks,
                c.max_abs_err,
                c.lost_fragments,
                c.capped_pixels,
                c.capped_visible_pixels,
                c.depth_complexity
            );
        }
    }
}

/// The distribution table of `runs`.
fn distribution_table(s: &mut String, d: &Distribution, runs: &[String]) {
    let _ = writeln!(
        s,
        "| technique | scenes | FLIP p50 | p90 | p99 | max | max err p50 | p90 | p99 | max | exact | NaN px | GPU ms p50 (p10–p90) |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for t in d.techniques.iter().filter(|t| runs.contains(&t.technique)) {
        let (f, e) = (t.flip_mean, t.max_abs_err);
        let gpu = t.gpu_ms.map_or("n/a".to_owned(), |g| {
            format!("{:.3} ({:.3}–{:.3})", g.p50, g.p10, g.p90)
        });
        let exact = match t.exact_off_edges_share {
            Some(e) => format!("{} ({} off edges)", share(t.exact_share), share(e)),
            None => share(t.exact_share),
        };
        let _ = writeln!(
            s,
            "| {} | {} | {:.4} | {:.4} | {:.4} | {:.4} | {} | {} | {} | {} | {exact} | {} | {gpu} |",
            t.technique, t.n, f.p50, f.p90, f.p99, f.max, e.p50, e.p90, e.p99, e.max, t.nan_px
        );
    }
}

/// A share as a percentage: whole numbers, except that a share short of all (or above
/// none) never rounds to 100 % (or 0 %).
fn share(x: f64) -> String {
    let p = x * 100.0;
    if (p.round() == 100.0 && x < 1.0) || (p.round() == 0.0 && x > 0.0) {
        format!("{p:.1} %")
    } else {
        format!("{p:.0} %")
    }
}

#[cfg(test)]
mod tests {
    use super::share;

    #[test]
    fn shares_short_of_all_or_above_none_never_round_to_it() {
        assert_eq!(share(1.0), "100 %");
        assert_eq!(share(296.0 / 297.0), "99.7 %");
        assert_eq!(share(0.5), "50 %");
        assert_eq!(share(0.001), "0.1 %");
        assert_eq!(share(0.0), "0 %");
    }
}
