//! Meshing many chunks of a world at once, in parallel with rayon (one after another on
//! wasm32, where a browser page has one thread).

#[cfg(not(target_arch = "wasm32"))]
use rayon::prelude::*;
use voxel_core::{ChunkPos, World};

use crate::{ChunkMeshes, Mesher, Result};

/// Meshes the chunks at `positions` in parallel (one [`Mesher`] per rayon worker; one
/// mesher in turn on wasm32). A position with no loaded chunk gets empty meshes, so a
/// renderer can drop what it drew there.
pub fn mesh_chunks(world: &World, positions: &[ChunkPos]) -> Result<Vec<(ChunkPos, ChunkMeshes)>> {
    let proto = Mesher::new(world.registry());
    let mesh = |mesher: &mut Mesher, &p: &ChunkPos| {
        let meshes = match world.chunk(p) {
            Some(c) => mesher.mesh(c, world.neighbourhood(p))?,
            None => ChunkMeshes::default(),
        };
        Ok((p, meshes))
    };
    #[cfg(not(target_arch = "wasm32"))]
    let meshes = positions
        .par_iter()
        .map_init(|| proto.clone(), mesh)
        .collect();
    #[cfg(target_arch = "wasm32")]
    let meshes = {
        let mut mesher = proto;
        positions.iter().map(|p| mesh(&mut mesher, p)).collect()
    };
    meshes
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
