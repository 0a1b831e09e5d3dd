//! Streaming on the GPU: what the streamer uploads draws exactly like the same chunks
//! meshed at once from a whole world, before and after an edit, for every draw path; and
//! after streaming away and back (the arena reusing freed room) the picture is the same;
//! compacting the quad arena keeps the picture.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use std::sync::Arc;

use glam::DVec3;
use voxel_core::{BlockRegistry, ChunkPos, TerrainConfig, TerrainGenerator, WorldPos, blocks};
use voxel_render::{
    Camera, ChunkStreamer, DrawMode, Renderer, RendererConfig, StreamConfig, Technique,
};

const SIZE: (u32, u32) = (240, 135);

fn generator() -> TerrainGenerator {
    TerrainGenerator::new(TerrainConfig::default())
}

fn renderer(ctx: &voxel_render::GpuContext, draw: DrawMode) -> Renderer {
    let mut config = RendererConfig {
        width: SIZE.0,
        height: SIZE.1,
        draw,
        ..RendererConfig::default()
    };
    config.oit.technique = Technique::SortedQuads;
    Renderer::new(ctx, &BlockRegistry::default(), config).unwrap()
}

fn settle(s: &mut ChunkStreamer, eye: DVec3, r: &mut Renderer) {
    for _ in 0..100_000 {
        let f = s.update(eye, r).unwrap();
        assert!(f.failed.is_empty(), "{:?}", f.failed);
        if s.is_idle() {
            return;
        }
        std::thread::sleep(std::time::Duration::from_micros(300));
    }
    panic!("the streamer never settled: {s:?}");
}

/// The chunks the streamer drew, meshed at once from a world that holds them and every
/// chunk the streamer holds (their neighbours), into a fresh renderer.
fn whole(ctx: &voxel_render::GpuContext, s: &ChunkStreamer, draw: DrawMode) -> Renderer {
    let mut r = renderer(ctx, draw);
    let drawn: Vec<ChunkPos> = s.uploaded().collect();
    for (pos, m) in voxel_mesh::mesh_chunks(s.world(), &drawn).unwrap() {
        r.upload_chunk(pos, &m).unwrap();
    }
    r
}

#[test]
fn streamed_chunks_draw_like_the_whole_world() {
    let Some(ctx) = tests::gpu() else { return };
    let out = tests::out_dir("stream");
    let g = generator();
    let eye = DVec3::new(0.5, g.height_at(0, 0) as f64 + 30.0, 0.5);
    let camera = Camera::from_yaw_pitch(eye, 0.6, -0.35, 70.0, 0.1, 400.0).unwrap();
    for draw in [DrawMode::Indirect, DrawMode::PerChunk] {
        let config = StreamConfig {
            view_distance: 3,
            vertical_distance: 2,
            ..StreamConfig::default()
        };
        let registry = Arc::new(BlockRegistry::default());
        let mut s = ChunkStreamer::new(registry, g.clone(), config).unwrap();
        let mut streamed = renderer(&ctx, draw);
        settle(&mut s, eye, &mut streamed);
        assert!(s.uploaded().count() > 20, "the terrain is drawn");
        let a = tests::frame(&ctx, &mut streamed, &camera);
        let b = tests::frame(&ctx, &mut whole(&ctx, &s, draw), &camera);
        assert!(tests::distinct_colours(&a) > 50, "a real picture");
        tests::assert_close(&format!("streamed_{}", draw.name()), &a, &b, 0);
        a.save_png(&out.join(format!("streamed_{}.png", draw.name())))
            .unwrap();

        // An edit: a glass wall in front of the eye, across a chunk border.
        let ground = g.height_at(20, 0) as i32;
        for y in ground..ground + 8 {
            for z in -4..4 {
                s.set_block(WorldPos::new(31, y, z), blocks::GLASS).unwrap();
                s.set_block(WorldPos::new(32, y, z), blocks::RED_GLASS)
                    .unwrap();
            }
        }
        settle(&mut s, eye, &mut streamed);
        let look = Camera::look_at(
            eye,
            DVec3::new(32.0, ground as f64 + 3.0, 0.0),
            70.0,
            0.1,
            400.0,
        )
        .unwrap();
        let a = tests::frame(&ctx, &mut streamed, &look);
        let b = tests::frame(&ctx, &mut whole(&ctx, &s, draw), &look);
        tests::assert_close(&format!("edited_{}", draw.name()), &a, &b, 0);
    }
}

#[test]
fn streaming_away_and_back_draws_the_same() {
    let Some(ctx) = tests::gpu() else { return };
    let g = generator();
    let eye = DVec3::new(0.5, g.height_at(0, 0) as f64 + 30.0, 0.5);
    let camera = Camera::from_yaw_pitch(eye, 2.0, -0.3, 70.0, 0.1, 400.0).unwrap();
    let config = StreamConfig {
        view_distance: 3,
        vertical_distance: 2,
        max_unloads: 16,
        ..StreamConfig::default()
    };
    let mut s = ChunkStreamer::new(Arc::new(BlockRegistry::default()), g, config).unwrap();
    let mut r = renderer(&ctx, DrawMode::Indirect);
    settle(&mut s, eye, &mut r);
    let before = tests::frame(&ctx, &mut r, &camera);
    // Far enough that everything unloads (its quads freed), then back: the arena reuses
    // freed room for the new meshes.
    settle(&mut s, eye + DVec3::X * 32.0 * 40.0, &mut r);
    settle(&mut s, eye, &mut r);
    let after = tests::frame(&ctx, &mut r, &camera);
    tests::assert_close("away_and_back", &after, &before, 0);
}

/// Small pages (a 64 KiB storage binding: 8192 quads a page) so that terrain spans many;
/// unloading most of it leaves pages nearly empty, and each frame compacts one away. The
/// picture equals that of a fresh renderer given only the chunks kept.
#[test]
fn compacting_the_arena_keeps_the_picture() {
    let Some(ctx) = tests::gpu_with_limits(|l| l.max_storage_buffer_binding_size = 64 << 10) else {
        return;
    };
    // The eye looks at the corner whose chunks are kept.
    let eye = DVec3::new(40.0, generator().height_at(40, 40) as f64 + 12.0, 40.0);
    let camera = Camera::look_at(eye, DVec3::new(90.0, 20.0, 90.0), 70.0, 0.1, 400.0).unwrap();
    let tests::Compacted {
        before,
        after,
        kept_quads,
        compacted: a,
        fresh: b,
    } = tests::compact_terrain(&ctx, &camera, |_| renderer(&ctx, DrawMode::Indirect));
    assert!(before.pages >= 4, "terrain spans several pages: {before:?}");
    assert!(
        after.pages < before.pages && after.arena_bytes < before.arena_bytes,
        "no page compacted away: {before:?} -> {after:?}"
    );
    assert_eq!(after.quad_bytes, kept_quads as u64 * 8);
    a.save_png(&tests::out_dir("stream").join("compacted.png"))
        .unwrap();
    assert!(tests::distinct_colours(&a) > 50, "a real picture");
    // Opaque quads grow by 1/64 px against cracks (`voxel_render::renderer`), so where two
    // coplanar quads meet, the one drawn first takes a pixel centre inside the sliver they
    // share; compaction changes that order. Such pixels differ by at most 1/255 here.
    tests::assert_close("compacted", &a, &b, 1);
}

/// The streamer's contract on a real renderer: edits near the eye, on the
/// outer face of the chunk at the view-distance edge, on the chunk past the margin next to
/// a drawn one, and far away; the eye flies two chunks away and back (the edge chunk's
/// outer neighbour passes the margin) and far away and back. Once idle, the streamed
/// picture equals that of a fresh renderer given fresh meshes of the true world (the
/// generator's terrain with every edit), and the chunks drawn are exactly those within
/// the view distance whose true meshes are not empty.
#[test]
fn streamed_edits_everywhere_draw_like_the_true_world() {
    let Some(ctx) = tests::gpu() else { return };
    let g = generator();
    let registry = Arc::new(BlockRegistry::default());
    let config = StreamConfig {
        view_distance: 3,
        vertical_distance: 1,
        hysteresis: 1,
        ..StreamConfig::default()
    };
    let mut s = ChunkStreamer::new(registry.clone(), g.clone(), config).unwrap();
    let mut streamed = renderer(&ctx, DrawMode::Indirect);
    let ground = |x: i32, z: i32| g.height_at(i64::from(x), i64::from(z)) as i32;
    let home = DVec3::new(16.0, f64::from(ground(16, 16)) + 20.0, 16.0);
    settle(&mut s, home, &mut streamed);
    let mut edits: Vec<(WorldPos, voxel_core::BlockId)> = Vec::new();
    let mut edit = |s: &mut ChunkStreamer, at: WorldPos, id| {
        s.set_block(at, id).unwrap();
        edits.push((at, id));
    };
    // A glass wall across the border of two chunks near the eye.
    for y in 0..6 {
        for z in 4..12 {
            let base = ground(31, z);
            edit(&mut s, WorldPos::new(31, base + y, z), blocks::GLASS);
            edit(&mut s, WorldPos::new(32, base + y, z), blocks::RED_GLASS);
        }
    }
    // Two chunks away and back: the outer neighbour of the edge chunk passes the margin.
    settle(&mut s, home - DVec3::X * 64.0, &mut streamed);
    settle(&mut s, home, &mut streamed);
    // The outer face of the chunk at the view-distance edge, and the chunk past it.
    for z in 0..32 {
        let at = WorldPos::new(3 * 32 + 31, ground(3 * 32 + 31, z) + 1, z);
        edit(&mut s, at, blocks::BLUE_GLASS);
        let beyond = WorldPos::new(4 * 32, ground(4 * 32, z) + 2, z);
        edit(&mut s, beyond, blocks::STONE);
    }
    // Far away, not loaded.
    edit(
        &mut s,
        WorldPos::new(40 * 32 + 5, ground(40 * 32 + 5, 9) + 1, 9),
        blocks::ICE,
    );
    settle(&mut s, home, &mut streamed);
    settle(&mut s, home + DVec3::X * 32.0 * 40.0, &mut streamed);
    settle(&mut s, home, &mut streamed);

    // The true world around the eye: the generator's chunks with every edit, in order.
    let centre = ChunkPos::new(0, (home.y / 32.0).floor() as i32, 0);
    let mut truth = voxel_core::World::new(registry);
    for x in -6..=6 {
        for y in centre.y - 3..=centre.y + 3 {
            for z in -6..=6 {
                let p = ChunkPos::new(x, y, z);
                truth.insert_chunk(p, g.generate_chunk(p)).unwrap();
            }
        }
    }
    for &(at, id) in &edits {
        if truth.chunk(at.split().0).is_some() {
            truth.set_block(at, id).unwrap();
        }
    }
    let wanted: Vec<ChunkPos> = (-3..=3)
        .flat_map(|x| (-3..=3).map(move |z| (x, z)))
        .filter(|(x, z)| x * x + z * z <= 9)
        .flat_map(|(x, z)| (-1..=1).map(move |dy| ChunkPos::new(x, centre.y + dy, z)))
        .collect();
    let drawn: std::collections::HashSet<ChunkPos> = s.uploaded().collect();
    let true_meshes = voxel_mesh::mesh_chunks(&truth, &wanted).unwrap();
    let should: std::collections::HashSet<ChunkPos> = true_meshes
        .iter()
        .filter(|(_, m)| !m.is_empty())
        .map(|(p, _)| *p)
        .collect();
    assert_eq!(
        drawn
            .iter()
            .filter(|p| wanted.contains(p))
            .copied()
            .collect::<std::collections::HashSet<_>>(),
        should
    );
    let held: Vec<ChunkPos> = drawn.iter().copied().collect();
    let mut fresh = renderer(&ctx, DrawMode::Indirect);
    for (pos, m) in voxel_mesh::mesh_chunks(&truth, &held).unwrap() {
        fresh.upload_chunk(pos, &m).unwrap();
    }
    let edge_eye = DVec3::new(90.0, f64::from(ground(100, 16)) + 25.0, 30.0);
    let edge = DVec3::new(3.0 * 32.0 + 31.0, f64::from(ground(127, 16)) + 1.0, 16.0);
    let wall = DVec3::new(32.0, f64::from(ground(32, 8)) + 3.0, 8.0);
    for (name, eye, target) in [("edge", edge_eye, edge), ("wall", home, wall)] {
        let look = Camera::look_at(eye, target, 70.0, 0.1, 400.0).unwrap();
        let a = tests::frame(&ctx, &mut streamed, &look);
        let b = tests::frame(&ctx, &mut fresh, &look);
        assert!(tests::distinct_colours(&a) > 50, "a real picture");
        tests::assert_close(&format!("stream_truth_{name}"), &a, &b, 0);
    }
}

/// A sink that keeps which chunks it holds (no GPU).
#[derive(Default)]
struct Held(std::collections::HashSet<ChunkPos>);

impl voxel_render::ChunkSink for Held {
    fn upload(&mut self, pos: ChunkPos, _: &voxel_mesh::ChunkMeshes) -> voxel_render::Result<()> {
        self.0.insert(pos);
        Ok(())
    }
    fn remove(&mut self, pos: ChunkPos) {
        self.0.remove(&pos);
    }
}

/// Updates until idle; checks that each update's `uploaded` names what reached the sink.
fn settle_held(s: &mut ChunkStreamer, eye: DVec3, sink: &mut Held) {
    for _ in 0..100_000 {
        let before = sink.0.clone();
        let f = s.update(eye, sink).unwrap();
        assert!(f.failed.is_empty(), "{:?}", f.failed);
        assert_eq!(f.uploaded.len(), f.uploads, "one position per upload");
        for p in &f.uploaded {
            assert!(
                sink.0.contains(p) || before.contains(p),
                "{p:?} never reached the sink"
            );
        }
        if s.is_idle() {
            return;
        }
        std::thread::sleep(std::time::Duration::from_micros(300));
    }
    panic!("the streamer never settled: {s:?}");
}

/// A game saves the streamer's edits (loaded and unloaded chunks alike) and loads
/// them into a new streamer: the same edits, and the same blocks wherever it loads, near
/// and far; a save naming a block the registry lacks is refused whole.
#[test]
fn saved_edits_load_back_into_the_same_world() {
    let g = generator();
    let registry = Arc::new(BlockRegistry::default());
    let config = StreamConfig {
        view_distance: 2,
        vertical_distance: 1,
        hysteresis: 1,
        ..StreamConfig::default()
    };
    let ground = |x: i32, z: i32| g.height_at(i64::from(x), i64::from(z)) as i32;
    let home = DVec3::new(16.0, f64::from(ground(16, 16)) + 20.0, 16.0);
    let far = home + DVec3::X * 32.0 * 20.0;
    let mut a = ChunkStreamer::new(registry.clone(), g.clone(), config).unwrap();
    let mut sink = Held::default();
    settle_held(&mut a, home, &mut sink);
    for z in 0..40 {
        a.set_block(WorldPos::new(20, ground(20, z) + 1, z), blocks::GLASS)
            .unwrap();
    }
    // Unloaded: 20 chunks east.
    let fx = 20 * 32 + 7;
    a.set_block(WorldPos::new(fx, ground(fx, 9) + 1, 9), blocks::ICE)
        .unwrap();
    let saved: Vec<_> = a.edits().collect();
    assert_eq!(saved.len(), 41);

    let mut b = ChunkStreamer::new(registry.clone(), g.clone(), config).unwrap();
    let bad = [(WorldPos::new(0, 0, 0), voxel_core::BlockId(9999))];
    assert!(b.restore_edits(saved.iter().copied().chain(bad)).is_err());
    assert_eq!(b.edits().count(), 0, "a refused save restores nothing");
    b.restore_edits(saved.iter().copied()).unwrap();
    let mut restored: Vec<_> = b.edits().collect();
    let mut want = saved.clone();
    restored.sort_by_key(|(p, _)| (p.x, p.y, p.z));
    want.sort_by_key(|(p, _)| (p.x, p.y, p.z));
    assert_eq!(restored, want);
    let mut sink_b = Held::default();
    settle_held(&mut b, home, &mut sink_b);
    let (near, far_edits): (Vec<_>, Vec<_>) = saved.iter().partition(|(at, _)| at.x < 600);
    assert_eq!((near.len(), far_edits.len()), (40, 1));
    for &(at, id) in &near {
        assert_eq!(b.world().get_block(at), id, "{at:?}");
    }
    assert_eq!(sink_b.0, sink.0, "the same chunks drawn");
    let mut compared = 0;
    for (pos, _) in a.world().iter() {
        if !b.is_resident(pos) {
            continue;
        }
        let o = pos.origin().map(|v| v as i32);
        for i in 0..32 * 32 * 32 {
            let at = WorldPos::new(o[0] + i % 32, o[1] + i / 32 % 32, o[2] + i / 1024);
            assert_eq!(b.world().get_block(at), a.world().get_block(at), "{at:?}");
        }
        compared += 1;
    }
    assert!(compared > 20, "{compared} chunks compared");
    // The far edit, once there.
    settle_held(&mut b, far, &mut sink_b);
    let (at, id) = far_edits[0];
    assert_eq!(b.world().get_block(at), id);
}
