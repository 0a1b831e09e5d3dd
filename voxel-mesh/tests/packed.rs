//! A world of packed chunks meshes exactly like the same world in mask form, whole and after
//! edits, with every mix of forms between a chunk and its neighbours.

use std::sync::Arc;

use voxel_core::blocks::{GLASS, STONE, WATER};
use voxel_core::{BlockRegistry, ChunkPos, TerrainConfig, TerrainGenerator, World, WorldPos};
use voxel_mesh::{ChunkMeshes, mesh_chunks, mesh_dirty};

fn terrain_world() -> World {
    TerrainGenerator::new(TerrainConfig::default())
        .generate_world(
            Arc::new(BlockRegistry::default()),
            ChunkPos::new(-2, 0, -2),
            ChunkPos::new(1, 1, 1),
        )
        .expect("valid world")
}

fn all_meshes(world: &World) -> Vec<(ChunkPos, ChunkMeshes)> {
    let mut all: Vec<ChunkPos> = world.iter().map(|(p, _)| p).collect();
    all.sort();
    mesh_chunks(world, &all).expect("known blocks")
}

#[test]
fn packed_worlds_mesh_like_mask_worlds() {
    let masks = terrain_world();
    let want = all_meshes(&masks);
    assert!(want.iter().any(|(_, m)| !m.translucent.is_empty()));
    let mut packed = masks.clone();
    packed.pack_all();
    assert!(
        packed
            .iter()
            .all(|(_, c)| c.is_packed() || c.as_uniform().is_some())
    );
    assert!(packed.chunk_memory_bytes() * 3 < masks.chunk_memory_bytes());
    // Packing keeps the palette order, so even the quad order is the same.
    assert_eq!(all_meshes(&packed), want);
    // Every other chunk packed: each chunk meets neighbours of both forms.
    let mut mixed = masks.clone();
    for (p, _) in masks.iter() {
        if (p.x + p.y + p.z).rem_euclid(2) == 0 {
            mixed.pack_chunk(p);
        }
    }
    assert_eq!(all_meshes(&mixed), want);
}

#[test]
fn edits_of_packed_chunks_remesh_like_edits_of_mask_chunks() {
    let mut masks = terrain_world();
    let mut packed = masks.clone();
    packed.pack_all();
    for w in [&mut masks, &mut packed] {
        w.take_dirty();
        // Across the border between chunks (0, 1, 0) and (1, 1, 0), and a box over four
        // chunks: new types in packed chunks, types removed.
        w.set_block(WorldPos::new(31, 40, 5), GLASS).expect("known");
        w.set_block(WorldPos::new(32, 40, 5), WATER).expect("known");
        w.fill_box(WorldPos::new(-5, 20, -5), WorldPos::new(5, 45, 5), STONE)
            .expect("known");
        w.fill_box(WorldPos::new(-3, 30, -3), WorldPos::new(3, 35, 3), GLASS)
            .expect("known");
    }
    assert!(
        packed
            .iter()
            .all(|(_, c)| !c.is_packed() || c.check_invariants().is_ok())
    );
    assert!(
        packed
            .chunk(ChunkPos::new(0, 1, 0))
            .expect("loaded")
            .is_packed()
    );
    let a = mesh_dirty(&mut masks).expect("known blocks");
    let b = mesh_dirty(&mut packed).expect("known blocks");
    assert!(!a.is_empty());
    assert_eq!(a.len(), b.len());
    for ((pa, ma), (pb, mb)) in a.iter().zip(&b) {
        assert_eq!(pa, pb);
        assert_eq!(ma.len(), mb.len(), "chunk {pa:?}");
        let sorted = |m: &ChunkMeshes| {
            let mut v: Vec<_> = [&m.opaque, &m.cutout, &m.translucent]
                .into_iter()
                .flatten()
                .map(|q| (q.geometry, q.block))
                .collect();
            v.sort_unstable();
            v
        };
        assert_eq!(sorted(ma), sorted(mb), "chunk {pa:?}");
    }
    for (p, c) in masks.iter() {
        assert_eq!(c.to_dense(), packed.chunk(p).expect("loaded").to_dense());
    }
}
