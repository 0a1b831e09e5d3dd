//! Issue 52's G1 cases as far as they were rebuilt here: a game's flat things lying on
//! glass under another glass layer (one across chunk borders, cut there), and particles
//! between two glass layers (`scenes/regressions/foam_on_glass_under_glass.toml`,
//! `particles_between_glass.toml`): `sorted-quads` within 1/255 of the A-buffer reference
//! off quad edges (where the rasteriser decides, not the order), as `depth-peeling` is.
//! These scenes are exact before and after the change that added them: the issue's own
//! `foam_on_glass_big*` scenes were not at hand, and what made them 20–22/255 off is not
//! known. On lavapipe, as CI runs it.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use voxel_lab::edges::{self, Edges};
use voxel_lab::headless::{Offscreen, render_image, renderer_for};
use voxel_lab::overlaps::object_mask;
use voxel_lab::scene::Scene;
use voxel_render::{GpuContext, Image, Technique};

const SIZE: (u32, u32) = (320, 180);

fn scene(name: &str) -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../scenes/regressions")
        .join(name);
    Scene::load(&path).unwrap()
}

/// Each technique's picture of `scene` against the reference's: the largest channel error
/// off quad edges and off pixels of objects that meet, and the pixels off by more than
/// 1/255 there.
fn off_edges(
    ctx: &GpuContext,
    scene: &Scene,
    name: &str,
    camera: usize,
    techniques: &[Technique],
) -> Vec<(Technique, u32, usize)> {
    let camera = scene.cameras[camera];
    let picture = |technique: Technique| {
        let config = tests::technique_config(technique, SIZE.0, SIZE.1);
        let mut r = renderer_for(ctx, scene, config).unwrap();
        let target = Offscreen::new(ctx, SIZE.0, SIZE.1);
        let image = render_image(ctx, &mut r, &target, &camera).unwrap();
        (image, r.renderer.drawn_camera(&camera))
    };
    let (reference, drawn) = picture(Technique::Reference);
    let quad_edges = Edges::new(&scene.world, &drawn, SIZE);
    let objects = object_mask(&scene.content, &drawn, SIZE);
    let out = tests::out_dir("cut_on_glass");
    let _ = reference.save_png(&out.join(format!("{name}_reference.png")));
    techniques
        .iter()
        .map(|&t| {
            let (image, _): (Image, _) = picture(t);
            let _ = image.save_png(&out.join(format!("{name}_{}.png", t.name())));
            let _ = tests::diff_image(&reference, &image)
                .save_png(&out.join(format!("{name}_{}_diff.png", t.name())));
            let off = edges::error_off_edges(&quad_edges, &objects, &reference, &image);
            let d = tests::diff(&reference, &image);
            eprintln!(
                "{name} {}: max {} ({} px over 1/255), off edges and overlaps max {} ({} px over 8/255)",
                t.name(),
                d.max,
                d.over_one,
                off.max,
                off.over_8
            );
            (t, off.max, d.over_one)
        })
        .collect()
}

fn assert_exact(name: &str) {
    let Some(ctx) = tests::gpu() else { return };
    let scene = scene(name);
    let mut failed = Vec::new();
    for camera in 0..scene.cameras.len() {
        let results = off_edges(
            &ctx,
            &scene,
            &format!("{}_{camera}", name.trim_end_matches(".toml")),
            camera,
            &[Technique::SortedQuads, Technique::DepthPeeling],
        );
        for (t, max, _) in results {
            if max > 1 {
                failed.push(format!("camera {camera}: {} {max}/255", t.name()));
            }
        }
    }
    assert!(
        failed.is_empty(),
        "{name}: off the reference off quad edges: {failed:?}"
    );
}

#[test]
fn flat_things_lying_on_glass_under_glass_are_exact_in_sorted_quads() {
    assert_exact("foam_on_glass_under_glass.toml");
}

#[test]
fn particles_between_glass_layers_are_exact_in_sorted_quads() {
    assert_exact("particles_between_glass.toml");
}
