//! `costs.md`: what each technique's frame asked of the GPU on each scene (the counters
//! of [`crate::summary::CostRecord`]) beside its GPU and CPU milliseconds and its pixels
//! off, and the ratios between techniques that the counters bound.

use std::fmt::Write as _;
use std::path::Path;

use crate::Result;
use crate::summary::{CostSums, EvalOptions, Record, Summary};

/// Megabytes (10⁶ bytes), for tables.
fn mb(bytes: Option<u64>) -> String {
    bytes.map_or("n/a".into(), |b| format!("{:.1}", b as f64 / 1e6))
}

fn opt<T: std::fmt::Display>(v: Option<T>) -> String {
    v.map_or("n/a".into(), |v| v.to_string())
}

fn ms(v: Option<f64>) -> String {
    v.map_or("n/a".into(), |v| format!("{v:.3}"))
}

/// Fragments per pixel, two decimals.
fn per_px(v: Option<f64>) -> String {
    v.map_or("n/a".into(), |v| format!("{v:.2}"))
}

/// The record of `technique` on `scene`.
fn find<'a>(summary: &'a Summary, scene: &str, technique: &str) -> Option<&'a Record> {
    summary
        .records
        .iter()
        .find(|r| r.scene == scene && r.technique == technique)
}

fn sums(r: &Record) -> Option<&CostSums> {
    r.cost.as_ref().map(|c| &c.translucent)
}

/// The scenes of the summary, in order.
fn scenes(summary: &Summary) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for r in &summary.records {
        if !out.contains(&r.scene) {
            out.push(r.scene.clone());
        }
    }
    out
}

/// The mean over the scenes where both have a figure of `a`'s figure over `b`'s, and the
/// largest such ratio with its scene.
fn ratio(
    summary: &Summary,
    a: &str,
    b: &str,
    figure: impl Fn(&CostSums) -> Option<f64>,
) -> Option<(f64, f64, String)> {
    let mut sum_a = 0.0;
    let mut sum_b = 0.0;
    let mut worst: Option<(f64, String)> = None;
    for scene in scenes(summary) {
        let (Some(x), Some(y)) = (
            find(summary, &scene, a).and_then(sums).and_then(&figure),
            find(summary, &scene, b).and_then(sums).and_then(&figure),
        ) else {
            continue;
        };
        if y <= 0.0 {
            continue;
        }
        sum_a += x;
        sum_b += y;
        let r = x / y;
        if worst.as_ref().is_none_or(|(w, _)| r > *w) {
            worst = Some((r, scene));
        }
    }
    let (w, scene) = worst?;
    Some((sum_a / sum_b, w, scene))
}

/// One figure of a technique's counters.
type Figure = fn(&CostSums) -> Option<f64>;

/// The ratios the counters bound: each technique against its peer, on the suite's
/// means and on the worst scene.
fn ratios(s: &mut String, summary: &Summary) {
    let names = summary.main_techniques();
    let pairs = [
        ("sorted-quads", "sorted"),
        ("wboit-mrt", "sorted-quads"),
        ("wboit-mrt", "wboit-two-pass"),
        ("mboit", "wboit-mrt"),
    ];
    let figures: [Figure; 4] = [
        |c| Some(f64::from(c.draws)),
        |c| c.fragments.map(|f| f as f64),
        |c| c.bytes().map(|b| b as f64),
        |c| Some(f64::from(c.full_screen_passes)),
    ];
    let _ = writeln!(
        s,
        "Ratios of the translucent work's counters (suite total of one over the other's; worst scene in brackets):\n"
    );
    let _ = writeln!(
        s,
        "| technique / peer | draws | fragments | bytes written + read | full-screen passes |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|");
    for (a, b) in pairs {
        if !names.iter().any(|n| n == a) || !names.iter().any(|n| n == b) {
            continue;
        }
        let cells: Vec<String> = figures
            .iter()
            .map(|f| match ratio(summary, a, b, f) {
                Some((mean, worst, scene)) => format!("{mean:.2} ({worst:.2} {scene})"),
                None => "n/a".into(),
            })
            .collect();
        let _ = writeln!(s, "| `{a}` / `{b}` | {} |", cells.join(" | "));
    }
    let _ = writeln!(s);
}

/// Per technique, the suite means of its translucent work's counters.
fn means(s: &mut String, summary: &Summary) {
    let _ = writeln!(
        s,
        "| technique | GPU ms | passes | full-screen | draws (calls) | pipelines | bind groups | fragments / px | MB cleared | MB written | MB read | uploads KB |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|---|---|");
    for t in summary.main_techniques() {
        let rs: Vec<&Record> = summary
            .records
            .iter()
            .filter(|r| r.technique == t)
            .collect();
        let costs: Vec<(&Record, &CostSums)> =
            rs.iter().filter_map(|r| sums(r).map(|c| (*r, c))).collect();
        if costs.is_empty() {
            continue;
        }
        let n = costs.len() as f64;
        let mean = |f: &dyn Fn(&CostSums) -> f64| costs.iter().map(|(_, c)| f(c)).sum::<f64>() / n;
        let mean_opt = |f: &dyn Fn(&CostSums) -> Option<f64>| {
            costs
                .iter()
                .map(|(_, c)| f(c))
                .sum::<Option<f64>>()
                .map(|v| v / n)
        };
        let gpu = rs
            .iter()
            .map(|r| r.gpu_ms)
            .sum::<Option<f64>>()
            .map(|v| v / rs.len() as f64);
        let uploads = costs
            .iter()
            .filter_map(|(r, _)| r.cost.as_ref().map(|c| c.upload_bytes as f64))
            .sum::<f64>()
            / n;
        let _ = writeln!(
            s,
            "| `{t}` | {} | {:.1} | {:.1} | {:.0} ({:.0}) | {:.1} | {:.1} | {} | {:.1} | {} | {} | {:.1} |",
            ms(gpu),
            mean(&|c| f64::from(c.passes)),
            mean(&|c| f64::from(c.full_screen_passes)),
            mean(&|c| f64::from(c.draws)),
            mean(&|c| f64::from(c.draw_calls)),
            mean(&|c| f64::from(c.pipelines)),
            mean(&|c| f64::from(c.bind_groups)),
            per_px(mean_opt(&|c| c.fragments_per_pixel)),
            mean(&|c| c.clear_bytes as f64) / 1e6,
            mb(mean_opt(&|c| c.bytes_written.map(|b| b as f64)).map(|v| v as u64)),
            mb(mean_opt(&|c| c.bytes_read.map(|b| b as f64)).map(|v| v as u64)),
            uploads / 1e3,
        );
    }
    let _ = writeln!(s);
}

/// The table of every scene × technique.
fn table(s: &mut String, summary: &Summary) {
    let _ = writeln!(
        s,
        "| scene | technique | GPU ms | CPU ms | passes (full-screen) | draws (calls) | pipelines | bind groups | fragments / px | MB written | MB read | media passes (copies) | media MB | uploads KB | % px off | max err |"
    );
    let _ = writeln!(
        s,
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    for r in &summary.records {
        let Some(c) = &r.cost else {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {:.3} | | | | | | | | | | | {:.2} | {} |",
                r.scene,
                r.technique,
                ms(r.gpu_ms),
                r.cpu_ms,
                100.0 * r.frac_bad_px,
                r.max_abs_err
            );
            continue;
        };
        let t = &c.translucent;
        let m = &c.media;
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.3} | {} ({}) | {} ({}) | {} | {} | {} | {} | {} | {} ({}) | {} | {:.1} | {:.2} | {} |",
            r.scene,
            r.technique,
            ms(r.gpu_ms),
            r.cpu_ms,
            t.passes,
            t.full_screen_passes,
            t.draws,
            t.draw_calls,
            t.pipelines,
            t.bind_groups,
            per_px(t.fragments_per_pixel),
            mb(t.bytes_written),
            mb(t.bytes_read),
            m.passes,
            m.copies,
            opt(m.bytes().map(|b| format!("{:.1}", b as f64 / 1e6))),
            c.upload_bytes as f64 / 1e3,
            100.0 * r.frac_bad_px,
            r.max_abs_err
        );
    }
    let _ = writeln!(s);
}

/// The section of `report.md` (and the whole of `costs.md`): what the counters count, the
/// means, the ratios and, with `full`, every scene × technique.
pub fn section(s: &mut String, summary: &Summary, full: bool) {
    if !summary.records.iter().any(|r| r.cost.is_some()) {
        return;
    }
    let _ = writeln!(
        s,
        "What each technique's frame asked of the GPU, counted in one frame after the timed ones \
         (`voxel_render::low_level::FrameCost`): for the translucent work (the technique's passes and \
         composites, what GPU ms times) the render passes and those drawing a full-screen triangle, \
         draws (each command of a multi-draw; API calls in brackets), pipeline and bind-group changes, \
         fragments shaded per pixel (pipeline-statistics queries; the samples written where the device \
         has none), and megabytes of targets written (samples written times the attachments' texel \
         bytes, plus clears) and read (blended attachments and depth per sample, plus the textures a \
         composite reads per fragment). The media passes (the eye's medium and volumes in view) run \
         before the technique and are counted apart. Uploads: the frame's own buffer writes.\n"
    );
    means(s, summary);
    ratios(s, summary);
    if full {
        table(s, summary);
    }
}

/// Writes `out/costs.md`: the counters of every scene × technique with GPU ms, CPU ms and
/// pixels off, their means and the ratios between techniques.
pub fn write(out: &Path, summary: &Summary, opts: &EvalOptions) -> Result<()> {
    let size = summary
        .records
        .first()
        .map_or((0, 0), |r| (r.width, r.height));
    let mut s = String::new();
    let _ = writeln!(s, "# GPU cost per scene and technique\n");
    let _ = writeln!(
        s,
        "Made by `{}` on **{}**, {}×{} pixels, median of {} timed frames after {} warm-up frames. \
         % px off: pixels whose largest channel differs from the exact reference by more than 1/255.\n",
        opts.command, summary.adapter, size.0, size.1, opts.frames, opts.warmup
    );
    if !summary.skipped.is_empty() {
        let _ = writeln!(
            s,
            "**Time budget spent**: {} scenes left out ({}).\n",
            summary.skipped.len(),
            summary.skipped.join(", ")
        );
    }
    section(&mut s, summary, true);
    crate::files::write_file(&out.join("costs.md"), s.as_bytes())
}
