//! The third exact reference: the CPU ray march (no mesh, no rasteriser, no GPU) against the
//! A-buffer reference on the whole suite, and the terrain a player can read: a one-block
//! step of flat-coloured terrain differs in brightness across the step (ambient occlusion),
//! and does not with the occlusion turned off.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use std::path::Path;

use glam::DVec3;
use voxel_core::blocks::{GRASS, STONE};
use voxel_lab::eval::raymarch_check;
use voxel_lab::scene::{Scene, scene_files};
use voxel_render::{Camera, RendererConfig, Technique};

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
    let vp = camera.view_proj(f64::from(size.0) / f64::from(size.1));
    let rel = (p - camera.eye).as_vec3();
    let clip = vp * rel.extend(1.0);
    let ndc = clip.truncate() / clip.w;
    let x = (ndc.x + 1.0) / 2.0 * size.0 as f32;
    let y = (1.0 - ndc.y) / 2.0 * size.1 as f32;
    (x as u32, y as u32)
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
