//! Meshing many chunks of a world at once, in parallel with rayon.

use rayon::prelude::*;
use voxel_core::{ChunkPos, World};

use crate::{ChunkMeshes, Mesher, Result};

/// Meshes the chunks at `positions` in parallel (one [`Mesher`] per rayon worker). A
/// position with no loaded chunk gets empty meshes, so a renderer can drop what it drew
/// there.
pub fn mesh_chunks(world: &World, positions: &[ChunkPos]) -> Result<Vec<(ChunkPos, ChunkMeshes)>> {
    let proto = Mesher::new(world.registry());
    positions
        .par_iter()
        .map_init(
            || proto.clone(),
            |mesher, &p| {
                let meshes = match world.chunk(p) {
                    Some(c) => mesher.mesh(c, world.neighbourhood(p))?,
                    None => ChunkMeshes::default(),
                };
                Ok((p, meshes))
            },
        )
        .collect()
}

/// Takes the world's dirty set and meshes those chunks in parallel. On error the dirty set
/// is restored, so nothing is lost.
pub fn mesh_dirty(world: &mut World) -> Result<Vec<(ChunkPos, ChunkMeshes)>> {
    let dirty = world.take_dirty();
    let result = mesh_chunks(world, &dirty);
    if result.is_err() {
        for p in dirty {
            world.mark_dirty(p);
        }
    }
    result
}
