//! After a device loss (here `Device::destroy`, what a driver reset looks like
//! to wgpu) every renderer call that returns a `Result` returns `Error::DeviceLost`, the
//! others do nothing (no panic through wgpu's default error handler), making a renderer
//! on the lost device is an error too, and a new renderer on a new device draws the same
//! picture as before the loss.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use voxel_render::{Error, NoGame, Renderer, Technique};

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
        r.render(&mut encoder, &target.view, &cam, &mut NoGame)
            .unwrap_err(),
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

/// Where in a frame the device is lost (a GPU reset can land anywhere, a game's code
/// included).
#[derive(Clone, Copy, Debug, PartialEq)]
enum When {
    Prepare,
    Opaque,
    /// In the technique's `n`-th pass that draws the game's translucent geometry.
    Translucent(usize),
    HdrOverlay,
    Overlay,
}

/// A game that draws nothing but declares every stage, and destroys the device at `when`.
struct Killer {
    ctx: voxel_render::GpuContext,
    when: When,
    contract: Option<u64>,
    translucent_calls: std::cell::Cell<usize>,
    killed: std::cell::Cell<bool>,
    objects: [voxel_render::TranslucentObject; 1],
}

impl Killer {
    fn kill(&self, now: When) {
        if now == self.when {
            self.ctx.device.destroy();
            self.killed.set(true);
        }
    }
}

impl voxel_render::GameStages for Killer {
    fn stages(&self) -> voxel_render::stages::Stages {
        voxel_render::stages::Stages {
            opaque: true,
            translucent: true,
            hdr_overlay: true,
            overlay: true,
        }
    }

    fn translucent_objects(&self) -> &[voxel_render::TranslucentObject] {
        &self.objects
    }

    fn translucent_contract_id(&self) -> Option<u64> {
        self.contract
    }

    fn prepare(&mut self, _: &voxel_render::GpuContext, _: &voxel_render::stages::GameFrame<'_>) {
        self.kill(When::Prepare);
    }

    fn opaque(&self, _: &mut wgpu::RenderPass<'_>, _: &voxel_render::stages::GameFrame<'_>) {
        self.kill(When::Opaque);
    }

    fn translucent(
        &self,
        _: &mut wgpu::RenderPass<'_>,
        _: &voxel_render::stages::GameFrame<'_>,
        _: usize,
        _: std::ops::Range<usize>,
    ) {
        let n = self.translucent_calls.get();
        self.translucent_calls.set(n + 1);
        self.kill(When::Translucent(n));
    }

    fn hdr_overlay(&self, _: &mut wgpu::RenderPass<'_>, _: &voxel_render::stages::GameFrame<'_>) {
        self.kill(When::HdrOverlay);
    }

    fn overlay(&self, _: &mut wgpu::RenderPass<'_>, _: &voxel_render::stages::GameFrame<'_>) {
        self.kill(When::Overlay);
    }
}

/// The device lost at each point of a frame (inside each game stage, in the first and a
/// later pass of the techniques with several, and right after a submit), for real-time
/// techniques and both exact references, under wgpu's default (panicking) error handler:
/// the frame and every later call that touches the GPU return `Error::DeviceLost`, the
/// calls without a result do nothing, and nothing panics.
#[test]
fn a_device_lost_at_any_point_of_a_frame_gives_errors_not_panics() {
    let scene = dense_sheets(3, 0.5);
    let cam = scene.cameras[0];
    let points = [
        When::Prepare,
        When::Opaque,
        When::Translucent(0),
        When::Translucent(2),
        When::HdrOverlay,
        When::Overlay,
    ];
    let mut cases = 0;
    for technique in [
        Technique::WboitMrt,
        Technique::SortedQuads,
        Technique::DepthPeeling,
        Technique::Reference,
        Technique::PeelReference,
    ] {
        for (i, when) in points.into_iter().chain([When::Prepare]).enumerate() {
            // The last case destroys the device between two frames instead.
            let between = i == points.len();
            let Some(ctx) = gpu() else { return };
            let what = format!(
                "{technique} at {when:?}{}",
                if between { " (between frames)" } else { "" }
            );
            let mut r = renderer_for(&ctx, &scene, technique_config(technique, 64, 48)).unwrap();
            let target = Offscreen::new(&ctx, 64, 48);
            // Some frames first, so that timings and counters are in flight.
            for _ in 0..3 {
                r.render_and_submit(&target.view, &cam).unwrap();
            }
            let contract = r.translucent_contract().unwrap().id;
            let mut game = Killer {
                ctx: ctx.clone(),
                when: if between {
                    When::Translucent(usize::MAX)
                } else {
                    when
                },
                contract: Some(contract),
                translucent_calls: std::cell::Cell::new(0),
                killed: std::cell::Cell::new(false),
                objects: [voxel_render::TranslucentObject::ball(
                    glam::DVec3::new(0.5, 0.5, 1.0),
                    0.5,
                )],
            };
            if between {
                ctx.device.destroy();
            }
            let result = r.renderer.render_and_submit(&target.view, &cam, &mut game);
            if !between && !game.killed.get() {
                // The technique draws the game in fewer passes: the device was not lost.
                assert!(
                    matches!(when, When::Translucent(n) if n > 0),
                    "{what}: never reached"
                );
                assert!(result.is_ok(), "{what}: {result:?}");
                continue;
            }
            lost(result.unwrap_err(), &what);
            cases += 1;
            // Every later call.
            lost(r.render_and_submit(&target.view, &cam).unwrap_err(), &what);
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            lost(
                r.renderer
                    .render(&mut encoder, &target.view, &cam, &mut game)
                    .unwrap_err(),
                &what,
            );
            drop(encoder);
            lost(r.prebuild_technique(Technique::Mboit).unwrap_err(), &what);
            lost(r.translucent_contract().unwrap_err(), &what);
            if let Err(e) = r.set_technique(Technique::Reference) {
                lost(e, &what);
            }
            lost(r.render_and_submit(&target.view, &cam).unwrap_err(), &what);
            if let Err(e) = r.set_technique(Technique::PeelReference) {
                lost(e, &what);
            }
            lost(r.render_and_submit(&target.view, &cam).unwrap_err(), &what);
            assert!(r.gpu_times().is_empty() || r.gpu_times_blocking().is_empty());
            lost(
                voxel_render::readback::read_texture(&ctx, &target.texture, 4).unwrap_err(),
                &what,
            );
            let e = target.read(&ctx).unwrap_err().to_string();
            assert!(e.contains("lost"), "{what}: {e}");
        }
    }
    assert!(cases >= 28, "{cases} cases");
}
