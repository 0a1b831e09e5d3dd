//! World-level meshing: parallel remeshing of dirty chunks, edits across chunk borders, and
//! the chunk storage's masks staying right through edits.

use std::sync::Arc;

use voxel_core::blocks::*;
use voxel_core::{
    BlockRegistry, Chunk, ChunkPos, TerrainConfig, TerrainGenerator, World, WorldPos,
};
use voxel_mesh::{ChunkMeshes, Mesher, mesh_chunks, mesh_dirty};

fn small_world() -> World {
    TerrainGenerator::new(TerrainConfig::default())
        .generate_world(
            Arc::new(BlockRegistry::default()),
            ChunkPos::new(-2, 0, -2),
            ChunkPos::new(1, 1, 1),
        )
        .expect("valid world")
}

/// A chunk rebuilt block by block from another's dense copy: no edit history at all.
fn rebuilt(c: &Chunk) -> Chunk {
    let dense = c.to_dense();
    let mut out = Chunk::default();
    for x in 0..32 {
        for y in 0..32 {
            for z in 0..32 {
                out.set(x, y, z, dense[Chunk::dense_index(x, y, z)])
                    .expect("in range");
            }
        }
    }
    out
}

fn same_quads(a: &ChunkMeshes, b: &ChunkMeshes) -> bool {
    let sorted = |v: &Vec<voxel_mesh::PackedQuad>| {
        let mut v: Vec<_> = v.iter().map(|q| (q.geometry, q.block)).collect();
        v.sort_unstable();
        v
    };
    sorted(&a.opaque) == sorted(&b.opaque)
        && sorted(&a.cutout) == sorted(&b.cutout)
        && sorted(&a.translucent) == sorted(&b.translucent)
}

fn serial_mesh(world: &World, p: ChunkPos) -> ChunkMeshes {
    let mut m = Mesher::new(world.registry());
    m.mesh(world.chunk(p).expect("loaded"), world.neighbourhood(p))
        .expect("known")
}

#[test]
fn parallel_dirty_meshing_equals_serial_meshing() {
    let mut world = small_world();
    assert_eq!(world.dirty().len(), 32);
    let meshes = mesh_dirty(&mut world).expect("known blocks");
    assert!(world.dirty().is_empty());
    assert_eq!(meshes.len(), 32);
    let mut translucent = 0;
    for (p, m) in &meshes {
        assert_eq!(*m, serial_mesh(&world, *p), "chunk {p:?}");
        translucent += m.translucent.len();
    }
    assert!(translucent > 0, "the world has water");
}

#[test]
fn border_edit_remeshes_both_chunks_and_matches_a_fresh_mesh() {
    let mut world = small_world();
    mesh_dirty(&mut world).expect("known blocks");
    // A glass block on the +x border of chunk (0, 0, 0), just above ground level.
    let p = WorldPos::new(31, 40, 5);
    world.set_block(p, GLASS).expect("known block");
    world
        .set_block(WorldPos::new(32, 40, 5), WATER)
        .expect("known block");
    let dirty: Vec<ChunkPos> = {
        let mut d: Vec<_> = world.dirty().iter().copied().collect();
        d.sort();
        d
    };
    assert_eq!(dirty, vec![ChunkPos::new(0, 1, 0), ChunkPos::new(1, 1, 0)]);
    let meshes = mesh_dirty(&mut world).expect("known blocks");
    for (pos, m) in &meshes {
        // The edited chunks mesh exactly like chunks rebuilt from scratch.
        let fresh = rebuilt(world.chunk(*pos).expect("loaded"));
        let nb = world.neighbourhood(*pos);
        let expect = Mesher::new(world.registry())
            .mesh(&fresh, nb)
            .expect("known");
        // The palette order may differ, and with it the order quads come out in.
        assert!(
            same_quads(m, &expect),
            "chunk {pos:?} differs from a fresh mesh"
        );
    }
    // Glass against water across the border: both faces are there, flagged as an
    // interface.
    let glass_faces: Vec<_> = meshes[0]
        .1
        .translucent
        .iter()
        .filter(|q| q.unpack().is_some_and(|u| u.block == GLASS))
        .collect();
    assert_eq!(glass_faces.len(), 6);
    let interfaces = glass_faces
        .iter()
        .filter(|q| q.flags() & voxel_mesh::FLAG_INTERFACE != 0);
    assert_eq!(interfaces.count(), 1, "the face toward the water");
}

#[test]
fn removed_chunks_mesh_empty_and_missing_neighbours_count_as_air() {
    let mut world = small_world();
    mesh_dirty(&mut world).expect("known blocks");
    let gone = ChunkPos::new(0, 0, 0);
    world.remove_chunk(gone);
    let meshes = mesh_dirty(&mut world).expect("known blocks");
    let (_, m) = meshes.iter().find(|(p, _)| *p == gone).expect("remeshed");
    assert!(m.is_empty());
    // The +x neighbour now shows its -x border to the hole.
    let all = mesh_chunks(&world, &[ChunkPos::new(1, 0, 0)]).expect("known blocks");
    let border_faces = all[0]
        .1
        .opaque
        .iter()
        .filter(|q| {
            q.unpack()
                .is_some_and(|u| u.pos[0] == 0 && u.face == voxel_core::Face::NegX)
        })
        .count();
    assert!(border_faces > 0);
}
