//! A minimal game loop embedding the renderer: the game owns its device, world and camera;
//! the renderer draws into the game's own texture. Run with
//! `cargo run --release -p voxel-render --example embed` (writes `embed.png`).

use std::sync::Arc;

use glam::DVec3;
use voxel_core::{BlockRegistry, ChunkPos, TerrainConfig, TerrainGenerator, WorldPos, blocks};
use voxel_render::{Camera, GpuContext, NoGame, Renderer, RendererConfig, Technique, readback};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // The game's own GPU objects, on the backend `WGPU_BACKEND` names (else wgpu's choice),
    // without wgpu's indirect-call validation on GL (`instance_descriptor`).
    let instance = wgpu::Instance::new(voxel_render::instance_descriptor(
        wgpu::Backends::from_env().unwrap_or(wgpu::Backends::all()),
    ));
    let adapter = pollster::block_on(instance.request_adapter(&Default::default()))?;
    let (device, queue) = pollster::block_on(voxel_render::request_device(&adapter))?;
    let ctx = GpuContext::from_device(&adapter, device, queue);

    // The game's world: 8 x 2 x 8 chunks of generated terrain.
    let registry = Arc::new(BlockRegistry::default());
    let generator = TerrainGenerator::new(TerrainConfig::default());
    let mut world = generator.generate_world(
        registry.clone(),
        ChunkPos::new(-4, 0, -4),
        ChunkPos::new(3, 1, 3),
    )?;

    let (width, height) = (640, 360);
    let mut config = RendererConfig {
        width,
        height,
        ..RendererConfig::default()
    };
    config.oit.technique = Technique::WboitMrt;
    let mut renderer = Renderer::new(&ctx, &registry, config)?;
    let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
    let format = wgpu::TextureFormat::Rgba8UnormSrgb;
    let output =
        voxel_render::stages::target(&ctx.device, "game_output", format, usage, (width, height));

    for frame in 0..60u32 {
        // Game logic: a glass pillar grows in front of the camera.
        if frame % 10 == 0 {
            let y = generator.height_at(0, 0) as i32 + 1 + (frame / 10) as i32;
            world.set_block(WorldPos::new(0, y, 0), blocks::BLUE_GLASS)?;
        }
        // Remesh what changed (in parallel) and hand it to the renderer.
        for (pos, meshes) in voxel_mesh::mesh_dirty(&mut world)? {
            renderer.upload_chunk(pos, &meshes)?;
        }
        // The camera circles the origin.
        let a = f64::from(frame) * 0.02;
        let eye = DVec3::new(30.0 * a.cos(), 45.0, 30.0 * a.sin());
        let camera = Camera::look_at(eye, DVec3::new(0.0, 28.0, 0.0), 70.0, 0.1, 500.0)?;
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        let stats = renderer.render(&mut encoder, &output.view, &camera, &mut NoGame)?;
        ctx.queue.submit([encoder.finish()]);
        // Nothing to call after submitting: GPU timings (and depth peeling's layer
        // counts) are read back by themselves once the commands are submitted, and arrive
        // a frame or more later.
        if frame % 20 == 0 {
            println!(
                "frame {frame}: {:?} meshes drawn, GPU ms {:?}",
                stats.meshes_drawn,
                renderer.gpu_times()
            );
        }
    }
    let rgba = readback::read_texture(&ctx, &output.texture, 4)?;
    voxel_render::Image {
        width,
        height,
        rgba,
    }
    .save_png(std::path::Path::new("embed.png"))?;
    println!("wrote embed.png");
    Ok(())
}
