//! What the light volume (`Renderer::set_light_volume`, `docs/light.md`, "Light for a
//! game's things") costs, on this machine's adapter:
//!
//! - reading chunks into it: `set_light_volume` over 4 × 4 × 4 chunks of lit terrain, and
//!   `update_light_volume` of one chunk (what an edit or a streamed chunk costs), against
//!   the peer in the same run, `update_sun_shadows` of the same chunk (a byte a block where
//!   the light volume writes 8);
//! - drawing a game's things lit by it: a frame with 2 000 particles and 200 boxes
//!   (`ContentStages`), with the volume and without, interleaved.
//!
//! Each figure is the median of several runs, each CPU work waited for on the GPU. Prints a
//! table; asserts nothing about time. `cargo bench -p voxel-lab --bench light_volume`.

use std::sync::Arc;
use std::time::Instant;

use glam::{DQuat, DVec3};
use voxel_core::{
    BlockRegistry, ChunkPos, LightField, TerrainConfig, TerrainGenerator, World, WorldPos,
};
use voxel_lab::headless::Offscreen;
use voxel_render::content::{Content, ContentStages, Entity};
use voxel_render::{
    Camera, GpuContext, MAX_LIGHT_CHUNKS, Renderer, RendererConfig, SunRegion, Technique,
};

const W: u32 = 640;
const H: u32 = 360;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn wait(ctx: &GpuContext) {
    ctx.queue.submit([]);
    let _ = ctx.device.poll(wgpu::PollType::wait_indefinitely());
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let ctx = GpuContext::headless(wgpu::Backends::VULKAN)?;
    println!("adapter: {}\n", ctx.caps.adapter_name);
    let generator = TerrainGenerator::new(TerrainConfig::default());
    let mut world = World::new(Arc::new(BlockRegistry::default()));
    for x in -3..=3 {
        for z in -3..=3 {
            for y in -2..=3 {
                let p = ChunkPos::new(x, y, z);
                world.insert_chunk(p, generator.generate_chunk(p))?;
            }
        }
    }
    let field = LightField::new(&world);
    let light = |p| field.shared(p);
    let ground = i32::try_from(generator.height_at(0, 0))?;
    let at = WorldPos::new(0, ground, 0);
    let region = SunRegion::around_at_most(&world, at, MAX_LIGHT_CHUNKS).ok_or("no region")?;
    let sun_region = SunRegion::around(&world, at).ok_or("no region")?;
    let config = RendererConfig {
        width: W,
        height: H,
        ..RendererConfig::default()
    };
    let mut r = Renderer::new(&ctx, world.registry(), config.clone())?;
    for (pos, m) in voxel_mesh::mesh_world(&world, Some(&field))? {
        r.upload_chunk(pos, &m)?;
    }
    r.set_sun_shadows(&world, sun_region)?;

    // Reading.
    let set_ms = median(
        (0..5)
            .map(|_| {
                let start = Instant::now();
                r.set_light_volume(&world, &light, region)
                    .expect("a region");
                wait(&ctx);
                start.elapsed().as_secs_f64() * 1e3
            })
            .collect(),
    );
    let chunks: Vec<ChunkPos> = region.positions().collect();
    let (mut light_us, mut sun_us) = (Vec::new(), Vec::new());
    for _ in 0..3 {
        for &p in &chunks {
            let start = Instant::now();
            r.update_light_volume(&world, &light, &[p]);
            wait(&ctx);
            light_us.push(start.elapsed().as_secs_f64() * 1e6);
            let start = Instant::now();
            r.update_sun_shadows(&world, &[p]);
            wait(&ctx);
            sun_us.push(start.elapsed().as_secs_f64() * 1e6);
        }
    }
    let (light_us, sun_us) = (median(light_us), median(sun_us));
    println!("| reading | ms or µs |\n|---|---:|");
    println!(
        "| set_light_volume, {} chunks (16 MiB) | {set_ms:.1} ms |",
        chunks.len()
    );
    println!("| update_light_volume, one chunk | {light_us:.0} µs |");
    println!("| update_sun_shadows, the same chunk (peer) | {sun_us:.0} µs |");
    println!("| ratio light / sun | {:.2}× |\n", light_us / sun_us);

    // Drawing.
    let eye = DVec3::new(0.5, f64::from(ground) + 12.0, 0.5);
    let camera = Camera::from_yaw_pitch(eye, 0.0, -0.35, 70.0, 0.1, 300.0)?;
    let mut content = Content {
        particles: Content::scatter(
            eye + DVec3::new(-30.0, -12.0, -60.0),
            eye + DVec3::new(30.0, 4.0, -5.0),
            2000,
            7,
            0.2,
            [240, 240, 255],
            0.6,
        ),
        entities: Vec::new(),
    };
    for i in 0..200 {
        let f = f64::from(i);
        content.entities.push(Entity {
            center: eye
                + DVec3::new(
                    (f * 7.3) % 50.0 - 25.0,
                    -10.0 + (f % 5.0),
                    -8.0 - (f * 3.1) % 50.0,
                ),
            half_extents: [0.4; 3],
            rotation: DQuat::from_rotation_y(f),
            color: [200, 150, 100],
            opacity: if i % 2 == 0 { 1.0 } else { 0.5 },
            emissive: 0.0,
        });
    }
    let target = Offscreen::new(&ctx, W, H);
    println!(
        "| frame with 2 000 particles and 200 boxes | without the volume ms | with ms | ratio |\n|---|---:|---:|---:|"
    );
    for technique in [Technique::WboitMrt, Technique::SortedQuads] {
        r.set_technique(technique)?;
        let mut game = ContentStages::new(&r, content.clone())?;
        let mut frame = |r: &mut Renderer| {
            let start = Instant::now();
            r.render_and_submit(&target.view, &camera, &mut game)
                .expect("a frame");
            let _ = ctx.device.poll(wgpu::PollType::wait_indefinitely());
            start.elapsed().as_secs_f64() * 1e3
        };
        for _ in 0..3 {
            frame(&mut r);
        }
        let (mut off, mut on) = (Vec::new(), Vec::new());
        for _ in 0..9 {
            r.clear_light_volume();
            wait(&ctx);
            off.push(frame(&mut r));
            r.set_light_volume(&world, &light, region)?;
            wait(&ctx);
            on.push(frame(&mut r));
        }
        let (off, on) = (median(off), median(on));
        println!(
            "| {} | {off:.1} | {on:.1} | {:.2}× |",
            technique.name(),
            on / off
        );
    }
    Ok(())
}
