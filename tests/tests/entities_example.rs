//! The entities example (`voxel-render/examples/entities.rs`): a game's things drawn by the
//! ready-made helper (`voxel_render::content`), run headless as a user would; and the
//! custom_stage example, the same things with the game's own shaders. Every technique draws its crate, glass cube and
//! bubbles. Depth peeling and sorted-quads differ from the A-buffer reference where the
//! bubbles and the crate lie inside the water: they put the whole path through the water
//! in front of them (a volume is composed at its entry face), where the reference splits it
//! at each; sorted-quads also where its order cannot be exact (the cube through the water
//! surface, bubbles at it).

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use std::process::Command;

use tests::{diff, distinct_colours, example_binary, gpu, out_dir};
use voxel_render::Image;

fn run(technique: &str) -> Image {
    run_example("entities", technique)
}

fn run_example(example: &str, technique: &str) -> Image {
    let out = out_dir("entities_example").join(format!("{example}_{technique}.png"));
    let _ = std::fs::remove_file(&out);
    let result = Command::new(example_binary(example))
        .args(["--frames", "3", "--technique", technique, "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        result.status.success(),
        "{technique}: {}\n{}",
        result.status,
        String::from_utf8_lossy(&result.stderr)
    );
    Image::load_png(&out).unwrap()
}

#[test]
fn the_entities_example_composes_its_things_with_every_technique() {
    let Some(_ctx) = gpu() else { return };
    let reference = run("reference");
    assert!(distinct_colours(&reference) > 200, "a flat picture");
    let peeled = run("depth-peeling");
    let d = diff(&peeled, &reference);
    let pixels = (reference.width * reference.height) as usize;
    assert!(
        d.over_one * 20 < pixels,
        "depth peeling differs from the reference on {} of {pixels} px",
        d.over_one
    );
    let sorted = run("sorted-quads");
    let d = diff(&sorted, &reference);
    assert!(
        d.over_one * 20 < pixels,
        "sorted-quads differs on {} of {pixels} px",
        d.over_one
    );
    for t in ["wboit-mrt", "stipple"] {
        let img = run(t);
        assert!(distinct_colours(&img) > 200, "{t}: a flat picture");
    }
}

/// The custom path draws its things with the game's own shaders, whatever the technique
/// (its translucent pipelines rebuilt for each technique's contract).
#[test]
fn the_custom_stage_example_draws_with_its_own_shaders() {
    let Some(_ctx) = gpu() else { return };
    for t in ["sorted-quads", "wboit-mrt"] {
        let img = run_example("custom_stage", t);
        assert!(distinct_colours(&img) > 200, "{t}: a flat picture");
    }
}
