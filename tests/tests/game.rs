//! A game's own geometry in the world: translucent game quads composed by every technique
//! with water and glass, opaque entities treated like terrain, and game draws that survive
//! technique switches, resizes and MSAA. The water here is a thin surface
//! ([`thin_water_world`]): these tests are about order, which the absorption of a volume
//! along the path would blur (`volumes.rs` tests volumes, the lab measures objects in them).

use glam::{DQuat, DVec3};
use tests::{Scene, diff, gpu, out_dir, technique_config, thin_water_world};
use voxel_core::blocks::{GLASS, SAND, WATER};
use voxel_render::content::{Content, ContentStages, Entity, Particle};
use voxel_render::{Image, RendererConfig, Technique};

const W: u32 = 160;
const H: u32 = 90;

/// A pool of water over sand and a glass pane above it, seen from above and in front. The
/// pane and the objects put near it lie in one chunk (x and z in 0..32), with water under
/// them: the case where the sorted techniques must place an object between the layers of
/// one chunk.
fn pool() -> Scene {
    let world = thin_water_world(&[
        ([-12, -8, -12], [12, -8, 12], SAND),
        ([-12, -7, -12], [12, 0, 12], WATER),
        ([2, 2, 6], [9, 5, 6], GLASS),
    ]);
    tests::scene("pool", world, [5.5, 6.0, 16.0], [5.5, -1.0, -2.0])
}

/// A translucent square facing the camera: the simplest game quad.
fn quad(center: [f64; 3]) -> Particle {
    Particle {
        center: DVec3::from(center),
        half_size: 1.5,
        color: [230, 40, 40],
        opacity: 0.5,
        emissive: 0.0,
    }
}

/// A translucent plate turned 40° about y and tilted: crosses what it is put through.
fn plate(center: [f64; 3], opacity: f32) -> Entity {
    Entity {
        center: DVec3::from(center),
        half_extents: [1.8, 1.8, 0.05],
        rotation: DQuat::from_rotation_y(40f64.to_radians())
            * DQuat::from_rotation_x(-25f64.to_radians()),
        color: [40, 60, 230],
        opacity,
        emissive: 0.0,
    }
}

fn particles(p: Vec<Particle>) -> Content {
    Content {
        particles: p,
        entities: vec![],
    }
}

fn entities(e: Vec<Entity>) -> Content {
    Content {
        particles: vec![],
        entities: e,
    }
}

/// A case: a name, the content, whether the sorted techniques' order is exact for it
/// (`sorted`, `sorted-quads`), and whether the object is the nearest translucent layer
/// wherever it is seen.
type Case = (&'static str, Content, [bool; 2], bool);

fn cases() -> Vec<Case> {
    vec![
        // Under the water surface: a chunk-wide test decides.
        (
            "under_water",
            particles(vec![quad([5.5, -3.5, 3.0])]),
            [true, true],
            false,
        ),
        // In front of the pane and over the water: every plane says in front.
        (
            "before_glass",
            particles(vec![quad([5.5, 3.5, 10.0])]),
            [true, true],
            true,
        ),
        // Over the water and behind the pane of the same chunk: no chunk-wide test
        // decides; sorted-quads draws it between their quads, sorted by the box's centre.
        (
            "behind_glass",
            particles(vec![quad([5.5, 3.5, 3.0])]),
            [false, true],
            false,
        ),
        // Over the water beside the pane, several at once.
        (
            "over_water",
            particles(vec![quad([14.5, 3.5, 3.0]), quad([20.5, 2.5, 8.0])]),
            [false, true],
            true,
        ),
        // Crossing a layer: the part on the other side is drawn on the wrong side.
        (
            "through_water",
            entities(vec![plate([5.5, 1.0, 3.0], 0.5)]),
            [false, false],
            false,
        ),
        (
            "through_glass",
            entities(vec![plate([5.5, 3.5, 7.0], 0.5)]),
            [false, false],
            false,
        ),
    ]
}

/// `scene` with `content`.
fn with(scene: &Scene, content: Content) -> Scene {
    Scene {
        content,
        ..scene.clone()
    }
}

fn render(scene: &Scene, config: RendererConfig) -> Image {
    // One device per test (each runs on a thread of its own): a new device for every
    // picture cost more than the picture.
    thread_local! {
        static CTX: voxel_render::GpuContext = gpu().expect("GPU");
    }
    CTX.with(|ctx| tests::render_with(ctx, scene, config))
}

/// Asserts that `got` is, within 1/255, what a fresh renderer with `config` draws of
/// `scene` (`what`: the step that led to `got`).
fn draws_as_fresh(got: &Image, scene: &Scene, config: RendererConfig, what: &str) {
    let d = diff(got, &render(scene, config));
    assert!(d.max <= 1, "{what}: {d:?}");
}

/// The largest channel difference of each pixel, in 1/255 steps.
fn pixel_diffs(a: &Image, b: &Image) -> Vec<u8> {
    a.rgba
        .chunks_exact(4)
        .zip(b.rgba.chunks_exact(4))
        .map(|(p, q)| (0..3).map(|c| p[c].abs_diff(q[c])).max().unwrap_or(0))
        .collect()
}

/// Mean of `pixel_diffs` over the pixels where `mask` holds.
fn mean_where(d: &[u8], mask: &[bool]) -> f64 {
    let (sum, n) = d
        .iter()
        .zip(mask)
        .filter(|(_, m)| **m)
        .fold((0u64, 0u64), |(s, n), (d, _)| (s + u64::from(*d), n + 1));
    sum as f64 / n.max(1) as f64
}

/// Every technique composes the game's translucent objects with water and glass: the exact
/// ones exactly (within 1/255 of the A-buffer reference), the sorted ones exactly where
/// their order is (the cases say where), and everywhere only where the object is; the
/// approximate ones draw the object (its footprint changes) and come nearer to the
/// reference there than the picture without it.
#[test]
fn every_technique_composes_game_objects_with_water_and_glass() {
    let Some(_ctx) = gpu() else { return };
    let base = pool();
    let refc = technique_config(Technique::Reference, W, H);
    let dir = out_dir("game");
    let mut failures = Vec::new();
    let mut report = String::new();
    let techniques: Vec<Technique> = Technique::ALL
        .into_iter()
        .filter(|t| *t != Technique::OpaqueOnly && *t != Technique::Reference)
        .collect();
    // The pool without the game's object, drawn once: the same for every case.
    let ref_without = render(&base, refc.clone());
    let withouts: Vec<Image> = techniques
        .iter()
        .map(|&t| render(&base, technique_config(t, W, H)))
        .collect();
    for (name, content, exact_sorted, nearest) in cases() {
        let scene = with(&base, content);
        let reference = render(&scene, refc.clone());
        reference
            .save_png(&dir.join(format!("{name}_reference.png")))
            .unwrap();
        // The object's footprint: where it changes the reference.
        let footprint: Vec<bool> = pixel_diffs(&reference, &ref_without)
            .iter()
            .map(|&d| d > 2)
            .collect();
        let area = footprint.iter().filter(|m| **m).count();
        assert!(
            area > 30,
            "{name}: the object covers {area} px of the reference"
        );
        for (&t, without) in techniques.iter().zip(&withouts) {
            let img = render(&scene, technique_config(t, W, H));
            img.save_png(&dir.join(format!("{name}_{}.png", t.name())))
                .unwrap();
            let d = diff(&img, &reference);
            let err = pixel_diffs(&img, &reference);
            let err_without = pixel_diffs(without, &reference);
            let drawn = pixel_diffs(&img, without)
                .iter()
                .zip(&footprint)
                .filter(|(d, m)| **m && **d > 2)
                .count();
            let (in_with, in_without) = (
                mean_where(&err, &footprint),
                mean_where(&err_without, &footprint),
            );
            report += &format!(
                "{name:14} {:15} max {:3} px>1 {:5} footprint {area:4} px, drawn on {drawn:4}, \
                 error there {in_with:6.2} (without {in_without:6.2})\n",
                t.name(),
                d.max,
                d.over_one
            );
            let mut check = |ok: bool, what: &str| {
                if !ok {
                    failures.push(format!("{name} {}: {what}", t.name()));
                }
            };
            match t {
                Technique::PeelReference | Technique::DepthPeeling => {
                    check(drawn * 2 > area, "not drawn on most of its footprint");
                    check(d.max <= 1, "an exact technique differs from the reference");
                }
                Technique::Sorted | Technique::SortedQuads => {
                    check(drawn * 2 > area, "not drawn on most of its footprint");
                    let exact = exact_sorted[usize::from(t == Technique::SortedQuads)];
                    if exact {
                        check(
                            d.max <= 1,
                            "differs from the reference where the order is exact",
                        );
                    }
                    // Wherever its order is wrong, only the object's pixels are.
                    let outside = err
                        .iter()
                        .zip(&footprint)
                        .filter(|(e, m)| !**m && **e > 1)
                        .count();
                    check(outside == 0, "differs outside the object's footprint");
                }
                // A screen door shows a half-opaque object on half its pixels, and none
                // under a layer more opaque than it (the same Bayer cell hides it).
                Technique::Stipple => {
                    if nearest {
                        check(drawn * 5 > area * 2, "not drawn on 40 % of its footprint");
                    }
                }
                _ => {
                    check(drawn * 2 > area, "not drawn on most of its footprint");
                    if nearest {
                        check(
                            in_with < in_without,
                            "not nearer the reference on the object's footprint with it",
                        );
                    }
                }
            }
        }
    }
    eprint!("{report}");
    assert!(failures.is_empty(), "{failures:#?}");
}

/// An opaque entity is drawn with the world's opaque geometry: under water, behind glass
/// and in front of it (hiding it) every exact and sorted technique shows it as the
/// reference does, and one buried under the sand changes no pixel.
#[test]
fn opaque_entities_are_seen_through_water_and_glass_and_hidden_by_terrain() {
    let Some(_ctx) = gpu() else { return };
    let base = pool();
    let dir = out_dir("game_opaque");
    let seen = with(
        &base,
        entities(vec![
            // Under water, behind the pane, in front of it.
            plate([5.5, -3.0, 3.0], 1.0),
            plate([5.5, 3.5, 3.0], 1.0),
            plate([8.0, 3.5, 9.5], 1.0),
        ]),
    );
    let buried = with(&base, entities(vec![plate([5.5, -12.0, 3.0], 1.0)]));
    let refc = technique_config(Technique::Reference, W, H);
    let reference = render(&seen, refc.clone());
    let without = render(&base, refc);
    let area = pixel_diffs(&reference, &without)
        .iter()
        .filter(|&&d| d > 2)
        .count();
    assert!(area > 200, "the entities cover {area} px");
    for t in [
        Technique::Sorted,
        Technique::SortedQuads,
        Technique::DepthPeeling,
        Technique::PeelReference,
        Technique::WboitMrt,
        Technique::Stipple,
    ] {
        let config = technique_config(t, W, H);
        let img = render(&seen, config.clone());
        img.save_png(&dir.join(format!("{}.png", t.name())))
            .unwrap();
        if t.is_exact() || matches!(t, Technique::Sorted | Technique::SortedQuads) {
            let d = diff(&img, &reference);
            assert!(d.max <= 1, "{}: {d:?} against the reference", t.name());
        }
        let d = diff(&render(&buried, config.clone()), &render(&base, config));
        assert_eq!(d.differing, 0, "{}: a buried entity shows", t.name());
    }
}

/// The game's draws survive what a game does between frames: a technique switch, a resize,
/// MSAA turned on. Each picture equals a fresh renderer's with the same settings.
#[test]
fn game_draws_survive_switches_resizes_and_msaa() {
    let Some(ctx) = gpu() else { return };
    let scene = with(
        &pool(),
        Content {
            particles: vec![quad([5.5, 3.5, 3.0]), quad([5.5, -3.5, 3.0])],
            entities: vec![plate([12.5, 1.0, 3.0], 0.5), plate([8.5, -3.0, 3.0], 1.0)],
        },
    );
    let camera = scene.cameras[0];
    let mut r =
        tests::renderer_for(&ctx, &scene, technique_config(Technique::WboitMrt, W, H)).unwrap();
    let shot = |r: &mut voxel_lab::headless::SceneRenderer| {
        let (w, h) = r.size();
        let target = tests::Offscreen::new(&ctx, w, h);
        voxel_lab::headless::render_image(&ctx, r, &target, &camera).unwrap()
    };
    let _ = shot(&mut r);
    for t in [
        Technique::SortedQuads,
        Technique::DepthPeeling,
        Technique::Stipple,
        Technique::Reference,
        Technique::WboitTwoPass,
    ] {
        r.set_technique(t).unwrap();
        let got = shot(&mut r);
        draws_as_fresh(
            &got,
            &scene,
            technique_config(t, W, H),
            &format!("after switching to {}", t.name()),
        );
    }
    r.resize(120, 68).unwrap();
    let got = shot(&mut r);
    let config = technique_config(Technique::WboitTwoPass, 120, 68);
    draws_as_fresh(&got, &scene, config, "after a resize");
    r.set_msaa(true).unwrap();
    let got = shot(&mut r);
    let config = RendererConfig {
        msaa: true,
        ..technique_config(Technique::WboitTwoPass, 120, 68)
    };
    draws_as_fresh(&got, &scene, config, "after MSAA on");
}

/// A game that keeps pipelines built for another technique's contract (it switched and
/// did not rebuild) gets `Error::StaleContract` before anything is recorded, under wgpu's
/// default (panicking) error handler; rebuilt, it draws what a fresh renderer draws. The
/// same technique and settings keep their contract id, so a switch back needs no rebuild.
#[test]
fn stale_game_pipelines_are_refused_before_recording() {
    let Some(ctx) = gpu() else { return };
    let scene = with(
        &pool(),
        Content {
            particles: vec![quad([5.5, 3.5, 3.0])],
            entities: vec![plate([12.5, 1.0, 3.0], 0.5)],
        },
    );
    let camera = scene.cameras[0];
    let mut r =
        tests::renderer_for(&ctx, &scene, technique_config(Technique::WboitMrt, W, H)).unwrap();
    let target = tests::Offscreen::new(&ctx, W, H);
    let mut content = r.content.take().unwrap();
    content.update_pipelines(&mut r.renderer).unwrap();
    let wboit = r.translucent_contract().unwrap().id;
    assert_eq!(
        voxel_render::GameStages::translucent_contract_id(&content),
        Some(wboit)
    );
    r.renderer
        .render_and_submit(&target.view, &camera, &mut content)
        .unwrap();

    r.set_technique(Technique::SortedQuads).unwrap();
    let quads = r.translucent_contract().unwrap().id;
    assert_ne!(quads, wboit);
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    let e = r
        .renderer
        .render(&mut encoder, &target.view, &camera, &mut content)
        .unwrap_err();
    match &e {
        voxel_render::Error::StaleContract {
            built_for, current, ..
        } => assert_eq!((*built_for, *current), (Some(wboit), quads)),
        other => panic!("{other:?}"),
    }
    assert!(e.to_string().contains("sorted-quads"), "{e}");
    // Nothing was recorded: the encoder submits as an empty one.
    ctx.queue.submit([encoder.finish()]);

    content.update_pipelines(&mut r.renderer).unwrap();
    r.renderer
        .render_and_submit(&target.view, &camera, &mut content)
        .unwrap();
    let got = target.read(&ctx).unwrap();
    draws_as_fresh(
        &got,
        &scene,
        technique_config(Technique::SortedQuads, W, H),
        "rebuilt",
    );

    // Back to WBOIT: the same id again, so pipelines a game kept for it are valid.
    r.set_technique(Technique::WboitMrt).unwrap();
    assert_eq!(r.translucent_contract().unwrap().id, wboit);
    let e = r
        .renderer
        .render_and_submit(&target.view, &camera, &mut content)
        .unwrap_err();
    assert!(
        matches!(e, voxel_render::Error::StaleContract { .. }),
        "{e:?}"
    );
}

/// `ContentStages` follows what the game switches by itself (`GameStages::follow_contract`
/// and the frame's sample count): no call between frames, each picture equals a fresh
/// renderer's, and a switch back to a technique it has drawn with builds nothing.
#[test]
fn content_stages_follow_switches_and_msaa_by_themselves() {
    let Some(ctx) = gpu() else { return };
    let scene = with(
        &pool(),
        Content {
            particles: vec![quad([5.5, 3.5, 3.0])],
            entities: vec![plate([12.5, 1.0, 3.0], 0.5), plate([8.5, -3.0, 3.0], 1.0)],
        },
    );
    let camera = scene.cameras[0];
    let mut r =
        tests::renderer_for(&ctx, &scene, technique_config(Technique::WboitMrt, W, H)).unwrap();
    let mut game = ContentStages::new(&r.renderer, scene.content.clone()).unwrap();
    let target = tests::Offscreen::new(&ctx, W, H);
    let shot = |r: &mut voxel_render::Renderer, game: &mut ContentStages| {
        r.render_and_submit(&target.view, &camera, game).unwrap();
        target.read(&ctx).unwrap()
    };
    let _ = shot(&mut r.renderer, &mut game);
    for t in [Technique::SortedQuads, Technique::DepthPeeling] {
        r.set_technique(t).unwrap();
        let got = shot(&mut r.renderer, &mut game);
        draws_as_fresh(
            &got,
            &scene,
            technique_config(t, W, H),
            &format!("after switching to {}", t.name()),
        );
    }
    let built = game.pipelines_built();
    r.set_technique(Technique::WboitMrt).unwrap();
    let _ = shot(&mut r.renderer, &mut game);
    assert_eq!(
        game.pipelines_built(),
        built,
        "a switch back built a pipeline"
    );
    r.set_msaa(true).unwrap();
    let got = shot(&mut r.renderer, &mut game);
    let config = RendererConfig {
        msaa: true,
        ..technique_config(Technique::WboitMrt, W, H)
    };
    draws_as_fresh(&got, &scene, config, "after MSAA on");
}

/// A flat translucent slab wholly above the water surface seen from under water, and its
/// mirror (wholly below, seen from above): its bounding ball reaches through the surface,
/// its box does not, and the sorted techniques order it by the box (exact, within 1/255
/// of the A-buffer reference), as depth peeling is.
#[test]
fn a_slab_beyond_the_water_surface_is_exact_from_either_side() {
    let Some(_ctx) = gpu() else { return };
    let world = thin_water_world(&[
        ([-12, -8, -12], [12, -8, 12], SAND),
        ([-12, -7, -12], [12, 0, 12], WATER),
    ]);
    let slab = |y: f64| Entity {
        center: DVec3::new(0.5, y, -2.0),
        half_extents: [3.0, 0.25, 3.0],
        rotation: DQuat::IDENTITY,
        color: [230, 60, 40],
        opacity: 0.5,
        emissive: 0.0,
    };
    let dir = out_dir("game_slab");
    for (name, eye, y) in [
        ("under_water_slab_above", [0.5, -4.0, 6.0], 3.0),
        ("above_water_slab_below", [0.5, 6.0, 6.0], -3.0),
    ] {
        let scene = with(
            &tests::scene(name, world.clone(), eye, [0.5, y, -2.0]),
            entities(vec![slab(y)]),
        );
        let reference = render(&scene, technique_config(Technique::Reference, W, H));
        let without = render(
            &with(&scene, entities(vec![])),
            technique_config(Technique::Reference, W, H),
        );
        assert!(
            diff(&reference, &without).over_one > 500,
            "{name}: the slab is seen"
        );
        for t in [
            Technique::SortedQuads,
            Technique::Sorted,
            Technique::DepthPeeling,
        ] {
            let img = render(&scene, technique_config(t, W, H));
            img.save_png(&dir.join(format!("{name}_{}.png", t.name())))
                .unwrap();
            let d = diff(&img, &reference);
            assert!(d.max <= 1, "{name} {}: {d:?}", t.name());
        }
    }
}

/// Equal depths: a flat object lying exactly in the water surface's plane, and one lying
/// exactly in a glass pane's face. One rule (at equal depth the block's face is in front
/// of the object's: an object's depth counts `OBJECT_DEPTH_BIAS` farther) that both exact
/// GPU references and the ray march follow: they agree within 2/255, and the ray march
/// finds no edge there to excuse a difference.
#[test]
fn objects_in_a_block_face_plane_follow_one_rule_in_every_reference() {
    let Some(ctx) = gpu() else { return };
    let plate = |center: [f64; 3], half: [f32; 3], color| Entity {
        center: DVec3::from(center),
        half_extents: half,
        rotation: DQuat::IDENTITY,
        color,
        opacity: 0.55,
        emissive: 0.0,
    };
    // The water's surface is the plane y = 1; the pane's +z face the plane z = 7: the
    // plates' faces seen from the camera lie in them (their other halves in the blocks).
    let scene = with(
        &pool(),
        entities(vec![
            plate([-3.5, 0.75, 3.0], [3.0, 0.25, 3.0], [230, 40, 40]),
            plate([5.5, 3.5, 6.75], [2.0, 1.0, 0.25], [40, 220, 60]),
        ]),
    );
    let cam = scene.cameras[0];
    let (w, h) = (192, 108);
    let abuffer = render(&scene, technique_config(Technique::Reference, w, h));
    let peeled = render(&scene, technique_config(Technique::PeelReference, w, h));
    let d = diff(&peeled, &abuffer);
    abuffer
        .save_png(&out_dir("game_coplanar").join("reference.png"))
        .unwrap();
    assert!(d.max <= 2, "the two exact references disagree: {d:?}");
    let check = voxel_lab::eval::raymarch_check(&ctx, &scene, &cam, (w, h)).unwrap();
    let c = &check.comparison;
    assert_eq!(
        (c.differing, c.cracks),
        (0, 0),
        "the ray march differs from the A-buffer: {:?}",
        c.worst
    );
    // The plates are seen (and not excused as edges).
    let without = render(&pool(), technique_config(Technique::Reference, w, h));
    assert!(diff(&abuffer, &without).over_one > 800);
    eprintln!(
        "differing on edges {}, seams {}",
        c.differing_on_edges, c.translucent_seams
    );
    assert!(
        c.differing_on_edges < 100,
        "{} pixels differ where the ray march sees edges",
        c.differing_on_edges
    );
}

/// The eye inside a game's translucent entity (a slime block around the camera, a diving
/// bell): its far faces are drawn and tint everything beyond, in every technique, as the
/// A-buffer reference and the ray march show it; the exact and sorted techniques within
/// 1/255 of the reference (no block face lies inside the box).
#[test]
fn the_eye_inside_a_translucent_entity_is_tinted_by_it() {
    let Some(ctx) = gpu() else { return };
    let base = pool();
    let eye = base.cameras[0].eye;
    let slime = Entity {
        center: eye + DVec3::new(0.3, -0.2, 0.1),
        half_extents: [2.0, 1.5, 2.5],
        rotation: DQuat::from_rotation_y(0.4),
        color: [90, 220, 80],
        opacity: 0.4,
        emissive: 0.0,
    };
    let scene = with(&base, entities(vec![slime]));
    let cam = scene.cameras[0];
    let reference = render(&scene, technique_config(Technique::Reference, W, H));
    let without = render(&base, technique_config(Technique::Reference, W, H));
    let tinted = diff(&reference, &without);
    assert!(
        tinted.over_one as u32 > W * H * 9 / 10,
        "the slime tints the picture: {tinted:?}"
    );
    // Greener everywhere.
    let green = |img: &Image| {
        img.rgba
            .chunks_exact(4)
            .map(|p| f64::from(p[1]) - f64::from(p[0]))
            .sum::<f64>()
    };
    assert!(green(&reference) > green(&without) + f64::from(W * H) * 10.0);
    let dir = out_dir("game_inside");
    reference.save_png(&dir.join("reference.png")).unwrap();
    for t in Technique::ALL {
        if matches!(t, Technique::OpaqueOnly | Technique::Reference) {
            continue;
        }
        let img = render(&scene, technique_config(t, W, H));
        img.save_png(&dir.join(format!("{}.png", t.name())))
            .unwrap();
        let d = diff(&img, &reference);
        match t {
            Technique::PeelReference
            | Technique::DepthPeeling
            | Technique::Sorted
            | Technique::SortedQuads => assert!(d.max <= 1, "{}: {d:?}", t.name()),
            // Tinted too, nearer the reference than the picture without the slime.
            _ => {
                let e = diff(&img, &without);
                assert!(
                    e.over_one as u32 > W * H / 2,
                    "{}: not tinted {e:?}",
                    t.name()
                );
            }
        }
    }
    let check = voxel_lab::eval::raymarch_check(&ctx, &scene, &cam, (W, H)).unwrap();
    let c = &check.comparison;
    assert_eq!(
        (c.differing, c.cracks),
        (0, 0),
        "the ray march differs from the A-buffer: {:?}",
        c.worst
    );
}
