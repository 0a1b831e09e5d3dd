use super::config::MAX_VIEW_DISTANCE;
use super::edits::{EDIT_BYTES, EDITED_CHUNK_BYTES};
use super::schedule::{StreamFrame, offset};
use super::*;
use glam::DVec3;
use std::collections::HashSet;
use voxel_core::{BlockId, CHUNK_SIZE, Neighbourhood, TerrainGenerator, WorldPos, blocks};
use voxel_mesh::{ChunkMeshes, Mesher};

mod contract;

/// A streamer over the default terrain with a game's registry whose ids name
/// other blocks is refused at `new`, naming the roles; with the default registry it is
/// made.
#[test]
fn a_generator_for_another_registry_is_refused_at_new() {
    let mut game = BlockRegistry::new();
    let _ = game.register(voxel_core::BlockDef::new(
        "amber_glass",
        [200, 140, 40],
        0.5,
    ));
    for (_, def) in BlockRegistry::default().iter().skip(1) {
        let _ = game.register(def.clone());
    }
    let generator = TerrainGenerator::new(voxel_core::TerrainConfig::default());
    let config = StreamConfig::default();
    let err = ChunkStreamer::new(Arc::new(game), generator.clone(), config)
        .unwrap_err()
        .to_string();
    assert!(err.contains("but this registry's"), "{err}");
    ChunkStreamer::new(Arc::new(BlockRegistry::default()), generator, config).unwrap();
}

/// A sink that records what it holds and checks the streamer's calls.
#[derive(Default)]
struct Recorder {
    held: HashMap<ChunkPos, usize>,
    order: Vec<ChunkPos>,
}

impl ChunkSink for Recorder {
    fn upload(&mut self, pos: ChunkPos, meshes: &ChunkMeshes) -> Result<()> {
        assert!(!meshes.is_empty(), "empty meshes uploaded at {pos:?}");
        self.held.insert(pos, meshes.len());
        self.order.push(pos);
        Ok(())
    }

    fn remove(&mut self, pos: ChunkPos) {
        assert!(
            self.held.remove(&pos).is_some(),
            "removed {pos:?}, never uploaded"
        );
    }
}

/// One glass block in every chunk at y = 0, stone in the chunks below: every chunk
/// near the eye has something to draw.
struct Pillars;

impl ChunkSource for Pillars {
    fn generate(&self, pos: ChunkPos) -> Chunk {
        match pos.y {
            y if y < 0 => Chunk::uniform(blocks::STONE),
            0 => {
                let mut c = Chunk::default();
                let _ = c.set(5, 5, 5, blocks::GLASS);
                c
            }
            _ => Chunk::default(),
        }
    }
}

fn registry() -> Arc<BlockRegistry> {
    Arc::new(BlockRegistry::default())
}

fn config(view_distance: u32) -> StreamConfig {
    StreamConfig {
        view_distance,
        vertical_distance: 1,
        ..StreamConfig::default()
    }
}

/// Updates until idle (at most `limit` updates), returning the frames.
fn settle(
    s: &mut ChunkStreamer,
    eye: DVec3,
    sink: &mut Recorder,
    limit: usize,
) -> Vec<StreamFrame> {
    let mut frames = Vec::new();
    for _ in 0..limit {
        frames.push(s.update(eye, sink).unwrap());
        if s.is_idle() {
            return frames;
        }
        std::thread::sleep(std::time::Duration::from_micros(200));
    }
    panic!("not idle after {limit} updates: {s:?}");
}

fn expected(centre: ChunkPos, view_distance: u32) -> HashSet<ChunkPos> {
    let r = view_distance as i32;
    let mut out = HashSet::new();
    for dx in -r..=r {
        for dz in -r..=r {
            if dx * dx + dz * dz <= r * r {
                // Only y = 0 draws: glass (stone below is hidden, the level below
                // shows its top faces: stone under air at y = -1).
                out.insert(ChunkPos::new(centre.x + dx, 0, centre.z + dz));
                out.insert(ChunkPos::new(centre.x + dx, -1, centre.z + dz));
            }
        }
    }
    out.retain(|p| centre.y - 1 <= p.y && p.y <= centre.y + 1);
    out
}

#[test]
fn loads_the_view_distance_nearest_first() {
    let eye = DVec3::new(16.0, 16.0, 16.0);
    // One job at a time: the order is exactly nearest first.
    let mut s = ChunkStreamer::new(
        registry(),
        Pillars,
        StreamConfig {
            max_jobs: 1,
            ..config(3)
        },
    )
    .unwrap();
    let mut sink = Recorder::default();
    settle(&mut s, eye, &mut sink, 10_000);
    let centre = ChunkPos::new(0, 0, 0);
    let keys: HashSet<ChunkPos> = sink.held.keys().copied().collect();
    assert_eq!(keys, expected(centre, 3));
    let d: Vec<i64> = sink
        .order
        .iter()
        .map(|p| distance2(offset(*p, centre)))
        .collect();
    assert!(
        d.windows(2).all(|w| w[0] <= w[1]),
        "not nearest first: {d:?}"
    );

    // Many jobs at once: the same chunks, uploaded once each.
    let mut s = ChunkStreamer::new(registry(), Pillars, config(3)).unwrap();
    let mut sink = Recorder::default();
    settle(&mut s, eye, &mut sink, 10_000);
    assert_eq!(sink.order.len(), sink.held.len(), "a chunk uploaded twice");
    assert_eq!(
        sink.held.keys().copied().collect::<HashSet<_>>(),
        expected(centre, 3)
    );
    // Meshed chunks are packed; uniform air is not stored.
    assert!(
        s.world()
            .iter()
            .all(|(p, c)| c.is_packed() || c.as_uniform().is_some() || !s.wanted(p, centre))
    );
    assert!(
        s.world()
            .iter()
            .all(|(_, c)| c.as_uniform() != Some(BlockId::AIR))
    );
}

#[test]
fn unloads_past_the_distance_and_hysteresis() {
    let mut s = ChunkStreamer::new(registry(), Pillars, config(3)).unwrap();
    let mut sink = Recorder::default();
    settle(&mut s, DVec3::splat(16.0), &mut sink, 10_000);
    // Four chunks along +x.
    let eye = DVec3::new(16.0 + 4.0 * 32.0, 16.0, 16.0);
    settle(&mut s, eye, &mut sink, 10_000);
    let centre = ChunkPos::new(4, 0, 0);
    let keep = |p: &ChunkPos| within(offset(*p, centre), 3 + 2, 1 + 2);
    assert!(
        sink.held.keys().all(keep),
        "a chunk past the hysteresis is drawn"
    );
    // Past the margin only the ring that drawn chunks' meshes were made from stays.
    let drawn_neighbour = |p: ChunkPos| {
        Neighbourhood::OFFSETS
            .iter()
            .any(|&d| p.offset(d).is_some_and(|n| sink.held.contains_key(&n)))
    };
    assert!(
        s.world()
            .iter()
            .all(|(p, _)| keep(&p) || drawn_neighbour(p)),
        "a chunk past it stays loaded"
    );
    assert!(s.world().iter().any(|(p, _)| !keep(&p)), "the ring is kept");
    // Within the hysteresis, what was drawn stays drawn.
    assert!(
        sink.held.contains_key(&ChunkPos::new(0, 0, 0)),
        "dropped within the margin"
    );
    for p in expected(centre, 3) {
        assert!(sink.held.contains_key(&p), "{p:?} not drawn");
    }
}

#[test]
fn uploads_stay_within_the_budget() {
    let mut s = ChunkStreamer::new(
        registry(),
        Pillars,
        StreamConfig {
            upload_budget_bytes: 100,
            ..config(4)
        },
    )
    .unwrap();
    let mut sink = Recorder::default();
    let frames = settle(&mut s, DVec3::splat(16.0), &mut sink, 20_000);
    let most = frames.iter().map(|f| f.upload_bytes).max().unwrap();
    // A glass block is 6 quads (48 bytes), a stone top 1 quad (8 bytes).
    assert!(most <= 100, "{most} bytes in one update");
    let total: usize = sink.held.values().map(|q| q * 8).sum();
    let busy = frames.iter().filter(|f| f.uploads > 0).count();
    assert!(busy >= total / 100, "{total} bytes in {busy} updates");
}

#[test]
fn a_teleport_drops_and_reloads_within_the_unload_budget() {
    let mut s = ChunkStreamer::new(
        registry(),
        Pillars,
        StreamConfig {
            max_unloads: 10,
            ..config(4)
        },
    )
    .unwrap();
    let mut sink = Recorder::default();
    settle(&mut s, DVec3::splat(16.0), &mut sink, 10_000);
    let before = sink.held.len();
    let far = DVec3::new(16.0 + 10_000.0 * 32.0, 16.0, 16.0);
    let frames = settle(&mut s, far, &mut sink, 20_000);
    assert!(frames.iter().all(|f| f.unloads <= 10));
    assert!(frames.iter().map(|f| f.unloads).sum::<usize>() >= before);
    let centre = ChunkPos::new(10_000, 0, 0);
    assert_eq!(
        sink.held.keys().copied().collect::<HashSet<_>>(),
        expected(centre, 4)
    );
    // Back again, and to the edge of the world.
    settle(&mut s, DVec3::splat(16.0), &mut sink, 20_000);
    assert_eq!(
        sink.held.keys().copied().collect::<HashSet<_>>(),
        expected(ChunkPos::new(0, 0, 0), 4)
    );
    let edge = DVec3::new(f64::from(i32::MAX) - 10.0, 16.0, 16.0);
    settle(&mut s, edge, &mut sink, 20_000);
    assert!(sink.held.keys().all(|p| p.is_valid()));
}

#[test]
fn edits_remesh_and_survive_unloading() {
    let mut s = ChunkStreamer::new(registry(), Pillars, config(2)).unwrap();
    let mut sink = Recorder::default();
    let eye = DVec3::splat(16.0);
    settle(&mut s, eye, &mut sink, 10_000);
    let at = ChunkPos::new(1, 0, 0);
    let quads = sink.held[&at];
    // A second glass block beside the first, not touching: 6 more quads.
    s.set_block(WorldPos::new(32 + 20, 5, 5), blocks::GLASS)
        .unwrap();
    settle(&mut s, eye, &mut sink, 10_000);
    assert_eq!(sink.held[&at], quads + 6);
    // A block on the border of two chunks remeshes both.
    let edge = s.set_block(WorldPos::new(31, 5, 5), blocks::STONE).unwrap();
    assert_eq!(edge, BlockId::AIR);
    settle(&mut s, eye, &mut sink, 10_000);
    assert_eq!(
        sink.held[&ChunkPos::new(0, 0, 0)],
        12,
        "glass and the new stone"
    );

    // Far away: generated, edited and kept; it comes back edited.
    let far = WorldPos::new(100 * 32 + 7, 7, 7);
    assert_eq!(s.set_block(far, blocks::GLASS).unwrap(), BlockId::AIR);
    assert_eq!(s.set_block(far, blocks::GLASS).unwrap(), blocks::GLASS);
    let there = DVec3::new(100.0 * 32.0 + 16.0, 16.0, 16.0);
    settle(&mut s, there, &mut sink, 20_000);
    assert_eq!(sink.held[&ChunkPos::new(100, 0, 0)], 12, "two glass blocks");
    // Away and back: the edit of chunk (1, 0, 0) is still there.
    settle(&mut s, eye, &mut sink, 20_000);
    assert_eq!(sink.held[&at], quads + 6);

    // Bad input.
    assert!(s.set_block(far, BlockId(60_000)).is_err());
    assert!(s.update(DVec3::NAN, &mut sink).is_err());
}

#[test]
fn bad_configurations_are_errors() {
    for (vd, vv, h) in [
        (0, 1, 2),
        (MAX_VIEW_DISTANCE + 1, 1, 2),
        (4, MAX_VIEW_DISTANCE + 1, 2),
        (4, 1, 0),
    ] {
        let c = StreamConfig {
            view_distance: vd,
            vertical_distance: vv,
            hysteresis: h,
            ..StreamConfig::default()
        };
        assert!(ChunkStreamer::new(registry(), Pillars, c).is_err(), "{c:?}");
        assert!(
            ChunkStreamer::new_local(registry(), Pillars, c).is_err(),
            "{c:?}"
        );
    }
    let c = StreamConfig {
        local_budget: std::time::Duration::from_millis(1001),
        ..config(2)
    };
    assert!(ChunkStreamer::new_local(registry(), Pillars, c).is_err());
    let mut s = ChunkStreamer::new(registry(), Pillars, config(2)).unwrap();
    assert!(s.set_view_distance(0).is_err());
    assert_eq!(s.config().view_distance, 2, "unchanged after an error");
    assert!(s.set_view_distance(MAX_VIEW_DISTANCE).is_ok());
}

/// A source that panics on one chunk and makes an unknown id in another.
struct Broken;

impl ChunkSource for Broken {
    fn generate(&self, pos: ChunkPos) -> Chunk {
        match (pos.x, pos.y, pos.z) {
            (1, 0, 0) => panic!("broken source"),
            (-1, 0, 0) => Chunk::uniform(BlockId(60_000)),
            _ => Pillars.generate(pos),
        }
    }
}

#[test]
fn a_broken_source_is_reported_and_never_hangs() {
    let mut s = ChunkStreamer::new(registry(), Broken, config(2)).unwrap();
    let mut sink = Recorder::default();
    let frames = settle(&mut s, DVec3::splat(16.0), &mut sink, 10_000);
    let failed: Vec<ChunkPos> = frames
        .iter()
        .flat_map(|f| f.failed.iter().map(|x| x.0))
        .collect();
    assert!(failed.contains(&ChunkPos::new(1, 0, 0)));
    assert!(failed.contains(&ChunkPos::new(-1, 0, 0)));
    assert!(
        sink.held.contains_key(&ChunkPos::new(0, 0, 0)),
        "its neighbours still draw"
    );
}
