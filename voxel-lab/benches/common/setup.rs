//! A renderer holding a bench's world: what the benches' set-ups share.

use voxel_core::{ChunkPos, World};
use voxel_lab::Result;
use voxel_mesh::mesh_chunks;
use voxel_render::{GpuContext, Renderer, RendererConfig, Technique};

/// A `size` renderer drawing with `technique`, holding the chunks `positions` of `world`,
/// meshed (in parallel) and uploaded.
pub fn renderer_of(
    ctx: &GpuContext,
    world: &World,
    positions: &[ChunkPos],
    technique: Technique,
    (width, height): (u32, u32),
) -> Result<Renderer> {
    let mut config = RendererConfig {
        width,
        height,
        ..RendererConfig::default()
    };
    config.oit.technique = technique;
    let mut renderer = Renderer::new(ctx, world.registry(), config)?;
    for (pos, meshes) in mesh_chunks(world, positions)? {
        renderer.upload_chunk(pos, &meshes)?;
    }
    Ok(renderer)
}
