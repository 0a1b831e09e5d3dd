//! A headless Bevy app with `VoxelPlugin` draws suite scenes as the crate draws them on its
//! own (same device, same camera), with every real-time technique, LDR and HDR; a
//! technique that cannot run in Bevy's frame is reported, not a panic.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

mod common;

use std::path::PathBuf;

use common::{Harness, have_gpu, save, share_over_one};
use voxel_bevy::{VoxelContent, VoxelMessage, VoxelStatus, VoxelTechnique, VoxelWorld};
use voxel_lab::scene::Scene;
use voxel_render::{Image, Technique};

fn scene(name: &str) -> Scene {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../scenes")
        .join(format!("{name}.toml"));
    Scene::load(&path).unwrap()
}

/// Renders `name` through Bevy with every real-time technique and compares each picture with
/// the crate's own render of the plugin's camera on Bevy's device (a lit scene lit on both
/// sides, with sun shadows).
fn matches_the_crate(name: &str, hdr: bool) {
    let s = scene(name);
    let cam = s.cameras[0];
    let size = (160, 120);
    let world = VoxelWorld::from_world(s.world.clone());
    let mut h = Harness::new(
        if s.light { world.with_light() } else { world },
        cam.eye,
        cam.forward,
        cam.fov_y_deg,
        cam.near,
        cam.far,
        size,
        hdr,
    );
    h.app.insert_resource(VoxelContent(s.content.clone()));
    h.frames(1);
    let ctx = h.ctx();
    let camera = h.camera();
    let mut reference_scene = Scene::new(name, s.world.clone(), camera);
    reference_scene.content = s.content.clone();
    reference_scene.light = s.light;
    for t in Technique::REAL_TIME {
        h.app.insert_resource(VoxelTechnique::Use(t));
        let bevy = h.frames(2);
        let drawing = h.app.world().resource::<VoxelStatus>().drawing.unwrap();
        let reference = tests::render(&ctx, &reference_scene, drawing, size.0, size.1);
        let tag = format!("{name}-{}{}", t.name(), if hdr { "-hdr" } else { "" });
        assert_same_picture(&tag, &bevy, &reference);
    }
}

/// Saves Bevy's picture and the crate's under `tag` and checks that at most 0.1 % of the
/// pixels differ by more than 1/255, and that Bevy's is not flat.
fn assert_same_picture(tag: &str, bevy: &Image, reference: &Image) {
    save(tag, bevy, reference);
    let share = share_over_one(bevy, reference);
    eprintln!("{tag}: {:.4} % of pixels over 1/255", share * 100.0);
    assert!(
        share <= 0.001,
        "{tag}: {:.3} % of the pixels differ by more than 1/255 ({:?})",
        share * 100.0,
        tests::diff(bevy, reference)
    );
    assert!(tests::distinct_colours(bevy) > 20, "{tag}: a flat picture");
}

/// The cathedral window (`light = true`): light through stained glass, a torch behind blue
/// glass, the sun's coloured patches on the floor (`VoxelWorld::with_light`).
#[test]
fn a_lit_scene_matches_the_crate_with_its_light_and_sun_shadows() {
    if !have_gpu() {
        return;
    }
    matches_the_crate("light/cathedral", false);
}

#[test]
fn water_through_glass_matches_the_crate_with_every_technique() {
    if have_gpu() {
        matches_the_crate("water_through_glass", false);
    }
}

#[test]
fn under_water_matches_the_crate_with_every_technique_hdr() {
    if have_gpu() {
        matches_the_crate("under_water", true);
    }
}

#[test]
fn game_through_panes_with_content_matches_the_crate_with_every_technique() {
    if have_gpu() {
        matches_the_crate("game_through_panes", false);
    }
}

#[test]
fn a_technique_that_stalls_is_reported_and_the_previous_one_draws_on() {
    if !have_gpu() {
        return;
    }
    let s = scene("water_through_glass");
    let cam = s.cameras[0];
    let mut h = Harness::new(
        VoxelWorld::from_world(s.world.clone()),
        cam.eye,
        cam.forward,
        cam.fov_y_deg,
        cam.near,
        cam.far,
        (96, 64),
        false,
    );
    h.app
        .insert_resource(VoxelTechnique::Use(Technique::Sorted));
    let before = h.frames(2);
    assert!(h.messages().iter().any(|m| matches!(
        m,
        VoxelMessage::TechniqueChanged {
            drawing: Technique::Sorted,
            ..
        }
    )));
    h.app
        .insert_resource(VoxelTechnique::Use(Technique::Reference));
    let after = h.frames(2);
    let messages = h.messages();
    assert!(
        messages.iter().any(
            |m| matches!(m, VoxelMessage::Unsupported { reason, .. } if reason.contains("waits"))
        ),
        "{messages:?}"
    );
    assert_eq!(
        h.app.world().resource::<VoxelStatus>().drawing,
        Some(Technique::Sorted)
    );
    assert_eq!(tests::diff(&before, &after).max, 0);
}

/// A streamed world with light (`VoxelWorld::streamed(..).with_light()`): the cathedral's
/// blocks streamed around the camera and lit as they stream, drawn through Bevy as the
/// crate draws the same lit streamer on its own (same device, same camera, once both are
/// idle).
#[test]
fn a_lit_streamed_world_matches_the_crate() {
    if !have_gpu() {
        return;
    }
    use std::sync::Arc;
    use voxel_render::{ChunkStreamer, Renderer, StreamConfig};
    let s = scene("light/cathedral");
    let cam = s.cameras[0];
    let size = (160, 120);
    let config = StreamConfig {
        view_distance: 4,
        vertical_distance: 2,
        ..StreamConfig::default()
    };
    let registry = s.world.registry().clone();
    let world = VoxelWorld::streamed(registry.clone(), s.world.clone(), config)
        .unwrap()
        .with_light();
    let mut h = Harness::new(
        world,
        cam.eye,
        cam.forward,
        cam.fov_y_deg,
        cam.near,
        cam.far,
        size,
        false,
    );
    h.app
        .insert_resource(VoxelTechnique::Use(Technique::SortedQuads));
    let idle = |h: &mut Harness| {
        let mut w = h.app.world_mut().resource_mut::<VoxelWorld>();
        let s = w.streamer().unwrap();
        assert!(s.has_light());
        s.is_idle()
    };
    let mut frames = 0;
    while !idle(&mut h) {
        h.frames(1);
        std::thread::sleep(std::time::Duration::from_millis(2));
        frames += 1;
        assert!(frames < 5_000, "the streamed world never idle");
    }
    let bevy = h.frames(2);
    let ctx = h.ctx();
    let camera = h.camera();
    let mut r = Renderer::new(
        &ctx,
        &registry,
        tests::technique_config(Technique::SortedQuads, size.0, size.1),
    )
    .unwrap();
    let mut streamer = ChunkStreamer::new(Arc::clone(&registry), s.world.clone(), config)
        .unwrap()
        .with_light();
    while !streamer.is_idle() {
        streamer.update(cam.eye, &mut r).unwrap();
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    let reference = tests::frame(&ctx, &mut r, &camera);
    assert_same_picture("cathedral-streamed-lit", &bevy, &reference);
}
