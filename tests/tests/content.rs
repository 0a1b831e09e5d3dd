//! The ready-made game content (`voxel_render::content`) as a game uses it for real: any
//! count of particles the API accepts draws (instances split over buffers within the
//! device's binding size), bad values are refused naming the thing and the field, things
//! glow by their own light through water and glass at night, and the content composes with
//! a game's own stages (`stages::Both`) as if it were one game.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use std::path::Path;

use glam::{DQuat, DVec3};
use tests::{Offscreen, Scene, diff, distinct_colours, gpu, gpu_with_limits, out_dir};
use voxel_lab::headless::{render_image, renderer_for};
use voxel_lab::raymarch::{RayMarcher, Shading};
use voxel_render::content::{Content, ContentStages, Entity, MAX_EMISSIVE, Particle};
use voxel_render::stages::Both;
use voxel_render::{
    Error, GameStages, GpuContext, Image, Lighting, NoGame, QuadFetch, Renderer, RendererConfig,
    Technique,
};

const W: u32 = 160;
const H: u32 = 90;

/// Water seen through a window of clear and blue glass from inside a stone room.
fn window_scene() -> Scene {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/water_through_glass.toml");
    Scene::load(&file).unwrap()
}

fn config(technique: Technique) -> RendererConfig {
    tests::technique_config(technique, W, H)
}

/// One frame of `scene`'s world (its own content left out) drawn with the game `make`
/// builds on the renderer.
fn draw<G: GameStages>(
    ctx: &GpuContext,
    scene: &Scene,
    config: RendererConfig,
    make: impl FnOnce(&Renderer) -> G,
) -> Image {
    let (w, h) = (config.width, config.height);
    let bare = Scene {
        content: Content::default(),
        ..scene.clone()
    };
    let mut r = renderer_for(ctx, &bare, config).unwrap();
    let mut game = make(&r.renderer);
    let target = Offscreen::new(ctx, w, h);
    r.renderer
        .render_and_submit(&target.view, &scene.cameras[0], &mut game)
        .unwrap();
    target.read(ctx).unwrap()
}

/// Bubbles over the water in front of the window, a translucent cube and an opaque crate:
/// `n` particles in all.
fn things(n: usize) -> Content {
    let mut particles = Content::scatter(
        DVec3::new(-8.0, -4.5, -20.0),
        DVec3::new(8.0, 1.0, -4.0),
        n,
        3,
        0.25,
        [225, 240, 255],
        0.5,
    );
    // Every tenth one red, so that a misplaced instance shows.
    for p in particles.iter_mut().step_by(10) {
        p.color = [230, 40, 40];
    }
    let cube = Entity {
        center: DVec3::new(-2.0, -1.0, -10.0),
        half_extents: [1.5; 3],
        rotation: DQuat::from_euler(glam::EulerRot::YXZ, 0.5, 0.3, 0.1),
        color: [90, 225, 140],
        opacity: 0.5,
        emissive: 0.0,
    };
    let crate_box = Entity {
        center: DVec3::new(3.0, -1.0, -12.0),
        opacity: 1.0,
        color: [160, 118, 75],
        ..cube
    };
    Content {
        particles,
        entities: vec![cube, crate_box],
    }
}

/// A device whose storage bindings (or, instanced, buffers) hold 16 KiB (204 instances) draws
/// content over many buffers; the picture is the one of a device that holds it in one,
/// with every technique, for content made at its size and for content grown by
/// `set_content` from a few things.
#[test]
fn content_split_over_many_buffers_draws_what_one_buffer_draws() {
    let Some(ctx) = gpu() else { return };
    let small_storage = gpu_with_limits(|l| l.max_storage_buffer_binding_size = 16 << 10).unwrap();
    let small_buffers = gpu_with_limits(|l| l.max_buffer_size = 1 << 20).unwrap();
    let scene = window_scene();
    let content = things(3000);
    for t in [
        Technique::SortedQuads,
        Technique::WboitMrt,
        Technique::DepthPeeling,
    ] {
        let made = |c: &Content| {
            let c = c.clone();
            move |r: &Renderer| ContentStages::new(r, c).unwrap()
        };
        let grown = |c: &Content, ctx: &GpuContext| {
            let (c, ctx) = (c.clone(), ctx.clone());
            move |r: &Renderer| {
                let mut s = ContentStages::new(r, things(5)).unwrap();
                s.set_content(&ctx, c).unwrap();
                s
            }
        };
        let expected = draw(&ctx, &scene, config(t), made(&content));
        assert!(distinct_colours(&expected) > 200, "{t}: a flat picture");
        let bare = draw(&ctx, &scene, config(t), |_| NoGame);
        assert!(
            diff(&expected, &bare).over_one > 1000,
            "{t}: no content seen"
        );
        let instanced = RendererConfig {
            quad_fetch: Some(QuadFetch::Instanced),
            ..config(t)
        };
        for (label, device, config) in [
            ("storage", &small_storage, config(t)),
            ("instanced", &small_buffers, instanced),
        ] {
            for (how, picture) in [
                ("made", draw(device, &scene, config.clone(), made(&content))),
                (
                    "grown",
                    draw(device, &scene, config.clone(), grown(&content, device)),
                ),
            ] {
                let d = diff(&picture, &expected);
                let dir = out_dir(&format!("content_pages_{label}_{how}_{t}"));
                picture.save_png(&dir.join("actual.png")).unwrap();
                expected.save_png(&dir.join("expected.png")).unwrap();
                assert_eq!(
                    d.max,
                    0,
                    "{t} {label} {how}: {} px differ; see {}",
                    d.differing,
                    dir.display()
                );
            }
        }
    }
}

/// A million particles, as a scene file may ask for, draw: made at that size, and grown to
/// it by `set_content` (to room for two million, more than one 128 MiB storage binding
/// holds at 80 bytes each). The millionth particle, alone at the centre of the view, is
/// seen.
#[test]
fn a_million_particles_draw_made_or_grown() {
    let Some(ctx) = gpu() else { return };
    let scene = window_scene();
    let camera = scene.cameras[0];
    let (w, h) = (64, 36);
    let mut content = Content {
        particles: Content::scatter(
            DVec3::new(-20.0, -5.0, -40.0),
            DVec3::new(20.0, -4.0, -30.0),
            1_000_000,
            9,
            0.02,
            [225, 240, 255],
            0.3,
        ),
        entities: Vec::new(),
    };
    // The last one: a large opaque red square in front of the eye.
    let last = content.particles.last_mut().unwrap();
    *last = Particle {
        center: camera.eye + camera.unit_forward() * 3.0,
        half_size: 0.4,
        color: [255, 0, 0],
        opacity: 1.0,
        emissive: 0.0,
    };
    let cfg = RendererConfig {
        width: w,
        height: h,
        ..config(Technique::WboitMrt)
    };
    let centre = |img: &Image| img.pixel(w / 2, h / 2);
    let made = draw(&ctx, &scene, cfg.clone(), |r| {
        ContentStages::new(r, content.clone()).unwrap()
    });
    let grown = draw(&ctx, &scene, cfg, |r| {
        let mut s = ContentStages::new(r, things(1000)).unwrap();
        s.set_content(&ctx, content.clone()).unwrap();
        s
    });
    for (how, img) in [("made", &made), ("grown", &grown)] {
        let [r, g, b, _] = centre(img);
        assert!(
            r > 200 && g < 60 && b < 60,
            "{how}: the millionth particle is not seen at the centre: {:?}",
            [r, g, b]
        );
    }
    assert_eq!(diff(&made, &grown).max, 0);
}

/// A NaN, infinite or out-of-range value is refused naming the particle or entity, its
/// index and the field, by `new` and by `set_content`; a refused `set_content` keeps what
/// was drawn, and no frame draws a magenta (non-finite) pixel.
#[test]
fn bad_values_are_refused_and_the_last_good_content_still_draws() {
    let Some(ctx) = gpu() else { return };
    let scene = window_scene();
    let mut r = renderer_for(
        &ctx,
        &Scene {
            content: Content::default(),
            ..scene.clone()
        },
        config(Technique::SortedQuads),
    )
    .unwrap();
    let good = things(200);
    let mut nan = good.clone();
    nan.particles[3].opacity = f32::NAN;
    match ContentStages::new(&r.renderer, nan.clone()) {
        Err(e @ Error::InvalidContent { .. }) => {
            let m = e.to_string();
            assert!(m.contains("particle 3") && m.contains("opacity"), "{m}");
        }
        other => panic!("NaN opacity: {other:?}"),
    }
    let mut stages = ContentStages::new(&r.renderer, good.clone()).unwrap();
    let target = Offscreen::new(&ctx, W, H);
    let camera = scene.cameras[0];
    let mut frame = |stages: &mut ContentStages| {
        r.renderer
            .render_and_submit(&target.view, &camera, stages)
            .unwrap();
        target.read(&ctx).unwrap()
    };
    let before = frame(&mut stages);
    let mut bad = [nan, good.clone(), good.clone(), good.clone()];
    bad[1].entities[1].center.y = f64::INFINITY;
    bad[2].entities[0].rotation = DQuat::from_xyzw(0.0, 0.0, 0.0, 0.0);
    bad[3].particles[199].emissive = -1.0;
    let fields = [
        ("particle 3", "opacity"),
        ("entity 1", "center"),
        ("entity 0", "rotation"),
        ("particle 199", "emissive"),
    ];
    for (content, (what, field)) in bad.into_iter().zip(fields) {
        let e = stages.set_content(&ctx, content).unwrap_err();
        let m = e.to_string();
        assert!(
            matches!(e, Error::InvalidContent { .. }) && m.contains(what) && m.contains(field),
            "{m}"
        );
        let after = frame(&mut stages);
        assert_eq!(diff(&after, &before).max, 0, "{what}: the picture changed");
        let magenta = after
            .rgba
            .chunks_exact(4)
            .filter(|p| p[..3] == [255, 0, 255])
            .count();
        assert_eq!(magenta, 0, "{what}: non-finite pixels");
    }
}

/// Fireflies under the water, seen through the window at midnight: lit only by the moon
/// they are dim; with their own light (`emissive`) they glow through the glass and the
/// water, which dim them as anything behind them, and the CPU ray march, which adds the
/// same light, draws the same picture.
#[test]
fn an_emissive_firefly_glows_through_water_and_glass_at_night() {
    let Some(ctx) = gpu() else { return };
    let night = Lighting::daytime(0.0);
    let cfg = |t| RendererConfig {
        flat_textures: true,
        sun_dir: night.sun_dir,
        ambient: night.ambient,
        brightness: night.brightness,
        sky: night.sky,
        ..tests::technique_config(t, 192, 108)
    };
    // Through the clear glass (left) and the blue glass (right), 2 to 3 blocks under the
    // surface.
    let fireflies = |emissive: f32| Content {
        particles: [-5.0, -4.0, 3.5, 4.5]
            .into_iter()
            .flat_map(|x| [-2.5, -3.3].map(|y| DVec3::new(x, y, -14.0)))
            .map(|center| Particle {
                center,
                half_size: 0.35,
                color: [255, 220, 90],
                opacity: 0.9,
                emissive,
            })
            .collect(),
        entities: Vec::new(),
    };
    let base = window_scene();
    let camera = base.cameras[0];
    let lit = |emissive| Scene {
        content: fireflies(emissive),
        ..base.clone()
    };
    let picture = |s: &Scene, t| tests::render_with(&ctx, s, cfg(t));
    let dim = picture(&lit(0.0), Technique::Reference);
    let glow = picture(&lit(6.0), Technique::Reference);
    let dir = out_dir("content_fireflies");
    dim.save_png(&dir.join("dim.png")).unwrap();
    glow.save_png(&dir.join("glow.png")).unwrap();
    // Each firefly's centre: much brighter with its own light, through both glasses.
    let aspect = 192.0 / 108.0;
    let vp = camera.view_proj(aspect);
    for p in fireflies(6.0).particles {
        let clip = vp * (p.center - camera.eye).as_vec3().extend(1.0);
        let x = ((clip.x / clip.w + 1.0) / 2.0 * 192.0) as u32;
        let y = ((1.0 - clip.y / clip.w) / 2.0 * 108.0) as u32;
        let (d, g) = (dim.pixel(x, y), glow.pixel(x, y));
        assert!(
            u32::from(g[0]) > u32::from(d[0]) + 60 && g[0] > g[2],
            "the firefly at {:?}: dim {d:?}, glowing {g:?}",
            p.center
        );
    }
    // The ray march adds the same light.
    let mut r = renderer_for(&ctx, &lit(6.0), cfg(Technique::Reference)).unwrap();
    let gpu_picture = render_image(&ctx, &mut r, &Offscreen::new(&ctx, 192, 108), &camera).unwrap();
    let drawn = r.drawn_camera(&camera);
    let shading = Shading::of(&cfg(Technique::Reference));
    let marcher = RayMarcher::with_content(&base.world, &fireflies(6.0));
    let ray = marcher.render(&drawn, 192, 108, &shading);
    let c = marcher.compare(&ray, &drawn, &shading, &gpu_picture, None);
    // Within 2/255 off edges: without their own light every pixel is within 1/255; with
    // it, a firefly six times as bright as its colour differs by 2/255 on 53 of its
    // pixels (one row of them), 13 at three times: the error grows with the light.
    assert!(
        c.max_abs_err_off_edges <= 2 && c.cracks == 0,
        "{} pixels off edges differ (max {}/255): {:?}",
        c.differing,
        c.max_abs_err_off_edges,
        c.worst
    );
    // The real-time default shows the glow as the reference does.
    let quads = picture(&lit(6.0), Technique::SortedQuads);
    let d = diff(&quads, &gpu_picture);
    assert!(d.over_one < 40, "sorted-quads against the reference: {d:?}");
}

/// Things at the largest emissive, stacked opaque-white in front of each other, keep every
/// technique's sums finite: no non-finite value in the scene colour, no magenta pixel.
#[test]
fn the_largest_emissive_stays_finite_in_every_technique() {
    let Some(ctx) = gpu() else { return };
    let base = window_scene();
    let camera = base.cameras[0];
    let content = Content {
        particles: (0..64)
            .map(|i| Particle {
                center: camera.eye + camera.unit_forward() * (2.0 + f64::from(i) * 0.05),
                half_size: 1.5,
                color: [255, 255, 255],
                opacity: 1.0,
                emissive: MAX_EMISSIVE,
            })
            .collect(),
        entities: vec![Entity {
            center: camera.eye + camera.unit_forward() * 6.0,
            half_extents: [2.0; 3],
            rotation: DQuat::IDENTITY,
            color: [255, 255, 255],
            opacity: 1.0,
            emissive: MAX_EMISSIVE,
        }],
    };
    let scene = Scene { content, ..base };
    for t in Technique::REAL_TIME
        .into_iter()
        .chain([Technique::Reference])
    {
        let mut r = renderer_for(&ctx, &scene, config(t)).unwrap();
        let img = render_image(&ctx, &mut r, &Offscreen::new(&ctx, W, H), &camera).unwrap();
        let hdr = tests::read_hdr(&ctx, r.scene_color());
        let bad = hdr
            .iter()
            .filter(|p| p.iter().any(|c| !c.is_finite()))
            .count();
        assert_eq!(bad, 0, "{t}: {bad} non-finite scene pixels");
        let [red, green, blue, _] = img.pixel(W / 2, H / 2);
        assert!(
            red > 250 && green > 250 && blue > 250,
            "{t}: the centre is {:?}, not white",
            [red, green, blue]
        );
    }
}

/// `Both` draws two games as one: the content split over two `ContentStages` (particles
/// in one, entities in the other) draws exactly what one `ContentStages` of it all draws,
/// with every technique (the sorted ones order the two parts' objects together and each
/// part draws its runs of that order), and content beside a game that draws nothing draws
/// what the content alone draws.
#[test]
fn both_draws_two_games_as_one() {
    let Some(ctx) = gpu() else { return };
    let scene = window_scene();
    let all = things(400);
    let particles = Content {
        particles: all.particles.clone(),
        entities: Vec::new(),
    };
    let entities = Content {
        particles: Vec::new(),
        entities: all.entities.clone(),
    };
    for t in Technique::REAL_TIME
        .into_iter()
        .chain([Technique::Reference])
    {
        let one = draw(&ctx, &scene, config(t), |r| {
            ContentStages::new(r, all.clone()).unwrap()
        });
        let two = draw(&ctx, &scene, config(t), |r| {
            Both::new(
                ContentStages::new(r, particles.clone()).unwrap(),
                ContentStages::new(r, entities.clone()).unwrap(),
            )
        });
        let beside = draw(&ctx, &scene, config(t), |r| {
            Both::new(NoGame, ContentStages::new(r, all.clone()).unwrap())
        });
        let dir = out_dir(&format!("content_both_{t}"));
        one.save_png(&dir.join("one.png")).unwrap();
        two.save_png(&dir.join("two.png")).unwrap();
        assert_eq!(
            diff(&two, &one).max,
            0,
            "{t}: split in two; see {}",
            dir.display()
        );
        assert_eq!(diff(&beside, &one).max, 0, "{t}: beside nothing");
    }
}
