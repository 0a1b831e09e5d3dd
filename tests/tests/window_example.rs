//! The window example (`voxel-render/examples/window.rs`) under Xvfb on lavapipe: a game's
//! own window, surface and passes. Its screenshot, read from the surface texture, is not
//! blank and shows the game's HUD (the crosshair) and the depth-tested selection box over
//! the renderer's picture.
//!
//! Without Xvfb or a Vulkan adapter the test skips with a loud message, unless `CI` is set:
//! then it fails.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use tests::{Xvfb, distinct_colours, example_binary, out_dir, skip_or_fail};
use voxel_render::{GpuContext, Image};

#[test]
fn the_window_example_draws_into_its_own_surface() {
    if GpuContext::headless(wgpu::Backends::VULKAN).is_err() {
        return skip_or_fail("no Vulkan adapter (install mesa-vulkan-drivers)");
    }
    let Some(x) = Xvfb::start() else {
        return skip_or_fail("Xvfb could not be started (install xvfb)");
    };
    let shot = out_dir("window_example").join("window.png");
    let _ = std::fs::remove_file(&shot);
    let out = x
        .command(example_binary("window"))
        .args(["--frames", "4", "--screenshot", shot.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "the example failed: {}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("wrote"), "{stdout}");
    let img = Image::load_png(&shot).unwrap();
    assert_eq!((img.width, img.height), (800, 500));
    // Not blank: terrain, water, leaves, glass.
    assert!(
        distinct_colours(&img) > 500,
        "{} colours",
        distinct_colours(&img)
    );
    // The HUD's crosshair, white, at the centre.
    assert_eq!(img.pixel(400, 250), [255, 255, 255, 255], "the crosshair");
    // The selection box, yellow, where the frame's depth lets it show.
    let yellow = img
        .rgba
        .chunks_exact(4)
        .filter(|p| p[0] > 230 && p[1] > 200 && p[2] < 130)
        .count();
    assert!(yellow > 100, "{yellow} pixels of the selection box");
}
