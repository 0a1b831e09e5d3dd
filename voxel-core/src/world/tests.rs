use std::sync::Arc;

use super::*;
use crate::BlockRegistry;
use crate::blocks::*;

fn world() -> World {
    World::new(Arc::new(BlockRegistry::default()))
}

#[test]
fn split_floors_negative_coordinates() {
    assert_eq!(
        WorldPos::new(-1, 0, 33).split(),
        (ChunkPos::new(-1, 0, 1), [31, 0, 1])
    );
    let (c, l) = WorldPos::new(i32::MIN, i32::MAX, 0).split();
    assert_eq!(c, ChunkPos::new(ChunkPos::MIN, ChunkPos::MAX, 0));
    assert_eq!(l, [0, 31, 0]);
    assert!(c.is_valid());
}

#[test]
fn neighbours_stop_at_the_edge_of_the_i32_world() {
    let edge = ChunkPos::new(ChunkPos::MAX, 0, ChunkPos::MIN);
    assert_eq!(edge.neighbour(Face::PosX), None);
    assert_eq!(edge.neighbour(Face::NegZ), None);
    assert_eq!(
        edge.neighbour(Face::NegX),
        Some(ChunkPos::new(ChunkPos::MAX - 1, 0, ChunkPos::MIN))
    );
    assert_eq!(ChunkPos::new(i32::MAX, 0, 0).neighbour(Face::PosX), None);
    assert_eq!(edge.origin()[0], i64::from(i32::MAX) - 31);
}

#[test]
fn set_get_at_the_i32_limits() {
    let mut w = world();
    for p in [
        WorldPos::new(i32::MAX, i32::MAX, i32::MAX),
        WorldPos::new(i32::MIN, i32::MIN, i32::MIN),
    ] {
        w.set_block(p, GLASS).unwrap();
        assert_eq!(w.get_block(p), GLASS);
    }
    assert_eq!(w.len(), 2);
}

#[test]
fn unknown_block_is_rejected() {
    let mut w = world();
    assert_eq!(
        w.set_block(WorldPos::new(0, 0, 0), BlockId(500)),
        Err(Error::UnknownBlock(BlockId(500), 13))
    );
    let mut c = Chunk::default();
    c.set(0, 0, 0, BlockId(77)).unwrap();
    assert!(matches!(
        w.insert_chunk(ChunkPos::new(0, 0, 0), c),
        Err(Error::UnknownBlock(BlockId(77), _))
    ));
    assert!(matches!(
        w.insert_chunk(ChunkPos::new(1 << 26, 0, 0), Chunk::default()),
        Err(Error::ChunkOutOfRange(p)) if p == ChunkPos::new(1 << 26, 0, 0)
    ));
}

#[test]
fn border_edits_dirty_the_neighbour() {
    let mut w = world();
    for x in -1..=1 {
        w.insert_chunk(ChunkPos::new(x, 0, 0), Chunk::default())
            .unwrap();
    }
    w.take_dirty();
    // Interior edit: only the chunk itself.
    w.set_block(WorldPos::new(5, 5, 5), STONE).unwrap();
    assert_eq!(w.take_dirty(), vec![ChunkPos::new(0, 0, 0)]);
    // Setting the same block again changes nothing.
    w.set_block(WorldPos::new(5, 5, 5), STONE).unwrap();
    assert!(w.take_dirty().is_empty());
    // Edit on the -x border: the -x neighbour too; the +y neighbour is not loaded.
    w.set_block(WorldPos::new(0, 31, 5), STONE).unwrap();
    assert_eq!(
        w.take_dirty(),
        vec![ChunkPos::new(-1, 0, 0), ChunkPos::new(0, 0, 0)]
    );
    w.set_block(WorldPos::new(31, 3, 3), WATER).unwrap();
    assert_eq!(
        w.take_dirty(),
        vec![ChunkPos::new(0, 0, 0), ChunkPos::new(1, 0, 0)]
    );
}

#[test]
fn edge_and_corner_edits_dirty_the_diagonal_neighbours() {
    let mut w = world();
    for d in Neighbourhood::OFFSETS.into_iter().chain([[0; 3]]) {
        w.insert_chunk(ChunkPos::new(d[0], d[1], d[2]), Chunk::default())
            .unwrap();
    }
    w.take_dirty();
    // On the +x face only: the chunk and its +x neighbour.
    w.set_block(WorldPos::new(31, 5, 5), STONE).unwrap();
    assert_eq!(w.take_dirty().len(), 2);
    // On the +x/-z edge: + the -z and the (+x, -z) edge neighbour.
    w.set_block(WorldPos::new(31, 5, 0), STONE).unwrap();
    let dirty = w.take_dirty();
    assert_eq!(dirty.len(), 4, "{dirty:?}");
    assert!(dirty.contains(&ChunkPos::new(1, 0, -1)));
    // On the (-x, +y, +z) corner: all 7 chunks that touch it, and the chunk.
    w.set_block(WorldPos::new(0, 31, 31), STONE).unwrap();
    let dirty = w.take_dirty();
    assert_eq!(dirty.len(), 8, "{dirty:?}");
    assert!(dirty.contains(&ChunkPos::new(-1, 1, 1)));
    assert_eq!(touched_neighbours([0, 31, 31]).count(), 7);
    assert_eq!(touched_neighbours([4, 31, 31]).count(), 3);
    assert_eq!(touched_neighbours([4, 4, 4]).count(), 0);
}

#[test]
fn neighbourhood_offsets_are_the_26_around_a_chunk() {
    let set: HashSet<[i32; 3]> = Neighbourhood::OFFSETS.into_iter().collect();
    assert_eq!(set.len(), 26);
    assert!(!set.contains(&[0, 0, 0]));
    for (i, f) in Face::ALL.iter().enumerate() {
        assert_eq!(Neighbourhood::OFFSETS[i], f.normal());
    }
    let stone = Chunk::uniform(STONE);
    let n = Neighbourhood::faces([Some(&stone), None, None, None, None, None]);
    assert!(n.face(Face::PosX).is_some());
    assert!(n.get([1, 1, 0]).is_none());
    assert!(n.get([0, 0, 0]).is_none());
    assert!(n.get([2, 0, 0]).is_none());
    let all = Neighbourhood::from_fn(|_| Some(&stone));
    assert!(Neighbourhood::OFFSETS.iter().all(|&d| all.get(d).is_some()));
}

#[test]
fn insert_and_remove_dirty_neighbours() {
    let mut w = world();
    w.insert_chunk(ChunkPos::new(0, 0, 0), Chunk::default())
        .unwrap();
    w.take_dirty();
    w.insert_chunk(ChunkPos::new(0, 1, 0), Chunk::uniform(STONE))
        .unwrap();
    assert_eq!(
        w.take_dirty(),
        vec![ChunkPos::new(0, 0, 0), ChunkPos::new(0, 1, 0)]
    );
    assert!(w.remove_chunk(ChunkPos::new(0, 1, 0)).is_some());
    assert_eq!(
        w.take_dirty(),
        vec![ChunkPos::new(0, 0, 0), ChunkPos::new(0, 1, 0)]
    );
    let around = w.neighbourhood(ChunkPos::new(0, 0, 0));
    assert!(
        Neighbourhood::OFFSETS
            .iter()
            .all(|&d| around.get(d).is_none())
    );
}

#[test]
fn fill_box_matches_setting_each_block() {
    let mut a = world();
    let mut b = world();
    let (min, max) = (WorldPos::new(-40, -3, 5), WorldPos::new(70, 33, 6));
    a.fill_box(min, max, GLASS).unwrap();
    for x in min.x..=max.x {
        for y in min.y..=max.y {
            for z in min.z..=max.z {
                b.set_block(WorldPos::new(x, y, z), GLASS).unwrap();
            }
        }
    }
    assert_eq!(a.len(), b.len());
    for (pos, chunk) in a.iter() {
        assert_eq!(
            chunk.to_dense(),
            b.chunk(pos).unwrap().to_dense(),
            "{pos:?}"
        );
    }
    assert!(a.fill_box(min, max, BlockId(99)).is_err());
    a.fill_box(WorldPos::new(0, 0, 0), WorldPos::new(-1, 0, 0), STONE)
        .unwrap();
    a.fill_box(WorldPos::new(500, 0, 0), WorldPos::new(600, 0, 0), AIR)
        .unwrap();
    assert_eq!(
        a.len(),
        b.len(),
        "empty boxes and air in missing chunks load nothing"
    );
}

#[test]
fn packed_chunks_read_and_edit_like_any_other() {
    let mut w = world();
    w.fill_box(WorldPos::new(-3, -3, -3), WorldPos::new(40, 2, 4), STONE)
        .unwrap();
    w.set_block(WorldPos::new(0, 0, 0), WATER).unwrap();
    let before: Vec<_> = {
        let mut v: Vec<_> = w.iter().map(|(p, c)| (p, c.to_dense())).collect();
        v.sort_by_key(|(p, _)| *p);
        v
    };
    let mask_bytes = w.chunk_memory_bytes();
    w.take_dirty();
    w.pack_all();
    assert!(w.dirty().is_empty(), "packing changes no block");
    assert!(
        w.iter()
            .all(|(_, c)| c.is_packed() || c.as_uniform().is_some())
    );
    assert!(w.chunk_memory_bytes() * 3 < mask_bytes);
    for (p, dense) in &before {
        assert_eq!(&w.chunk(*p).unwrap().to_dense(), dense);
    }
    assert_eq!(w.get_block(WorldPos::new(0, 0, 0)), WATER);
    assert_eq!(w.get_block(WorldPos::new(-1, -1, -1)), STONE);
    assert_eq!(w.set_block(WorldPos::new(1, 1, 1), GLASS).unwrap(), STONE);
    let c = ChunkPos::new(0, 0, 0);
    assert!(w.chunk(c).unwrap().is_packed(), "an edit keeps the form");
    w.chunk(c).unwrap().check_invariants().unwrap();
    assert!(w.unpack_chunk(c));
    assert!(!w.chunk(c).unwrap().is_packed());
    assert_eq!(w.get_block(WorldPos::new(1, 1, 1)), GLASS);
    assert!(w.pack_chunk(c));
    assert!(w.chunk(c).unwrap().is_packed());
    assert!(!w.pack_chunk(ChunkPos::new(9, 9, 9)));
    assert!(!w.unpack_chunk(ChunkPos::new(9, 9, 9)));
}

#[test]
fn setting_air_in_a_missing_chunk_loads_nothing() {
    let mut w = world();
    assert_eq!(w.set_block(WorldPos::new(1, 2, 3), AIR).unwrap(), AIR);
    assert!(w.is_empty());
    assert!(w.dirty().is_empty());
}

#[test]
fn the_medium_at_a_point_is_its_translucent_block() {
    let mut w = World::new(Arc::new(BlockRegistry::default()));
    w.set_block(WorldPos::new(0, -1, 0), WATER).unwrap();
    w.set_block(WorldPos::new(0, 0, 0), STONE).unwrap();
    assert_eq!(w.medium_at([0.5, -0.5, 0.5]), Some(WATER));
    assert_eq!(
        w.medium_at([0.5, -1.0, 0.99]),
        Some(WATER),
        "the bottom face is inside"
    );
    assert_eq!(w.medium_at([0.5, 0.0, 0.5]), None, "stone is no medium");
    assert_eq!(w.medium_at([0.5, 1.5, 0.5]), None, "air");
    assert_eq!(w.medium_at([f64::NAN, 0.0, 0.0]), None);
    assert_eq!(w.medium_at([3e9, 0.0, 0.0]), None);
}

#[test]
fn the_block_holding_a_point_and_the_loaded_chunks_bounds() {
    assert_eq!(
        WorldPos::containing([0.5, -0.5, 31.99]),
        WorldPos::new(0, -1, 31)
    );
    assert_eq!(
        WorldPos::containing([f64::NAN, 1e12, -1e12]),
        WorldPos::new(0, i32::MAX, i32::MIN)
    );
    let mut w = world();
    assert_eq!(w.chunk_bounds(), None);
    w.set_block(WorldPos::new(-40, 5, 70), STONE).unwrap();
    w.set_block(WorldPos::new(10, -3, 0), STONE).unwrap();
    assert_eq!(
        w.chunk_bounds(),
        Some((ChunkPos::new(-2, -1, 0), ChunkPos::new(0, 0, 2)))
    );
}
