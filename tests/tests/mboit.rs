//! Moment-based OIT on lavapipe against the A-buffer reference: exact for one layer, better
//! than fitted WBOIT where layers of different colours spread over similar depths (the
//! case the moments resolve and a weight of depth cannot), and its 16-bit fallback.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use voxel_core::blocks::*;
use voxel_render::{RendererConfig, Technique};

use tests::*;

const W: u32 = 192;
const H: u32 = 108;

fn config(technique: Technique) -> RendererConfig {
    technique_config(technique, W, H)
}

/// Mean FLIP of `technique` against the reference on `scene`, saving its picture.
fn flip(scene: &Scene, config: RendererConfig, name: &str) -> f64 {
    let ctx = gpu().unwrap();
    let reference = render_with(&ctx, scene, technique_config(Technique::Reference, W, H));
    let img = render_with(&ctx, scene, config);
    let dir = out_dir("mboit");
    img.save_png(&dir.join(format!("{}_{name}.png", scene.name)))
        .unwrap();
    reference
        .save_png(&dir.join(format!("{}_reference.png", scene.name)))
        .unwrap();
    voxel_lab::metrics::compare(&reference, &img).0.flip_mean
}

/// Eight sheets of four coloured glasses and water, two blocks apart, over a stone wall,
/// seen head-on from a few blocks away: eight layers on every pixel, all at similar depths
/// (the nearest 6 blocks away, the farthest 20), where the order decides the colour.
fn coloured_sheets() -> Scene {
    let kinds = [RED_GLASS, BLUE_GLASS, GREEN_GLASS, WATER];
    let mut boxes = vec![([-60, -40, -24], [60, 40, -22], STONE)];
    for i in 0..8 {
        let z = -2 * i;
        boxes.push(([-30, -20, z], [30, 20, z], kinds[i as usize % 4]));
    }
    scene(
        "coloured_sheets",
        box_world(&boxes),
        [0.5, 0.5, 6.0],
        [0.5, 0.5, 0.0],
    )
}

#[test]
fn one_layer_is_exact() {
    let Some(ctx) = gpu() else { return };
    let world = box_world(&[
        ([-60, -40, -20], [60, 40, -18], STONE),
        ([-50, -30, -5], [50, 30, -5], WATER),
    ]);
    let s = scene("water_wall", world, [0.5, 0.5, 10.0], [0.5, 0.5, 0.0]);
    let reference = render_with(&ctx, &s, config(Technique::Reference));
    let img = render_with(&ctx, &s, config(Technique::Mboit));
    // The average of one colour is that colour, and coverage 1 − e^(ln(1 − α)) is α: only
    // rounding (the 16-bit accumulation) remains.
    assert_close("mboit_one_layer", &img, &reference, 1);
}

#[test]
fn layers_of_similar_depth_are_resolved_better_than_by_wboit() {
    if gpu().is_none() {
        return;
    }
    let s = coloured_sheets();
    let mboit = flip(&s, config(Technique::Mboit), "mboit");
    let wboit = flip(&s, config(Technique::WboitMrt), "wboit-mrt");
    eprintln!("coloured sheets: mboit FLIP {mboit:.4}, fitted wboit {wboit:.4}");
    // Measured when written: mboit 0.0876, fitted wboit 0.2314 (0.38 of it). The paper's
    // claim, at half the error or better; and the error itself bounded with a margin of
    // about a third over the measured value.
    assert!(mboit <= 0.5 * wboit, "mboit {mboit}, wboit {wboit}");
    assert!(mboit < 0.12, "mboit {mboit}");
}

#[test]
fn half_precision_moments_stay_finite_and_close() {
    let Some(ctx) = gpu() else { return };
    let s = coloured_sheets();
    let mut c = config(Technique::Mboit);
    c.oit.mboit.half_precision = true;
    let mut r = renderer_for(&ctx, &s, c.clone()).unwrap();
    let target = Offscreen::new(&ctx, W, H);
    let stats = r.render_and_submit(&target.view, &s.cameras[0]).unwrap();
    let report = stats.technique.mboit.unwrap();
    assert_eq!(report.moments, wgpu::TextureFormat::Rgba16Float);
    let hdr = read_hdr(&ctx, r.scene_color());
    assert!(hdr.iter().all(|p| p.iter().all(|v| v.is_finite())));
    let half = flip(&s, c, "mboit_f16");
    let single = flip(&s, config(Technique::Mboit), "mboit");
    eprintln!("coloured sheets: 16-bit moments FLIP {half:.4}, 32-bit {single:.4}");
    // Measured when written: 0.0880 against 0.0876: the larger bias costs little here.
    assert!(half < 0.12, "16-bit moments: {half}");
    assert!(
        (half - single).abs() < 0.01,
        "16-bit {half}, 32-bit {single}"
    );
    // lavapipe blends 32-bit floats: the default there is single precision.
    let mut r = renderer_for(&ctx, &s, config(Technique::Mboit)).unwrap();
    let stats = r.render_and_submit(&target.view, &s.cameras[0]).unwrap();
    let report = stats.technique.mboit.unwrap();
    assert_eq!(report.moments, wgpu::TextureFormat::Rgba32Float);
    assert!(report.depth_range[0] >= 4.0 && report.depth_range[1] <= 60.0);
}

#[test]
fn bad_settings_are_errors() {
    let mut c = config(Technique::Mboit);
    c.oit.mboit.overestimation = 2.0;
    assert!(c.oit.validate().is_err());
}
