//! Issue 26: after a device loss (here `Device::destroy`, what a driver reset looks like
//! to wgpu) every renderer call that returns a `Result` returns `Error::DeviceLost`, the
//! others do nothing (no panic through wgpu's default error handler), making a renderer
//! on the lost device is an error too, and a new renderer on a new device draws the same
//! picture as before the loss.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use voxel_render::{Error, Renderer, Technique};

use tests::*;

fn lost(e: Error, call: &str) {
    assert!(matches!(e, Error::DeviceLost { .. }), "{call}: {e:?}");
    assert!(e.to_string().contains("lost"), "{call}: {e}");
}

#[test]
fn a_lost_device_gives_errors_and_a_new_device_works() {
    let Some(ctx) = gpu() else { return };
    let scene = dense_sheets(4, 0.5);
    let cam = scene.cameras[0];
    let config = technique_config(Technique::SortedQuads, 96, 64);
    let mut r = renderer_for(&ctx, &scene, config.clone()).unwrap();
    let before = frame(&ctx, &mut r, &cam);
    assert!(distinct_colours(&before) > 8);
    let target = Offscreen::new(&ctx, 96, 64);

    ctx.device.destroy();
    lost(
        r.render_and_submit(&target.view, &cam).unwrap_err(),
        "render",
    );
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    lost(
        r.render(&mut encoder, &target.view, &cam).unwrap_err(),
        "render",
    );
    r.after_submit();
    let (pos, meshes) = {
        let all: Vec<_> = scene.world.iter().map(|(p, _)| p).collect();
        voxel_mesh::mesh_chunks(&scene.world, &all)
            .unwrap()
            .remove(0)
    };
    lost(r.upload_chunk(pos, &meshes).unwrap_err(), "upload_chunk");
    lost(r.resize(128, 64).unwrap_err(), "resize");
    lost(r.set_msaa(true).unwrap_err(), "set_msaa");
    lost(r.set_ao_strength(0.5).unwrap_err(), "set_ao_strength");
    let oit = r.config().oit.clone();
    lost(r.set_oit_config(oit).unwrap_err(), "set_oit_config");
    lost(
        r.set_technique(Technique::WboitMrt).unwrap_err(),
        "set_technique",
    );
    lost(
        r.translucent_contract().unwrap_err(),
        "translucent_contract",
    );
    // The calls without a result do nothing harmful.
    r.remove_chunk(pos);
    r.clear_chunks();
    r.set_weight(voxel_render::WeightFunction::McGuire8);
    r.set_fade_in_frames(4);
    assert!(r.gpu_times_blocking().is_empty());
    let _ = r.gpu_times();
    lost(
        voxel_render::readback::read_texture(&ctx, &target.texture, 4).unwrap_err(),
        "read_texture",
    );
    lost(
        Renderer::new(&ctx, scene.world.registry(), config.clone()).unwrap_err(),
        "Renderer::new",
    );
    drop(r);

    let fresh = gpu().unwrap();
    let mut r = renderer_for(&fresh, &scene, config).unwrap();
    let after = frame(&fresh, &mut r, &cam);
    assert_close("device_lost_new_device", &after, &before, 0);
}
