//! What a game needs to embed the renderer, on lavapipe: its own images per face
//! group (checkers where they belong, cutout and translucent alpha from the image, bad
//! images refused), lighting changed on a live renderer (the picture of a renderer built
//! with it, no chunk uploaded again), every output format a surface offers, techniques
//! built ahead of a switch, frames with nothing called after the submit, and the ray
//! march sampling textures as the GPU does.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use std::path::Path;
use std::sync::Arc;

use glam::DVec3;
use tests::{
    Offscreen, Scene, diff, frame, gpu, out_dir, png_header_bomb, renderer_for, technique_config,
};
use voxel_core::{BlockDef, BlockId, BlockImage, BlockRegistry, FaceImages, World, blocks};
use voxel_lab::raymarch::{RayMarcher, Shading};
use voxel_render::textures::{load_block_image, srgb_to_linear};
use voxel_render::{Camera, Image, Lighting, NoGame, RendererConfig, Technique, readback};

/// An `n` × `n` checker of `a` (where x + y is even) and `b`.
fn checker(a: [u8; 4], b: [u8; 4], n: u32) -> BlockImage {
    let rgba = (0..n * n)
        .flat_map(|i| {
            if (i % n + i / n).is_multiple_of(2) {
                a
            } else {
                b
            }
        })
        .collect();
    BlockImage::new(n, n, rgba).unwrap()
}

/// A world over `registry` with `boxes` of blocks (inclusive corners).
fn world(registry: BlockRegistry, boxes: &[([i32; 3], [i32; 3], BlockId)]) -> World {
    let mut world = World::new(Arc::new(registry));
    for &(min, max, id) in boxes {
        voxel_lab::scene::fill_box(&mut world, min, max, id).unwrap();
    }
    world
}

fn scene(world: World, eye: [f64; 3], target: [f64; 3]) -> Scene {
    let camera = Camera::look_at(DVec3::from(eye), DVec3::from(target), 60.0, 0.1, 500.0).unwrap();
    Scene::new("embed", world, camera)
}

/// The pixel a world point projects to.
fn pixel(camera: &Camera, size: (u32, u32), p: [f64; 3]) -> (u32, u32) {
    let vp = camera.view_proj(f64::from(size.0) / f64::from(size.1));
    let rel = (DVec3::from(p) - camera.eye).as_vec3();
    let clip = vp * rel.extend(1.0);
    let ndc = clip.truncate() / clip.w;
    let x = (ndc.x + 1.0) / 2.0 * size.0 as f32;
    let y = (1.0 - ndc.y) / 2.0 * size.1 as f32;
    (x as u32, y as u32)
}

/// Renders `scene` with `config` and keeps the picture under `target/test-output/name`.
fn render(name: &str, scene: &Scene, config: RendererConfig) -> Image {
    let ctx = gpu().unwrap();
    let img = tests::render_with(&ctx, scene, config);
    img.save_png(&out_dir("embed").join(format!("{name}.png")))
        .unwrap();
    img
}

const RED: [u8; 4] = [255, 0, 0, 255];
const WHITE: [u8; 4] = [255, 255, 255, 255];
const BLUE: [u8; 4] = [0, 0, 255, 255];
const BLACK: [u8; 4] = [0, 0, 0, 255];

#[test]
fn a_checker_image_shows_on_its_faces_and_top_and_side_differ() {
    if gpu().is_none() {
        return;
    }
    let mut registry = BlockRegistry::default();
    let id = registry
        .register(
            BlockDef::new("crate", [128, 128, 128], 1.0).with_images(FaceImages {
                top: Some(checker(RED, WHITE, 2)),
                bottom: None,
                side: Some(checker(BLUE, BLACK, 2)),
            }),
        )
        .unwrap();
    let s = scene(
        world(registry, &[([0, 0, 0], [0, 0, 0], id)]),
        [0.5, 2.3, 2.4],
        [0.5, 0.6, 0.5],
    );
    let size = (256, 256);
    let img = render(
        "checker",
        &s,
        technique_config(Technique::SortedQuads, size.0, size.1),
    );
    let at = |p| {
        let (x, y) = pixel(&s.cameras[0], size, p);
        img.pixel(x, y)
    };
    let red = |c: [u8; 4]| c[0] > 120 && c[1] < 40 && c[2] < 40;
    let white = |c: [u8; 4]| c[0] > 120 && c[1] > 120 && c[2] > 120;
    let blue = |c: [u8; 4]| c[2] > 120 && c[0] < 40 && c[1] < 40;
    let black = |c: [u8; 4]| c[0] < 30 && c[1] < 30 && c[2] < 30;
    // The top: the image's x along +x, its y along +z; texel (0, 0) red.
    for (p, want, name) in [
        ([0.25, 1.0, 0.25], red as fn([u8; 4]) -> bool, "red"),
        ([0.75, 1.0, 0.25], white, "white"),
        ([0.25, 1.0, 0.75], white, "white"),
        ([0.75, 1.0, 0.75], red, "red"),
        // The +z side, upright: its first row (blue, black) along the top edge.
        ([0.25, 0.75, 1.0], blue, "blue"),
        ([0.75, 0.75, 1.0], black, "black"),
        ([0.25, 0.25, 1.0], black, "black"),
        ([0.75, 0.25, 1.0], blue, "blue"),
    ] {
        assert!(want(at(p)), "{p:?} should be {name}: {:?}", at(p));
    }
}

#[test]
fn a_cutout_image_cuts_where_its_alpha_is_zero() {
    if gpu().is_none() {
        return;
    }
    let mut registry = BlockRegistry::default();
    // Left column transparent, right column solid magenta.
    let clear = [0, 255, 0, 0];
    let magenta = [255, 0, 255, 255];
    let image = BlockImage::new(2, 2, [clear, magenta, clear, magenta].concat()).unwrap();
    let id = registry
        .register(BlockDef::cutout("vine", [10, 200, 10]).with_images(FaceImages::all(image)))
        .unwrap();
    let wall = ([-4, -4, -3], [4, 4, -3], blocks::STONE);
    let eye = [0.5, 0.5, 3.0];
    let size = (192, 192);
    let config = technique_config(Technique::SortedQuads, size.0, size.1);
    let with = scene(
        world(registry.clone(), &[wall, ([0, 0, 0], [0, 0, 0], id)]),
        eye,
        [0.5, 0.5, 0.0],
    );
    let without = scene(world(registry, &[wall]), eye, [0.5, 0.5, 0.0]);
    let a = render("cutout", &with, config.clone());
    let b = render("cutout_wall", &without, config);
    let cam = with.cameras[0];
    // The cut half shows the wall exactly; the solid half is magenta.
    let (x, y) = pixel(&cam, size, [0.25, 0.5, 1.0]);
    assert_eq!(a.pixel(x, y), b.pixel(x, y), "the cut half shows the wall");
    let (x, y) = pixel(&cam, size, [0.75, 0.5, 1.0]);
    let m = a.pixel(x, y);
    assert!(m[0] > 120 && m[2] > 120 && m[1] < 30, "magenta: {m:?}");
}

#[test]
fn a_translucent_image_alpha_is_the_opacity() {
    if gpu().is_none() {
        return;
    }
    let mut registry = BlockRegistry::default();
    let color = [200, 120, 60];
    // The block says 0.2; the image says 153/255 = 0.6.
    let alpha = 153u8;
    let image = BlockImage::solid([color[0], color[1], color[2], alpha]);
    let id = registry
        .register(BlockDef::new("tinted", color, 0.2).with_images(FaceImages::all(image)))
        .unwrap();
    let wall = ([-6, -6, -3], [6, 6, -3], blocks::STONE);
    let eye = [0.5, 0.5, 4.0];
    let size = (128, 128);
    let config = technique_config(Technique::SortedQuads, size.0, size.1);
    let with = scene(
        world(registry.clone(), &[wall, ([-2, -2, 0], [2, 2, 0], id)]),
        eye,
        [0.5, 0.5, 0.0],
    );
    let without = scene(world(registry, &[wall]), eye, [0.5, 0.5, 0.0]);
    let a = render("translucent", &with, config.clone());
    let b = render("translucent_wall", &without, config.clone());
    // Lambert on the +z face with the default sun and ambient, no occlusion on a sheet.
    let sun = glam::Vec3::from(config.sun_dir).normalize();
    let light = config.ambient + (1.0 - config.ambient) * sun.z.max(0.0);
    let lit = color.map(|c| srgb_to_linear(c) * light);
    let encode = voxel_render::textures::linear_to_srgb;
    let blend = |alpha: f32, bg: [u8; 4]| -> [u8; 3] {
        [0, 1, 2].map(|c| encode(lit[c] * alpha + srgb_to_linear(bg[c]) * (1.0 - alpha)))
    };
    let mut checked = 0;
    for y in (8..size.1 - 8).step_by(8) {
        for x in (8..size.0 - 8).step_by(8) {
            let (got, bg) = (a.pixel(x, y), b.pixel(x, y));
            let want = blend(f32::from(alpha) / 255.0, bg);
            for c in 0..3 {
                assert!(
                    got[c].abs_diff(want[c]) <= 2,
                    "({x}, {y}): {got:?}, the image's alpha gives {want:?}"
                );
            }
            // The block's own opacity would give another colour.
            let block = blend(0.2, bg);
            assert!((0..3).any(|c| got[c].abs_diff(block[c]) > 20));
            checked += 1;
        }
    }
    assert!(checked > 100);
}

#[test]
fn bad_images_are_clear_errors() {
    let dir = out_dir("embed_bad_images");
    let png = |name: &str, w: u32, h: u32| {
        let path = dir.join(name);
        Image {
            width: w,
            height: h,
            rgba: vec![200; (w * h * 4) as usize],
        }
        .save_png(&path)
        .unwrap();
        path
    };
    let message = |path: &Path| load_block_image(path).unwrap_err().to_string();
    let good = png("good.png", 32, 32);
    assert_eq!(load_block_image(&good).unwrap().size(), 32);
    let e = message(&png("wide.png", 32, 16));
    assert!(e.contains("wide.png") && e.contains("square"), "{e}");
    let e = message(&png("odd.png", 24, 24));
    assert!(e.contains("odd.png") && e.contains("power of two"), "{e}");
    let e = message(&png("huge.png", 512, 512));
    assert!(e.contains("huge.png") && e.contains("256"), "{e}");
    let garbage = dir.join("garbage.png");
    std::fs::write(&garbage, b"not a png at all").unwrap();
    let e = message(&garbage);
    assert!(
        e.contains("garbage.png") && e.contains("PNG decoding: "),
        "{e}"
    );
    let e = message(&dir.join("missing.png"));
    assert!(
        e.contains("missing.png") && e.len() > "missing.png: ".len(),
        "{e}"
    );
    // In memory: the wrong number of bytes.
    let e = BlockImage::new(4, 4, vec![0; 63]).unwrap_err().to_string();
    assert!(e.contains("64 bytes"), "{e}");
}

/// PNG header bombs (a few bytes whose header claims a huge image) are refused from the
/// header, before anything is allocated, through the library and through a scene file's
/// `texture =` key; so is a real image larger than a block image may be.
#[test]
fn png_header_bombs_are_refused_before_decoding() {
    let dir = out_dir("embed_png_bombs");
    for (w, h) in [(100_000, 100_000), (16_384, 16_384), (257, 257), (4096, 1)] {
        let path = dir.join(format!("bomb_{w}x{h}.png"));
        png_header_bomb(&path, w, h);
        assert!(std::fs::metadata(&path).unwrap().len() < 100);
        let start = std::time::Instant::now();
        let e = load_block_image(&path).unwrap_err();
        assert!(matches!(e, voxel_render::Error::Image { .. }), "{e:?}");
        let e = e.to_string();
        assert!(
            e.contains(&format!("bomb_{w}x{h}.png")) && e.contains(&format!("{w}x{h} pixels")),
            "{e}"
        );
        assert!(e.contains("at most 256"), "{e}");
        // Refused from the header: no decoding of a gigabyte (generous for a loaded CI).
        assert!(start.elapsed().as_secs() < 5, "{e}");
        // The general reader has its own bound, from the header too.
        let e = Image::load_png(&path);
        if w > Image::MAX_PNG_SIDE {
            assert!(e.unwrap_err().to_string().contains("at most 16384"));
        } else {
            // Within the bound: decoding starts and finds the data missing.
            assert!(e.unwrap_err().to_string().contains("PNG decoding"));
        }
    }
    let scene = dir.join("bomb.toml");
    std::fs::write(
        &scene,
        "name = \"bomb\"\n[[blocks]]\nname = \"b\"\ncolor = [1, 2, 3]\nopacity = 1.0\n\
         texture = \"bomb_100000x100000.png\"\n\
         [[cameras]]\neye = [0.0, 0.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\n",
    )
    .unwrap();
    let e = Scene::load(&scene).unwrap_err().to_string();
    assert!(
        e.contains("blocks.texture") && e.contains("100000x100000 pixels"),
        "{e}"
    );
}

/// Grass, water and glass on stone: lit faces of every direction.
fn lit_scene() -> Scene {
    let w = world(
        BlockRegistry::default(),
        &[
            ([-12, -2, -12], [12, -1, 12], blocks::STONE),
            ([-12, 0, -12], [12, 0, 12], blocks::GRASS),
            ([-12, 1, -12], [-3, 2, 12], blocks::GRASS),
            ([0, 1, -4], [6, 1, 4], blocks::WATER),
            ([2, 2, -1], [4, 5, -1], blocks::GLASS),
        ],
    );
    scene(w, [9.0, 7.0, 9.0], [0.0, 1.0, 0.0])
}

#[test]
fn lighting_changed_at_run_time_equals_a_renderer_built_with_it() {
    let Some(ctx) = gpu() else { return };
    let s = lit_scene();
    let cam = s.cameras[0];
    let config = technique_config(Technique::WboitMrt, 160, 120);
    let mut live = renderer_for(&ctx, &s, config.clone()).unwrap();
    let noon = frame(&ctx, &mut live, &cam);
    let generations = |r: &voxel_render::Renderer| -> Vec<u64> {
        let mut g: Vec<u64> = voxel_render::low_level::chunks(r)
            .iter()
            .map(|c| c.generation())
            .collect();
        g.sort_unstable();
        g
    };
    let before = generations(&live);
    let dusk = Lighting::daytime(17.5);
    live.set_lighting(dusk).unwrap();
    assert_eq!(live.lighting(), dusk);
    let changed = frame(&ctx, &mut live, &cam);
    assert_eq!(generations(&live), before, "no chunk was uploaded again");
    let built = RendererConfig {
        sun_dir: dusk.sun_dir,
        ambient: dusk.ambient,
        sky: dusk.sky,
        ..config
    };
    let mut fresh = renderer_for(&ctx, &s, built).unwrap();
    let expected = frame(&ctx, &mut fresh, &cam);
    tests::assert_close("embed_lighting", &changed, &expected, 0);
    assert!(diff(&noon, &changed).max > 20, "the light did change");
    // Bad values are errors and change nothing.
    for bad in [
        Lighting {
            sun_dir: [0.0; 3],
            ..dusk
        },
        Lighting {
            ambient: 1.5,
            ..dusk
        },
        Lighting {
            sky: [f32::NAN, 0.0, 0.0],
            ..dusk
        },
    ] {
        assert!(live.set_lighting(bad).is_err(), "{bad:?}");
    }
    assert_eq!(live.lighting(), dusk);
}

#[test]
fn every_format_a_surface_offers_draws_the_same_picture() {
    let Some(ctx) = gpu() else { return };
    let s = lit_scene();
    let cam = s.cameras[0];
    let (w, h) = (96, 72);
    // Made for the default RGBA sRGB output; no setting changes below.
    let mut r = renderer_for(&ctx, &s, technique_config(Technique::SortedQuads, w, h)).unwrap();
    let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
    let draw = |r: &mut voxel_render::Renderer, format| {
        let t = voxel_render::stages::target(&ctx.device, "surface_like", format, usage, (w, h));
        r.render_and_submit(&t.view, &cam, &mut NoGame).unwrap();
        assert_eq!(
            r.config().output_format,
            format,
            "the config follows the output"
        );
        t.texture
    };
    use wgpu::TextureFormat as F;
    let first = readback::read_image(&ctx, &draw(&mut r, F::Rgba8UnormSrgb)).unwrap();
    for format in [
        F::Bgra8UnormSrgb,
        F::Bgra8Unorm,
        F::Rgba8Unorm,
        F::Rgba8UnormSrgb,
    ] {
        let img = readback::read_image(&ctx, &draw(&mut r, format)).unwrap();
        // Linear formats are encoded by the shader instead of the GPU: rounding apart.
        let d = diff(&first, &img);
        assert!(d.max <= 1, "{format:?}: differs by {}/255", d.max);
    }
    // Half float is written linear.
    let half = draw(&mut r, F::Rgba16Float);
    let bytes = readback::read_texture(&ctx, &half, 8).unwrap();
    let encode = voxel_render::textures::linear_to_srgb;
    let mut worst = 0;
    for (p, q) in bytes.chunks_exact(8).zip(first.rgba.chunks_exact(4)) {
        for c in 0..3 {
            let v = readback::f16_to_f32(u16::from_le_bytes([p[2 * c], p[2 * c + 1]]));
            worst = worst.max(encode(v).abs_diff(q[c]));
        }
    }
    assert!(worst <= 1, "Rgba16Float differs by {worst}/255");
}

#[test]
fn a_technique_built_ahead_switches_without_building() {
    let Some(ctx) = gpu() else { return };
    let s = lit_scene();
    let cam = s.cameras[0];
    let config = technique_config(Technique::WboitMrt, 96, 72);
    let mut r = renderer_for(&ctx, &s, config.clone()).unwrap();
    frame(&ctx, &mut r, &cam);
    let builds = |r: &voxel_render::Renderer| voxel_render::low_level::oit(r).builds();
    assert_eq!(builds(&r), 1, "WBOIT built at its first frame");
    assert_eq!(
        r.prebuild_technique(Technique::SortedQuads).unwrap(),
        Technique::SortedQuads
    );
    assert_eq!(builds(&r), 2);
    // Resized while waiting: it follows.
    r.resize(80, 60).unwrap();
    r.set_technique(Technique::SortedQuads).unwrap();
    let sorted = frame(&ctx, &mut r, &cam);
    assert_eq!(builds(&r), 2, "the switch built nothing");
    // Back and forth: WBOIT was not built ahead, the sorted technique stays built.
    r.set_technique(Technique::WboitMrt).unwrap();
    frame(&ctx, &mut r, &cam);
    assert_eq!(builds(&r), 3);
    r.set_technique(Technique::SortedQuads).unwrap();
    let again = frame(&ctx, &mut r, &cam);
    assert_eq!(builds(&r), 3);
    let mut fresh =
        renderer_for(&ctx, &s, technique_config(Technique::SortedQuads, 80, 60)).unwrap();
    let expected = frame(&ctx, &mut fresh, &cam);
    tests::assert_close("embed_prebuilt", &sorted, &expected, 0);
    tests::assert_close("embed_prebuilt_again", &again, &expected, 0);
    // A setting it is built from rebuilds it at the change, not at the next switch.
    r.prebuild_technique(Technique::DepthPeeling).unwrap();
    let n = builds(&r);
    let mut oit = r.config().oit.clone();
    oit.peeling.layers = 6;
    r.set_oit_config(oit).unwrap();
    assert_eq!(builds(&r), n + 1);
    r.set_technique(Technique::DepthPeeling).unwrap();
    frame(&ctx, &mut r, &cam);
    assert_eq!(builds(&r), n + 1);
    // Released: switching to it builds again.
    r.set_technique(Technique::Stipple).unwrap();
    r.release_technique(Technique::SortedQuads);
    r.set_technique(Technique::SortedQuads).unwrap();
    frame(&ctx, &mut r, &cam);
    assert!(builds(&r) > n + 1);
}

#[test]
fn real_time_techniques_are_those_that_never_stall() {
    let stalling = [Technique::Reference, Technique::PeelReference];
    let want: Vec<_> = Technique::ALL
        .into_iter()
        .filter(|t| !stalling.contains(t))
        .collect();
    assert_eq!(Technique::REAL_TIME.to_vec(), want);
    assert!(
        Technique::ALL
            .iter()
            .all(|t| t.stalls() == stalling.contains(t))
    );
}

#[test]
fn frames_need_nothing_called_after_the_submit() {
    let Some(ctx) = gpu() else { return };
    // Depth peeling adapts its layer count to counts it reads back: without any call
    // after the submits they still arrive.
    let s = tests::dense_sheets(6, 0.5);
    let cam = s.cameras[0];
    let mut r = renderer_for(&ctx, &s, technique_config(Technique::DepthPeeling, 64, 48)).unwrap();
    for _ in 0..4 {
        let target = Offscreen::new(&ctx, 64, 48);
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        r.render(&mut encoder, &target.view, &cam, &mut NoGame)
            .unwrap();
        ctx.queue.submit([encoder.finish()]);
        ctx.device
            .poll(wgpu::PollType::wait_indefinitely())
            .unwrap();
    }
    let report = r
        .render_and_submit(&Offscreen::new(&ctx, 64, 48).view, &cam)
        .unwrap()
        .technique
        .peeling
        .unwrap();
    assert!(
        report.layers.is_some_and(|l| l >= 6),
        "layers read back: {report:?}"
    );
    if !ctx.caps.timestamps() {
        eprintln!("no timestamp queries on this adapter: timings not checked");
        return;
    }
    assert!(!r.gpu_times_blocking().is_empty(), "timings arrived");
    // Two frames in one encoder (the second goes untimed), and a frame whose encoder is
    // dropped: no validation error, and timings keep coming.
    let target = Offscreen::new(&ctx, 64, 48);
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    r.render(&mut encoder, &target.view, &cam, &mut NoGame)
        .unwrap();
    r.render(&mut encoder, &target.view, &cam, &mut NoGame)
        .unwrap();
    ctx.queue.submit([encoder.finish()]);
    let mut dropped = ctx.device.create_command_encoder(&Default::default());
    r.render(&mut dropped, &target.view, &cam, &mut NoGame)
        .unwrap();
    drop(dropped);
    for _ in 0..3 {
        r.render_and_submit(&target.view, &cam).unwrap();
    }
    let times = r.gpu_times_blocking();
    assert!(
        times
            .get(voxel_render::GpuPass::Opaque)
            .is_some_and(|ms| ms > 0.0),
        "{times:?}"
    );
}

#[test]
fn the_ray_march_samples_textures_as_the_gpu_does() {
    let Some(ctx) = gpu() else { return };
    let mut registry = BlockRegistry::default();
    // Every texel a different colour: a mirrored or turned image would show.
    let gradient: Vec<u8> = (0..16 * 16)
        .flat_map(|i| [(i % 16 * 16) as u8, (i / 16 * 16) as u8, 128, 255])
        .collect();
    let gradient = BlockImage::new(16, 16, gradient).unwrap();
    let id = registry
        .register(
            BlockDef::new("gradient", [1, 1, 1], 1.0).with_images(FaceImages {
                top: Some(checker(RED, WHITE, 4)),
                bottom: None,
                side: Some(gradient),
            }),
        )
        .unwrap();
    // Close enough that every face is magnified (the GPU filters minified textures; the
    // ray march reads level 0 only).
    let w = world(
        registry,
        &[
            ([0, 0, 0], [0, 0, 0], id),
            ([-1, 0, 0], [-1, 0, 0], blocks::GRASS),
            ([0, 0, -1], [0, 0, -1], id),
            ([1, 0, 1], [1, 0, 1], blocks::RED_GLASS),
        ],
    );
    let s = scene(w, [1.9, 2.1, 2.3], [0.2, 0.4, 0.2]);
    let size = (384, 288);
    let config = RendererConfig {
        ao_strength: 0.0,
        ..technique_config(Technique::SortedQuads, size.0, size.1)
    };
    let mut r = renderer_for(&ctx, &s, config.clone()).unwrap();
    let gpu_img = frame(&ctx, &mut r, &s.cameras[0]);
    let drawn = r.drawn_camera(&s.cameras[0]);
    let marched = RayMarcher::new(&s.world).render(&drawn, size.0, size.1, &Shading::of(&config));
    let dir = out_dir("embed_raymarch");
    gpu_img.save_png(&dir.join("gpu.png")).unwrap();
    marched.image.save_png(&dir.join("raymarch.png")).unwrap();
    tests::diff_image(&gpu_img, &marched.image)
        .save_png(&dir.join("diff.png"))
        .unwrap();
    let off = gpu_img
        .rgba
        .chunks_exact(4)
        .zip(marched.image.rgba.chunks_exact(4))
        .filter(|(p, q)| (0..3).any(|c| p[c].abs_diff(q[c]) > 2))
        .count();
    let pixels = (size.0 * size.1) as usize;
    // Geometric edges through a pixel centre may go either way: a few pixels (9 of
    // 110 592 when written). A mirrored or turned face would differ on most of its own.
    assert!(
        off * 500 < pixels,
        "{off} of {pixels} pixels differ by more than 2/255; see {}",
        dir.display()
    );
    assert!(
        tests::distinct_colours(&gpu_img) > 200,
        "a textured picture"
    );
}

#[test]
fn a_game_registry_generates_the_default_terrain_through_a_mapping() {
    use voxel_core::{ChunkPos, TerrainBlocks, TerrainConfig, TerrainGenerator, TerrainRole};
    // The game's own blocks, in its own order, none named like a role.
    let mut game = BlockRegistry::new();
    game.register(BlockDef::new("amber_glass", [200, 140, 40], 0.5))
        .unwrap();
    let defaults = BlockRegistry::default();
    let map: Vec<(TerrainRole, BlockId)> = TerrainRole::ALL
        .into_iter()
        .map(|role| {
            let def = defaults.get(role.default_block()).unwrap().clone();
            let name = format!("my_{}", role.name());
            (role, game.register(BlockDef { name, ..def }).unwrap())
        })
        .collect();
    let config = TerrainConfig::default();
    let err = TerrainBlocks::from_registry(&game, &config, &map[..3]).unwrap_err();
    assert!(err.to_string().contains("sand"), "{err}");
    let blocks = TerrainBlocks::from_registry(&game, &config, &map).unwrap();
    let (min, max) = (ChunkPos::new(-1, 0, -1), ChunkPos::new(0, 1, 0));
    let game = Arc::new(game);
    // A generator of the default blocks refuses the game's registry.
    let default_generator = TerrainGenerator::new(config.clone());
    assert!(
        default_generator
            .generate_world(game.clone(), min, max)
            .is_err()
    );
    let mapped = TerrainGenerator::with_blocks(config, blocks);
    let ours = mapped.generate_world(game, min, max).unwrap();
    let theirs = default_generator
        .generate_world(Arc::new(defaults), min, max)
        .unwrap();
    let role_of = |id: BlockId| map.iter().find(|(_, b)| *b == id).map(|(r, _)| *r);
    for (pos, chunk) in theirs.iter() {
        let mine = ours.chunk(pos).unwrap().to_dense();
        for (a, b) in chunk.to_dense().into_iter().zip(mine) {
            let want = TerrainRole::ALL
                .into_iter()
                .find(|r| r.default_block() == a);
            assert_eq!(role_of(b), want, "chunk {pos:?}");
        }
    }
}

/// Every real-time technique built ahead, with a game's translucent pipelines for its
/// contract (`translucent_contract_for`, whose id is the one the contract has once in
/// force): switching through them builds no render pipeline, neither the renderer's
/// (counted by `gpu::pipelines_built`) nor the game's, and each first frame after a switch
/// draws what a fresh renderer of that technique draws.
#[test]
fn switching_to_prebuilt_techniques_builds_no_pipeline() {
    let Some(ctx) = gpu() else { return };
    let s = tests::Scene {
        content: voxel_render::content::Content {
            particles: (0..40)
                .map(|i| voxel_render::content::Particle {
                    center: DVec3::new(
                        -6.0 + f64::from(i) * 0.3,
                        1.5 + f64::from(i % 5) * 0.4,
                        1.0,
                    ),
                    half_size: 0.2,
                    color: [240, 200, 120],
                    opacity: 0.5,
                    emissive: 0.0,
                })
                .collect(),
            entities: vec![],
        },
        ..lit_scene()
    };
    let cam = s.cameras[0];
    let (w, h) = (96, 72);
    let mut r = renderer_for(&ctx, &s, technique_config(Technique::OpaqueOnly, w, h)).unwrap();
    let mut game = r.content.take().unwrap();
    let mut ids = Vec::new();
    for t in Technique::REAL_TIME {
        r.prebuild_technique(t).unwrap();
        game.prebuild(&mut r.renderer, t).unwrap();
        ids.push(r.translucent_contract_for(t).unwrap().id);
    }
    let target = Offscreen::new(&ctx, w, h);
    let game_built = game.pipelines_built();
    for (t, id) in Technique::REAL_TIME.into_iter().zip(ids).rev() {
        let built = voxel_render::low_level::pipelines_built();
        r.set_technique(t).unwrap();
        assert_eq!(
            r.translucent_contract().unwrap().id,
            id,
            "{t}: the id said ahead"
        );
        game.update_pipelines(&mut r.renderer).unwrap();
        r.renderer
            .render_and_submit(&target.view, &cam, &mut game)
            .unwrap();
        let got = target.read(&ctx).unwrap();
        assert_eq!(
            voxel_render::low_level::pipelines_built(),
            built,
            "{t}: the switch built a pipeline"
        );
        assert_eq!(
            game.pipelines_built(),
            game_built,
            "{t}: the game built one"
        );
        let expected = tests::render_with(&ctx, &s, technique_config(t, w, h));
        tests::assert_close(&format!("embed_switch_{t}"), &got, &expected, 0);
    }
}
