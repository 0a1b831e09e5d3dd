//! What a game pays at run time for three things it does, on this machine's
//! adapter, CPU milliseconds:
//!
//! - a lighting change (dusk): `Renderer::set_lighting` and the next frame, against what a
//!   game had to do without it: a new renderer with the lighting, every chunk meshed and
//!   uploaded again, and its first frame;
//! - a technique switch: the first frame after `set_technique`, which builds the
//!   technique's pipelines and targets, against the same switch to a technique built ahead
//!   with `prebuild_technique` (built at load time, not measured here);
//! - an output format the renderer has not drawn yet (BGRA after RGBA): the first frame
//!   builds its tonemap pipeline.
//!
//! The world is the generated terrain (seed 1) of every chunk column within VD chunks of
//! the origin, layers -2 to 3, seen from 40 blocks above the ground at 640×360; each
//! frame is waited for before the next. A "steady" frame is the median of 10 frames after
//! warm-up. Set `MESA_SHADER_CACHE_DISABLE=true` so that lavapipe compiles every pipeline
//! afresh. Prints a table; asserts nothing about time.
//! `MESA_SHADER_CACHE_DISABLE=true cargo bench -p voxel-lab --bench embed`.

use std::sync::Arc;
use std::time::Instant;
use voxel_lab::Result;

use glam::DVec3;
use rayon::prelude::*;
use voxel_core::{BlockRegistry, ChunkPos, TerrainConfig, TerrainGenerator, World};
use voxel_lab::headless::Offscreen;
use voxel_mesh::mesh_chunks;
use voxel_render::{
    Camera, GpuContext, Lighting, NoGame, Renderer, RendererConfig, Technique, readback, stages,
};

const W: u32 = 640;
const H: u32 = 360;

/// The terrain of the disc of radius `vd` chunks.
fn world(vd: i32) -> Result<(World, Vec<ChunkPos>)> {
    let generator = TerrainGenerator::new(TerrainConfig::default());
    let mut positions = Vec::new();
    for dx in -vd..=vd {
        for dz in -vd..=vd {
            if dx * dx + dz * dz <= vd * vd {
                positions.extend((-2..=3).map(|y| ChunkPos::new(dx, y, dz)));
            }
        }
    }
    let chunks: Vec<_> = positions
        .par_iter()
        .map(|&p| (p, generator.generate_chunk(p)))
        .collect();
    let mut world = World::new(Arc::new(BlockRegistry::default()));
    for (p, c) in chunks {
        world.insert_chunk(p, c)?;
    }
    Ok((world, positions))
}

/// A renderer of `world` with `config`, every chunk meshed and uploaded.
fn renderer(
    ctx: &GpuContext,
    world: &World,
    positions: &[ChunkPos],
    config: RendererConfig,
) -> Result<Renderer> {
    let mut r = Renderer::new(ctx, world.registry(), config)?;
    for (pos, meshes) in mesh_chunks(world, positions)? {
        r.upload_chunk(pos, &meshes)?;
    }
    Ok(r)
}

fn camera(vd: i32) -> Result<Camera> {
    let g = TerrainGenerator::new(TerrainConfig::default());
    let eye = DVec3::new(0.5, g.height_at(0, 0) as f64 + 40.0, 0.5);
    let far = f64::from(vd) * 32.0 * 1.5;
    Camera::from_yaw_pitch(eye, std::f64::consts::FRAC_PI_2, -0.25, 70.0, 0.1, far)
        .map_err(voxel_lab::Error::Render)
}

/// One frame into `target`, waited for; its CPU milliseconds (`FrameStats::cpu_ms`, the
/// recording, technique preparation and any pipeline built on the way).
fn frame(ctx: &GpuContext, r: &mut Renderer, target: &wgpu::TextureView, cam: &Camera) -> f64 {
    let stats = r
        .render_and_submit(target, cam, &mut NoGame)
        .expect("a frame");
    let _ = ctx.device.poll(wgpu::PollType::wait_indefinitely());
    stats.cpu_ms
}

fn steady(ctx: &GpuContext, r: &mut Renderer, target: &wgpu::TextureView, cam: &Camera) -> f64 {
    for _ in 0..3 {
        frame(ctx, r, target, cam);
    }
    let mut ms: Vec<f64> = (0..10).map(|_| frame(ctx, r, target, cam)).collect();
    ms.sort_by(f64::total_cmp);
    ms[ms.len() / 2]
}

fn config(technique: Technique) -> RendererConfig {
    let mut c = RendererConfig {
        width: W,
        height: H,
        ..RendererConfig::default()
    };
    c.oit.technique = technique;
    c
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let ctx = GpuContext::headless(wgpu::Backends::VULKAN)?;
    let target = Offscreen::new(&ctx, W, H);
    let dusk = Lighting::daytime(17.5);
    println!("adapter: {}\n", ctx.caps.adapter_name);

    println!("| lighting change | VD 8 ms | VD 16 ms |\n|---|---:|---:|");
    let mut rows = [[0.0; 2]; 4];
    for (k, vd) in [8, 16].into_iter().enumerate() {
        let (world, positions) = world(vd)?;
        let cam = camera(vd)?;
        let mut r = renderer(&ctx, &world, &positions, config(Technique::WboitMrt))?;
        rows[0][k] = steady(&ctx, &mut r, &target.view, &cam);
        let start = Instant::now();
        r.set_lighting(dusk)?;
        let set = start.elapsed().as_secs_f64() * 1e3;
        rows[1][k] = set + frame(&ctx, &mut r, &target.view, &cam);
        // Without a setter: a renderer built with the lighting, every chunk again.
        let start = Instant::now();
        let mut lit = config(Technique::WboitMrt);
        (lit.sun_dir, lit.ambient, lit.sky) = (dusk.sun_dir, dusk.ambient, dusk.sky);
        let mut fresh = renderer(&ctx, &world, &positions, lit)?;
        frame(&ctx, &mut fresh, &target.view, &cam);
        rows[2][k] = start.elapsed().as_secs_f64() * 1e3;
        rows[3][k] = positions.len() as f64;
    }
    for (name, row) in [
        "a steady frame",
        "set_lighting + the next frame",
        "a new renderer with the lighting: mesh, upload, first frame",
        "(chunks)",
    ]
    .iter()
    .zip(rows)
    {
        println!("| {name} | {:.2} | {:.2} |", row[0], row[1]);
    }

    let (world, positions) = world(8)?;
    let cam = camera(8)?;
    println!(
        "\n| switch to (VD 8) | first frame, built at the switch ms | first frame, built ahead ms | steady frame ms |\n|---|---:|---:|---:|"
    );
    for t in Technique::REAL_TIME
        .into_iter()
        .filter(|t| *t != Technique::OpaqueOnly)
    {
        // Cold: the technique is built in the first frame after the switch.
        let mut r = renderer(&ctx, &world, &positions, config(Technique::OpaqueOnly))?;
        steady(&ctx, &mut r, &target.view, &cam);
        r.set_technique(t)?;
        let cold = frame(&ctx, &mut r, &target.view, &cam);
        let settled = steady(&ctx, &mut r, &target.view, &cam);
        // Built ahead at load time.
        let mut r = renderer(&ctx, &world, &positions, config(Technique::OpaqueOnly))?;
        r.prebuild_technique(t)?;
        steady(&ctx, &mut r, &target.view, &cam);
        r.set_technique(t)?;
        let ahead = frame(&ctx, &mut r, &target.view, &cam);
        println!("| `{t}` | {cold:.2} | {ahead:.2} | {settled:.2} |");
    }

    let mut r = renderer(&ctx, &world, &positions, config(Technique::SortedQuads))?;
    let rgba = steady(&ctx, &mut r, &target.view, &cam);
    let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
    let bgra = stages::target(
        &ctx.device,
        "bgra_output",
        wgpu::TextureFormat::Bgra8UnormSrgb,
        usage,
        (W, H),
    );
    let first = frame(&ctx, &mut r, &bgra.view, &cam);
    let again = steady(&ctx, &mut r, &bgra.view, &cam);
    let img = readback::read_image(&ctx, &bgra.texture)?;
    println!(
        "\n| output format (VD 8, sorted-quads) | ms |\n|---|---:|\n| steady frame into Rgba8UnormSrgb | {rgba:.2} |\n| first frame into Bgra8UnormSrgb | {first:.2} |\n| steady frame into Bgra8UnormSrgb | {again:.2} |"
    );
    println!(
        "\n({}x{} read back from the BGRA target)",
        img.width, img.height
    );
    Ok(())
}
