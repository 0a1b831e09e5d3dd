//! Baseline for the frame-recording bench: the renderer before the quad arena (one buffer,
//! bind group and draw per chunk mesh), on the same worlds and camera as
//! voxel-lab/benches/record.rs of the new code. Prints render ms and render + finish ms.
use std::sync::Arc;
use std::time::Instant;

use demo::headless::{self, Offscreen};
use glam::DVec3;
use rayon::prelude::*;
use voxel_core::{BlockRegistry, ChunkPos, TerrainConfig, TerrainGenerator, World};
use voxel_mesh::mesh_chunks;
use voxel_render::{Camera, Renderer, RendererConfig};

fn pct(v: &[f64], p: f64) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * p).round() as usize]
}

fn main() {
    let ctx = headless::context().unwrap();
    let frames: usize = std::env::var("RECORD_FRAMES").ok().and_then(|v| v.parse().ok()).unwrap_or(40);
    println!("old renderer (4b354a8), {}", ctx.caps.adapter_name);
    println!("| VD | chunks | meshes | render ms p50 (p95) | +finish p50 (p95) |");
    for vd in [8i32, 16, 24, 32] {
        let registry = Arc::new(BlockRegistry::default());
        let generator = TerrainGenerator::new(TerrainConfig { seed: 1, ..TerrainConfig::default() });
        let mut positions = Vec::new();
        for dx in -vd..=vd {
            for dz in -vd..=vd {
                if dx * dx + dz * dz <= vd * vd {
                    positions.extend((-2..=3).map(|y| ChunkPos::new(dx, y, dz)));
                }
            }
        }
        let chunks: Vec<_> = positions.par_iter().map(|&p| (p, generator.generate_chunk(p))).collect();
        let mut world = World::new(registry.clone());
        for (p, c) in chunks {
            world.insert_chunk(p, c).unwrap();
        }
        let config = RendererConfig { width: 640, height: 360, ..RendererConfig::default() };
        let mut renderer = Renderer::new(&ctx, &registry, config).unwrap();
        for (pos, meshes) in mesh_chunks(&world, &positions).unwrap() {
            renderer.upload_chunk(pos, &meshes);
        }
        let target = Offscreen::new(&ctx, 640, 360);
        let eye = DVec3::new(0.5, generator.height_at(0, 0) as f64 + 40.0, 0.5);
        let pitch: f64 = -0.25;
        let dir = DVec3::new(pitch.cos(), pitch.sin(), 0.0);
        let camera = Camera::look_at(eye, eye + dir, 70.0, 0.1, f64::from(vd) * 32.0 * 1.5).unwrap();
        let (mut ms, mut fin) = (Vec::new(), Vec::new());
        let mut drawn = [0usize; 3];
        for i in 0..4 + frames {
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            let s = renderer.render(&mut encoder, &target.view, &camera).unwrap();
            let t = Instant::now();
            let cmd = encoder.finish();
            let f = t.elapsed().as_secs_f64() * 1e3;
            ctx.queue.submit([cmd]);
            renderer.after_submit();
            let _ = ctx.device.poll(wgpu::PollType::wait_indefinitely());
            if i >= 4 {
                ms.push(s.cpu_ms);
                fin.push(s.cpu_ms + f);
                drawn = s.meshes_drawn;
            }
        }
        println!(
            "| {vd} | {} | {} / {} / {} | {:.3} ({:.3}) | {:.3} ({:.3}) |",
            renderer.chunks().len(), drawn[0], drawn[1], drawn[2],
            pct(&ms, 0.5), pct(&ms, 0.95), pct(&fin, 0.5), pct(&fin, 0.95)
        );
    }
}
