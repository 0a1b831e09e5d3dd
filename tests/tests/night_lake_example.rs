//! The night_lake example (`voxel-render/examples/night_lake.rs`): the ready-made content
//! (glowing fireflies, a boat, a lantern) beside the game's own mist and HUD in one frame
//! (`stages::Both`), run headless as a user would on Vulkan, on wgpu's GL backend
//! (`WGPU_BACKEND=gl`) and under WebGL2's limits on both: it exits cleanly (no panic, no
//! validation error), draws its glowing things and its HUD, and each device draws what
//! Vulkan draws.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use std::process::Command;

use tests::{diff, example_binary, gpu, out_dir};
use voxel_render::{GpuContext, Image, LimitsPreset};

/// Runs the example with `technique` on `backend` (`WGPU_BACKEND`) with `limits`.
fn run(backend: &str, limits: &str, technique: &str) -> Image {
    let out = out_dir("night_lake_example").join(format!("{backend}_{limits}_{technique}.png"));
    let _ = std::fs::remove_file(&out);
    let result = Command::new(example_binary("night_lake"))
        .env("WGPU_BACKEND", backend)
        .args([
            "--frames",
            "3",
            "--technique",
            technique,
            "--limits",
            limits,
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        result.status.success(),
        "{backend} {limits} {technique}: {}\n{}",
        result.status,
        String::from_utf8_lossy(&result.stderr)
    );
    Image::load_png(&out).unwrap()
}

/// Pixels of the fireflies' and the lantern's glow: bright yellow at night.
fn glowing(img: &Image) -> usize {
    img.rgba
        .chunks_exact(4)
        .filter(|p| p[0] > 200 && p[1] > 160 && p[2] < 170)
        .count()
}

#[test]
fn the_night_lake_example_runs_on_vulkan_gl_and_webgl2_limits() {
    if gpu().is_none() {
        return;
    }
    if GpuContext::headless_with(wgpu::Backends::GL, LimitsPreset::Adapter).is_err() {
        return tests::skip_or_fail("no GL adapter (install libegl1 libegl-mesa0 libgles2)");
    }
    for technique in ["sorted-quads", "wboit-mrt"] {
        let vulkan = run("vulkan", "adapter", technique);
        let glow = glowing(&vulkan);
        assert!(glow > 300, "{technique}: {glow} glowing pixels");
        // The HUD: a white frame 12 px inside the edges, over everything.
        for (x, y) in [(13, 180), (626, 180), (320, 13), (320, 346)] {
            assert_eq!(
                vulkan.pixel(x, y)[..3],
                [255, 255, 255],
                "{technique}: HUD at {x},{y}"
            );
        }
        for (backend, limits) in [("vulkan", "webgl2"), ("gl", "adapter"), ("gl", "webgl2")] {
            let img = run(backend, limits, technique);
            let d = diff(&img, &vulkan);
            eprintln!("{technique} {backend} {limits}: {d:?}");
            // The same picture but where GL's rasteriser path differs from Vulkan's on a few
            // edge pixels (as the world's, `backends.rs`).
            let pixels = (img.width * img.height) as usize;
            assert!(
                d.over_one * 1000 <= pixels,
                "{technique} {backend} {limits}: {} of {pixels} px off by more than 1/255",
                d.over_one
            );
            assert!(glowing(&img) > 300, "{technique} {backend} {limits}");
        }
    }
}
