//! The third exact reference: the CPU ray march (no mesh, no rasteriser, no GPU) against the
//! A-buffer reference on the whole suite, and the terrain a player can read: a one-block
//! step of flat-coloured terrain differs in brightness across the step (ambient occlusion),
//! and does not with the occlusion turned off.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use std::path::Path;

use glam::DVec3;
use voxel_core::blocks::{GRASS, STONE};
use voxel_lab::eval::raymarch_check;
use voxel_lab::raymarch::{RayMarcher, Shading};
use voxel_lab::scene::{Scene, scene_files};
use voxel_render::{Camera, Lighting, RendererConfig, Technique};

/// Small enough for CI, large enough that the terrain scenes hold steps, water and glass.
const SIZE: (u32, u32) = (192, 108);

#[test]
fn the_ray_march_agrees_with_the_reference_on_the_suite() {
    let Some(ctx) = tests::gpu() else { return };
    let files = scene_files(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes")).unwrap();
    assert!(files.len() >= 10);
    for file in files
        .iter()
        .filter(|f| f.extension().is_some_and(|e| e == "toml"))
    {
        let scene = Scene::load(file).unwrap();
        let check = raymarch_check(&ctx, &scene, &scene.cameras[0], SIZE).unwrap();
        let c = &check.comparison;
        let name = file.display();
        assert!(
            check.ray.end.iter().any(Option::is_some),
            "{name}: the ray march met no surface"
        );
        // Every pixel off geometric edges within 1/255 (flat textures: each block one
        // colour), and no background through closed geometry.
        assert_eq!(
            (c.differing, c.cracks),
            (0, 0),
            "{name}: {} pixels off edges differ (max {}/255), {} cracks: {:?}",
            c.differing,
            c.max_abs_err_off_edges,
            c.cracks,
            c.worst
        );
        // Pixels on edges are few: the comparison is not waved through.
        assert!(
            c.differing_on_edges + c.translucent_seams < c.pixels / 50,
            "{name}: {} of {} pixels differ on edges or seams",
            c.differing_on_edges + c.translucent_seams,
            c.pixels
        );
    }
}

/// The renderer's settings with the lighting of `hour` (flat textures, as the ray march
/// draws them).
fn at_hour(hour: f32, technique: Technique) -> RendererConfig {
    let l = Lighting::daytime(hour);
    RendererConfig {
        flat_textures: true,
        sun_dir: l.sun_dir,
        ambient: l.ambient,
        brightness: l.brightness,
        sky: l.sky,
        ..tests::technique_config(technique, SIZE.0, SIZE.1)
    }
}

#[test]
fn at_night_the_world_is_moonlit_and_the_ray_march_agrees() {
    let Some(ctx) = tests::gpu() else { return };
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/water_through_glass.toml");
    let scene = Scene::load(&file).unwrap();
    let camera = scene.cameras[0];
    let mean = |img: &voxel_render::Image| {
        let rgb = img.rgba.chunks_exact(4).flat_map(|p| &p[..3]);
        let sum: u64 = rgb.map(|&c| u64::from(c)).sum();
        sum as f64 / (img.rgba.len() / 4 * 3) as f64
    };
    let noon = tests::render_with(&ctx, &scene, at_hour(12.0, Technique::Reference));
    let night_config = at_hour(0.0, Technique::Reference);
    let mut r = voxel_lab::headless::renderer_for(&ctx, &scene, night_config.clone()).unwrap();
    let night = tests::frame(&ctx, &mut r, &camera);
    // Moonlight is an eighth of daylight in linear light: after the sRGB curve the picture
    // is well under half as bright, but not black.
    let (day, dark) = (mean(&noon), mean(&night));
    assert!(
        dark < 0.45 * day && dark > 4.0,
        "night mean {dark:.1} against noon {day:.1}"
    );
    // The CPU ray march, lit by the same moon, draws the same picture.
    let drawn = r.drawn_camera(&camera);
    let shading = Shading::of(&night_config);
    let marcher = RayMarcher::with_content(&scene.world, &scene.content);
    let ray = marcher.render(&drawn, SIZE.0, SIZE.1, &shading);
    let c = marcher.compare(&ray, &drawn, &shading, &night, None);
    assert_eq!(
        (c.differing, c.cracks),
        (0, 0),
        "{} pixels off edges differ (max {}/255): {:?}",
        c.differing,
        c.max_abs_err_off_edges,
        c.worst
    );
    // The real-time default draws the night as faithfully as the day.
    let off = |hour: f32, reference: &voxel_render::Image| {
        let quads = tests::render_with(&ctx, &scene, at_hour(hour, Technique::SortedQuads));
        tests::diff(&quads, reference)
    };
    let (by_day, by_night) = (off(12.0, &noon), off(0.0, &night));
    assert!(
        by_night.over_one <= by_day.over_one && by_night.max <= by_day.max.max(1),
        "sorted-quads against the reference: night {by_night:?}, day {by_day:?}"
    );
}

/// A floor of grass with a one-block step of stone-capped grass on its -x half, seen from
/// the +x side: the step's wall faces the camera, the lower terrace runs toward it.
fn terrace() -> Scene {
    let world = tests::box_world(&[
        ([-16, -2, -16], [16, -1, 16], STONE),
        ([-16, 0, -16], [16, 0, 16], GRASS),
        ([-16, 1, -16], [-1, 1, 16], GRASS),
    ]);
    tests::scene("terrace", world, [12.0, 6.0, 0.5], [-2.0, 0.0, 0.5])
}

/// The pixel a world point projects to.
fn pixel(camera: &Camera, size: (u32, u32), p: DVec3) -> (u32, u32) {
    tests::project(camera, size, p)
}

#[test]
fn a_one_block_step_differs_in_brightness_across_the_step() {
    let Some(ctx) = tests::gpu() else { return };
    let scene = terrace();
    let camera = scene.cameras[0];
    let size = (320, 180);
    // The centre of the lower terrace's top face at the foot of the step (block x = 0),
    // and of one three blocks away from it: both +y faces of grass, lit alike.
    let foot = pixel(&camera, size, DVec3::new(0.5, 1.0, 0.5));
    let open = pixel(&camera, size, DVec3::new(3.5, 1.0, 0.5));
    let green = |strength: f32| {
        let config = RendererConfig {
            width: size.0,
            height: size.1,
            flat_textures: true,
            ao_strength: strength,
            ..tests::technique_config(Technique::SortedQuads, size.0, size.1)
        };
        let img = tests::render_with(&ctx, &scene, config);
        (img.pixel(foot.0, foot.1)[1], img.pixel(open.0, open.1)[1])
    };
    let (foot_ao, open_ao) = green(1.0);
    // Halfway across the face at the foot the occlusion is (1 + 0.817) / 2 of the light:
    // about 15 levels of 8-bit green darker.
    assert!(
        foot_ao + 8 <= open_ao,
        "the foot of the step ({foot_ao}) must be darker than the open terrace ({open_ao})"
    );
    let (foot_flat, open_flat) = green(0.0);
    assert!(
        foot_flat.abs_diff(open_flat) <= 1,
        "without occlusion the two faces are lit alike ({foot_flat} and {open_flat})"
    );
    assert_eq!(open_flat, open_ao, "the open terrace has no occlusion");
}
