//! The lab in CI: a small, few-frame evaluation of the whole scene suite with every
//! technique, checking that the two exact methods agree, that nothing overflows or turns
//! NaN, and that every output file is written.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use std::path::Path;

use voxel_lab::EvalOptions;
use voxel_lab::scene::scene_files;
use voxel_render::{Technique, WeightFunction};

#[test]
fn small_eval_of_the_suite() {
    let Some(ctx) = tests::gpu() else { return };
    let out = tests::out_dir("lab");
    let _ = std::fs::remove_dir_all(&out);
    let scenes = scene_files(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes")).unwrap();
    assert!(scenes.len() >= 10, "the suite has at least 10 scenes");
    let opts = EvalOptions {
        scenes: scenes.clone(),
        techniques: Technique::ALL.to_vec(),
        weights: WeightFunction::ALL.to_vec(),
        size: Some((96, 54)),
        frames: 1,
        warmup: 1,
        out: out.clone(),
        stability: true,
        flicker_frames: 3,
        sweep_points: 2,
        command: "cargo test -p tests --test lab".into(),
        heatmap_width: Some(48),
        random: None,
        checks: Default::default(),
    };

    let summary = voxel_lab::evaluate(&ctx, &opts).unwrap();

    // The reference is right: the two exact methods agree on every scene, nothing lost.
    assert_eq!(summary.reference_checks.len(), scenes.len());
    for c in &summary.reference_checks {
        assert!(
            c.max_abs_err <= 1,
            "{}: A-buffer and peeling differ by {}/255",
            c.scene,
            c.max_abs_err
        );
        assert_eq!(c.lost_fragments, 0, "{}: A-buffer lost fragments", c.scene);
        // The CPU ray march (no mesh, no rasteriser) agrees with the A-buffer to 1/255 on
        // every pixel off geometric edges, and no background shows through closed geometry.
        let r = &c.raymarch;
        assert_eq!(
            (r.differing, r.cracks),
            (0, 0),
            "{}: the ray march differs from the A-buffer off edges (max {}/255): {:?}",
            c.scene,
            r.max_abs_err_off_edges,
            r.worst
        );
        assert!(c.exact, "{}: the reference is not exact", c.scene);
    }
    assert!(
        summary
            .reference_checks
            .iter()
            .any(|c| c.depth_complexity >= 32),
        "the suite holds a scene of 32+ layers"
    );
    // One record per scene and technique (plus the weight runs), none with NaN or inf.
    assert_eq!(
        summary.records.len(),
        scenes.len() * (Technique::ALL.len() + WeightFunction::ALL.len())
    );
    for r in &summary.records {
        assert_eq!(r.nan_px, 0, "{} {}: NaN/inf pixels", r.scene, r.technique);
        assert!(out.join(&r.heatmap).is_file(), "missing {}", r.heatmap);
        if r.scene == "opaque_only" {
            assert_eq!(
                r.max_abs_err, 0,
                "{}: no translucency, so no error",
                r.technique
            );
        }
        if r.technique == "reference" {
            assert_eq!(r.max_abs_err, 0);
        }
    }

    // The fitted weight has the lowest suite-mean FLIP of every weight, well under the
    // alpha-cubed weight's: 0.42 of it with water as a thin surface, 0.61 with water a
    // volume (a water face then carries the path behind it, which the fit, made from the
    // faces' opacities, does not know).
    let mean_flip = |w: WeightFunction| {
        let runs: Vec<f64> = summary
            .records
            .iter()
            .filter(|r| r.technique == format!("wboit-mrt/{}", w.name()))
            .map(|r| r.flip_mean)
            .collect();
        assert_eq!(runs.len(), scenes.len(), "{}", w.name());
        runs.iter().sum::<f64>() / runs.len() as f64
    };
    let fitted = mean_flip(WeightFunction::Fitted);
    for w in WeightFunction::ALL {
        if w != WeightFunction::Fitted {
            assert!(fitted < mean_flip(w), "fitted {fitted} vs {}", w.name());
        }
    }
    let alpha_cubed = mean_flip(WeightFunction::AlphaCubed);
    assert!(
        fitted <= 0.7 * alpha_cubed,
        "fitted {fitted}, alpha-cubed {alpha_cubed}"
    );

    // Moment-based OIT against the reference on the suite: its mean FLIP is bounded and
    // below fitted WBOIT's (the same weights' pass, `wboit-mrt`). Measured when written
    // at this size: 0.0198 against 0.0303; the bound leaves about 30 % for other drivers'
    // rounding.
    let suite_mean = |technique: &str| {
        let runs: Vec<f64> = summary
            .records
            .iter()
            .filter(|r| r.technique == technique)
            .map(|r| r.flip_mean)
            .collect();
        assert_eq!(runs.len(), scenes.len(), "{technique}");
        runs.iter().sum::<f64>() / runs.len() as f64
    };
    let mboit = suite_mean("mboit");
    let wboit = suite_mean("wboit-mrt");
    eprintln!("suite mean FLIP: mboit {mboit:.4}, wboit-mrt {wboit:.4}");
    assert!(mboit < wboit, "mboit {mboit}, wboit-mrt {wboit}");
    // 0.026 at most with water as a thin surface; 0.043 with water a volume, whose faces
    // carry an opacity near 1 that the moments reconstruct worst (docs/techniques.md).
    assert!(mboit <= 0.05, "mboit {mboit}");

    // summary.json: an array of records with the documented keys.
    let json: Vec<serde_json::Value> =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(json.len(), summary.records.len());
    for key in [
        "scene",
        "technique",
        "width",
        "height",
        "gpu_ms",
        "cpu_ms",
        "rmse",
        "psnr",
        "flip_mean",
        "max_abs_err",
        "frac_bad_px",
        "nan_px",
    ] {
        assert!(
            json.iter().all(|r| r.get(key).is_some()),
            "summary.json lacks {key}"
        );
    }
    for file in [
        "speed_vs_accuracy.png",
        "speed_vs_accuracy.svg",
        "report.md",
        "stability/opacity.png",
        "stability/layers.png",
        "stability/distance.png",
        "stability/stability.json",
        "stability/flicker_terrain_greenhouse.png",
    ] {
        let len = std::fs::metadata(out.join(file))
            .map(|m| m.len())
            .unwrap_or(0);
        assert!(len > 500, "{file}: {len} bytes");
    }
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    for c in &summary.reference_checks {
        assert!(report.contains(&c.scene), "report.md lacks {}", c.scene);
    }
}
