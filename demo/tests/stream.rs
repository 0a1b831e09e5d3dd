//! A short `demo stream` run (view distance 4, 60 frames) as a user runs it: it writes its
//! report with every field, its frames and its chart, with sane values. Needs a Vulkan
//! adapter (lavapipe); without one it skips loudly, unless `CI` is set: then it fails.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use std::process::Command;

#[test]
fn a_short_stream_writes_its_report() {
    if voxel_render::GpuContext::headless(wgpu::Backends::VULKAN).is_err() {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI is set but no Vulkan adapter"
        );
        eprintln!("\n!!!! SKIPPING STREAM TEST: no Vulkan adapter !!!!\n");
        return;
    }
    let out = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("stream-vd4");
    let _ = std::fs::remove_dir_all(&out);
    let run = Command::new(env!("CARGO_BIN_EXE_demo"))
        .args([
            "stream",
            "--view-distance",
            "4",
            "--frames",
            "60",
            "--size",
            "160x90",
        ])
        .arg("--out")
        .arg(&out)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(stdout.contains("per frame CPU p50"), "{stdout}");

    let text = std::fs::read_to_string(out.join("stream.json")).unwrap();
    let r: serde_json::Value = serde_json::from_str(&text).unwrap();
    for key in [
        "view_distance",
        "frames",
        "chunks_resident",
        "chunks_drawn_p50",
        "cpu_frame_ms",
        "gpu_frame_ms_p50",
        "upload_bytes_per_frame_p95",
        "gpu_buffer_bytes",
        "chunk_storage_bytes",
        "rss_bytes",
        "hitches",
    ] {
        assert!(r.get(key).is_some(), "stream.json lacks {key}: {text}");
    }
    assert_eq!(r["view_distance"], 4);
    assert_eq!(r["frames"], 60);
    assert_eq!(r["failed"], 0);
    let n = |k: &str| r[k].as_f64().unwrap();
    // A 4-chunk circle is 49 columns; the terrain spans two chunk layers.
    assert!(n("chunks_resident") >= 49.0, "{text}");
    assert!(n("chunks_drawn_p50") > 10.0, "{text}");
    let cpu = &r["cpu_frame_ms"];
    let (p50, p95, max) = (
        cpu["p50"].as_f64().unwrap(),
        cpu["p95"].as_f64().unwrap(),
        cpu["max"].as_f64().unwrap(),
    );
    assert!(0.0 < p50 && p50 <= p95 && p95 <= max, "{text}");
    // Flying at 4 blocks a frame, 60 frames cross 7 chunks: new ones stream in.
    assert!(n("upload_bytes_per_frame_p95") > 0.0, "{text}");
    // Blocks resident within 2x a packed-index palette (the bound the streamer keeps).
    assert!(
        n("chunk_storage_bytes") <= 2.0 * n("packed_index_bytes"),
        "{text}"
    );
    assert!(n("gpu_quad_bytes") == 8.0 * n("quads"), "{text}");

    let frames: Vec<serde_json::Value> =
        serde_json::from_str(&std::fs::read_to_string(out.join("frames.json")).unwrap()).unwrap();
    assert_eq!(frames.len(), 60);
    for chart in ["cpu_ms.png", "cpu_ms.svg"] {
        assert!(
            std::fs::metadata(out.join(chart)).unwrap().len() > 1000,
            "{chart}"
        );
    }
}
