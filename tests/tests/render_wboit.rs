//! Renderer and WBOIT on a real (software) GPU: every variant draws the default scene, the
//! two WBOIT variants agree, one layer equals alpha blending, scenes without translucency
//! are identical under every technique, fp16 overflow never reaches the picture, and
//! resizing and switching techniques cause no validation error.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use voxel_core::blocks::*;
use voxel_render::low_level::{HEADROOM_SCALE, RGBA8_SCALE};
use voxel_render::{GpuPass, Renderer, RendererConfig, Technique, WeightFunction};

use tests::*;

const W: u32 = 320;
const H: u32 = 180;

fn default_scene() -> Scene {
    voxel_lab::scene::default_scene(1).unwrap()
}

#[test]
fn every_variant_draws_the_default_scene() {
    let Some(ctx) = gpu() else { return };
    let scene = default_scene();
    let dir = out_dir("every_variant_draws_the_default_scene");
    let opaque = render(&ctx, &scene, Technique::OpaqueOnly, W, H);
    opaque.save_png(&dir.join("opaque-only.png")).unwrap();
    // Not blank: terrain, trees, sky and glass make well over a hundred colours even at
    // this small size (a blank or single-colour picture has a handful).
    assert!(
        distinct_colours(&opaque) > 100,
        "{} colours",
        distinct_colours(&opaque)
    );
    for t in [
        Technique::WboitMrt,
        Technique::WboitTwoPass,
        Technique::Sorted,
    ] {
        let img = render(&ctx, &scene, t, W, H);
        img.save_png(&dir.join(format!("{t}.png"))).unwrap();
        assert!(
            distinct_colours(&img) > 100,
            "{t}: {} colours",
            distinct_colours(&img)
        );
        // The water and glass change a good part of the picture.
        let d = diff(&img, &opaque);
        assert!(
            d.differing > (W * H / 10) as usize,
            "{t}: only {} pixels show translucency",
            d.differing
        );
    }
}

#[test]
fn wboit_variants_agree_within_one_level() {
    let Some(ctx) = gpu() else { return };
    let scene = default_scene();
    let mrt = render(&ctx, &scene, Technique::WboitMrt, W, H);
    let two = render(&ctx, &scene, Technique::WboitTwoPass, W, H);
    // Same maths, different plumbing: only rounding may differ.
    assert_close("wboit_variants_agree", &two, &mrt, 1);
}

/// Two convex translucent slabs side by side with a gap, the camera in front of the gap:
/// every pixel ray enters at most one slab, through one face, so each pixel holds at most
/// one translucent layer.
fn one_layer_scene() -> Scene {
    let world = thin_water_world(&[
        ([-40, -20, -2], [40, 20, -1], STONE),
        ([-30, -12, 6], [-2, 12, 6], WATER),
        ([2, -12, 6], [30, 12, 6], RED_GLASS),
        ([-8, -4, 0], [8, 4, 2], GRASS),
    ]);
    scene("one_layer", world, [0.5, 0.5, 30.0], [0.5, 0.5, 0.0])
}

#[test]
fn one_layer_wboit_equals_alpha_blending() {
    let Some(ctx) = gpu() else { return };
    let scene = one_layer_scene();
    let blended = render(&ctx, &scene, Technique::Sorted, W, H);
    let opaque = render(&ctx, &scene, Technique::OpaqueOnly, W, H);
    assert!(
        diff(&blended, &opaque).differing > (W * H / 4) as usize,
        "the slabs cover the view"
    );
    for t in [Technique::WboitMrt, Technique::WboitTwoPass] {
        let img = render(&ctx, &scene, t, W, H);
        // With one layer, avg = C exactly and revealage = 1 − α: the only differences are
        // fp16 accumulation and the 8-bit revealage (±0.5/255 of α) — within 2/255.
        assert_close(&format!("one_layer_{t}"), &img, &blended, 2);
    }
}

#[test]
fn without_translucent_blocks_every_technique_is_identical() {
    let Some(ctx) = gpu() else { return };
    let world = thin_water_world(&[
        ([-20, -2, -20], [20, 0, 20], GRASS),
        ([-3, 1, -3], [3, 6, 3], STONE),
        ([5, 1, -2], [8, 4, 1], LEAVES),
    ]);
    let scene = scene("opaque_only", world, [14.0, 9.0, 18.0], [0.0, 2.0, 0.0]);
    let reference = render(&ctx, &scene, Technique::OpaqueOnly, W, H);
    assert!(distinct_colours(&reference) > 50);
    for t in Technique::ALL {
        let img = render(&ctx, &scene, t, W, H);
        assert_close(&format!("no_translucency_{t}"), &img, &reference, 0);
    }
}

/// 40 sheets of ice (α 0.92) one block apart in front of the camera: with the `flat`
/// weight (about 3000·α) the accumulated α·w reaches 40 × 2760 = 110 000, past fp16's 65504.
fn overflow_scene() -> Scene {
    let mut boxes = vec![([-30, -30, -90], [30, 30, -88], STONE)];
    for i in 0..40 {
        let z = -2 * i - 2;
        boxes.push(([-30, -30, z], [30, 30, z], ICE));
    }
    scene(
        "overflow",
        thin_water_world(&boxes),
        [0.5, 0.5, 1.0],
        [0.5, 0.5, -10.0],
    )
}

fn overflow_renderer(ctx: &voxel_render::GpuContext, scene: &Scene, headroom: bool) -> Renderer {
    let mut config = RendererConfig {
        width: 64,
        height: 48,
        ..RendererConfig::default()
    };
    config.oit.technique = Technique::WboitMrt;
    config.oit.wboit.weight = WeightFunction::Flat;
    config.oit.wboit.headroom = headroom;
    renderer_for(ctx, scene, config).unwrap().renderer
}

/// The WBOIT accumulation target's texels after `r`'s last frame.
fn accumulation(ctx: &voxel_render::GpuContext, r: &Renderer) -> Vec<[f32; 4]> {
    read_hdr(
        ctx,
        voxel_render::low_level::oit(r)
            .accumulation_target()
            .unwrap(),
    )
}

#[test]
fn fp16_overflow_never_reaches_the_picture() {
    let Some(ctx) = gpu() else { return };
    let scene = overflow_scene();
    let finite = |px: &[[f32; 4]]| px.iter().all(|p| p.iter().all(|c| c.is_finite()));

    // Without headroom the accumulation really overflows (to inf on most GPUs; lavapipe
    // saturates at 65504), and the composite's guard keeps the scene finite.
    let mut r = overflow_renderer(&ctx, &scene, false);
    let img = frame(&ctx, &mut r, &scene.cameras[0]);
    let accum = accumulation(&ctx, &r);
    assert!(
        accum.iter().any(|p| p[3] >= 65504.0),
        "the test scene must overflow fp16"
    );
    assert!(
        finite(&read_hdr(&ctx, r.scene_color())),
        "NaN or inf in the scene colour"
    );
    img.save_png(&out_dir("fp16_overflow").join("no_headroom.png"))
        .unwrap();

    // With the headroom scale (the default) nothing overflows in the first place, and the
    // picture matches the exact blend of the sheets (the sorted baseline is exact here:
    // parallel sheets, one per chunk layer, drawn back to front).
    let mut r = overflow_renderer(&ctx, &scene, true);
    let img = frame(&ctx, &mut r, &scene.cameras[0]);
    let accum = accumulation(&ctx, &r);
    assert!(finite(&accum), "headroom keeps the sums finite");
    assert!(finite(&read_hdr(&ctx, r.scene_color())));
    img.save_png(&out_dir("fp16_overflow").join("headroom.png"))
        .unwrap();
    // 40 layers of α 0.92 let almost nothing through: every pixel is the ice colour.
    assert!(distinct_colours(&img) < 40);
}

#[test]
fn resize_to_zero_and_back_and_switch_techniques_without_validation_errors() {
    let Some(ctx) = gpu() else { return };
    let scene = default_scene();
    let scope = ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
    let config = technique_config(Technique::WboitMrt, 96, 64);
    let mut r = renderer_for(&ctx, &scene, config).unwrap();
    let cam = scene.cameras[0];
    let first = frame(&ctx, &mut r, &cam);
    r.resize(0, 0).unwrap();
    r.resize(0, 64).unwrap();
    assert_eq!(r.size(), (96, 64), "zero sizes are ignored");
    assert_eq!(frame(&ctx, &mut r, &cam), first, "same size, same picture");
    r.resize(128, 72).unwrap();
    assert_eq!(frame(&ctx, &mut r, &cam).width, 128);
    r.resize(96, 64).unwrap();
    for t in [
        Technique::WboitTwoPass,
        Technique::Sorted,
        Technique::WboitMrt,
        Technique::OpaqueOnly,
        Technique::WboitMrt,
    ] {
        r.set_technique(t).unwrap();
        frame(&ctx, &mut r, &cam);
    }
    r.set_msaa(true).unwrap();
    frame(&ctx, &mut r, &cam);
    r.set_msaa(false).unwrap();
    assert_eq!(frame(&ctx, &mut r, &cam), first, "back where we started");
    let error = pollster::block_on(scope.pop());
    assert!(error.is_none(), "validation error: {error:?}");
}

#[test]
fn techniques_create_resources_only_when_translucency_is_on_screen() {
    let Some(ctx) = gpu() else { return };
    let scene = one_layer_scene();
    let mut r = renderer_for(
        &ctx,
        &scene,
        RendererConfig {
            width: 64,
            height: 48,
            ..Default::default()
        },
    )
    .unwrap();
    // Looking away from the slabs, from outside their chunk: nothing translucent in view.
    let away = voxel_render::Camera::look_at(
        glam::DVec3::new(0.5, 0.5, 70.0),
        glam::DVec3::new(0.5, 0.5, 90.0),
        60.0,
        0.1,
        500.0,
    )
    .unwrap();
    frame(&ctx, &mut r, &away);
    assert!(
        !voxel_render::low_level::oit(&r).has_resources(),
        "no translucent chunk visible: no WBOIT targets"
    );
    let times = r.gpu_times_blocking();
    assert!(
        times.get(GpuPass::Translucent).is_none() && times.get(GpuPass::Composite).is_none(),
        "{times:?}"
    );
    frame(&ctx, &mut r, &scene.cameras[0]);
    assert!(voxel_render::low_level::oit(&r).has_resources());
    let times = r.gpu_times_blocking();
    assert!(times.get(GpuPass::Translucent).is_some(), "{times:?}");
    assert!(times.iter().all(|(_, ms)| ms.is_finite() && ms >= 0.0));
}

/// The shader's weight functions against `weights.rs` (the one place a weight is defined for
/// readers; the WGSL copy is what draws, and this test fails when the two differ): one water
/// sheet straight ahead at known distances, near, middle and far, so that each formula's
/// fall with depth is compared; the accumulation's alpha at the centre pixel is α · w · scale.
#[test]
fn shader_weights_match_the_rust_formulas() {
    let Some(ctx) = gpu() else { return };
    for distance in [12.5, 3.5, 60.0] {
        shader_weights_match_at(&ctx, distance);
    }
    assert_eq!(RGBA8_SCALE, 1.0 / 24000.0);
}

fn shader_weights_match_at(ctx: &voxel_render::GpuContext, distance: f64) {
    // A red glass sheet nearer, just right of the centre pixel: the fitted weight's depth
    // range runs from it to the water, and the centre pixel's screen tile (pixels 16.5 to
    // 20.6 of 33) has some of its optical depth in front of the water.
    let world = thin_water_world(&[
        ([-20, -20, -20], [20, 20, -20], WATER),
        ([1, -3, -12], [6, 3, -12], RED_GLASS),
    ]);

    // The sheet's front face is the plane z = -19; the eye sits `distance` in front of it.
    let scene = scene(
        "weights",
        world,
        [0.5, 0.5, -19.0 + distance],
        [0.5, 0.5, -30.0],
    );
    let cam = scene.cameras[0];
    // Texture alpha of water, as stored in RGBA8.
    let alpha = (0.7f32 * 255.0).round() / 255.0;
    let (n, f, d) = (cam.near, cam.far, distance);
    let z = (1.0 - n * (f - d) / (d * (f - n))) as f32;
    for weight in WeightFunction::ALL {
        let mut config = RendererConfig {
            width: 33,
            height: 33,
            ..Default::default()
        };
        config.oit.technique = Technique::WboitMrt;
        config.oit.wboit.weight = weight;
        let mut r = renderer_for(ctx, &scene, config).unwrap();
        let stats = r
            .render_and_submit(&Offscreen::new(ctx, 33, 33).view, &cam)
            .unwrap();
        let accum = accumulation(ctx, &r);

        let got = accum[16 * 33 + 16][3];
        let fit = stats
            .technique
            .wboit
            .and_then(|w| w.fit)
            .unwrap_or_default();
        let centre = [16.5 / 33.0; 2];
        if weight == WeightFunction::Fitted && distance == 12.5 {
            assert!(
                fit.range[0] < 9.0 && fit.range[1] > 12.4,
                "the range spans the sheets: {:?}",
                fit.range
            );
            assert!(
                fit.optical_depth_at(centre, d as f32) > 0.05,
                "the glass counts in the centre tile"
            );
        } else if weight != WeightFunction::Fitted {
            assert!(
                fit.optical_depth.is_empty(),
                "no estimate without its weight"
            );
        }
        let want = alpha * weight.weight(z, d as f32, alpha, centre, &fit) * HEADROOM_SCALE;

        // fp16 stores 11 significant bits: 1e-3 relative, with margin.
        assert!(
            (got - want).abs() <= 2e-3 * want,
            "{weight:?} at {distance} blocks: shader {got}, rust {want}"
        );
    }
}

/// A small pane of red glass in the middle of the view, in front of a stone wall: its
/// chunk's translucent box covers a small part of the screen.
fn pane_scene() -> Scene {
    let world = thin_water_world(&[
        ([-40, -20, -2], [40, 20, -1], STONE),
        ([-3, -2, 6], [3, 2, 6], RED_GLASS),
    ]);
    scene("pane", world, [0.5, 0.5, 30.0], [0.5, 0.5, 0.0])
}

/// The composite covers only the translucent boxes' rectangle, or nothing when no box is
/// on screen, and the picture is the same as with a composite over the whole screen:
/// outside the rectangle it would discard every pixel.
#[test]
fn the_composite_scissor_keeps_every_picture() {
    let Some(ctx) = gpu() else { return };
    let suite = |name: &str| {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../scenes/{name}.toml"));
        voxel_lab::scene::Scene::load(&path).unwrap()
    };
    // The pane, then the pane with the camera turned away from it (its chunk may still
    // be in view, its box is not on screen), then suite scenes.
    let pane = pane_scene();
    let mut away = pane.clone();
    away.cameras[0] = voxel_render::Camera::look_at(
        glam::DVec3::new(0.5, 0.5, 30.0),
        glam::DVec3::new(40.0, 0.5, 60.0),
        60.0,
        0.1,
        500.0,
    )
    .unwrap();
    let scenes = [
        ("pane", pane),
        ("away", away),
        ("stained_glass_corridor", suite("stained_glass_corridor")),
        ("water_through_glass", suite("water_through_glass")),
    ];
    let mut smaller = 0;
    for (name, scene) in &scenes {
        for technique in [Technique::WboitMrt, Technique::WboitTwoPass] {
            let picture = |scissor: bool| {
                let mut config = technique_config(technique, W, H);
                config.oit.wboit.composite_scissor = scissor;
                let mut r = renderer_for(&ctx, scene, config).unwrap();
                let target = Offscreen::new(&ctx, W, H);
                let stats = r
                    .render_and_submit(&target.view, &scene.cameras[0])
                    .unwrap();
                // None: WBOIT drew nothing (no translucent chunk in view).
                let rect = stats.technique.wboit.map(|w| w.composite_rect);
                (target.read(&ctx).unwrap(), rect)
            };
            let (full, none) = picture(false);
            assert!(
                none.is_none_or(|r| r.is_none()),
                "{name}: no scissor asked for"
            );
            let (cut, rect) = picture(true);
            if *name == "away" {
                assert!(
                    rect.is_none_or(|r| r.is_some_and(|r| r[2] * r[3] == 0)),
                    "no pane on screen, no composite: {rect:?}"
                );
            }
            let rect = rect.flatten().unwrap_or([0, 0, W, H]);
            if rect[2] * rect[3] < W * H {
                smaller += 1;
            }
            if *name == "pane" {
                assert!(
                    rect[2] < W / 2 && rect[3] < H / 2 && rect[2] * rect[3] > 0,
                    "the pane's rectangle: {rect:?}"
                );
                let opaque = render(&ctx, scene, Technique::OpaqueOnly, W, H);
                assert!(diff(&cut, &opaque).differing > 500, "the pane shows");
            }
            assert_close(&format!("scissor_{name}_{technique}"), &cut, &full, 0);
        }
    }
    assert!(
        smaller >= 4,
        "the rectangle is smaller than the screen somewhere"
    );
}

/// A weight change on a running renderer builds that weight's pipelines and draws what a
/// new renderer with that weight draws; back to the first weight, its kept pipelines draw
/// the first picture again.
#[test]
fn switching_the_weight_draws_what_a_new_renderer_draws() {
    let Some(ctx) = gpu() else { return };
    let scene = default_scene();
    let camera = scene.cameras[0];
    let with = |weight: WeightFunction| {
        let mut config = technique_config(Technique::WboitMrt, W, H);
        config.oit.wboit.weight = weight;
        config
    };
    let fresh = |weight| render_with(&ctx, &scene, with(weight));
    let mut r = renderer_for(&ctx, &scene, with(WeightFunction::Fitted)).unwrap();
    let fitted = frame(&ctx, &mut r, &camera);
    for weight in [WeightFunction::McGuire10, WeightFunction::Fitted] {
        r.set_oit_config(with(weight).oit).unwrap();
        let img = frame(&ctx, &mut r, &camera);
        assert_close(
            &format!("weight_switch_{}", weight.name()),
            &img,
            &fresh(weight),
            0,
        );
    }
    let eq10 = fresh(WeightFunction::McGuire10);
    assert!(diff(&fitted, &eq10).differing > 100, "the weights differ");
}
