//! The world and camera of the record bench (`record.rs`), which `wboit_fit.rs` measures on
//! too: the generated terrain (default [`TerrainConfig`], seed [`SEED`]) of every chunk
//! column within a circle of radius VD chunks around the origin chunk, chunk layers
//! [`LAYERS`], and a camera 40 blocks above the ground at the origin looking along +x
//! pitched down 0.25 rad, far plane VD × 32 × 1.5 blocks.

use std::sync::Arc;
use voxel_lab::Result;

use glam::DVec3;
use rayon::prelude::*;
use voxel_core::{BlockRegistry, ChunkPos, TerrainConfig, TerrainGenerator, World};

use voxel_render::{Camera, GpuContext, Renderer, Technique};

#[path = "setup.rs"]
mod setup;

pub const SEED: u32 = 1;
pub const W: u32 = 640;
pub const H: u32 = 360;
/// Chunk layers generated: the terrain's ground lies in 0 and 1 (heights 8 to 44, trees and
/// structures below 64); -2 and -1 are solid stone, 2 and 3 air.
pub const LAYERS: std::ops::RangeInclusive<i32> = -2..=3;

fn generator() -> TerrainGenerator {
    TerrainGenerator::new(TerrainConfig {
        seed: SEED,
        ..TerrainConfig::default()
    })
}

/// The terrain of the disc of radius `vd` chunks, meshed and uploaded into a new `W`×`H`
/// renderer drawing with `technique`.
pub fn renderer(ctx: &GpuContext, vd: i32, technique: Technique) -> Result<Renderer> {
    let registry = Arc::new(BlockRegistry::default());
    let generator = generator();
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
        world.insert_chunk(p, c)?;
    }
    setup::renderer_of(ctx, &world, &positions, technique, (W, H))
}

/// The camera of view distance `vd`.
pub fn camera(vd: i32) -> Result<Camera> {
    let eye = DVec3::new(0.5, generator().height_at(0, 0) as f64 + 40.0, 0.5);
    let pitch: f64 = -0.25;
    let dir = DVec3::new(pitch.cos(), pitch.sin(), 0.0);
    Camera::look_at(eye, eye + dir, 70.0, 0.1, f64::from(vd) * 32.0 * 1.5)
        .map_err(voxel_lab::Error::Render)
}
