//! Under water and inside glass: translucent surfaces seen from inside their volume, and
//! the medium's fog (`voxel_render::medium`). Every technique draws the reference's picture
//! from inside, the surface is there on every frame of a dive through it, and nothing of
//! this changes a picture taken from outside (the golden and technique tests cover that).

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use voxel_core::blocks::*;
use voxel_render::{Camera, Image, RendererConfig, Technique};

use tests::*;

const W: u32 = 160;
const H: u32 = 96;

fn config(technique: Technique) -> RendererConfig {
    technique_config(technique, W, H)
}

/// A sea (surface at y = 1) over sand and a stone pillar through it, with a glass block
/// deep in the water when `glass`.
fn sea(eye: [f64; 3], target: [f64; 3], glass: bool) -> Scene {
    let mut boxes = vec![
        ([-40, -12, -40], [40, -12, 40], SAND),
        ([-40, -11, -40], [40, 0, 40], WATER),
        ([4, -11, -10], [6, 6, -8], STONE),
    ];
    if glass {
        boxes.push(([-3, -6, -14], [-2, -5, -13], RED_GLASS));
    }
    scene("sea", box_world(&boxes), eye, target)
}

fn pixels_apart(a: &Image, b: &Image, by: u8) -> f64 {
    let n = a
        .rgba
        .chunks_exact(4)
        .zip(b.rgba.chunks_exact(4))
        .filter(|(p, q)| (0..3).any(|c| p[c].abs_diff(q[c]) > by))
        .count();
    n as f64 / f64::from(a.width * a.height)
}

#[test]
fn from_under_water_every_technique_draws_the_surface_like_the_reference() {
    let Some(ctx) = gpu() else { return };
    // Looking up at the surface: one translucent layer (its way out), the sky beyond.
    let s = sea([0.5, -2.5, 4.0], [0.5, 3.0, -8.0], false);
    assert_eq!(s.cameras[0].medium, Some(WATER), "the eye is in the water");
    let reference = render_with(&ctx, &s, config(Technique::Reference));
    let opaque = render_with(&ctx, &s, config(Technique::OpaqueOnly));
    // The surface seen from below covers the upper part of the view: the picture is not
    // the opaque one there.
    assert!(
        pixels_apart(&reference, &opaque, 8) > 0.3,
        "the surface is missing: {}",
        pixels_apart(&reference, &opaque, 8)
    );
    for t in [
        Technique::SortedQuads,
        Technique::WboitMrt,
        Technique::WboitTwoPass,
        Technique::Mboit,
        Technique::DepthPeeling,
        Technique::PeelReference,
    ] {
        let img = render_with(&ctx, &s, config(t));
        assert_close(&format!("under_water_{t}"), &img, &reference, 2);
    }
}

#[test]
fn inside_glass_the_glass_tints_the_view_and_fogs_it() {
    let Some(ctx) = gpu() else { return };
    // A big glass room (glass walls 1 thick around air) would be seen from outside; here
    // the eye is inside a solid block of glass, looking out at stone.
    let world = box_world(&[
        ([-20, -1, -30], [20, -1, 10], STONE),
        ([-20, 0, -30], [20, 10, -30], STONE),
        ([-4, 0, -4], [4, 6, 4], BLUE_GLASS),
    ]);
    let s = scene("in_glass", world, [0.5, 2.5, 0.5], [0.5, 2.0, -20.0]);
    assert_eq!(s.cameras[0].medium, Some(BLUE_GLASS));
    let reference = render_with(&ctx, &s, config(Technique::Reference));
    let opaque = render_with(&ctx, &s, config(Technique::OpaqueOnly));
    assert!(pixels_apart(&reference, &opaque, 8) > 0.5);
    // The way out of the glass is one layer; every technique agrees.
    for t in [
        Technique::SortedQuads,
        Technique::WboitMrt,
        Technique::Mboit,
        Technique::DepthPeeling,
    ] {
        let img = render_with(&ctx, &s, config(t));
        assert_close(&format!("in_glass_{t}"), &img, &reference, 2);
    }
}

#[test]
fn a_dive_through_the_surface_keeps_the_surface_on_every_frame() {
    let Some(ctx) = gpu() else { return };
    // No glass under the water: the water behind a glass block that stands in it is a
    // second passage, approximate in sorted-quads (docs/techniques.md, "Volumes"), and
    // this test is about the surface.
    let s = sea([0.5, 3.0, 4.0], [0.5, 0.0, -12.0], false);
    let mut reference = renderer_for(&ctx, &s, config(Technique::Reference)).unwrap();
    let mut opaque = renderer_for(&ctx, &s, config(Technique::OpaqueOnly)).unwrap();
    let mut sorted = renderer_for(&ctx, &s, config(Technique::SortedQuads)).unwrap();
    let mut wboit = renderer_for(&ctx, &s, config(Technique::WboitMrt)).unwrap();
    let start = s.cameras[0];
    // From 2 blocks above the surface (y = 1) to 2 below, in steps that land within the
    // near plane of it, and exactly on it.
    let mut ys: Vec<f64> = (0..=40).map(|i| 3.0 - f64::from(i) * 0.1).collect();
    ys.extend([1.0, 1.0 + 1e-4, 1.0 - 1e-4, 1.0005, 0.9995]);
    for y in ys {
        let eye = glam::DVec3::new(start.eye.x, y, start.eye.z);
        let medium = s.world.medium_at(eye.to_array());
        let camera = Camera { eye, ..start }.in_medium(medium);
        let r = frame(&ctx, &mut reference, &camera);
        let o = frame(&ctx, &mut opaque, &camera);
        let q = frame(&ctx, &mut sorted, &camera);
        frame(&ctx, &mut wboit, &camera);
        let hdr = read_hdr(&ctx, wboit.scene_color());
        assert!(
            hdr.iter().all(|p| p.iter().all(|c| c.is_finite())),
            "y {y}: NaN or inf"
        );
        // The surface is on the picture, from above or from below: far from opaque-only.
        let apart = pixels_apart(&r, &o, 8);
        assert!(apart > 0.3, "y {y}: the surface is missing ({apart})");
        assert!(
            diff(&q, &r).max <= 2,
            "y {y}: sorted quads and the reference differ by {}",
            diff(&q, &r).max
        );
    }
}
