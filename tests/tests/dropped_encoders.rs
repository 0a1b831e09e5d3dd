//! A game that drops every frame's encoder unsubmitted keeps its memory flat: wgpu holds a
//! queue's writes (the frame's uniforms and draw commands) and their staging memory until
//! the next submit, so the renderer flushes a dropped frame's writes with an empty submit
//! (it learns of the drop at the next frame). Alone in its binary: it reads the process's
//! resident memory.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use tests::*;
use voxel_render::NoGame;
use voxel_render::Technique;

/// Resident bytes of this process.
fn rss() -> u64 {
    let statm = std::fs::read_to_string("/proc/self/statm").unwrap();
    statm
        .split_whitespace()
        .nth(1)
        .unwrap()
        .parse::<u64>()
        .unwrap()
        * 4096
}

#[test]
fn dropped_encoders_keep_memory_flat() {
    let Some(ctx) = gpu() else { return };
    let scene = voxel_lab::scene::default_scene_with_radius(1, 2).unwrap();
    let cam = scene.cameras[0];
    let mut r = renderer_for(&ctx, &scene, technique_config(Technique::WboitMrt, 160, 90)).unwrap();
    let target = Offscreen::new(&ctx, 160, 90);
    let mut frames = |n: usize| {
        for _ in 0..n {
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            r.render(&mut encoder, &target.view, &cam, &mut NoGame)
                .unwrap();
            drop(encoder);
        }
    };
    frames(300);
    let before = rss();
    frames(1500);
    let grown = rss().saturating_sub(before) as f64 / 1048576.0;
    eprintln!("1500 dropped frames: resident memory grew {grown:.1} MiB");
    // Unflushed, each frame kept about 20 KiB (30 MiB here).
    assert!(grown < 6.0, "1500 dropped frames grew {grown:.1} MiB");
    // And a submitted frame after them draws.
    let img = frame(&ctx, &mut r, &cam);
    assert!(distinct_colours(&img) > 8);
}
