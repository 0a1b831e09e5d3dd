//! A small `demo far` run as a user runs it (full detail to 4 chunks, levels to 16, compared
//! with full detail): its pictures, its report with a row per level, and bad options
//! refused before anything is built. Needs a Vulkan adapter (lavapipe); without one it
//! skips loudly, unless `CI` is set: then it fails.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

mod common;

use common::demo;

#[test]
fn a_small_far_view_writes_its_pictures_and_report() {
    if voxel_render::GpuContext::headless(wgpu::Backends::VULKAN).is_err() {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI is set but no Vulkan adapter"
        );
        eprintln!("\n!!!! SKIPPING FAR TEST: no Vulkan adapter !!!!\n");
        return;
    }
    let out = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("far-16");
    let _ = std::fs::remove_dir_all(&out);
    let run = demo(&[
        "far",
        "--full-detail",
        "4",
        "--view-distance",
        "16",
        "--size",
        "320x180",
        "--techniques",
        "sorted-quads,wboit-mrt",
        "--fly-frames",
        "30",
        "--compare",
        "--out",
        out.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(stdout.contains("the finished view after"), "{stdout}");
    assert!(stdout.contains("against full detail: holes"), "{stdout}");
    for f in [
        "far-sorted-quads.png",
        "far-wboit-mrt.png",
        "full.png",
        "levels.png",
        "compare-map.png",
    ] {
        assert!(out.join(f).is_file(), "{f} not written");
    }
    let text = std::fs::read_to_string(out.join("far.json")).unwrap();
    let r: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(r["view_distance"], 16);
    assert_eq!(r["coarsest"], 2);
    assert_eq!(r["views"], 3, "not built coarse first: {text}");
    let levels = r["levels"].as_array().unwrap();
    assert_eq!(levels.len(), 3);
    for l in levels {
        assert!(l["chunks"].as_u64().unwrap() > 0, "{l}");
        assert!(l["bytes"].as_u64().unwrap() > 0, "{l}");
    }
    assert_eq!(r["flight_frames"], 30);
    assert!(r["compare"]["holes"].as_f64().unwrap() <= 0.0001, "{text}");
}

#[test]
fn bad_far_runs_are_refused_before_building() {
    for (args, says) in [
        (
            &["far", "--full-detail", "3", "--out", "x"][..],
            "--full-detail",
        ),
        (
            &[
                "far",
                "--full-detail",
                "8",
                "--view-distance",
                "4",
                "--out",
                "x",
            ][..],
            "--view-distance",
        ),
        (
            &["far", "--view-distance", "4096", "--out", "x"][..],
            "--view-distance",
        ),
        (
            &["far", "--view-distance", "128", "--compare", "--out", "x"][..],
            "--compare",
        ),
        (
            &["far", "--techniques", "nope", "--out", "x"][..],
            "--techniques",
        ),
    ] {
        let run = demo(args);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(!run.status.success(), "{args:?} ran");
        assert!(stderr.contains(says), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
}
