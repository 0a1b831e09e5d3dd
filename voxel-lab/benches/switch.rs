//! What a game's technique switch costs once it prepared every technique at loading time:
//! the first frame after `set_technique` against a steady frame of the same technique, CPU
//! milliseconds of `Renderer::render` (`FrameStats::cpu_ms`), and the render
//! pipelines the renderer built in that frame (`low_level::pipelines_built`).
//!
//! The world is the record bench's generated terrain at view distance `SWITCH_VD` (default
//! 16), seen from 40 blocks above the ground at 640×360; the game draws 2 000 bubbles
//! over the water ahead and a translucent crate through the renderer's content stages
//! (`voxel_render::content`). At loading time every real-time technique is built
//! (`prebuild_technique`) and the game's pipelines for its contract
//! (`translucent_contract_for`, through `ContentStages::prebuild`). Then the game switches
//! through every real-time technique in turn. Each frame is waited for before the next.
//! Medians of 10 steady frames. Prints a table (and writes it to
//! `results/switch-bench.md`); asserts nothing about time.
//! `cargo bench -p voxel-lab --bench switch`.

use std::time::Instant;
use voxel_lab::Result;

use glam::{DQuat, DVec3};
use voxel_lab::headless::Offscreen;
use voxel_render::content::{Content, ContentStages, Entity, Particle};
use voxel_render::{Camera, GpuContext, Renderer, Technique, low_level};

#[path = "common/record_world.rs"]
mod record_world;
#[path = "common/report.rs"]
mod report;
use record_world::{H, W, camera, renderer};
use report::Report;

/// A frame of `technique`: its CPU ms, and the pipelines the renderer built in it.
fn frame(
    ctx: &GpuContext,
    r: &mut Renderer,
    game: &mut ContentStages,
    target: &Offscreen,
    cam: &Camera,
) -> Result<(f64, u64)> {
    let before = low_level::pipelines_built();
    let stats = r.render_and_submit(&target.view, cam, game)?;
    let _ = ctx.device.poll(wgpu::PollType::wait_indefinitely());
    Ok((stats.cpu_ms, low_level::pipelines_built() - before))
}

/// The game's things: bubbles rising ahead of the camera, and a glass crate.
fn content(cam: &Camera) -> Content {
    let mut next = report::numbers(0x2545_f491_4f6c_dd1d);
    let ahead = cam.eye + cam.unit_forward() * 30.0;
    Content {
        particles: (0..2000)
            .map(|_| Particle {
                center: ahead
                    + DVec3::new(next() - 0.5, next() - 0.5, next() - 0.5)
                        * DVec3::new(40.0, 30.0, 40.0),
                half_size: 0.12,
                color: [220, 235, 255],
                opacity: 0.4,
                emissive: 0.0,
            })
            .collect(),
        entities: vec![Entity {
            center: ahead,
            half_extents: [2.0, 2.0, 2.0],
            rotation: DQuat::from_rotation_y(0.6),
            color: [150, 220, 235],
            opacity: 0.45,
            emissive: 0.0,
        }],
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let vd: i32 = std::env::var("SWITCH_VD")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(16);
    let ctx = voxel_lab::headless::context()?;
    let target = Offscreen::new(&ctx, W, H);
    let cam = camera(vd)?;
    let first = Technique::REAL_TIME[0];
    let mut r = renderer(&ctx, vd, first)?;
    let mut game = ContentStages::new(&r, content(&cam))?;
    let start = Instant::now();
    for t in Technique::REAL_TIME {
        r.prebuild_technique(t)?;
        game.prebuild(&mut r, t)?;
    }
    let loading = start.elapsed().as_secs_f64() * 1e3;
    for _ in 0..3 {
        frame(&ctx, &mut r, &mut game, &target, &cam)?;
    }
    let chunks = voxel_render::low_level::chunks(&r).len();
    let detail = format!("; view distance {vd}, {chunks} chunks");
    let mut out = Report::new("switch", &ctx.caps.adapter_name, &detail);
    out.line(&format!(
        "Every real-time technique and the game's pipelines for it built at loading time: {loading:.0} ms.\n"
    ));
    out.line("| switch to | first frame CPU ms | pipelines built in it | steady frame CPU ms | first / steady |\n|---|---:|---:|---:|---:|");
    for t in Technique::REAL_TIME.into_iter().skip(1).chain([first]) {
        r.set_technique(t)?;
        let (ms, built) = frame(&ctx, &mut r, &mut game, &target, &cam)?;
        let mut steady: Vec<f64> = (0..10)
            .map(|_| frame(&ctx, &mut r, &mut game, &target, &cam).map(|f| f.0))
            .collect::<Result<_, _>>()?;
        steady.sort_by(f64::total_cmp);
        let median = steady[steady.len() / 2];
        out.line(&format!(
            "| `{t}` | {ms:.3} | {built} | {median:.3} | {:.2} |",
            ms / median
        ));
    }
    out.write("switch-bench.md")?;
    Ok(())
}
