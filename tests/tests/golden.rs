//! Golden images: the exact reference's picture of three suite scenes, stored in
//! `tests/golden/`, compared with FLIP. The per-technique tests compare techniques with
//! each other; this one catches a regression that changes every technique alike (lighting,
//! tonemap, textures, the mesher, the camera).
//!
//! Regenerate (after a deliberate change, and look at the pictures before committing):
//! `VOXEL_UPDATE_GOLDEN=1 cargo test --release -p tests --test golden`.
//!
//! Threshold: mean FLIP at most [`MAX_FLIP`]. The pictures are 160×90 of a reference
//! technique, so on the same driver they come out bit-identical (FLIP 0); a different
//! driver or GPU rasterises edge pixels and filters textures a little differently, which
//! moves the mean FLIP by a few thousandths. A change that matters is far above it: the
//! test below checks that lighting with 10% more ambient light (0.45 → 0.5) is caught.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use std::path::{Path, PathBuf};

use voxel_lab::metrics::compare;
use voxel_render::{Image, RendererConfig, Technique};

use tests::*;

const SCENES: [&str; 3] = [
    "terrain_greenhouse",
    "stained_glass_corridor",
    "water_through_glass",
];
const SIZE: (u32, u32) = (160, 90);
/// Largest mean FLIP against a golden picture; see the module docs.
const MAX_FLIP: f64 = 0.01;

fn golden(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("golden")
        .join(format!("{name}.png"))
}

fn reference(ctx: &voxel_render::GpuContext, name: &str, ambient: f32) -> Image {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../scenes/{name}.toml"));
    let scene = voxel_lab::scene::Scene::load(&path).unwrap();
    let mut config = RendererConfig {
        width: SIZE.0,
        height: SIZE.1,
        ambient,
        ..RendererConfig::default()
    };
    config.oit.technique = Technique::Reference;
    render_with(ctx, &scene, config)
}

#[test]
fn reference_pictures_match_the_golden_images() {
    let Some(ctx) = gpu() else { return };
    let ambient = RendererConfig::default().ambient;
    let update = std::env::var_os("VOXEL_UPDATE_GOLDEN").is_some();
    for name in SCENES {
        let actual = reference(&ctx, name, ambient);
        assert!(distinct_colours(&actual) > 200, "{name}: a blank picture");
        if update {
            actual.save_png(&golden(name)).unwrap();
            continue;
        }
        let expected = Image::load_png(&golden(name)).unwrap_or_else(|e| {
            panic!("{name}: no golden image ({e}); make them with VOXEL_UPDATE_GOLDEN=1")
        });
        let (metrics, heat) = compare(&expected, &actual);
        let dir = out_dir(&format!("golden_{name}"));
        actual.save_png(&dir.join("actual.png")).unwrap();
        heat.save_png(&dir.join("flip.png")).unwrap();
        assert!(
            metrics.flip_mean <= MAX_FLIP,
            "{name}: mean FLIP {:.4} against the golden image (max {MAX_FLIP}); see {}",
            metrics.flip_mean,
            dir.display()
        );
    }
}

#[test]
fn a_small_lighting_change_is_caught() {
    let Some(ctx) = gpu() else { return };
    let name = SCENES[0];
    let Ok(expected) = Image::load_png(&golden(name)) else {
        panic!("{name}: no golden image; make them with VOXEL_UPDATE_GOLDEN=1")
    };
    let brighter = reference(&ctx, name, 0.5);
    let flip = compare(&expected, &brighter).0.flip_mean;
    eprintln!("{name}: ambient 0.45 -> 0.5 moves the mean FLIP by {flip:.4}");
    assert!(
        flip > MAX_FLIP,
        "10% more ambient light gives FLIP {flip:.4}, within the threshold {MAX_FLIP}"
    );
}
