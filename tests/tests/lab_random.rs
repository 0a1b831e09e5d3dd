//! The lab on random scenes in CI: a small draw (40 scenes at 96×54, one timed frame),
//! asserting from it that nothing turns NaN, that the two exact methods agree on every
//! scene, that `sorted-quads` is exact wherever its quad order has no cycle and no game
//! content is drawn (off the
//! pixels on quad edges, where sub-pixel snapping decides: rare), that the
//! default WBOIT weight has the lowest median FLIP of all weights, and that a worst scene
//! written to `worst/` replays with the same error.
//!
//! A scene that breaks one of these is a finding about the renderer, not noise: its scene
//! file is saved under `target/test-output/lab-random/findings/` and named in the failure.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use std::path::PathBuf;
use std::sync::OnceLock;
use std::time::Instant;

use voxel_lab::EvalOptions;
use voxel_lab::distribution::{self, Distribution};
use voxel_lab::random::RandomSet;
use voxel_lab::summary::Summary;
use voxel_render::{Technique, WeightFunction};

const COUNT: usize = 40;
const SEED: u64 = 1;
const SIZE: (u32, u32) = (96, 54);

/// Every technique but `peel-reference`: the lab renders peeling to convergence on every
/// scene anyway, as the second exact method its reference check compares with the
/// A-buffer; timing it once more as a technique would peel again (up to 512 layers on
/// the draw's deepest scene) and check nothing the reference check does not.
fn techniques() -> Vec<Technique> {
    Technique::ALL
        .into_iter()
        .filter(|t| *t != Technique::PeelReference)
        .collect()
}

fn options(out: PathBuf, scenes: Vec<PathBuf>, random: Option<RandomSet>) -> EvalOptions {
    EvalOptions {
        scenes,
        techniques: techniques(),
        weights: WeightFunction::ALL.to_vec(),
        size: random.map(|_| SIZE),
        frames: 1,
        warmup: 1,
        out,
        stability: false,
        flicker_frames: 0,
        sweep_points: 0,
        command: "cargo test -p tests --test lab_random".into(),
        heatmap_width: None,
        random,
        checks: Default::default(),
    }
}

/// Saves the scene file of `scene` under `findings/` and returns its path.
fn save_finding(out: &std::path::Path, set: RandomSet, summary: &Summary, scene: &str) -> PathBuf {
    let index = summary
        .features
        .iter()
        .position(|f| f.scene == scene)
        .unwrap();
    let dir = out.join("findings");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{scene}.toml"));
    std::fs::write(&path, set.scene(index, SIZE).text).unwrap();
    path
}

/// The draw, evaluated once for every test of this file (`None`: no GPU, skipped).
fn draw() -> Option<&'static (Summary, Distribution)> {
    static DRAW: OnceLock<Option<(Summary, Distribution)>> = OnceLock::new();
    DRAW.get_or_init(|| {
        let ctx = tests::gpu()?;
        let out = out();
        let _ = std::fs::remove_dir_all(&out);
        let start = Instant::now();
        let summary = voxel_lab::evaluate(&ctx, &options(out, Vec::new(), Some(set()))).unwrap();
        eprintln!(
            "{COUNT} random scenes evaluated in {:.1} s",
            start.elapsed().as_secs_f64()
        );
        let d = distribution::compute(&summary, set());
        Some((summary, d))
    })
    .as_ref()
}

fn set() -> RandomSet {
    RandomSet::new(COUNT, SEED).unwrap()
}

fn out() -> PathBuf {
    tests::out_dir("lab-random")
}

/// Fails naming every finding, after saving each scene's file under `findings/`.
fn no_findings(claim: &str, findings: &[(String, String)], summary: &Summary) {
    let lines: Vec<String> = findings
        .iter()
        .map(|(scene, what)| {
            let p = save_finding(&out(), set(), summary, scene);
            format!("{scene}: {what} ({})", p.display())
        })
        .collect();
    assert!(
        lines.is_empty(),
        "{claim} fails on {} random scenes:\n{}",
        lines.len(),
        lines.join("\n")
    );
}

#[test]
fn random_draw_has_what_it_should() {
    let Some((summary, d)) = draw() else { return };
    assert_eq!(d.count, COUNT);
    assert_eq!(
        summary.records.len(),
        COUNT * (techniques().len() + WeightFunction::ALL.len())
    );
    // Translucency is in view in most scenes, and the draw covers the features.
    assert!(
        d.translucent_not_in_view_share <= 0.2,
        "{} of {COUNT} scenes show nothing translucent",
        d.translucent_not_in_view
    );
    for f in [
        "the eye inside a translucent volume",
        "the eye exactly on a face plane",
        "a grazing view along a surface",
        "a stack of 9–24 layers",
        "extra block types",
        "a large surface with small objects",
        "a glass floor or ceiling",
        "cutout blocks (leaves)",
    ] {
        let share = d.features.iter().find(|s| s.feature == f).unwrap();
        assert!(share.scenes > 0, "no scene with {f}");
    }
    files(&out(), d);
}

#[test]
fn no_nan_on_random_scenes() {
    let Some((summary, _)) = draw() else { return };
    let findings: Vec<(String, String)> = summary
        .records
        .iter()
        .filter(|r| r.nan_px > 0)
        .map(|r| {
            (
                r.scene.clone(),
                format!("{} has {} NaN/inf pixels", r.technique, r.nan_px),
            )
        })
        .collect();
    no_findings("no NaN", &findings, summary);
}

#[test]
fn the_ray_march_agrees_with_the_reference_on_random_scenes() {
    let Some((summary, _)) = draw() else { return };
    let findings: Vec<(String, String)> = summary
        .reference_checks
        .iter()
        .filter(|c| c.raymarch.differing > 0 || c.raymarch.cracks > 0 || c.lost_fragments > 0)
        .map(|c| {
            (
                c.scene.clone(),
                format!(
                    "the ray march and the A-buffer differ on {} pixels off edges (max {}/255), {} cracks, {} lost fragments: {:?}",
                    c.raymarch.differing,
                    c.raymarch.max_abs_err_off_edges,
                    c.raymarch.cracks,
                    c.lost_fragments,
                    c.raymarch.worst
                ),
            )
        })
        .collect();
    no_findings("the ray march's agreement", &findings, summary);
}

#[test]
fn sorted_quads_is_exact_without_cycles() {
    let Some((summary, _)) = draw() else { return };
    let runs: Vec<_> = summary
        .records
        .iter()
        .filter(|r| r.technique == "sorted-quads")
        .collect();
    assert_eq!(runs.len(), COUNT);
    // A game's particles and entities are ordered by their centres, which is not exact
    // (the sorted techniques): only scenes of blocks count here.
    let blocks_only = |scene: &str| {
        summary.features.iter().any(|f| {
            f.scene == scene
                && f.features.particles == 0
                && f.features.translucent_entities == 0
                && f.features.opaque_entities == 0
        })
    };
    let without_cycle: Vec<_> = runs
        .iter()
        .filter(|r| r.sort_cycles == Some(0) && blocks_only(&r.scene))
        .collect();
    assert!(
        without_cycle.len() >= COUNT / 3,
        "most scenes of blocks have no quad cycle"
    );
    // Off quad edges, where the order alone decides the colour (`voxel_lab::edges`).
    let findings: Vec<(String, String)> = without_cycle
        .iter()
        .filter(|r| r.max_abs_err_off_edges.unwrap() > 1)
        .map(|r| {
            (
                r.scene.clone(),
                format!(
                    "sorted-quads off by {}/255 away from quad edges ({}/255 over all, FLIP {:.4}, {} pixels, {} on edges) with no cycle in its quad order",
                    r.max_abs_err_off_edges.unwrap(),
                    r.max_abs_err,
                    r.flip_mean,
                    (r.frac_bad_px * f64::from(r.width * r.height)).round(),
                    r.edge_px.unwrap()
                ),
            )
        })
        .collect();
    // On edges: single pixels where sub-pixel snapping decides, rare.
    let edge_px: u32 = without_cycle.iter().map(|r| r.edge_px.unwrap()).sum();
    let px = without_cycle.len() as u32 * SIZE.0 * SIZE.1;
    eprintln!("sorted-quads without cycles: {edge_px} edge pixels off of {px}");
    assert!(
        edge_px * 10_000 <= px,
        "{edge_px} edge pixels off of {px}: more than 1 in 10000"
    );
    no_findings(
        "sorted-quads within 1/255 off quad edges",
        &findings,
        summary,
    );
}

#[test]
fn the_default_weight_has_the_lowest_median_flip() {
    let Some((_, d)) = draw() else { return };
    let p50 = |w: WeightFunction| {
        d.techniques
            .iter()
            .find(|t| t.technique == format!("wboit-mrt/{}", w.name()))
            .unwrap()
            .flip_mean
            .p50
    };
    let default = voxel_lab::eval::default_weight();
    assert_eq!(default, WeightFunction::Fitted);
    let all: Vec<String> = WeightFunction::ALL
        .iter()
        .map(|w| format!("{} {:.5}", w.name(), p50(*w)))
        .collect();
    for w in WeightFunction::ALL {
        if w != default {
            assert!(
                p50(default) < p50(w),
                "the default weight {} is not the best on random scenes: median FLIP {}",
                default.name(),
                all.join(", ")
            );
        }
    }
}

#[test]
fn worst_scenes_replay_with_the_same_error() {
    let Some((summary, d)) = draw() else { return };
    let ctx = tests::gpu().unwrap();
    replay(&ctx, &out(), summary, d);
}

/// Every output file exists and holds what it should.
fn files(out: &std::path::Path, d: &Distribution) {
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("distribution.json")).unwrap())
            .unwrap();
    assert_eq!(json["count"], COUNT);
    let techniques = json["techniques"].as_array().unwrap();
    assert_eq!(
        techniques.len(),
        self::techniques().len() + WeightFunction::ALL.len()
    );
    for t in techniques {
        for key in ["n", "exact_share", "nan_px"] {
            assert!(t.get(key).is_some(), "{key}");
        }
        for key in ["flip_mean", "max_abs_err"] {
            for p in ["p50", "p90", "p99", "max"] {
                assert!(t[key][p].is_number(), "{key}.{p}");
            }
        }
    }
    let scenes: Vec<serde_json::Value> =
        serde_json::from_str(&std::fs::read_to_string(out.join("scenes.json")).unwrap()).unwrap();
    assert_eq!(scenes.len(), COUNT);
    for t in &d.techniques {
        if t.technique != "reference" {
            let f = out.join(distribution::worst_file(&t.technique));
            assert!(f.is_file(), "{}", f.display());
        }
    }
    for file in [
        "speed_vs_accuracy.png",
        "speed_vs_accuracy.svg",
        "speed_vs_accuracy_scenes.png",
        "max_abs_err_histogram.png",
        "max_abs_err_histogram.svg",
        "summary.json",
        "report.md",
    ] {
        let len = std::fs::metadata(out.join(file))
            .map(|m| m.len())
            .unwrap_or(0);
        assert!(len > 500, "{file}: {len} bytes");
    }
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(report.contains("## Error distribution"), "{report}");
    assert!(report.contains("## Where each technique fails"));
    for w in &d.where_it_fails {
        assert!(report.contains(&format!("### {}", w.technique)));
    }
}

/// The worst scenes of two techniques, replayed from `worst/` as scene files, give every
/// technique the same error as in the random run.
fn replay(
    ctx: &voxel_render::GpuContext,
    out: &std::path::Path,
    summary: &Summary,
    d: &Distribution,
) {
    let picks = ["sorted-quads", "stipple"];
    let files: Vec<PathBuf> = picks
        .iter()
        .map(|t| out.join(distribution::worst_file(t)))
        .collect();
    let replay = voxel_lab::evaluate(ctx, &options(out.join("replay"), files, None)).unwrap();
    for t in picks {
        let worst = d.techniques.iter().find(|x| x.technique == t).unwrap();
        let scene = t.to_owned(); // the replayed file's stem
        for r in replay.records.iter().filter(|r| r.scene == scene) {
            let original = summary
                .records
                .iter()
                .find(|o| o.scene == worst.worst_scene && o.technique == r.technique)
                .unwrap();
            assert_eq!(
                (r.max_abs_err, r.width, r.height),
                (original.max_abs_err, original.width, original.height),
                "replay of {} ({}) with {}",
                worst.worst_scene,
                t,
                r.technique
            );
            assert!(
                (r.flip_mean - original.flip_mean).abs() < 1e-9,
                "replay of {} with {}: FLIP {} vs {}",
                worst.worst_scene,
                r.technique,
                r.flip_mean,
                original.flip_mean
            );
        }
        let r = replay
            .records
            .iter()
            .find(|r| r.scene == scene && r.technique == t)
            .unwrap();
        assert_eq!(r.max_abs_err, worst.worst_max_abs_err, "{t}");
    }
}
