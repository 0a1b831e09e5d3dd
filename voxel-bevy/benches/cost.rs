//! What the plugin costs over the crate's own `Renderer::render` on the same scene, camera
//! and device: the thread CPU time of a frame (median of rounds), and the GPU work of one
//! frame by the crate's cost counters (draws, fragments).
//!
//! The plugin's CPU per frame is Bevy's frame with the plugin and a `VoxelCamera` less the
//! same app without the plugin (the same camera settings: Bevy alone), both measured as the
//! calling thread's CPU time of `App::update` (Bevy without its `multi_threaded` feature
//! runs every system, the render world's included, on that thread). The crate's own frame
//! is `render` + `finish` + `submit` of one encoder on Bevy's device. The GPU is waited for
//! after each frame, outside the timing.
//!
//! `cargo bench --workspace --bench cost [-- FRAMES]`

#![allow(unsafe_code)] // one libc call: the thread's CPU clock, which std does not offer
#![allow(clippy::unwrap_used)] // a bench: a failure is a failed run

#[path = "../tests/common/mod.rs"]
mod common;

use std::path::PathBuf;
use std::time::Duration;

use common::Harness;
use voxel_bevy::{VoxelContent, VoxelCountNextFrame, VoxelStatus, VoxelTechnique, VoxelWorld};
use voxel_lab::scene::Scene;
use voxel_render::content::ContentStages;
use voxel_render::low_level::{count_next_frame, frame_cost};
use voxel_render::{Renderer, Technique};

fn thread_cpu() -> Duration {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `t` is a valid timespec the call writes; the clock id is a constant.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) };
    assert_eq!(rc, 0, "clock_gettime(CLOCK_THREAD_CPUTIME_ID)");
    Duration::new(t.tv_sec as u64, t.tv_nsec as u32)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

fn wait(ctx: &voxel_render::GpuContext) {
    ctx.device
        .poll(wgpu::PollType::wait_indefinitely())
        .unwrap();
}

/// The thread CPU time of one `App::update`, the GPU waited for after it (untimed).
fn bevy_frame(h: &mut Harness, ctx: &voxel_render::GpuContext) -> Duration {
    let t0 = thread_cpu();
    h.app.update();
    let dt = thread_cpu() - t0;
    wait(ctx);
    dt
}

fn main() {
    if !common::have_gpu() {
        return;
    }
    let frames: usize = std::env::args()
        .filter_map(|a| a.parse().ok())
        .next()
        .unwrap_or(40);
    let name = "game_through_panes";
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("../scenes/{name}.toml"));
    let scene = Scene::load(&path).unwrap();
    let cam = scene.cameras[0];
    let size = (640, 360);
    let app = |plugin| {
        let mut h = Harness::with_plugin(
            VoxelWorld::from_world(scene.world.clone()),
            cam.eye,
            cam.forward,
            cam.fov_y_deg,
            cam.near,
            cam.far,
            size,
            false,
            plugin,
            wgpu::Backends::VULKAN,
        );
        h.app.insert_resource(VoxelContent(scene.content.clone()));
        h
    };
    let mut with = app(true);
    let mut without = app(false);
    with.frames(1);
    let ctx = with.ctx();
    // Bevy alone runs on its own device.
    let alone_ctx = without.ctx();
    let mut second = app(false);
    let second_ctx = second.ctx();
    let camera = with.camera();
    println!(
        "scene {name}, {}x{}, {frames} rounds a median, {}",
        size.0, size.1, ctx.caps.adapter_name
    );
    println!(
        "| technique | Bevy + plugin (ms CPU) | Bevy alone | plugin | zero (Bevy alone twice) | crate's render + submit | plugin / crate | crate's `render` alone | plugin / `render` | draws plugin / crate | fragments plugin / crate |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    for t in [
        Technique::SortedQuads,
        Technique::Sorted,
        Technique::WboitMrt,
        Technique::DepthPeeling,
    ] {
        with.app.insert_resource(VoxelTechnique::Use(t));
        // The crate on its own: the same scene, camera, technique and device.
        let config = tests::technique_config(t, size.0, size.1);
        let mut renderer = Renderer::new(&ctx, scene.world.registry(), config).unwrap();
        let positions: Vec<_> = scene.world.iter().map(|(p, _)| p).collect();
        for (pos, meshes) in voxel_mesh::mesh_chunks(&scene.world, &positions).unwrap() {
            renderer.upload_chunk(pos, &meshes).unwrap();
        }
        let mut content = ContentStages::new(&renderer, scene.content.clone()).unwrap();
        let target = tests::Offscreen::new(&ctx, size.0, size.1);
        // `render` alone, and with its encoder's `finish` and `submit`.
        let mut own_frame = |renderer: &mut Renderer| {
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            let t0 = thread_cpu();
            renderer
                .render(&mut encoder, &target.view, &camera, &mut content)
                .unwrap();
            let rendered = thread_cpu() - t0;
            ctx.queue.submit([encoder.finish()]);
            let dt = thread_cpu() - t0;
            wait(&ctx);
            (rendered, dt)
        };
        // The crate's frame, counted (after warm-up frames).
        for _ in 0..4 {
            own_frame(&mut renderer);
        }
        count_next_frame(&mut renderer);
        own_frame(&mut renderer);
        let own_cost = frame_cost(&mut renderer).unwrap().unwrap();
        for _ in 0..5 {
            bevy_frame(&mut without, &alone_ctx);
            bevy_frame(&mut with, &ctx);
            bevy_frame(&mut second, &second_ctx);
            own_frame(&mut renderer);
        }
        // Rounds of one frame each (Bevy alone, Bevy with the plugin, a second Bevy alone,
        // the crate alone), so that the machine's drifting load hits all alike, in turn
        // forwards and backwards (what runs right after another may find warmer caches);
        // the plugin's cost is the median of each round's difference, and the difference of
        // the two apps without the plugin is the measurement's own zero.
        let (mut alone, mut plugin_on, mut own, mut plugin) = (vec![], vec![], vec![], vec![]);
        let (mut render_only, mut zero) = (vec![], vec![]);
        for round in 0..frames {
            let (a, w, b);
            if round % 2 == 0 {
                a = bevy_frame(&mut without, &alone_ctx);
                w = bevy_frame(&mut with, &ctx);
                b = bevy_frame(&mut second, &second_ctx);
            } else {
                b = bevy_frame(&mut second, &second_ctx);
                w = bevy_frame(&mut with, &ctx);
                a = bevy_frame(&mut without, &alone_ctx);
            }
            let (r, o) = own_frame(&mut renderer);
            let [a, w, b, r, o] = [a, w, b, r, o].map(ms);
            render_only.push(r);
            own.push(o);
            alone.push(a);
            plugin_on.push(w);
            plugin.push(w - a);
            zero.push(b - a);
        }
        let [bevy_alone, with_plugin, own, render_only, plugin, zero] =
            [alone, plugin_on, own, render_only, plugin, zero].map(median);
        // The plugin's frame, counted.
        with.app.insert_resource(VoxelCountNextFrame(true));
        for _ in 0..3 {
            with.app.update();
            wait(&ctx);
        }
        let plugin_cost = with
            .app
            .world()
            .resource::<VoxelStatus>()
            .last_cost
            .clone()
            .unwrap();
        let (p, o) = (plugin_cost.all(), own_cost.all());
        let frag = |f: Option<u64>| f.map_or("-".into(), |f| f.to_string());
        println!(
            "| `{}` | {:.3} | {:.3} | {:.3} | {:+.3} | {:.3} | {:.2} | {:.3} | {:.2} | {} / {} | {} / {} |",
            t.name(),
            with_plugin,
            bevy_alone,
            plugin,
            zero,
            own,
            plugin / own,
            render_only,
            plugin / render_only,
            p.draws,
            o.draws,
            frag(p.fragments),
            frag(o.fragments),
        );
    }
}
