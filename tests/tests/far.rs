//! Far views in levels of detail (issue 50): a chunk of a level is drawn where its cells
//! are, its water reads as the fine water it replaces, every technique draws level
//! geometry (`sorted-quads` as the A-buffer does), and the far view of the default terrain
//! against full detail of the same view: no holes, the far ground's and water's colour.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use glam::DVec3;
use tests::{Offscreen, diff, frame, gpu, out_dir, technique_config};
use voxel_core::{BlockRegistry, Chunk, ChunkPos, TerrainConfig, TerrainGenerator, blocks};
use voxel_lab::far;
use voxel_mesh::Mesher;
use voxel_mesh::levels::LevelRings;
use voxel_render::{Camera, Image, Renderer, Technique, level_key};

/// A chunk of level `level` (over the default registry) holding `cells` (inclusive
/// corners, cells) of `id`, and the full-detail world holding the same blocks.
fn level_box_and_fine(
    level: u8,
    min: [usize; 3],
    max: [usize; 3],
    id: voxel_core::BlockId,
) -> (Chunk, voxel_core::World) {
    let mut chunk = Chunk::default();
    chunk.fill_box(min, max, id).unwrap();
    let s = voxel_core::level_scale(level) as i32;
    let lo = [min[0] as i32 * s, min[1] as i32, min[2] as i32 * s];
    let hi = [
        (max[0] as i32 + 1) * s - 1,
        max[1] as i32,
        (max[2] as i32 + 1) * s - 1,
    ];
    (chunk, tests::box_world(&[(lo, hi, id)]))
}

/// Draws a level chunk at level `level`, position 0, with `technique`, from `camera`.
fn draw_level(
    ctx: &voxel_render::GpuContext,
    chunk: &Chunk,
    level: u8,
    technique: Technique,
    camera: &Camera,
) -> Image {
    let registry = BlockRegistry::default();
    let mut renderer =
        Renderer::new(ctx, &registry, technique_config(technique, 320, 180)).unwrap();
    let meshes = Mesher::new(&registry)
        .mesh(chunk, voxel_core::Neighbourhood::default())
        .unwrap();
    renderer
        .upload_level_chunk(level, ChunkPos::new(0, 0, 0), &meshes)
        .unwrap();
    frame(ctx, &mut renderer, camera)
}

#[test]
fn a_level_chunk_is_drawn_where_its_cells_are_and_its_water_reads_as_fine_water() {
    let Some(ctx) = gpu() else { return };
    let camera = Camera::look_at(
        DVec3::new(-14.0, 22.0, -9.0),
        DVec3::new(12.0, 3.0, 10.0),
        60.0,
        0.1,
        500.0,
    )
    .unwrap();
    let dir = out_dir("far/level-chunk");
    for (name, id, techniques) in [
        ("stone", blocks::STONE, vec![Technique::SortedQuads]),
        (
            "water",
            blocks::WATER,
            vec![
                Technique::SortedQuads,
                Technique::Reference,
                Technique::WboitMrt,
            ],
        ),
        ("glass", blocks::RED_GLASS, vec![Technique::SortedQuads]),
    ] {
        // Level 2: cells of 4 × 1 × 4 blocks; a box of 5 × 3 × 4 cells is 20 × 3 × 16
        // blocks, drawn as the full-detail box of those blocks is.
        let (chunk, world) = level_box_and_fine(2, [1, 2, 0], [5, 4, 3], id);
        for technique in techniques {
            let coarse = draw_level(&ctx, &chunk, 2, technique, &camera);
            let scene = tests::scene(name, world.clone(), [0.0; 3], [1.0; 3]);
            let mut renderer =
                tests::renderer_for(&ctx, &scene, technique_config(technique, 320, 180)).unwrap();
            let fine = frame(&ctx, &mut renderer.renderer, &camera);
            coarse
                .save_png(&dir.join(format!("{name}-{technique}-level.png")))
                .unwrap();
            fine.save_png(&dir.join(format!("{name}-{technique}-fine.png")))
                .unwrap();
            let d = diff(&coarse, &fine);
            let drawn = tests::distinct_colours(&fine);
            assert!(drawn > 4, "{name}: the box is not in the picture");
            // The same quads at the same places: at most rounding apart (the coarse box's
            // quads are the fine box's merged quads, scaled).
            assert!(
                d.max <= 1,
                "{name} with {technique}: the level chunk differs by {}/255 on {} pixels from \
                 the fine blocks it stands for; see {}",
                d.max,
                d.over_one,
                dir.display()
            );
        }
    }
    // Bad levels and positions are errors, not panics.
    let registry = BlockRegistry::default();
    let mut renderer = Renderer::new(
        &ctx,
        &registry,
        technique_config(Technique::SortedQuads, 8, 8),
    )
    .unwrap();
    let empty = voxel_mesh::ChunkMeshes::default();
    assert!(
        renderer
            .upload_level_chunk(voxel_core::MAX_LEVEL + 1, ChunkPos::new(0, 0, 0), &empty)
            .is_err()
    );
    assert!(
        renderer
            .upload_level_chunk(6, ChunkPos::new(ChunkPos::MAX, 0, 0), &empty)
            .is_err()
    );
    assert_eq!(
        level_key(3, ChunkPos::new(-2, 1, 5)),
        Some(ChunkPos::new(-16, 1, 40))
    );
}

/// The default far view, small: full detail to 8 chunks, levels to 32.
fn small_rings() -> LevelRings {
    LevelRings::reaching(8, 32)
}

#[test]
fn every_technique_draws_level_geometry_and_sorted_quads_as_the_a_buffer_does() {
    let Some(ctx) = gpu() else { return };
    let generator = TerrainGenerator::new(TerrainConfig::default());
    let registry = BlockRegistry::default();
    let rings = small_rings();
    assert_eq!((rings.coarsest, rings.view_distance()), (2, 32));
    let camera = far::default_view(&generator).unwrap();
    let meshes = far::build(&generator, &registry, &rings, &camera).unwrap();
    let (w, h) = (480, 270);
    let mut renderer = Renderer::new(
        &ctx,
        &registry,
        technique_config(Technique::Reference, w, h),
    )
    .unwrap();
    far::upload(&mut renderer, &meshes).unwrap();
    let target = Offscreen::new(&ctx, w, h);
    let reference = far::picture(&ctx, &mut renderer, &target, &camera).unwrap();
    let dir = out_dir("far/techniques");
    reference.save_png(&dir.join("reference.png")).unwrap();
    renderer.set_technique(Technique::OpaqueOnly).unwrap();
    let dry = far::picture(&ctx, &mut renderer, &target, &camera).unwrap();
    // Water and glass are drawn: the reference differs from the picture without them.
    let wet = diff(&reference, &dry).over_one;
    assert!(
        wet > (w * h / 50) as usize,
        "hardly any water drawn: {wet} pixels"
    );
    for technique in Technique::supported(&ctx.caps) {
        if matches!(technique, Technique::Reference | Technique::OpaqueOnly) {
            continue;
        }
        renderer.set_technique(technique).unwrap();
        let image = far::picture(&ctx, &mut renderer, &target, &camera).unwrap();
        image
            .save_png(&dir.join(format!("{technique}.png")))
            .unwrap();
        let d = diff(&image, &reference);
        let over_8 = image
            .rgba
            .chunks_exact(4)
            .zip(reference.rgba.chunks_exact(4))
            .filter(|(p, q)| (0..3).any(|c| p[c].abs_diff(q[c]) > 8))
            .count();
        let share = over_8 as f64 / f64::from(w * h);
        println!(
            "{technique}: {} pixels off by more than 1/255, {over_8} ({:.3} %) by more than 8, at most {}/255",
            d.over_one,
            share * 100.0,
            d.max
        );
        // Every technique draws the water of the levels (its picture is not the dry one).
        assert!(
            diff(&image, &dry).over_one > wet / 2,
            "{technique} does not draw the levels' water"
        );
        if matches!(technique, Technique::SortedQuads | Technique::PeelReference) {
            assert!(
                share <= 0.001,
                "{technique}: {:.3} % of pixels off the A-buffer by more than 8/255; see {}",
                share * 100.0,
                dir.display()
            );
        }
    }
}

#[test]
fn the_far_view_against_full_detail_has_no_holes_and_the_far_colours_of_full_detail() {
    let Some(ctx) = gpu() else { return };
    let generator = TerrainGenerator::new(TerrainConfig::default());
    let registry = BlockRegistry::default();
    let rings = small_rings();
    let camera = far::default_view(&generator).unwrap();
    let levels = far::build(&generator, &registry, &rings, &camera).unwrap();
    let full_rings = LevelRings {
        radius: 32,
        coarsest: 0,
        finest: 0,
        y: rings.y.clone(),
    };
    let full = far::build(&generator, &registry, &full_rings, &camera).unwrap();
    let (w, h) = (640, 360);
    let mut renderer = Renderer::new(
        &ctx,
        &registry,
        technique_config(Technique::SortedQuads, w, h),
    )
    .unwrap();
    let target = Offscreen::new(&ctx, w, h);
    let dir = out_dir("far/against-full-detail");
    let c = far::compare(
        &ctx,
        &mut renderer,
        &target,
        &camera,
        &levels,
        &full,
        &rings,
        &dir,
    )
    .unwrap();
    println!("{c:#?}");
    println!(
        "far water step {:.2}/255, far ground step {:.2}/255",
        c.water_step(),
        c.ground_step()
    );
    assert!(c.far_pixels > 0.01, "the levels are hardly in the picture");
    assert!(c.far_water_pixels > 0.001, "no far water in the picture");
    assert!(
        c.holes <= 0.0001,
        "holes on {:.4} % of pixels; see {}",
        c.holes * 100.0,
        dir.display()
    );
    assert!(
        c.skyline <= 0.005,
        "the skyline differs on {:.3} %",
        c.skyline * 100.0
    );
    assert!(
        c.ground_step() <= 2.0,
        "far ground {:.2}/255 off",
        c.ground_step()
    );
    assert!(
        c.water_step() <= 3.0,
        "far water {:.2}/255 off",
        c.water_step()
    );
}

/// Each full-detail chunk column of `drawn` (level, position) counted: every one once.
fn assert_tiles_once(drawn: &[(u8, ChunkPos)], what: &str) {
    let mut cover = std::collections::HashMap::<[i64; 3], u32>::new();
    for &(l, p) in drawn {
        let s = voxel_core::level_scale(l);
        for dx in 0..s {
            for dz in 0..s {
                *cover
                    .entry([
                        i64::from(p.x) * s + dx,
                        i64::from(p.y),
                        i64::from(p.z) * s + dz,
                    ])
                    .or_default() += 1;
            }
        }
    }
    assert!(
        cover.values().all(|&n| n == 1),
        "{what}: a place drawn twice"
    );
}

/// A far field of the default terrain with full detail to 4 chunks and levels to 32
/// (`upload_budget` bytes a swap update), a `sorted-quads` renderer of `w` × `h` and the
/// default far view.
fn field_and_renderer(
    ctx: &voxel_render::GpuContext,
    upload_budget: u64,
    (w, h): (u32, u32),
) -> (voxel_render::far::FarField, Renderer, Camera) {
    use std::sync::Arc;
    use voxel_render::far::{FarConfig, FarField};
    let generator = Arc::new(TerrainGenerator::new(TerrainConfig::default()));
    let registry = Arc::new(BlockRegistry::default());
    let config = FarConfig {
        rings: LevelRings::reaching(4, 32),
        upload_budget,
        ..FarConfig::default()
    };
    assert_eq!(config.rings.coarsest, 3);
    let field = FarField::new(Arc::clone(&generator), Arc::clone(&registry), config).unwrap();
    let renderer = Renderer::new(
        ctx,
        &registry,
        technique_config(Technique::SortedQuads, w, h),
    )
    .unwrap();
    (field, renderer, far::default_view(&generator).unwrap())
}

#[test]
fn a_far_field_is_built_coarse_first_off_the_frame_and_follows_the_eye() {
    use voxel_render::far::FarField;
    let Some(ctx) = gpu() else { return };
    let (w, h) = (480, 270);
    // A small upload budget, so that a swap takes several updates, a square at a time.
    let (mut field, mut renderer, camera) = field_and_renderer(&ctx, 256 << 10, (w, h));
    let dir = out_dir("far/field");
    // Updates until a view with `finest` level 0 is drawn, or 120 s; the finest level of
    // each view swapped in, and the updates' longest time.
    let run = |field: &mut FarField, renderer: &mut Renderer, eye: DVec3, what: &str| {
        let start = std::time::Instant::now();
        let mut swaps = Vec::new();
        let mut longest = 0f64;
        loop {
            let t = std::time::Instant::now();
            let s = field.update(renderer, eye).unwrap();
            longest = longest.max(t.elapsed().as_secs_f64() * 1e3);
            if s.swapped {
                swaps.push((s.drawn_finest.unwrap(), s.swap_bytes));
                let drawn: Vec<_> = field.drawn().collect();
                assert_tiles_once(&drawn, what);
                // The renderer holds the field's chunks (those with a face: an empty mesh is
                // not kept), and nothing else.
                let held = voxel_render::low_level::chunks(renderer).len();
                assert!(
                    held <= drawn.len() && held * 4 > drawn.len() * 3,
                    "{what}: the renderer holds {held} chunks, the field drew {}",
                    drawn.len()
                );
                let cam = Camera { eye, ..camera };
                let target = Offscreen::new(&ctx, w, h);
                let image = far::picture(&ctx, renderer, &target, &cam).unwrap();
                image
                    .save_png(&dir.join(format!("{what}-{}.png", swaps.len())))
                    .unwrap();
                if s.drawn_finest == Some(0) {
                    break;
                }
            }
            assert!(
                start.elapsed().as_secs() < 120,
                "{what}: not finished in 120 s"
            );
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        println!(
            "{what}: views drawn (finest level, bytes uploaded) {swaps:?}; longest update {longest:.1} ms"
        );
        swaps
    };
    // From nothing: the coarsest level alone first, then one level finer at a time.
    let first = run(&mut field, &mut renderer, camera.eye, "start");
    assert_eq!(
        first.iter().map(|s| s.0).collect::<Vec<_>>(),
        [3, 2, 1, 0],
        "not built coarse first"
    );
    let total: u64 = first.iter().map(|s| s.1).sum();
    // Within the hysteresis the view stays.
    let near = camera.eye + DVec3::new(10.0, 0.0, -10.0);
    for _ in 0..20 {
        let s = field.update(&mut renderer, near).unwrap();
        assert!(
            !s.swapped && s.missing == 0,
            "replanned within the hysteresis: {s:?}"
        );
    }
    // Past it, the finished view around the eye, built from what is drawn: only the
    // chunks that changed are uploaded.
    let moved = run(
        &mut field,
        &mut renderer,
        camera.eye + DVec3::new(70.0, 0.0, 0.0),
        "moved",
    );
    assert_eq!(
        moved.len(),
        1,
        "a step of the eye rebuilt the view coarse first"
    );
    assert!(
        moved[0].1 * 2 < total,
        "a step of the eye uploaded {} bytes of {total}",
        moved[0].1
    );
    // A jump far away: coarse first again.
    let far_eye = camera.eye + DVec3::new(100_000.0, 0.0, 0.0);
    let jumped = run(&mut field, &mut renderer, far_eye, "jumped");
    assert_eq!(jumped[0].0, 3, "after a jump the horizon comes first");
    // A NaN eye changes nothing.
    let before: Vec<_> = field.drawn().collect();
    let s = field.update(&mut renderer, DVec3::NAN).unwrap();
    assert!(!s.swapped);
    assert_eq!(field.drawn().collect::<Vec<_>>(), before);
}

#[test]
fn an_edit_reaches_every_drawn_level_within_a_bounded_time_and_stays_through_rebuilds() {
    use voxel_core::{BlockId, WorldPos};
    use voxel_render::far::{FarConfig, FarField};
    let Some(ctx) = gpu() else { return };
    let (w, h) = (480, 270);
    let budget = FarConfig::default().upload_budget;
    let (mut field, mut renderer, camera) = field_and_renderer(&ctx, budget, (w, h));
    let target = Offscreen::new(&ctx, w, h);
    let dir = out_dir("far/edit");
    // Updates at `eye` until the field is idle, or 120 s; the updates it took, and seconds.
    let settle = |field: &mut FarField, renderer: &mut Renderer, eye: DVec3| {
        let start = std::time::Instant::now();
        for n in 1.. {
            let s = field.update(renderer, eye).unwrap();
            if field.is_idle() {
                assert_eq!(s.edit_chunks_pending, 0);
                return (n, start.elapsed().as_secs_f64());
            }
            assert!(
                start.elapsed().as_secs() < 120,
                "not settled in 120 s: {s:?}"
            );
            std::thread::sleep(std::time::Duration::from_millis(2));
        }
        unreachable!()
    };
    settle(&mut field, &mut renderer, camera.eye);
    // Every level holds quads, and the levels' chunks are the drawn ones.
    let memory = field.memory();
    assert_eq!(memory.len(), 4);
    assert!(memory.iter().all(|m| m.quads > 0), "{memory:?}");
    assert_eq!(
        memory.iter().map(|m| m.chunks).sum::<usize>(),
        field.drawn().count()
    );
    let before = far::picture(&ctx, &mut renderer, &target, &camera).unwrap();
    before.save_png(&dir.join("before.png")).unwrap();

    // An unknown block changes nothing.
    assert!(
        field
            .set_block(WorldPos::new(0, 30, 0), BlockId(9999))
            .is_err()
    );
    // Two stone pillars ahead of the eye: one in the full-detail ring, one 700 blocks away,
    // on a sample column of the level drawn there.
    let ahead = camera.forward.with_y(0.0).normalize();
    let near = camera.eye + ahead * 40.0;
    let far_at = camera.eye + ahead * 700.0;
    let chunk_of =
        |v: f64, level: u8| (v / (32.0 * voxel_core::level_scale(level) as f64)).floor() as i32;
    let level = field
        .drawn()
        .find(|&(l, p)| p.x == chunk_of(far_at.x, l) && p.z == chunk_of(far_at.z, l))
        .map(|(l, _)| l)
        .unwrap();
    assert!(level >= 2, "700 blocks away at level {level}");
    let s = voxel_core::level_scale(level);
    let sample = |v: f64| ((v / s as f64).floor() as i64 * s + s / 2) as i32;
    let pillars = [
        (near.x.floor() as i32, near.z.floor() as i32),
        (sample(far_at.x), sample(far_at.z)),
    ];
    for (x, z) in pillars {
        for y in 10..=62 {
            field
                .set_block(WorldPos::new(x, y, z), blocks::STONE)
                .unwrap();
        }
    }
    let (updates, secs) = settle(&mut field, &mut renderer, camera.eye);
    let edited = far::picture(&ctx, &mut renderer, &target, &camera).unwrap();
    edited.save_png(&dir.join("edited.png")).unwrap();
    println!(
        "the edits drawn after {updates} updates ({:.0} ms); level {level} 700 blocks away",
        secs * 1e3
    );
    // Both pillars show: pixels changed around each one's place in the picture.
    let vp = camera.view_proj(f64::from(w) / f64::from(h));
    // Pixels changed in the screen box of the pillar at `p` (its top and its foot, 10
    // pixels either side), clipped to the picture.
    let changed_near = |p: DVec3| {
        let screen = |y: f64| {
            let c = vp * (p.with_y(y) - camera.eye).as_vec3().extend(1.0);
            assert!(c.w > 0.0, "the pillar is behind the eye");
            let ndc = c.truncate() / c.w;
            (
                ((ndc.x + 1.0) * 0.5 * w as f32) as i64,
                ((1.0 - ndc.y) * 0.5 * h as f32) as i64,
            )
        };
        let (top, foot) = (screen(62.0), screen(10.0));
        let clip = |v: i64, n: u32| v.clamp(0, i64::from(n)) as u32;
        let xs = clip(top.0.min(foot.0) - 10, w)..clip(top.0.max(foot.0) + 10, w);
        let ys = clip(top.1.min(foot.1), h)..clip(top.1.max(foot.1), h);
        let mut n = 0;
        for y in ys {
            for x in xs.clone() {
                let i = ((y * w + x) * 4) as usize;
                if (0..3).any(|c| before.rgba[i + c].abs_diff(edited.rgba[i + c]) > 8) {
                    n += 1;
                }
            }
        }
        n
    };
    let (a, b) = (changed_near(near), changed_near(far_at));
    println!("pixels changed by the near pillar {a}, by the far one {b}");
    assert!(
        a > 200,
        "the near pillar: {a} pixels changed; see {}",
        dir.display()
    );
    assert!(
        b > 20,
        "the far pillar: {b} pixels changed; see {}",
        dir.display()
    );

    // The eye goes away (the view is rebuilt around it) and comes back: chunks meshed again
    // carry the edits, and the picture is the edited one.
    settle(
        &mut field,
        &mut renderer,
        camera.eye + DVec3::new(300.0, 0.0, 300.0),
    );
    settle(&mut field, &mut renderer, camera.eye);
    let back = far::picture(&ctx, &mut renderer, &target, &camera).unwrap();
    back.save_png(&dir.join("back.png")).unwrap();
    let d = diff(&back, &edited);
    assert!(
        d.over_one * 1000 < (w * h) as usize,
        "after a rebuild {} pixels differ from the edited picture",
        d.over_one
    );
}
