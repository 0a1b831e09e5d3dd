//! `report.md`: every figure of an evaluation in tables, with the charts and heat maps.

use std::fmt::Write as _;
use std::path::Path;

use crate::eval::{EvalOptions, Record, Summary, main_techniques, suite_mean};
use crate::stability::Stability;

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
        .filter(|r| {
            !matches!(
                r.technique.as_str(),
                "reference" | "peel-reference" | "opaque-only"
            )
        })
        .collect();
    v.sort_by(|a, b| a.flip_mean.total_cmp(&b.flip_mean));
    v
}

/// Writes `report.md` into `out`.
pub fn write(
    out: &Path,
    summary: &Summary,
    stability: Option<&Stability>,
    opts: &EvalOptions,
) -> Result<(), String> {
    let mut s = String::new();
    let size = summary
        .records
        .first()
        .map_or((0, 0), |r| (r.width, r.height));
    let worst_check = summary
        .reference_checks
        .iter()
        .map(|c| c.max_abs_err)
        .max()
        .unwrap_or(0);
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
    let _ = writeln!(
        s,
        "Errors are measured against the exact reference (per-pixel sorted fragment lists, an A-buffer), which agrees with \
         the second exact method (depth peeling until a pass writes nothing) within {worst_check}/255 on every scene. \
         GPU ms is the translucent work of a frame (the translucent passes and their composite), from timestamp queries; \
         on a software rasteriser (lavapipe) only the ratios between techniques mean much. FLIP is NVIDIA's perceptual \
         difference (0 = identical).\n"
    );
    let _ = writeln!(s, "![speed against accuracy](speed_vs_accuracy.png)\n");

    let _ = writeln!(s, "## Suite means\n");
    let _ = writeln!(
        s,
        "| technique | GPU ms | CPU ms | mean FLIP | mean RMSE | worst max err (1/255) | mean share > 1/255 | NaN/inf px |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|");
    for t in main_techniques(summary) {
        let (gpu, cpu, flip, rmse) = suite_mean(summary, &t);
        let rs: Vec<&Record> = summary
            .records
            .iter()
            .filter(|r| r.technique == t)
            .collect();
        let worst = rs.iter().map(|r| r.max_abs_err).max().unwrap_or(0);
        let bad = rs.iter().map(|r| r.frac_bad_px).sum::<f64>() / rs.len().max(1) as f64;
        let nan: usize = rs.iter().map(|r| r.nan_px).sum();
        let _ = writeln!(
            s,
            "| {t} | {} | {cpu:.3} | {flip:.4} | {rmse:.4} | {worst} | {bad:.4} | {nan} |",
            ms(gpu)
        );
    }

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

    let weights: Vec<String> = {
        let mut v: Vec<String> = summary
            .records
            .iter()
            .filter(|r| r.technique.contains('/'))
            .map(|r| r.technique.clone())
            .collect();
        v.dedup();
        let mut seen = Vec::new();
        v.retain(|n| {
            let new = !seen.contains(n);
            seen.push(n.clone());
            new
        });
        v
    };
    if !weights.is_empty() {
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
            let (gpu, _, flip, _) = suite_mean(summary, w);
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
                "| {} | {flip:.4} | {} | {} |",
                w.trim_start_matches("wboit-mrt/"),
                ms(gpu),
                per.join(" | ")
            );
        }
    }

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
            "Reference picture: [heatmaps/{0}__reference.png](heatmaps/{0}__reference.png). Depth complexity {1}.\n",
            c.scene, c.depth_complexity
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

    let _ = writeln!(s, "## Reference cross-check\n");
    let _ = writeln!(
        s,
        "| scene | A-buffer vs peel-to-convergence, max err (1/255) | A-buffer overflow | depth complexity |"
    );
    let _ = writeln!(s, "|---|---|---|---|");
    for c in &summary.reference_checks {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} |",
            c.scene, c.max_abs_err, c.overflow, c.depth_complexity
        );
    }

    if let Some(st) = stability {
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
    std::fs::write(out.join("report.md"), s).map_err(|e| format!("{}: {e}", out.display()))
}
