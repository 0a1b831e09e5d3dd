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

use std::sync::Arc;

use glam::{DQuat, DVec3};
use voxel_core::{BlockRegistry, World, WorldPos, blocks};
use voxel_render::content::{Content, ContentStages, Entity, Particle};
use voxel_render::{Camera, GpuContext, Renderer, RendererConfig, Technique};

/// The game's things at `t` seconds: the crate bobbing, the cube turning, the bubbles rising.
fn things(t: f64) -> Content {
    let crate_box = Entity {
        center: DVec3::new(-3.0, 0.1 + 0.08 * (t * 1.7).sin(), 1.0),
        half_extents: [1.0, 0.6, 1.0],
        rotation: DQuat::from_rotation_y(0.3),
        color: [160, 118, 75],
        opacity: 1.0,
        emissive: 0.0,
    };
    let cube = Entity {
        center: DVec3::new(2.5, 0.2 * (t * 0.9).sin(), -1.0),
        half_extents: [1.2; 3],
        rotation: DQuat::from_euler(glam::EulerRot::YXZ, t * 0.7, 0.6, 0.2),
        color: [89, 218, 137],
        opacity: 0.5,
        emissive: 0.0,
    };
    let bubble = |i: u64| {
        let h = |k: u64| hash(i << 8 | k);
        let rise = (h(1) * 6.0 + t * (0.5 + h(2))).rem_euclid(6.0);
        Particle {
            center: DVec3::new(h(3) * 10.0 - 5.0, rise - 6.0, h(4) * 8.0 - 4.0),
            half_size: (0.08 + 0.1 * h(5)) as f32,
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

/// A fixed scatter for the bubbles: `x` hashed to [0, 1].
fn hash(x: u64) -> f64 {
    let mut z = x.wrapping_mul(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    (z ^ (z >> 31)) as f64 / u64::MAX as f64
}

/// A pool of water on sand, walled with stone, a glass wall across one end.
fn pool_world() -> Result<World, voxel_core::Error> {
    let mut world = World::new(Arc::new(BlockRegistry::default()));
    let fill = |w: &mut World, a: [i32; 3], b: [i32; 3], id| {
        w.fill_box(
            WorldPos::new(a[0], a[1], a[2]),
            WorldPos::new(b[0], b[1], b[2]),
            id,
        )
    };
    fill(&mut world, [-10, -8, -10], [10, -8, 10], blocks::SAND)?;
    fill(&mut world, [-11, -8, -11], [11, 0, -11], blocks::STONE)?;
    fill(&mut world, [-11, -8, -11], [-11, 0, 11], blocks::STONE)?;
    fill(&mut world, [11, -8, -11], [11, 0, 11], blocks::STONE)?;
    fill(&mut world, [-10, -7, -10], [10, -1, 10], blocks::WATER)?;
    fill(&mut world, [-10, 0, -10], [10, 3, -10], blocks::GLASS)?;
    Ok(world)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let arg = |name: &str| {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1).cloned())
    };
    let frames: u32 = arg("--frames").map_or(Ok(60), |v| v.parse())?;
    let out = arg("--out").unwrap_or_else(|| "custom_stage.png".into());
    let technique = match arg("--technique") {
        Some(name) => Technique::from_name(&name)?,
        None => Technique::WboitMrt,
    };

    // The game's own GPU objects.
    let instance = wgpu::Instance::new(voxel_render::instance_descriptor(wgpu::Backends::all()));
    let adapter = pollster::block_on(instance.request_adapter(&Default::default()))?;
    let (device, queue) = pollster::block_on(voxel_render::request_device(&adapter))?;
    let ctx = GpuContext::from_device(&adapter, device, queue);

    let mut world = pool_world()?;
    let (width, height) = (640, 360);
    let mut config = RendererConfig {
        width,
        height,
        ..RendererConfig::default()
    };
    config.oit.technique = technique;
    let mut renderer = Renderer::new(&ctx, world.registry(), config)?;
    for (pos, meshes) in voxel_mesh::mesh_dirty(&mut world)? {
        renderer.upload_chunk(pos, &meshes)?;
    }
    let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
    let output = voxel_render::stages::target(
        &ctx.device,
        "game_output",
        wgpu::TextureFormat::Rgba8UnormSrgb,
        usage,
        (width, height),
    );
    let camera = Camera::look_at(
        DVec3::new(1.0, 7.0, 17.0),
        DVec3::new(0.0, -2.0, -2.0),
        70.0,
        0.1,
        300.0,
    )?;
    // The game's things, drawn by every technique: opaque boxes with the world's opaque
    // geometry, the bubbles and the glass cube composed with water and glass.
    let mut game = ContentStages::new(&renderer, things(0.0))?;
    for frame in 0..frames.max(1) {
        game.set_content(&ctx, things(f64::from(frame) / 30.0))?;
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        renderer.render(&mut encoder, &output.view, &camera, &mut game)?;
        ctx.queue.submit([encoder.finish()]);
    }
    let rgba = voxel_render::readback::read_texture(&ctx, &output.texture, 4)?;
    voxel_render::Image {
        width,
        height,
        rgba,
    }
    .save_png(std::path::Path::new(&out))?;
    println!(
        "wrote {out}: {frames} frames of {} with a crate, a glass cube and 1000 bubbles",
        technique.name()
    );
    Ok(())
}
