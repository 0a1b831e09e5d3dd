//! The entities example (`voxel-render/examples/entities.rs`): a game's own shaders and
//! stages, run headless as a user would. Every technique draws its crate, glass cube and
//! bubbles; depth peeling matches the A-buffer reference, and sorted-quads differs only
//! where its order cannot be exact (the cube through the water surface, bubbles at it).

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use std::process::Command;

use tests::{diff, distinct_colours, example_binary, gpu, out_dir};
use voxel_render::Image;

fn run(technique: &str) -> Image {
    let out = out_dir("entities_example").join(format!("{technique}.png"));
    let _ = std::fs::remove_file(&out);
    let result = Command::new(example_binary("entities"))
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
    assert!(d.max <= 1, "depth peeling against the reference: {d:?}");
    let sorted = run("sorted-quads");
    let d = diff(&sorted, &reference);
    let pixels = (reference.width * reference.height) as usize;
    assert!(
        d.over_one * 100 < pixels,
        "sorted-quads differs on {} of {pixels} px",
        d.over_one
    );
    for t in ["wboit-mrt", "stipple"] {
        let img = run(t);
        assert!(distinct_colours(&img) > 200, "{t}: a flat picture");
    }
}
