//! A game loop with its own things in the world, composed with the crate's water and glass
//! by whatever transparency technique is in force: an opaque crate floating half in a pool,
//! a translucent cube turning through the water surface, and bubbles rising to it. The game
//! describes them (`voxel_render::content`: particles and boxes with colour and opacity)
//! and draws them through the frame's stages with `ContentStages`, which writes no WGSL of
//! the game's and follows a technique switch by itself. `examples/custom_stage.rs` draws
//! the same with the game's own shaders.
//!
//! Headless: `cargo run --release -p voxel-render --example entities -- --frames 60 --out
//! entities.png [--technique sorted-quads]`.

use glam::DQuat;
use voxel_render::content::{Content, ContentStages, Entity, Particle};

mod common;

/// The game's things at `t` seconds: the crate bobbing, the cube turning, the bubbles rising.
fn things(t: f64) -> Content {
    let crate_box = Entity {
        center: common::crate_center(t),
        half_extents: [1.0, 0.6, 1.0],
        rotation: DQuat::from_rotation_y(0.3),
        color: [160, 118, 75],
        opacity: 1.0,
        emissive: 0.0,
    };
    let (center, rotation) = common::cube_pose(t);
    let cube = Entity {
        center,
        half_extents: [1.2; 3],
        rotation,
        color: [89, 218, 137],
        opacity: 0.5,
        emissive: 0.0,
    };
    let bubble = |i: u64| {
        let (center, half_size) = common::bubble(i, t);
        Particle {
            center,
            half_size: half_size as f32,
            color: [237, 246, 255],
            opacity: 0.45,
            emissive: 0.0,
        }
    };
    Content {
        particles: (0..1000).map(bubble).collect(),
        entities: vec![crate_box, cube],
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = common::Args::parse("entities.png")?;
    let ctx = common::game_device()?;
    let (mut renderer, output, camera) = common::pool(&ctx, args.technique)?;
    // The game's things, drawn by every technique: opaque boxes with the world's opaque
    // geometry, the bubbles and the glass cube composed with water and glass.
    let mut game = ContentStages::new(&renderer, things(0.0))?;
    for frame in 0..args.frames {
        game.set_content(&ctx, things(f64::from(frame) / 30.0))?;
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        renderer.render(&mut encoder, &output.view, &camera, &mut game)?;
        ctx.queue.submit([encoder.finish()]);
    }
    common::save(
        &ctx,
        &output,
        &args,
        "with a crate, a glass cube and 1000 bubbles",
    )?;
    Ok(())
}
