//! Meshing many chunks of a world at once, in parallel with rayon (one after another on
//! wasm32, where a browser page has one thread).

#[cfg(not(target_arch = "wasm32"))]
use rayon::prelude::*;
use voxel_core::{ChunkPos, LightField, Neighbourhood, World};

use crate::{ChunkMeshes, Mesher, Result};

/// Meshes the chunks at `positions` in parallel (one [`Mesher`] per rayon worker; one
/// mesher in turn on wasm32). A position with no loaded chunk gets empty meshes, so a
/// renderer can drop what it drew there.
pub fn mesh_chunks(world: &World, positions: &[ChunkPos]) -> Result<Vec<(ChunkPos, ChunkMeshes)>> {
    mesh_positions(world, None, positions)
}

/// [`mesh_chunks`] with the light of `light` ([`Mesher::mesh_lit`]).
pub fn mesh_chunks_lit(
    world: &World,
    light: &LightField,
    positions: &[ChunkPos],
) -> Result<Vec<(ChunkPos, ChunkMeshes)>> {
    mesh_positions(world, Some(light), positions)
}

/// Every loaded chunk of `world` meshed, with the light of `light` when given: what a
/// whole scene uploads ([`mesh_chunks`], [`mesh_chunks_lit`]).
pub fn mesh_world(
    world: &World,
    light: Option<&LightField>,
) -> Result<Vec<(ChunkPos, ChunkMeshes)>> {
    let positions: Vec<_> = world.iter().map(|(p, _)| p).collect();
    mesh_positions(world, light, &positions)
}

fn mesh_positions(
    world: &World,
    light: Option<&LightField>,
    positions: &[ChunkPos],
) -> Result<Vec<(ChunkPos, ChunkMeshes)>> {
    let proto = Mesher::new(world.registry());
    let mesh = |mesher: &mut Mesher, &p: &ChunkPos| {
        let meshes = match (world.chunk(p), light) {
            (Some(c), Some(l)) => mesher.mesh_lit(c, world.neighbourhood(p), l, p)?,
            (Some(c), None) => mesher.mesh(c, world.neighbourhood(p))?,
            (None, _) => ChunkMeshes::default(),
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

/// [`mesh_dirty`] with light: meshes the world's dirty chunks and every loaded chunk whose
/// light or whose neighbours' light changed since the last call
/// ([`LightField::take_changed`]: a chunk's border vertices read its neighbours' light),
/// with [`mesh_chunks_lit`]. On error both sets are restored, as dirty chunks.
pub fn mesh_dirty_lit(
    world: &mut World,
    light: &mut LightField,
) -> Result<Vec<(ChunkPos, ChunkMeshes)>> {
    let mut positions = world.take_dirty();
    for p in light.take_changed() {
        let around = Neighbourhood::OFFSETS.iter().filter_map(|&d| p.offset(d));
        positions.extend(around.chain([p]).filter(|q| world.chunk(*q).is_some()));
    }
    positions.sort_unstable();
    positions.dedup();
    let result = mesh_chunks_lit(world, light, &positions);
    if result.is_err() {
        for p in positions {
            world.mark_dirty(p);
        }
    }
    result
}
