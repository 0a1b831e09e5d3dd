//! A game's frames in water and across surfaces (the suite's `game_*` scenes: things in the
//! eye's water, things through a surface or a pane, foam on a surface, the eye inside an
//! entity, kelp poking out of the water), every real-time technique against the A-buffer
//! reference:
//! - `sorted-quads` within 1/255 on at least 99.5 % of the pixels, and nowhere over 8/255
//!   off quad edges and off pixels where two of the game's objects interpenetrate (no order
//!   of whole objects is right there) or nearly touch (their bounding balls meet: their
//!   centres order them, which can be wrong there), both counted, but for at most 4 pixels a
//!   frame where two objects' centres order them wrongly though their balls do not meet;
//! - `depth-peeling` within 2/255 off quad edges wherever it has the layers (8);
//! - no technique makes a channel 0 or 255 where the reference has none within 32/255 (the
//!   composition inside a volume never leaves the range of its inputs).

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use std::path::Path;

use voxel_lab::edges::{self, Edges};
use voxel_lab::headless::{Offscreen, render_image, renderer_for};
use voxel_lab::overlaps::object_mask;
use voxel_lab::scene::Scene;
use voxel_render::{Image, Technique};

const SIZE: (u32, u32) = (192, 108);

fn game_frames() -> Vec<std::path::PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            p.file_name().and_then(|n| n.to_str()).is_some_and(|n| {
                (n.starts_with("game_") || n == "particles_over_water.toml") && n.ends_with(".toml")
            })
        })
        .collect();
    files.sort();
    files
}

/// Pixels where `test` has a channel at 0 or 255 that `reference` has nowhere near
/// (its channels all within 32/255 of neither end).
fn out_of_range(reference: &Image, test: &Image) -> usize {
    let mut n = 0;
    for y in 0..reference.height {
        for x in 0..reference.width {
            let (r, t) = (reference.pixel(x, y), test.pixel(x, y));
            let reference_near_ends = (0..3).any(|c| r[c] <= 32 || r[c] >= 255 - 32);
            let saturated = (0..3).any(|c| t[c] == 0 || t[c] == 255);
            n += usize::from(saturated && !reference_near_ends);
        }
    }
    n
}

#[test]
fn a_games_frames_in_water_and_across_surfaces() {
    let Some(ctx) = tests::gpu() else { return };
    let scenes = game_frames();
    assert!(
        scenes.len() >= 14,
        "the four game frames and the ten new ones"
    );
    let mut failures = Vec::new();
    let (mut overlapping, mut near) = (0, 0);
    for path in &scenes {
        let scene = Scene::load(path).unwrap();
        let name = path.file_stem().unwrap().to_string_lossy().into_owned();
        let camera = scene.cameras[0];
        let picture = |technique: Technique| {
            let config = tests::technique_config(technique, SIZE.0, SIZE.1);
            let mut r = renderer_for(&ctx, &scene, config).unwrap();
            let target = Offscreen::new(&ctx, SIZE.0, SIZE.1);
            let image = render_image(&ctx, &mut r, &target, &camera).unwrap();
            (image, r.renderer.drawn_camera(&camera))
        };
        let (reference, drawn) = picture(Technique::Reference);
        let quad_edges = Edges::new(&scene.world, &drawn, SIZE);
        let objects = object_mask(&scene.content, &drawn, SIZE);
        for technique in Technique::REAL_TIME
            .into_iter()
            .filter(|&t| t != Technique::OpaqueOnly)
        {
            let (image, _) = picture(technique);
            let saturated = out_of_range(&reference, &image);
            if saturated > 0 {
                failures.push(format!(
                    "{name} {}: {saturated} pixels with a channel at 0 or 255",
                    technique.name()
                ));
            }
            let off = edges::error_off_edges(&quad_edges, &objects, &reference, &image);
            let d = tests::diff(&reference, &image);
            let share = d.over_one as f64 / f64::from(SIZE.0 * SIZE.1);
            match technique {
                Technique::SortedQuads => {
                    overlapping += off.on_overlaps;
                    near += off.on_near;
                    eprintln!(
                        "{name}: sorted-quads off by more than 1/255 on {:.3} %, max {} ({} elsewhere; {} edge, {} interpenetrating, {} near-pair pixels)",
                        100.0 * share,
                        d.max,
                        off.max,
                        off.on_edges,
                        off.on_overlaps,
                        off.on_near
                    );
                    // At most a few pixels over 8/255 elsewhere: objects near each other on
                    // screen whose centres order them wrongly without their bounding balls
                    // meeting (3 pixels of `game_base` at 192×108 when this was written).
                    if share > 0.005 || off.over_8 > 4 {
                        failures.push(format!(
                            "{name} sorted-quads: {:.3} % off, {}/255 off edges and overlaps",
                            100.0 * share,
                            off.max
                        ));
                        let out = tests::out_dir("game_frames");
                        let _ = image.save_png(&out.join(format!("{name}_sorted-quads.png")));
                        let _ = reference.save_png(&out.join(format!("{name}_reference.png")));
                    }
                }
                Technique::DepthPeeling if off.max > 2 => {
                    failures.push(format!("{name} depth-peeling: {}/255 off edges", off.max))
                }
                _ => {}
            }
        }
    }
    eprintln!(
        "pixels off on interpenetrating objects (sorted-quads): {overlapping}; on objects near each other: {near}"
    );
    assert!(failures.is_empty(), "{failures:#?}");
}
