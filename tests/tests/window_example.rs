//! The window example (`voxel-render/examples/window.rs`) under Xvfb, on Vulkan (lavapipe)
//! and on GL (llvmpipe, picked with `WGPU_BACKEND=gl` as a game's user would): a game's
//! own window, surface and passes. Its screenshot, drawn into a texture of its own (GL's
//! surface textures cannot be copied from), is not blank and shows the game's HUD (the
//! crosshair) and the depth-tested selection box over the renderer's picture.
//!
//! Without Xvfb or an adapter the test skips with a loud message, unless `CI` is set:
//! then it fails.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use tests::{Xvfb, distinct_colours, example_binary, out_dir, skip_or_fail};
use voxel_render::{GpuContext, Image};

/// Runs the example with `WGPU_BACKEND=backend` and checks that `drew` drew its
/// screenshot.
fn run_on(backend: &str, drew: wgpu::Backend) {
    if GpuContext::headless(drew.into()).is_err() {
        return skip_or_fail(&format!(
            "no {backend} adapter (install mesa-vulkan-drivers and libegl-mesa0)"
        ));
    }
    let Some(x) = Xvfb::start() else {
        return skip_or_fail("Xvfb could not be started (install xvfb)");
    };
    let shot = out_dir("window_example").join(format!("window_{backend}.png"));
    let _ = std::fs::remove_file(&shot);
    let out = x
        .command(example_binary("window"))
        .env("WGPU_BACKEND", backend)
        .args(["--frames", "4", "--screenshot", shot.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{backend}: the example failed: {}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("wrote"), "{stdout}");
    // The backend asked for is the one that drew.
    assert!(
        stdout.contains(&format!("({drew:?})")),
        "{backend}: {stdout}"
    );
    let img = Image::load_png(&shot).unwrap();
    assert_eq!((img.width, img.height), (800, 500));
    // Not blank: terrain, water, leaves, glass.
    assert!(
        distinct_colours(&img) > 500,
        "{backend}: {} colours",
        distinct_colours(&img)
    );
    // The HUD's crosshair, white, at the centre.
    assert_eq!(
        img.pixel(400, 250),
        [255, 255, 255, 255],
        "{backend}: the crosshair"
    );
    // The selection box, yellow, where the frame's depth lets it show.
    let yellow = img
        .rgba
        .chunks_exact(4)
        .filter(|p| p[0] > 230 && p[1] > 200 && p[2] < 130)
        .count();
    assert!(
        yellow > 100,
        "{backend}: {yellow} pixels of the selection box"
    );
}

#[test]
fn the_window_example_draws_into_its_own_surface() {
    run_on("vulkan", wgpu::Backend::Vulkan);
}

/// GL from a winit window: the instance honours `WGPU_BACKEND` and has the display handle
/// GL presents with; the screenshot works though GL's surface has no `COPY_SRC`.
#[test]
fn the_window_example_runs_on_gl() {
    run_on("gl", wgpu::Backend::Gl);
}
