//! The quad arena under a frame in flight: no frame draws a page state that
//! compaction or an upload changed after the frame's lists were built, for every
//! technique (sorted-quads' first sort included), each compared with a fresh renderer
//! given the same chunks; a mesh larger than a storage binding is an error; pages left
//! empty are given back.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use glam::DVec3;
use voxel_core::{BlockId, ChunkPos, Face, blocks};
use voxel_mesh::{ChunkMeshes, PackedQuad};
use voxel_render::low_level::MeshKind;
use voxel_render::{Camera, GpuContext, NoGame, Renderer, Technique};

use tests::*;

const SIZE: (u32, u32) = (96, 64);
/// 64 KiB storage bindings: pages of 8192 quads, so that a few small meshes span pages.
const PAGE_QUADS: usize = 8192;

fn small_pages() -> Option<GpuContext> {
    gpu_with_limits(|l| l.max_storage_buffer_binding_size = (PAGE_QUADS * 8) as u64)
}

/// Crossing sheets of four glass colours over a stone floor, in two chunks: seen from
/// +z or -z, their right order differs from the order the mesher emits them in.
fn sheets(extra: bool) -> voxel_core::World {
    let mut boxes = vec![
        ([0, 0, 0], [40, 0, 24], blocks::STONE),
        ([4, 2, 6], [36, 14, 6], blocks::RED_GLASS),
        ([4, 2, 12], [36, 14, 12], blocks::BLUE_GLASS),
        ([10, 2, 3], [10, 14, 20], blocks::GREEN_GLASS),
        ([28, 2, 3], [28, 14, 20], blocks::GLASS),
        ([4, 8, 3], [36, 8, 20], blocks::WATER),
    ];
    if extra {
        // The edited version: a stone pillar and another sheet.
        boxes.push(([20, 1, 9], [22, 12, 10], blocks::STONE));
        boxes.push(([4, 2, 17], [36, 14, 17], blocks::ICE));
    }
    box_world(&boxes)
}

fn meshes_of(world: &voxel_core::World) -> Vec<(ChunkPos, ChunkMeshes)> {
    let all: Vec<ChunkPos> = world.iter().map(|(p, _)| p).collect();
    voxel_mesh::mesh_chunks(world, &all).unwrap()
}

/// `n` opaque quads in a chunk far below every camera here (never visible).
fn filler(i: i32, n: usize) -> (ChunkPos, ChunkMeshes) {
    let quad = PackedQuad::new([0, 0, 0], 1, 1, Face::PosY, blocks::STONE);
    let meshes = ChunkMeshes {
        opaque: vec![quad; n],
        ..Default::default()
    };
    (ChunkPos::new(i, -100, 0), meshes)
}

fn camera(from_front: bool) -> Camera {
    let (eye, target) = if from_front {
        (DVec3::new(20.5, 9.0, 40.0), DVec3::new(20.5, 7.0, 10.0))
    } else {
        (DVec3::new(20.5, 9.0, -18.0), DVec3::new(20.5, 7.0, 10.0))
    };
    Camera::look_at(eye, target, 60.0, 0.1, 500.0).unwrap()
}

fn new_renderer(ctx: &GpuContext, technique: Technique) -> Renderer {
    Renderer::new(
        ctx,
        &voxel_core::BlockRegistry::default(),
        technique_config(technique, SIZE.0, SIZE.1),
    )
    .unwrap()
}

fn fresh(ctx: &GpuContext, technique: Technique, chunks: &[(ChunkPos, ChunkMeshes)]) -> Renderer {
    let mut r = new_renderer(ctx, technique);
    for (pos, m) in chunks {
        r.upload_chunk(*pos, m).unwrap();
    }
    r
}

/// A renderer whose next frame compacts the page holding the sheets: they go up first
/// (page 0), fillers of 1000 quads fill page 0 and two more pages, then the fillers of
/// page 0 leave. Returns it and the fillers kept.
fn about_to_compact(
    ctx: &GpuContext,
    technique: Technique,
    kept: &[(ChunkPos, ChunkMeshes)],
) -> (Renderer, Vec<(ChunkPos, ChunkMeshes)>) {
    let mut r = fresh(ctx, technique, kept);
    let fillers: Vec<_> = (0..16).map(|i| filler(i, 1000)).collect();
    for (pos, m) in &fillers {
        r.upload_chunk(*pos, m).unwrap();
    }
    let page = |r: &Renderer, pos| {
        voxel_render::low_level::chunks(r)
            .get(pos)
            .unwrap()
            .mesh(MeshKind::Opaque)
    };
    let mut left = Vec::new();
    for (pos, m) in fillers {
        if page(&r, pos).unwrap().page == 0 {
            r.remove_chunk(pos);
        } else {
            left.push((pos, m));
        }
    }
    let memory = r.chunk_memory();
    assert_eq!(memory.pages, 3, "{memory:?}");
    for (pos, _) in kept {
        let c = voxel_render::low_level::chunks(&r).get(*pos).unwrap();
        for kind in [MeshKind::Opaque, MeshKind::Translucent] {
            assert!(c.mesh(kind).is_none_or(|a| a.page == 0), "{pos:?} {kind:?}");
        }
    }
    (r, left)
}

fn check(name: &str, technique: Technique, actual: &Image, expected: &Image) {
    // `opaque-only` draws the floor alone: sky and a few shades of stone.
    let least = if technique.draws() { 12 } else { 3 };
    assert!(
        distinct_colours(expected) >= least,
        "{name}: a real picture ({} colours)",
        distinct_colours(expected)
    );
    // The same chunks, meshes and quad order: the same picture, bit for bit.
    assert_close(name, actual, expected, 0);
}

use voxel_render::Image;

/// Compaction runs in the very first frame, the one in which `sorted-quads` sorts the
/// moved chunks for the first time (its writes must land after the copy, not under it);
/// this frame and the next equal a fresh renderer's, for every technique and from both
/// sides.
#[test]
fn compaction_in_a_first_frame_keeps_every_technique_exact() {
    let Some(ctx) = small_pages() else { return };
    let kept = meshes_of(&sheets(false));
    let quads: usize = kept.iter().map(|(_, m)| m.len()).sum();
    assert!(quads < 1000, "the sheets fit one filler's room: {quads}");
    for technique in Technique::ALL {
        for from_front in [true, false] {
            let cam = camera(from_front);
            let (mut r, left) = about_to_compact(&ctx, technique, &kept);
            let name = format!("arena_first_sort_{}_{from_front}", technique.name());
            let first = frame(&ctx, &mut r, &cam);
            let memory = r.chunk_memory();
            assert_eq!(memory.pages, 2, "page 0 compacted away: {memory:?}");
            let moved = voxel_render::low_level::chunks(&r).get(kept[0].0).unwrap();
            assert!(
                moved
                    .mesh(MeshKind::Translucent)
                    .is_some_and(|a| a.page != 0)
            );
            let mut same: Vec<_> = kept.clone();
            same.extend(left);
            let expected = frame(&ctx, &mut fresh(&ctx, technique, &same), &cam);
            check(&name, technique, &first, &expected);
            let second = frame(&ctx, &mut r, &cam);
            check(&format!("{name}_next"), technique, &second, &expected);
        }
    }
}

/// Compaction, then before the frame is submitted a moved chunk is re-uploaded with new
/// meshes, a chunk removed and a new one uploaded (which would take the removed chunk's
/// slot and places if they were free): the frame draws what its lists were built from,
/// the next frame the new state, both equal to fresh renderers, for every technique.
#[test]
fn uploads_before_the_submit_never_change_the_frame_in_flight() {
    let Some(ctx) = small_pages() else { return };
    let old = meshes_of(&sheets(false));
    let new = meshes_of(&sheets(true));
    let cam = camera(true);
    // A chunk beside the sheets that leaves, and one that comes, while the frame is in
    // flight.
    let leaving = (
        ChunkPos::new(-1, 0, 0),
        meshes_of(&box_world(&[(
            [-20, 1, 4],
            [-4, 10, 4],
            blocks::GREEN_GLASS,
        )]))
        .remove(0)
        .1,
    );
    let coming = (
        ChunkPos::new(0, 0, -1),
        meshes_of(&box_world(&[([2, 1, -6], [38, 16, -6], blocks::STONE)]))
            .remove(0)
            .1,
    );
    let mut kept = old.clone();
    kept.push(leaving.clone());
    for technique in Technique::ALL {
        let (mut r, left) = about_to_compact(&ctx, technique, &kept);
        let target = Offscreen::new(&ctx, SIZE.0, SIZE.1);
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        r.render(&mut encoder, &target.view, &cam, &mut NoGame)
            .unwrap();
        assert_eq!(r.chunk_memory().pages, 2, "compacted in this frame");
        for (pos, m) in &new {
            r.upload_chunk(*pos, m).unwrap();
        }
        r.remove_chunk(leaving.0);
        r.upload_chunk(coming.0, &coming.1).unwrap();
        ctx.queue.submit([encoder.finish()]);
        r.after_submit();
        let in_flight = target.read(&ctx).unwrap();

        let name = format!("arena_upload_in_flight_{}", technique.name());
        let mut before = kept.clone();
        before.extend(left.iter().cloned());
        let expected = frame(&ctx, &mut fresh(&ctx, technique, &before), &cam);
        check(&name, technique, &in_flight, &expected);

        let mut after = new.clone();
        after.push(coming.clone());
        after.extend(left.iter().cloned());
        let next = frame(&ctx, &mut r, &cam);
        let expected = frame(&ctx, &mut fresh(&ctx, technique, &after), &cam);
        check(&format!("{name}_next"), technique, &next, &expected);
    }
}

/// A mesh of one quad more than a page holds is refused with an error naming the limit,
/// and the chunk keeps what it had; a mesh of exactly a page is drawn.
#[test]
fn a_mesh_over_the_storage_binding_is_an_error() {
    let Some(ctx) = small_pages() else { return };
    let mut r = new_renderer(&ctx, Technique::WboitMrt);
    let pos = ChunkPos::new(0, 0, 0);
    let stone = PackedQuad::new([3, 0, 3], 1, 1, Face::PosY, blocks::STONE);
    let glass = PackedQuad::new([5, 1, 5], 1, 1, Face::PosY, blocks::GLASS);
    let small = ChunkMeshes {
        opaque: vec![stone; 10],
        ..Default::default()
    };
    r.upload_chunk(pos, &small).unwrap();
    for kind in 0..3 {
        let mut big = ChunkMeshes::default();
        let quads = vec![if kind == 2 { glass } else { stone }; PAGE_QUADS + 1];
        match kind {
            0 => big.opaque = quads,
            1 => big.cutout = quads,
            _ => big.translucent = quads,
        }
        let e = r.upload_chunk(pos, &big).unwrap_err();
        assert!(matches!(e, voxel_render::Error::TooLarge { .. }), "{e:?}");
        let msg = e.to_string();
        assert!(
            msg.contains(&(PAGE_QUADS + 1).to_string()) && msg.contains(&PAGE_QUADS.to_string()),
            "{msg}"
        );
        let c = voxel_render::low_level::chunks(&r).get(pos).unwrap();
        assert_eq!(c.mesh(MeshKind::Opaque).map(|a| a.quads), Some(10));
    }
    let full = ChunkMeshes {
        translucent: vec![glass; PAGE_QUADS],
        ..Default::default()
    };
    r.upload_chunk(pos, &full).unwrap();
    let cam = Camera::look_at(
        DVec3::new(5.5, 8.0, 12.0),
        DVec3::new(5.5, 1.0, 5.5),
        60.0,
        0.1,
        100.0,
    )
    .unwrap();
    let target = Offscreen::new(&ctx, SIZE.0, SIZE.1);
    let stats = r
        .render_and_submit(&target.view, &cam, &mut NoGame)
        .unwrap();
    assert_eq!(stats.meshes_drawn, [0, 0, 1]);
    assert_eq!(stats.translucent_quads, PAGE_QUADS);
}

/// 2000 chunks uploaded and removed, 6 rounds, with and without frames between (each
/// round's chunks overlap the last's by all but 50): once no frame is in flight, no page
/// is held with no chunk (the documented bound: 0 bytes), and every round peaks alike.
#[test]
fn empty_pages_are_given_back() {
    let Some(ctx) = gpu() else { return };
    let mut r = new_renderer(&ctx, Technique::SortedQuads);
    let quad = |i: usize| {
        PackedQuad::new(
            [i % 32, (i / 32) % 32, 0],
            1,
            1,
            Face::PosZ,
            BlockId(1 + (i % 12) as u16),
        )
    };
    let meshes: Vec<ChunkMeshes> = (0..8)
        .map(|k| ChunkMeshes {
            opaque: (0..300 + 40 * k).map(quad).collect(),
            translucent: (0..20 * k).map(|i| quad(i + 7)).collect(),
            ..Default::default()
        })
        .collect();
    let cam = Camera::look_at(
        DVec3::new(0.0, 40.0, 0.0),
        DVec3::new(300.0, 0.0, 300.0),
        60.0,
        0.1,
        2000.0,
    )
    .unwrap();
    let target = Offscreen::new(&ctx, SIZE.0, SIZE.1);
    let mut peak = Vec::new();
    for round in 0..6 {
        let positions: Vec<ChunkPos> = (0..2000)
            .map(|i| ChunkPos::new(i % 50, 0, i / 50 + round))
            .collect();
        for (i, pos) in positions.iter().enumerate() {
            r.upload_chunk(*pos, &meshes[i % meshes.len()]).unwrap();
        }
        let held = r.chunk_memory();
        assert!(held.pages >= 2, "{held:?}");
        peak.push(held.arena_bytes);
        let with_frame = round % 2 == 1;
        if with_frame {
            r.render_and_submit(&target.view, &cam, &mut NoGame)
                .unwrap();
            // A frame in flight: what it draws is kept until it is submitted.
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            r.render(&mut encoder, &target.view, &cam, &mut NoGame)
                .unwrap();
            for pos in &positions {
                r.remove_chunk(*pos);
            }
            assert!(r.chunk_memory().arena_bytes > 0, "freed under the frame");
            ctx.queue.submit([encoder.finish()]);
            r.after_submit();
        } else {
            for pos in &positions {
                r.remove_chunk(*pos);
            }
        }
        let empty = r.chunk_memory();
        assert_eq!(
            (empty.pages, empty.arena_bytes, empty.quad_bytes),
            (0, 0, 0),
            "round {round}: {empty:?}"
        );
    }
    assert!(peak.iter().all(|&b| b == peak[0]), "{peak:?}");
    // And the renderer still draws.
    let (pos, m) = &meshes_of(&sheets(false))[0];
    r.upload_chunk(*pos, m).unwrap();
    let img = frame(&ctx, &mut r, &camera(true));
    assert!(distinct_colours(&img) > 8);
}
