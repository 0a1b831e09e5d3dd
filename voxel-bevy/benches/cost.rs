//! What the plugin costs over the crate's own `Renderer::render` on the same scene, camera
//! and device: the thread CPU time of a frame (median of runs), and the GPU work of one
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

fn median(mut v: Vec<Duration>) -> Duration {
    v.sort();
    v[v.len() / 2]
}

fn wait(ctx: &voxel_render::GpuContext) {
    ctx.device
        .poll(wgpu::PollType::wait_indefinitely())
        .unwrap();
}

fn bevy_frames(h: &mut Harness, frames: usize) -> Duration {
    let ctx = h.ctx();
    for _ in 0..5 {
        h.app.update();
        wait(&ctx);
    }
    let mut times = Vec::new();
    for _ in 0..frames {
        let t0 = thread_cpu();
        h.app.update();
        times.push(thread_cpu() - t0);
        wait(&ctx);
    }
    median(times)
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
        );
        h.app.insert_resource(VoxelContent(scene.content.clone()));
        h
    };
    let mut with = app(true);
    let mut without = app(false);
    with.frames(1);
    let ctx = with.ctx();
    let camera = with.camera();
    println!(
        "scene {name}, {}x{}, {frames} frames a median, {}",
        size.0, size.1, ctx.caps.adapter_name
    );
    println!(
        "| technique | Bevy + plugin (ms CPU) | Bevy alone | plugin | crate's render | plugin / crate | draws plugin / crate | fragments plugin / crate |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for t in [
        Technique::SortedQuads,
        Technique::Sorted,
        Technique::WboitMrt,
        Technique::DepthPeeling,
    ] {
        with.app.insert_resource(VoxelTechnique::Use(t));
        // Bevy alone next to each technique's frames: the machine's load drifts.
        let bevy_alone = bevy_frames(&mut without, frames);
        let with_plugin = bevy_frames(&mut with, frames);
        // The crate on its own: the same scene, camera, technique and device.
        let config = tests::technique_config(t, size.0, size.1);
        let mut renderer = Renderer::new(&ctx, scene.world.registry(), config).unwrap();
        let positions: Vec<_> = scene.world.iter().map(|(p, _)| p).collect();
        for (pos, meshes) in voxel_mesh::mesh_chunks(&scene.world, &positions).unwrap() {
            renderer.upload_chunk(pos, &meshes).unwrap();
        }
        let mut content = ContentStages::new(&renderer, scene.content.clone()).unwrap();
        let target = tests::Offscreen::new(&ctx, size.0, size.1);
        let mut own = Vec::new();
        let mut own_cost = None;
        for i in 0..frames + 6 {
            let counted = i == 4;
            if counted {
                count_next_frame(&mut renderer);
            }
            let t0 = thread_cpu();
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            renderer
                .render(&mut encoder, &target.view, &camera, &mut content)
                .unwrap();
            ctx.queue.submit([encoder.finish()]);
            let dt = thread_cpu() - t0;
            wait(&ctx);
            if counted {
                own_cost = frame_cost(&mut renderer).unwrap();
            } else if i > 5 {
                own.push(dt);
            }
        }
        let own = median(own);
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
        let own_cost = own_cost.unwrap();
        let (p, o) = (plugin_cost.all(), own_cost.all());
        let plugin = with_plugin.saturating_sub(bevy_alone);
        let ms = |d: Duration| d.as_secs_f64() * 1e3;
        let frag = |f: Option<u64>| f.map_or("-".into(), |f| f.to_string());
        println!(
            "| `{}` | {:.3} | {:.3} | {:.3} | {:.3} | {:.2} | {} / {} | {} / {} |",
            t.name(),
            ms(with_plugin),
            ms(bevy_alone),
            ms(plugin),
            ms(own),
            ms(plugin) / ms(own),
            p.draws,
            o.draws,
            frag(p.fragments),
            frag(o.fragments),
        );
    }
}
