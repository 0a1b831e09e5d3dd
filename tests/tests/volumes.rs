//! Water as a volume (`voxel_render::medium`): what lies behind a water surface keeps
//! `exp(−σ d)` of its light over the `d` blocks the ray travels inside, from outside as from
//! inside, in the exact references and in the techniques exact on one medium over opaque
//! ground; a cutout block standing in water keeps the water around it.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use std::path::Path;
use std::sync::Arc;

use glam::DVec3;
use voxel_core::blocks::*;
use voxel_core::{BlockDef, BlockRegistry, RenderClass, World};
use voxel_lab::eval::raymarch_check;
use voxel_render::{Camera, Image, RendererConfig, Technique};

use tests::*;

const W: u32 = 384;
const H: u32 = 216;

/// The techniques exact on one medium over opaque ground.
const EXACT: [Technique; 4] = [
    Technique::Reference,
    Technique::PeelReference,
    Technique::SortedQuads,
    Technique::Sorted,
];

fn config(technique: Technique) -> RendererConfig {
    technique_config(technique, W, H)
}

/// The pixel a world point projects to.
fn pixel(camera: &Camera, p: DVec3) -> (u32, u32) {
    project(camera, (W, H), p)
}

/// The mean RGB (0–255) of the 5 × 5 pixels around `(x, y)`.
fn patch(img: &Image, (x, y): (u32, u32)) -> [f64; 3] {
    let mut sum = [0.0; 3];
    for py in y - 2..=y + 2 {
        for px in x - 2..=x + 2 {
            let i = ((py * img.width + px) * 4) as usize;
            for (c, s) in sum.iter_mut().enumerate() {
                *s += f64::from(img.rgba[i + c]) / 25.0;
            }
        }
    }
    sum
}

fn apart(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|c| (a[c] - b[c]).abs()).fold(0.0, f64::max)
}

fn load(name: &str) -> Scene {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    Scene::load(&dir.join(name)).unwrap()
}

#[test]
fn deep_water_is_darker_than_shallow_water_in_the_reference_and_every_exact_technique() {
    let Some(ctx) = gpu() else { return };
    // One surface over sand: 30 blocks deep for x < 0, 2 for x ≥ 0.
    let s = load("lake_depths.toml");
    let camera = s.cameras[0];
    let deep = pixel(&camera, DVec3::new(-8.0, 0.0, -4.0));
    let shallow = pixel(&camera, DVec3::new(8.0, 0.0, -4.0));
    let reference = render_with(&ctx, &s, config(Technique::Reference));
    for t in EXACT {
        let img = if t == Technique::Reference {
            reference.clone()
        } else {
            render_with(&ctx, &s, config(t))
        };
        let by = apart(patch(&img, deep), patch(&img, shallow));
        assert!(
            by >= 25.0,
            "{t}: 30 and 2 blocks of water over sand differ by {by:.1}/255"
        );
        assert_close(&format!("lake_depths_{t}"), &img, &reference, 2);
    }
}

/// Water between the eye and a wall of `wall`, 9 blocks of it on the way: from outside
/// (eye in air 10 blocks before the surface, the wall in the water) or from inside (eye in
/// the water 9 blocks behind its surface, the wall in air beyond), or no water at all.
fn passage(inside: Option<bool>, wall: voxel_core::BlockId) -> Scene {
    let mut boxes = vec![([-20, -20, -9], [20, 20, -9], wall)];
    match inside {
        Some(false) => boxes.push(([-20, -20, -8], [20, 20, 0], WATER)),
        Some(true) => boxes.push(([-20, -20, 2], [20, 20, 20], WATER)),
        None => {}
    }
    let s = scene(
        "passage",
        box_world(&boxes),
        [0.5, 0.5, 11.0],
        [0.5, 0.5, -20.0],
    );
    assert_eq!(s.cameras[0].medium.is_some(), inside == Some(true));
    s
}

/// The HDR scene colour of `scene` drawn with `technique` (flat textures).
fn hdr(ctx: &voxel_render::GpuContext, scene: &Scene, technique: Technique) -> Vec<[f32; 4]> {
    let config = RendererConfig {
        flat_textures: true,
        ..config(technique)
    };
    let mut renderer = renderer_for(ctx, scene, config).unwrap();
    frame(ctx, &mut renderer, &scene.cameras[0]);
    read_hdr(ctx, renderer.scene_color())
}

#[test]
fn the_same_path_through_water_absorbs_the_same_from_outside_and_from_inside() {
    let Some(ctx) = gpu() else { return };
    // The difference a wall's colour makes behind the water: whatever the water adds in
    // front (its surface, its colour) cancels, what is left is (1 − α) · T · Δwall, the
    // surface's transmission times the volume's, in either order.
    let centre: Vec<usize> = (H / 2 - 8..H / 2 + 8)
        .flat_map(|y| (W / 2 - 8..W / 2 + 8).map(move |x| (y * W + x) as usize))
        .collect();
    let delta = |inside: Option<bool>, t: Technique| -> Vec<[f32; 3]> {
        let a = hdr(&ctx, &passage(inside, SAND), t);
        let b = hdr(&ctx, &passage(inside, STONE), t);
        centre
            .iter()
            .map(|&i| std::array::from_fn(|c| a[i][c] - b[i][c]))
            .collect()
    };
    let bare = delta(None, Technique::Reference);
    for t in EXACT {
        let outside = delta(Some(false), t);
        let inside = delta(Some(true), t);
        for ((o, i), b) in outside.iter().zip(&inside).zip(&bare) {
            for c in 0..3 {
                assert!(
                    (o[c] - i[c]).abs() <= 2.0 / 255.0,
                    "{t}: from outside {o:?}, from inside {i:?} (no water {b:?})"
                );
                // The water absorbs, and lets something through: 0.3 of the surface's
                // and exp(−0.075 · 9) ≈ 0.51 of the volume's.
                let kept = o[c] / b[c];
                assert!(
                    (0.1..0.2).contains(&kept),
                    "{t}: {kept} of the wall's difference comes through"
                );
            }
        }
    }
}

/// A registry with kelp: a cutout block standing in water, or (`in_water` false) the
/// same block standing in nothing.
fn kelp_world(in_water: bool, kelp: bool) -> World {
    let mut registry = BlockRegistry::default();
    let mut def = BlockDef::new("kelp", [60, 140, 50], 1.0);
    def.class = RenderClass::Cutout;
    def.pattern = voxel_core::Pattern::Leaves;
    if in_water {
        def = def.in_medium(WATER);
    }
    let id = registry.register(def).unwrap();
    let mut world = World::new(Arc::new(registry));
    let fill = voxel_lab::scene::fill_box;
    fill(&mut world, [-24, -14, -24], [23, -14, 23], SAND).unwrap();
    fill(&mut world, [-24, -13, -24], [23, -1, 23], WATER).unwrap();
    if kelp {
        fill(&mut world, [-2, -13, 0], [1, -3, 0], id).unwrap();
    }
    world
}

#[test]
fn the_holes_of_a_cutout_block_in_water_show_the_water_as_the_ray_march_computes() {
    let Some(ctx) = gpu() else { return };
    let (eye, target) = ([0.5, 1.0, 8.0], [0.5, -8.0, 0.5]);
    let with = scene("kelp", kelp_world(true, true), eye, target);
    let without = scene("no_kelp", kelp_world(true, false), eye, target);
    let dry = scene("dry_kelp", kelp_world(false, true), eye, target);
    // The kelp's box on the picture.
    let camera = with.cameras[0];
    let corners: Vec<_> = [-2.0, 2.0]
        .into_iter()
        .flat_map(|x| [-12.0, -2.0].map(|y| (x, y)))
        .flat_map(|(x, y)| [0.0, 1.0].map(|z| pixel(&camera, DVec3::new(x, y, z))))
        .collect();
    let (x0, x1) = (
        corners.iter().map(|c| c.0).min().unwrap(),
        corners.iter().map(|c| c.0).max().unwrap(),
    );
    let (y0, y1) = (
        corners.iter().map(|c| c.1).min().unwrap(),
        corners.iter().map(|c| c.1).max().unwrap(),
    );
    // Pixels of the box that show what the water alone shows there (the holes), and
    // pixels far from it (the leaves).
    let holes_and_leaves = |a: &Image, b: &Image| {
        let (mut holes, mut leaves, mut all) = (0, 0, 0);
        for y in y0..=y1 {
            for x in x0..=x1 {
                let i = ((y * W + x) * 4) as usize;
                let d = (0..3).map(|c| a.rgba[i + c].abs_diff(b.rgba[i + c])).max();
                all += 1;
                match d.unwrap() {
                    0..=2 => holes += 1,
                    12.. => leaves += 1,
                    _ => {}
                }
            }
        }
        (
            f64::from(holes) / f64::from(all),
            f64::from(leaves) / f64::from(all),
        )
    };
    let water = render_with(&ctx, &without, config(Technique::Reference));
    let mut in_water = f64::MAX;
    for t in EXACT {
        let img = render_with(&ctx, &with, config(t));
        let (holes, leaves) = holes_and_leaves(&img, &water);
        let dir = out_dir("kelp_in_water");
        img.save_png(&dir.join(format!("{t}.png"))).unwrap();
        water.save_png(&dir.join("water.png")).unwrap();
        eprintln!("{t}: holes {holes:.3}, leaves {leaves:.3}");
        assert!(
            holes > 0.3 && leaves > 0.15,
            "{t}: {holes:.2} of the kelp's box shows the water, {leaves:.2} the leaves"
        );
        if t == Technique::Reference {
            in_water = holes;
        }
    }
    // Standing in nothing, the kelp is a pocket of air in the water, walled by the water's
    // faces: fewer of its pixels show what the water alone shows (the box's pixels beside
    // the kelp still do).
    let img = render_with(&ctx, &dry, config(Technique::Reference));
    let (holes, leaves) = holes_and_leaves(&img, &water);
    img.save_png(&out_dir("kelp_in_water").join("dry.png"))
        .unwrap();
    eprintln!("dry kelp: holes {holes:.3}, leaves {leaves:.3}");
    assert!(
        holes < in_water - 0.05,
        "dry kelp: {holes:.2} of its box shows the water, {in_water:.2} when it stands in water"
    );
    // The ray march, which knows only the blocks, agrees with the reference.
    for s in [&with, &dry] {
        let check = raymarch_check(&ctx, s, &s.cameras[0], (W, H)).unwrap();
        let c = &check.comparison;
        assert_eq!(
            (c.differing, c.cracks),
            (0, 0),
            "{}: {} pixels off edges differ (max {}/255): {:?}",
            s.name,
            c.differing,
            c.max_abs_err_off_edges,
            c.worst
        );
    }
}

/// Translucent things inside water (a game's plates and bubbles under the surface of the
/// deep lake, seen from above): the sorted techniques compose them against the volume's
/// entry (`inside_volume.wgsl`) and come out as the reference, which splits the path at
/// each; the weighted ones put the whole path in front of them and are measured only.
#[test]
fn things_inside_water_are_composed_with_the_path_split_at_them() {
    use voxel_render::content::{Content, Entity, Particle};
    let Some(ctx) = gpu() else { return };
    let lake = load("lake_depths.toml");
    let content = Content {
        particles: (0..60)
            .map(|i| Particle {
                center: DVec3::new(
                    -12.0 + f64::from(i % 10) * 2.5,
                    -3.0 - f64::from(i / 10) * 3.0,
                    -6.0 + f64::from(i % 7),
                ),
                half_size: 0.8,
                color: [225, 240, 255],
                opacity: 0.5,
                emissive: 0.0,
            })
            .collect(),
        entities: vec![Entity {
            center: DVec3::new(6.0, -1.6, -4.0),
            half_extents: [2.0, 0.3, 2.0],
            rotation: glam::DQuat::IDENTITY,
            color: [230, 60, 40],
            opacity: 0.6,
            emissive: 0.0,
        }],
    };
    let scene = Scene { content, ..lake };
    let reference = render_with(&ctx, &scene, config(Technique::Reference));
    let without = render_with(
        &ctx,
        &Scene {
            content: Content::default(),
            ..scene.clone()
        },
        config(Technique::Reference),
    );
    let seen = diff(&reference, &without).over_one;
    assert!(seen > 1000, "the things are seen on {seen} px");
    for t in [
        Technique::SortedQuads,
        Technique::Sorted,
        Technique::DepthPeeling,
        Technique::PeelReference,
    ] {
        let img = render_with(&ctx, &scene, config(t));
        assert_close(&format!("things_in_water_{t}"), &img, &reference, 2);
    }
}

/// A game's water as a game defines it with `BlockDef::new` (no absorption: not a volume)
/// between the eye and a wall, as in [`passage`]; `volume`: the built-in water instead.
fn games_water_passage(inside: Option<bool>, wall: voxel_core::BlockId, volume: bool) -> Scene {
    let mut registry = BlockRegistry::default();
    let own = registry
        .register(BlockDef::new("lake_water", [25, 105, 165], 0.7))
        .unwrap();
    let water = if volume { WATER } else { own };
    let mut world = World::new(Arc::new(registry));
    let fill = voxel_lab::scene::fill_box;
    fill(&mut world, [-20, -20, -9], [20, 20, -9], wall).unwrap();
    match inside {
        Some(false) => fill(&mut world, [-20, -20, -8], [20, 20, 0], water).unwrap(),
        Some(true) => fill(&mut world, [-20, -20, 2], [20, 20, 20], water).unwrap(),
        None => {}
    }
    let s = scene("games_water", world, [0.5, 0.5, 11.0], [0.5, 0.5, -20.0]);
    assert_eq!(s.cameras[0].medium.is_some(), inside == Some(true));
    s
}

/// A game's own water block made as before volumes existed (`BlockDef::new`, opacity 0.7)
/// keeps the look it had: from inside, the fog every translucent block had (16 blocks dim
/// as one surface), which is exactly the built-in water's absorption at that opacity;
/// from outside, a thin surface (only its opacity tints what lies behind, however deep).
/// The ray march, which knows only the blocks, agrees.
#[test]
fn a_games_own_water_keeps_its_look() {
    let Some(ctx) = gpu() else { return };
    let centre: Vec<usize> = (H / 2 - 8..H / 2 + 8)
        .flat_map(|y| (W / 2 - 8..W / 2 + 8).map(move |x| (y * W + x) as usize))
        .collect();
    // What comes through of a wall's colour difference (sand against stone).
    let delta = |inside: Option<bool>, volume: bool, t: Technique| -> Vec<[f32; 3]> {
        let a = hdr(&ctx, &games_water_passage(inside, SAND, volume), t);
        let b = hdr(&ctx, &games_water_passage(inside, STONE, volume), t);
        centre
            .iter()
            .map(|&i| std::array::from_fn(|c| a[i][c] - b[i][c]))
            .collect()
    };
    let bare = delta(None, false, Technique::Reference);
    for t in [
        Technique::Reference,
        Technique::SortedQuads,
        Technique::WboitMrt,
        Technique::Mboit,
    ] {
        // From inside: fogged as the built-in water (a volume of the same opacity) is.
        let own = hdr(&ctx, &games_water_passage(Some(true), SAND, false), t);
        let built_in = hdr(&ctx, &games_water_passage(Some(true), SAND, true), t);
        for &i in &centre {
            for c in 0..3 {
                assert!(
                    (own[i][c] - built_in[i][c]).abs() <= 1.0 / 255.0,
                    "{t}: the game's water from inside {:?}, the built-in {:?}",
                    own[i],
                    built_in[i]
                );
            }
        }
        let inside = delta(Some(true), false, t);
        let outside = delta(Some(false), false, t);
        for ((i, o), b) in inside.iter().zip(&outside).zip(&bare) {
            for c in 0..3 {
                // Inside: 0.3 of the surface's and exp(−0.075 · 9) ≈ 0.51 of the fog's.
                let kept = i[c] / b[c];
                assert!(
                    (0.1..0.2).contains(&kept),
                    "{t}: from inside {kept} of the wall's difference comes through"
                );
                // Outside: the surface alone, 0.3, however deep the water behind it.
                let kept = o[c] / b[c];
                assert!(
                    (0.27..0.33).contains(&kept),
                    "{t}: from outside {kept} of the wall's difference comes through"
                );
            }
        }
    }
    for inside in [Some(true), Some(false)] {
        let s = games_water_passage(inside, SAND, false);
        let check = raymarch_check(&ctx, &s, &s.cameras[0], (W, H)).unwrap();
        let c = &check.comparison;
        assert_eq!(
            (c.differing, c.cracks),
            (0, 0),
            "{inside:?}: {} pixels off edges differ (max {}/255): {:?}",
            c.differing,
            c.max_abs_err_off_edges,
            c.worst
        );
    }
}

/// Dense volumes (absorption 0.3 to 1 a block): a thing just under the surface of a pool of
/// slime, seen from above and from inside the slime. The real-time techniques see each
/// fragment through its own path (nothing is divided by a transmittance that reaches 1e-7
/// here), so the thing neither vanishes nor glows: within 2/255 of the A-buffer.
#[test]
fn a_thing_in_a_dense_volume_is_seen_through_its_own_path() {
    use voxel_render::content::{Content, Entity};
    let Some(ctx) = gpu() else { return };
    for absorption in [0.3f32, 1.0] {
        let mut registry = BlockRegistry::default();
        let slime = registry
            .register(BlockDef::new("dense_slime", [90, 200, 70], 0.5).with_absorption(absorption))
            .unwrap();
        let mut world = World::new(Arc::new(registry));
        voxel_lab::scene::fill_box(&mut world, [-16, -17, -16], [15, -17, 15], SAND).unwrap();
        voxel_lab::scene::fill_box(&mut world, [-16, -16, -16], [15, -1, 15], slime).unwrap();
        let entity = |y: f64| Entity {
            center: DVec3::new(0.5, y, -2.0),
            half_extents: [1.5, 0.2, 1.5],
            rotation: glam::DQuat::from_rotation_y(0.4),
            color: [230, 60, 40],
            opacity: 0.7,
            emissive: 0.0,
        };
        let content = Content {
            particles: Vec::new(),
            entities: vec![entity(-0.6), entity(-3.0)],
        };
        for (eye, target) in [
            ([0.5, 5.0, 6.0], [0.5, -2.0, -2.0]),
            ([0.5, -1.5, 3.0], [0.5, -3.0, -2.0]),
        ] {
            let mut scene = tests::scene("dense", world.clone(), eye, target);
            scene.content = content.clone();
            let reference = render_with(&ctx, &scene, config(Technique::Reference));
            let bare = render_with(
                &ctx,
                &Scene {
                    content: Content::default(),
                    ..scene.clone()
                },
                config(Technique::Reference),
            );
            assert!(
                diff(&reference, &bare).over_one > 100,
                "absorption {absorption}, eye {eye:?}: the things are seen"
            );
            for t in [
                Technique::SortedQuads,
                Technique::Sorted,
                Technique::DepthPeeling,
            ] {
                let img = render_with(&ctx, &scene, config(t));
                assert_close(
                    &format!("dense_{absorption}_{}_{t}", eye[1]),
                    &img,
                    &reference,
                    2,
                );
            }
        }
    }
}
