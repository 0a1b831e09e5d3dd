//! CPU cost of `ContentStages::set_content` for a game's things (a lake's 2 000: bubbles,
//! fireflies, glass boxes and boats), beside the clone of the same `Content` the call takes
//! (what a game that keeps its own copy pays anyway) and `Content::validate` on its own, in
//! the same run. Medians of `ROUNDS` calls, each with new positions (the things move).
//! Prints a table (and writes it to `results/set-content.md`); asserts nothing about time.
//! `cargo bench -p voxel-lab --bench set_content` (`CONTENT_THINGS=2000,20000` chooses
//! rows).

use std::time::Instant;

use glam::{DQuat, DVec3};
use voxel_lab::headless;
use voxel_lab::scene::Scene;
use voxel_render::content::{Content, ContentStages, Entity, Particle};

#[path = "common/report.rs"]
mod report;
use report::{Report, list, median, numbers};

const ROUNDS: usize = 301;

/// `n` things: nine in ten particles (bubbles and fireflies), the rest boxes, one in
/// three of those opaque; moved by `t`.
fn things(n: usize, t: f64) -> Content {
    let mut next = numbers(7);
    let mut content = Content::default();
    for i in 0..n {
        let c = DVec3::new(next() * 60.0 - 30.0, next() * 20.0, next() * 60.0 - 30.0)
            + DVec3::new(t.sin(), t * 0.1, t.cos());
        if i % 10 != 0 {
            content.particles.push(Particle {
                center: c,
                half_size: 0.1,
                color: [220, 235, 255],
                opacity: 0.4,
                emissive: if i % 7 == 0 { 4.0 } else { 0.0 },
            });
        } else {
            content.entities.push(Entity {
                center: c,
                half_extents: [1.0, 0.5, 2.0],
                rotation: DQuat::from_rotation_y(t + i as f64),
                color: [40, 200, 90],
                opacity: if i % 30 == 0 { 1.0 } else { 0.5 },
                emissive: 0.0,
            });
        }
    }
    content
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let ctx = headless::context()?;
    let scene = Scene::new(
        "set_content",
        voxel_core::World::new(std::sync::Arc::new(voxel_core::BlockRegistry::default())),
        voxel_render::Camera::look_at(DVec3::new(0.0, 10.0, 40.0), DVec3::ZERO, 60.0, 0.1, 500.0)?,
    );
    let renderer = headless::renderer_for(
        &ctx,
        &scene,
        voxel_render::RendererConfig {
            width: 64,
            height: 64,
            ..Default::default()
        },
    )?;
    let mut out = Report::new("set_content", &ctx.caps.adapter_name, "");
    out.line(&format!(
        "Medians of {ROUNDS} calls, each with things moved.\n\n| things | set_content ms | Content::clone ms | validate ms | set_content / clone |\n|---:|---:|---:|---:|---:|"
    ));
    for n in list("CONTENT_THINGS", &[2_000, 20_000]) {
        let mut stages = ContentStages::new(&renderer, things(n, 0.0))?;
        let frames: Vec<Content> = (0..8).map(|k| things(n, f64::from(k))).collect();
        let (mut set, mut clone, mut validate) = (Vec::new(), Vec::new(), Vec::new());
        for round in 0..ROUNDS {
            let content = &frames[round % frames.len()];
            let start = Instant::now();
            let copy = std::hint::black_box(content.clone());
            clone.push(start.elapsed().as_secs_f64() * 1e3);
            let start = Instant::now();
            std::hint::black_box(&copy).validate()?;
            validate.push(start.elapsed().as_secs_f64() * 1e3);
            let start = Instant::now();
            stages.set_content(renderer.context(), copy)?;
            set.push(start.elapsed().as_secs_f64() * 1e3);
        }
        let (set, clone, validate) = (median(&mut set), median(&mut clone), median(&mut validate));
        out.line(&format!(
            "| {n} | {set:.4} | {clone:.4} | {validate:.4} | {:.2} |",
            set / clone
        ));
    }
    out.write("set-content.md")?;
    Ok(())
}
