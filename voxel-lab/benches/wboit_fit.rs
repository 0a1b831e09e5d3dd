//! CPU cost of the fitted WBOIT weight (`oit::wboit::fit`, run in the technique's
//! `prepare`) on the record bench's worlds (`record.rs`: generated terrain within VD chunks,
//! the camera 40 blocks above the ground): per frame, `wboit-mrt` with the fitted weight
//! against the same renderer with the flat weight (no fit), frames alternating between the
//! two. Reports the median of the technique's `prepare_ms` and of `Renderer::render`'s CPU
//! ms. Prints figures; asserts nothing about time.
//! `cargo bench -p voxel-lab --bench wboit_fit` (FIT_VD=8,32 picks view distances).

use std::sync::Arc;

use glam::DVec3;
use rayon::prelude::*;
use voxel_core::{BlockRegistry, ChunkPos, TerrainConfig, TerrainGenerator, World};
use voxel_lab::eval::oit_config;
use voxel_lab::headless::{self, Offscreen};
use voxel_mesh::mesh_chunks;
use voxel_render::{Camera, GpuContext, Renderer, RendererConfig, Technique, WeightFunction};

const WARMUP: usize = 4;
const FRAMES: usize = 40;
const SEED: u32 = 1;
const W: u32 = 640;
const H: u32 = 360;
/// The record bench's chunk layers (the ground lies in 0 and 1).
const LAYERS: std::ops::RangeInclusive<i32> = -2..=3;

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The terrain of the disc of radius `vd` chunks in a `wboit-mrt` renderer.
fn renderer(ctx: &GpuContext, vd: i32) -> Result<Renderer, String> {
    let registry = Arc::new(BlockRegistry::default());
    let generator = TerrainGenerator::new(TerrainConfig {
        seed: SEED,
        ..TerrainConfig::default()
    });
    let mut positions = Vec::new();
    for dx in -vd..=vd {
        for dz in -vd..=vd {
            if dx * dx + dz * dz <= vd * vd {
                positions.extend(LAYERS.map(|y| ChunkPos::new(dx, y, dz)));
            }
        }
    }
    let chunks: Vec<_> = positions
        .par_iter()
        .map(|&p| (p, generator.generate_chunk(p)))
        .collect();
    let mut world = World::new(registry.clone());
    for (p, c) in chunks {
        world.insert_chunk(p, c).map_err(|e| e.to_string())?;
    }
    let mut config = RendererConfig {
        width: W,
        height: H,
        ..RendererConfig::default()
    };
    config.oit.technique = Technique::WboitMrt;
    let mut renderer = Renderer::new(ctx, &registry, config).map_err(|e| voxel_lab::chain(&e))?;
    for (pos, meshes) in mesh_chunks(&world, &positions).map_err(|e| e.to_string())? {
        renderer
            .upload_chunk(pos, &meshes)
            .map_err(|e| voxel_lab::chain(&e))?;
    }
    Ok(renderer)
}

/// The record bench's camera.
fn camera(vd: i32) -> Result<Camera, String> {
    let generator = TerrainGenerator::new(TerrainConfig {
        seed: SEED,
        ..TerrainConfig::default()
    });
    let eye = DVec3::new(0.5, generator.height_at(0, 0) as f64 + 40.0, 0.5);
    let pitch: f64 = -0.25;
    let dir = DVec3::new(pitch.cos(), pitch.sin(), 0.0);
    Camera::look_at(eye, eye + dir, 70.0, 0.1, f64::from(vd) * 32.0 * 1.5)
        .map_err(|e| voxel_lab::chain(&e))
}

fn main() -> Result<(), String> {
    let ctx = headless::context()?;
    let vds: Vec<i32> = std::env::var("FIT_VD")
        .ok()
        .map(|v| v.split(',').filter_map(|x| x.trim().parse().ok()).collect())
        .unwrap_or_else(|| vec![8, 16, 32]);
    println!(
        "# Fitted WBOIT weight, CPU (cargo bench -p voxel-lab --bench wboit_fit)\n\n\
         {} at {W}x{H}, the record bench's worlds and camera; `wboit-mrt`, frames alternating \
         between the fitted and the flat weight; median of {FRAMES} frames each after {WARMUP} \
         warm-up frames. prepare = the technique's CPU work before recording (the fit, the \
         uniform's upload); render = `Renderer::render`.\n",
        ctx.caps.adapter_name
    );
    println!(
        "| VD | translucent meshes | prepare fitted ms | prepare flat ms | fit ms (difference) | render fitted ms | render flat ms |"
    );
    println!("|---:|---:|---:|---:|---:|---:|---:|");
    for vd in vds {
        let mut renderer = renderer(&ctx, vd)?;
        let target = Offscreen::new(&ctx, W, H);
        let camera = camera(vd)?;
        let weights = [WeightFunction::Fitted, WeightFunction::Flat];
        let mut prepare: [Vec<f64>; 2] = Default::default();
        let mut render: [Vec<f64>; 2] = Default::default();
        let mut meshes = 0;
        for i in 0..WARMUP + FRAMES {
            let order = if i % 2 == 0 { [0, 1] } else { [1, 0] };
            for m in order {
                renderer
                    .set_oit_config(oit_config(Technique::WboitMrt, weights[m]))
                    .map_err(|e| voxel_lab::chain(&e))?;
                let mut encoder = ctx
                    .device
                    .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
                let s = renderer
                    .render(&mut encoder, &target.view, &camera)
                    .map_err(|e| voxel_lab::chain(&e))?;
                ctx.queue.submit([encoder.finish()]);
                ctx.device
                    .poll(wgpu::PollType::wait_indefinitely())
                    .map_err(|e| e.to_string())?;
                if i >= WARMUP {
                    prepare[m].push(s.technique.prepare_ms);
                    render[m].push(s.cpu_ms);
                }
                meshes = s.meshes_drawn[2];
            }
        }
        let [pf, pl] = prepare.each_mut().map(|v| median(v));
        let [rf, rl] = render.each_mut().map(|v| median(v));
        println!(
            "| {vd} | {meshes} | {pf:.3} | {pl:.3} | {:.3} | {rf:.3} | {rl:.3} |",
            pf - pl
        );
    }
    Ok(())
}
