//! `report.md`: every figure of an evaluation in tables, with the charts and heat maps.

use std::fmt::Write as _;
use std::path::Path;

use crate::charts::{self, Series};
use crate::stability::Stability;
use crate::summary::{EvalOptions, Record, Summary, is_real_time};

fn ms(v: Option<f64>) -> String {
    v.map_or("n/a".into(), |v| format!("{v:.3}"))
}

fn row(r: &Record) -> String {
    format!(
        "| {} | {} | {:.3} | {:.4} | {:.4} | {:.1} | {} | {:.4} | {} | [map]({}) |",
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
pub fn chart(out: &Path, summary: &Summary, opts: &EvalOptions) -> Result<(), String> {
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
        &out.join("speed_vs_accuracy"),
        &format!(
            "Speed vs accuracy, {} scenes, {w}x{h}, {}",
            opts.scenes.len(),
            summary.adapter
        ),
        &per_scene,
        &means,
    )
}

/// Draws the stability charts into `out/stability/`: one per sweep, one per flicker path.
pub fn stability_charts(out: &Path, st: &Stability) -> Result<(), String> {
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
    stability: Option<&Stability>,
    opts: &EvalOptions,
) -> Result<(), String> {
    let mut s = String::new();
    header(&mut s, summary, opts);
    suite_means(&mut s, summary);
    winners(&mut s, summary);
    weights(&mut s, summary);
    per_scene(&mut s, summary, opts);
    reference_checks(&mut s, summary);
    if let Some(st) = stability {
        stability_section(&mut s, st);
    }
    std::fs::write(out.join("report.md"), s).map_err(|e| format!("{}: {e}", out.display()))
}

fn header(s: &mut String, summary: &Summary, opts: &EvalOptions) {
    let size = summary
        .records
        .first()
        .map_or((0, 0), |r| (r.width, r.height));
    let _ = writeln!(s, "# Transparency techniques: speed and accuracy\n");
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
         scene against the second exact method (depth peeling until a pass writes nothing): they agree within {}/255 at \
         worst. {} GPU ms is the translucent work of a frame (the technique's passes and composites), from timestamp \
         queries; on a software rasteriser (lavapipe) only the ratios between techniques mean much. FLIP is NVIDIA's \
         perceptual difference (0 = identical).\n",
        summary.worst_reference_disagreement(),
        if inexact.is_empty() {
            "Every scene's reference is exact.".to_owned()
        } else {
            format!(
                "**Reference not exact** (the methods disagree by more than {}/255, or the A-buffer capped pixels visibly), \
                 so not scored in means and charts: {}.",
                crate::summary::EXACT_AGREEMENT,
                inexact.join(", ")
            )
        }
    );
    let _ = writeln!(s, "![speed against accuracy](speed_vs_accuracy.png)\n");
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
        "The same WBOIT pass (single MRT) with each weight; the cost is the same for all of them.\n"
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
        "| scene | A-buffer vs peel-to-convergence, max err (1/255) | exact | A-buffer lost fragments | capped pixels (visibly) | depth complexity |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|");
    for c in &summary.reference_checks {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} ({}) | {} |",
            c.scene,
            c.max_abs_err,
            if c.exact { "yes" } else { "**no**" },
            c.lost_fragments,
            c.capped_pixels,
            c.capped_visible_pixels,
            c.depth_complexity
        );
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
    for f in &st.flicker {
        let _ = writeln!(
            s,
            "### Flicker along a {}-frame camera path: {}\n\nThe reference itself changes by {:.3}/255 per frame on average; the table gives what each technique changes beyond that.\n\n![flicker](stability/flicker_{1}.png)\n",
            f.frames, f.scene, f.reference_change
        );
        let _ = writeln!(
            s,
            "| technique | excess change per frame (1/255) |\n|---|---|"
        );
        for (t, e) in &f.excess {
            let _ = writeln!(s, "| {t} | {e:.3} |");
        }
        let _ = writeln!(s);
    }
}
