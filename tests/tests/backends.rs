//! The capability ladder on the bottom rungs: wgpu's GL backend (Mesa's llvmpipe through
//! EGL, a GLES 3.2 device) and a Vulkan device with WebGL2's limits (no storage buffers, no
//! optional feature). Every real-time technique draws there like on Vulkan, or says which
//! capability it lacks; `Technique::supported` agrees with what draws; the world drawn
//! without storage buffers is the world drawn with them. Under `CI` none of these skips.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use std::path::Path;

use tests::{Diff, diff, distinct_colours, gpu, gpu_with_limits, out_dir, technique_config};
use voxel_lab::headless::{Offscreen, render_image, renderer_for};
use voxel_lab::scene::{self, Scene};
use voxel_render::{
    Error, GpuContext, Image, OitConfig, QuadFetch, Renderer, RendererConfig, Technique,
};

const W: u32 = 320;
const H: u32 = 180;

/// What an [`Error::Unsupported`] names: one of the kinds of [`voxel_render::low_level::Need`].
const CAPABILITY_WORDS: [&str; 4] = ["downlevel flag", "of at least", "render targets", "feature"];

/// The default scene (terrain, water, a greenhouse), the eye under water (the medium's
/// boundary, depth copies and fog), and particles over water (a game's geometry through
/// the stages, with the techniques' preludes); `content`: with the scene of game content
/// (its shaders pull from storage buffers, as the lab's stand-in for a game's geometry).
fn scenes(content: bool) -> Vec<Scene> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let mut out = vec![
        scene::default_scene_with_radius(1, 2).unwrap(),
        Scene::load(&dir.join("under_water.toml")).unwrap(),
    ];
    if content {
        out.push(Scene::load(&dir.join("particles_over_water.toml")).unwrap());
    }
    out
}

/// Mean absolute difference of RGB, in 1/255 steps.
fn mean_error(a: &Image, b: &Image) -> f64 {
    let sum: u64 = a
        .rgba
        .chunks_exact(4)
        .zip(b.rgba.chunks_exact(4))
        .map(|(p, q)| (0..3).map(|c| u64::from(p[c].abs_diff(q[c]))).sum::<u64>())
        .sum();
    sum as f64 / (3 * a.rgba.len() / 4) as f64
}

/// Pixels whose largest channel differs by more than `by`/255.
fn pixels_off(a: &Image, b: &Image, by: u8) -> usize {
    a.rgba
        .chunks_exact(4)
        .zip(b.rgba.chunks_exact(4))
        .filter(|(p, q)| (0..3).any(|c| p[c].abs_diff(q[c]) > by))
        .count()
}

fn render(ctx: &GpuContext, scene: &Scene, config: RendererConfig) -> Image {
    let (w, h) = (config.width, config.height);
    let mut r = renderer_for(ctx, scene, config).unwrap();
    render_image(ctx, &mut r, &Offscreen::new(ctx, w, h), &scene.cameras[0]).unwrap()
}

/// Asserts that `e` is an [`Error::Unsupported`] naming a capability.
fn assert_names_capability(e: &Error, what: &str) {
    let m = e.to_string();
    assert!(
        matches!(e, Error::Unsupported(_)) && CAPABILITY_WORDS.iter().any(|w| m.contains(w)),
        "{what}: not an Unsupported error naming a capability: {m}"
    );
    assert!(!m.contains("Validation Error"), "{what}: {m}");
}

/// What `technique` does on `ctx` with `scene`: the technique that drew and its picture,
/// or the error (checked to be an Unsupported naming a capability, the same that
/// `Technique::resolve` gives).
fn draw_or_refuse(
    ctx: &GpuContext,
    scene: &Scene,
    technique: Technique,
) -> Option<(Technique, Image)> {
    let config = technique_config(technique, W, H);
    let what = format!("{technique} on {}", ctx.caps.adapter_name);
    match Renderer::new(ctx, scene.world.registry(), config.clone()) {
        Err(e) => {
            assert_names_capability(&e, &what);
            let resolved = technique.resolve(&config.oit, &ctx.caps).unwrap_err();
            assert_eq!(resolved.to_string(), e.to_string(), "{what}");
            None
        }
        Ok(r) => {
            let drew = r.config().oit.technique;
            assert_eq!(
                Ok(drew),
                technique
                    .resolve(&config.oit, &ctx.caps)
                    .map_err(|e| e.to_string())
            );
            Some((drew, render(ctx, scene, config)))
        }
    }
}

/// The Vulkan settings that draw what `technique` drew on `ctx`: MBOIT's moments are 16-bit
/// where the device cannot blend 32-bit floats (no `FLOAT32_BLENDABLE`: GL, WebGL2), and
/// Vulkan's picture to compare with is made the same way.
fn vulkan_config(ctx: &GpuContext, technique: Technique) -> RendererConfig {
    let mut config = technique_config(technique, W, H);
    config.oit.mboit.half_precision =
        !voxel_render::low_level::single_precision(&ctx.caps, &config.oit.mboit);
    config
}

/// Compares `actual` (on `label`'s device) with `expected` (Vulkan's): at most `mean`/255
/// on average and `share` of the pixels off by more than 3/255. Leaves the pictures under
/// `target/test-output/backends_<label>_<scene>_<technique>/`.
fn assert_like_vulkan(
    label: &str,
    scene: &Scene,
    t: Technique,
    actual: &Image,
    expected: &Image,
    (mean, share): (f64, f64),
) {
    let dir = out_dir(&format!(
        "backends_{label}_{}_{t}",
        scene.name.replace(' ', "_")
    ));
    actual.save_png(&dir.join("actual.png")).unwrap();
    expected.save_png(&dir.join("vulkan.png")).unwrap();
    tests::diff_image(actual, expected)
        .save_png(&dir.join("diff.png"))
        .unwrap();
    let (m, off) = (
        mean_error(actual, expected),
        pixels_off(actual, expected, 3),
    );
    let Diff { max, .. } = diff(actual, expected);
    eprintln!(
        "{label} {} {t}: mean {m:.4}/255, {off} pixels off by more than 3/255, max {max}",
        scene.name
    );
    assert!(
        distinct_colours(actual) > 50,
        "{label} {} {t}: a blank picture; see {}",
        scene.name,
        dir.display()
    );
    assert!(
        m <= mean && off as f64 <= share * (W * H) as f64,
        "{label} {} {t}: mean {m:.4}/255 (at most {mean}), {off} pixels off by more than 3/255 (at most {:.0}); see {}",
        scene.name,
        share * (W * H) as f64,
        dir.display()
    );
}

/// Every real-time technique on `ctx` with each of `scenes`: refused naming a capability,
/// or drawing like Vulkan (`vk`) with the same technique, as [`assert_like_vulkan`] with
/// `label` and `tolerance` checks.
fn every_technique_like_vulkan(
    vk: &GpuContext,
    ctx: &GpuContext,
    scenes: Vec<Scene>,
    label: &str,
    tolerance: (f64, f64),
) {
    for scene in scenes {
        for t in Technique::REAL_TIME {
            let Some((drew, picture)) = draw_or_refuse(ctx, &scene, t) else {
                continue;
            };
            let expected = render(vk, &scene, vulkan_config(ctx, drew));
            assert_like_vulkan(label, &scene, t, &picture, &expected, tolerance);
        }
    }
}

/// GL against Vulkan: llvmpipe and lavapipe share Mesa's rasteriser and shader compiler,
/// but not the whole path (GLSL from naga, not SPIR-V; sRGB output written by another
/// route), so a few edge pixels differ: 33 of 230 400 at 640×360 on the default scene, a
/// mean of 0.005/255. A tenth of a step on average and half a percent of the pixels leave
/// room for that and fail on any real difference (a missing layer moves the mean by
/// several steps).
const GL_TOLERANCE: (f64, f64) = (0.1, 0.005);

#[test]
fn every_real_time_technique_on_gl_draws_like_vulkan_or_names_what_it_lacks() {
    let (Some(vk), Some(gl)) = (gpu(), tests::gl()) else {
        return;
    };
    assert_eq!(
        gl.caps.backend,
        wgpu::Backend::Gl,
        "{}",
        gl.caps.adapter_name
    );
    every_technique_like_vulkan(&vk, &gl, scenes(true), "gl", GL_TOLERANCE);
}

/// GL with WebGL2's limits: instanced quads through naga's GLSL ES (integer vertex
/// attributes, a uniform at a dynamic offset, the GL backend's emulated first instance).
#[test]
fn every_real_time_technique_on_gl_with_webgl2_limits_draws_like_vulkan_or_names_what_it_lacks() {
    let (Some(vk), Some(gl)) = (gpu(), tests::gl_webgl2()) else {
        return;
    };
    assert_eq!(
        gl.caps.backend,
        wgpu::Backend::Gl,
        "{}",
        gl.caps.adapter_name
    );
    assert_eq!(
        QuadFetch::choose(&gl.caps, None).unwrap(),
        QuadFetch::Instanced
    );
    every_technique_like_vulkan(&vk, &gl, scenes(false), "gl_webgl2", GL_TOLERANCE);
}

#[test]
fn the_low_end_techniques_on_gl_are_within_the_targets() {
    // The targets: stipple and sorted-quads within 3/255 mean of Vulkan's picture of the
    // default scene (at the demo's size).
    let (Some(vk), Some(gl)) = (gpu(), tests::gl()) else {
        return;
    };
    let scene = scene::default_scene(1).unwrap();
    for t in [Technique::Stipple, Technique::SortedQuads] {
        let config = technique_config(t, 640, 360);
        let picture = render(&gl, &scene, config.clone());
        let expected = render(&vk, &scene, config);
        let m = mean_error(&picture, &expected);
        assert!(m <= 3.0, "{t}: mean {m:.4}/255 off Vulkan's picture");
        assert!(distinct_colours(&picture) > 1000, "{t}: a blank picture");
    }
}

#[test]
fn under_webgl2_limits_the_world_is_drawn_without_storage_buffers_and_matches_vulkan() {
    let (Some(vk), Some(w2)) = (gpu(), tests::webgl2()) else {
        return;
    };
    assert_eq!(w2.caps.limits.max_storage_buffers_per_shader_stage, 0);
    assert!(w2.caps.features.is_empty(), "no optional feature");
    assert_eq!(
        QuadFetch::choose(&w2.caps, None).unwrap(),
        QuadFetch::Instanced
    );
    // The floor: these draw the world under WebGL2's limits, as themselves.
    let supported = Technique::supported(&w2.caps);
    for t in [
        Technique::OpaqueOnly,
        Technique::Stipple,
        Technique::Sorted,
        Technique::SortedQuads,
    ] {
        assert!(
            supported.contains(&t),
            "{t} under WebGL2 limits: {supported:?}"
        );
    }
    // The A-buffer writes storage buffers in fragments: its replacement draws.
    assert_eq!(
        Technique::Reference
            .resolve(&OitConfig::default(), &w2.caps)
            .unwrap(),
        Technique::PeelReference
    );
    // The same shader arithmetic on the same rasteriser: the same picture.
    every_technique_like_vulkan(&vk, &w2, scenes(false), "webgl2", (0.0, 0.0));
}

#[test]
fn instanced_quads_draw_what_storage_buffers_draw() {
    let Some(ctx) = gpu() else { return };
    for scene in scenes(true) {
        for t in Technique::REAL_TIME {
            let config = |fetch| RendererConfig {
                quad_fetch: Some(fetch),
                ..technique_config(t, W, H)
            };
            let storage = render(&ctx, &scene, config(QuadFetch::Storage));
            let instanced = render(&ctx, &scene, config(QuadFetch::Instanced));
            assert_like_vulkan("instanced", &scene, t, &instanced, &storage, (0.0, 0.0));
        }
    }
}

/// For each device: a technique `Technique::supported` lists draws as itself (and draws
/// translucency where it draws at all); one it does not list is refused naming what is
/// missing, or draws as a replacement it lists.
#[test]
fn supported_agrees_with_what_draws() {
    let devices: Vec<GpuContext> = [gpu(), tests::gl(), tests::webgl2(), tests::gl_webgl2()]
        .into_iter()
        .flatten()
        .collect();
    if devices.len() < 4 {
        return;
    }
    let scene = tests::dense_sheets(3, 0.5);
    for ctx in &devices {
        let supported = Technique::supported(&ctx.caps);
        let what = |t| format!("{t} on {}", ctx.caps.adapter_name);
        let opaque = render(ctx, &scene, technique_config(Technique::OpaqueOnly, 64, 48));
        for t in Technique::ALL {
            let config = technique_config(t, 64, 48);
            match Renderer::new(ctx, scene.world.registry(), config.clone()) {
                Ok(r) if supported.contains(&t) => {
                    assert_eq!(r.config().oit.technique, t, "{}", what(t));
                    let picture = render(ctx, &scene, config);
                    // Three sheets of opacity 0.5 over stone: far from the opaque picture.
                    assert_eq!(
                        t.draws(),
                        mean_error(&picture, &opaque) > 10.0,
                        "{}: draws translucency exactly when it is a technique that does",
                        what(t)
                    );
                }
                Ok(r) => {
                    let drew = r.config().oit.technique;
                    assert_ne!(drew, t, "{} draws but is not listed", what(t));
                    assert!(
                        supported.contains(&drew),
                        "{}: its replacement {drew}",
                        what(t)
                    );
                }
                Err(e) => {
                    assert!(!supported.contains(&t), "{} is listed: {e}", what(t));
                    assert_names_capability(&e, &what(t));
                }
            }
        }
        assert!(supported.contains(&Technique::LOW_END));
        assert_eq!(
            Technique::best_available(&ctx.caps).unwrap(),
            Technique::LADDER
                .into_iter()
                .find(|t| supported.contains(t))
                .unwrap()
        );
    }
}

/// A device that lacks what a technique needs, and has no replacement for it: the
/// renderer's calls refuse it, name the capability, and change nothing.
#[test]
fn a_technique_the_device_lacks_is_refused_by_every_call_naming_the_capability() {
    // One colour attachment a pass: no MRT (MBOIT's moments, one-pass WBOIT).
    let Some(ctx) = gpu_with_limits(|l| l.max_color_attachments = 1) else {
        return;
    };
    let scene = tests::dense_sheets(2, 0.5);
    let registry = scene.world.registry();
    let config = |t| technique_config(t, 64, 48);
    let e = Renderer::new(&ctx, registry, config(Technique::Mboit)).unwrap_err();
    assert_names_capability(&e, "Renderer::new");
    assert!(e.to_string().contains("max_color_attachments"), "{e}");
    // One-pass WBOIT has a replacement that runs.
    let r = Renderer::new(&ctx, registry, config(Technique::WboitMrt)).unwrap();
    assert_eq!(r.config().oit.technique, Technique::WboitTwoPass);
    let mut r = renderer_for(&ctx, &scene, config(Technique::Stipple)).unwrap();
    let e = r.set_technique(Technique::Mboit).unwrap_err();
    assert_names_capability(&e, "set_technique");
    assert_eq!(r.config().oit.technique, Technique::Stipple, "unchanged");
    let e = r.prebuild_technique(Technique::Mboit).unwrap_err();
    assert_names_capability(&e, "prebuild_technique");
    let e = r
        .set_oit_config(OitConfig::with(Technique::Mboit))
        .unwrap_err();
    assert_names_capability(&e, "set_oit_config");
    assert!(!Technique::supported(&ctx.caps).contains(&Technique::Mboit));
    // The world itself, refused: quads forced through storage buffers where the vertex
    // stage has none.
    let Some(w2) = tests::webgl2() else { return };
    let e = Renderer::new(
        &w2,
        registry,
        RendererConfig {
            quad_fetch: Some(QuadFetch::Storage),
            ..config(Technique::Stipple)
        },
    )
    .unwrap_err();
    assert_names_capability(&e, "storage quad fetch under WebGL2 limits");
    assert!(
        e.to_string()
            .contains("max_storage_buffers_per_shader_stage of at least 5 (this device: 0)"),
        "{e}"
    );
}

/// No rung at all: a device whose vertex stage passes too few values to the fragment stage
/// for the world's shaders. Every technique is refused, the best available included.
#[test]
fn a_device_below_the_last_rung_is_refused_naming_the_capability() {
    let Some(ctx) = gpu_with_limits(|l| l.max_inter_stage_shader_variables = 4) else {
        return;
    };
    assert!(Technique::supported(&ctx.caps).is_empty());
    let e = Technique::best_available(&ctx.caps).unwrap_err();
    assert_names_capability(&e, "best_available");
    assert!(
        e.to_string().contains("max_inter_stage_shader_variables"),
        "{e}"
    );
    let scene = tests::dense_sheets(1, 0.5);
    let e = Renderer::new(
        &ctx,
        scene.world.registry(),
        technique_config(Technique::LOW_END, 64, 48),
    )
    .unwrap_err();
    assert_names_capability(&e, "Renderer::new");
}

/// The arena's pages as vertex buffers: small ones (a 128 KiB buffer limit: 16 384 quads a
/// page) so that terrain spans several; unloading most of it and drawing compacts pages
/// away, and the picture equals a fresh renderer's given only the chunks kept, as with
/// storage pages (`tests/tests/stream.rs`).
#[test]
fn instanced_pages_compact_and_keep_the_picture() {
    let Some(ctx) = gpu_with_limits(|l| l.max_buffer_size = 128 << 10) else {
        return;
    };
    let camera = voxel_render::Camera::look_at(
        glam::DVec3::new(40.0, 60.0, 40.0),
        glam::DVec3::new(90.0, 20.0, 90.0),
        70.0,
        0.1,
        400.0,
    )
    .unwrap();
    let tests::Compacted {
        before,
        after,
        compacted: a,
        fresh: b,
        ..
    } = tests::compact_terrain(&ctx, &camera, |world| {
        let config = RendererConfig {
            quad_fetch: Some(QuadFetch::Instanced),
            // Small enough that its readback fits the buffer limit.
            ..technique_config(Technique::SortedQuads, 160, 90)
        };
        Renderer::new(&ctx, world.registry(), config).unwrap()
    });
    assert!(before.pages >= 3, "terrain spans several pages: {before:?}");
    assert!(
        after.pages < before.pages,
        "no page compacted away: {before:?} -> {after:?}"
    );
    assert!(distinct_colours(&a) > 50, "a real picture");
    // As with storage pages: where coplanar grown opaque quads meet, the draw order (which
    // compaction changes) picks the pixel, within 1/255.
    tests::assert_close("backends_instanced_compacted", &a, &b, 1);
}

/// The ready-made game content under WebGL2's limits (no storage buffers in the vertex
/// stage) draws its instances from vertex buffers, as the world draws its quads, and the
/// picture is the storage path's: on Vulkan against Vulkan's storage path, on GL against
/// GL's (llvmpipe has vertex storage buffers without the limits), every real-time
/// technique the device runs, within 1/255. A validation error would panic here (wgpu's
/// default handler).
#[test]
fn game_content_under_webgl2_limits_draws_from_vertex_buffers_like_the_storage_path() {
    let scene = scenes(true).pop().unwrap();
    assert!(!scene.content.is_empty(), "{}", scene.name);
    let pairs = [
        ("vulkan", gpu(), tests::webgl2()),
        ("gl", tests::gl(), tests::gl_webgl2()),
    ];
    for (label, full, w2) in pairs {
        let mut compared = 0;
        let (Some(full), Some(w2)) = (full, w2) else {
            continue;
        };
        assert!(
            full.caps
                .downlevel
                .contains(wgpu::DownlevelFlags::VERTEX_STORAGE),
            "{label}: the storage path to compare with"
        );
        for t in Technique::REAL_TIME {
            let Some((drew, picture)) = draw_or_refuse(&w2, &scene, t) else {
                continue;
            };
            let r = renderer_for(&w2, &scene, technique_config(drew, W, H)).unwrap();
            let fetch = r.content.as_ref().map(|c| c.fetch());
            assert_eq!(fetch, Some(QuadFetch::Instanced), "{label} {t}");
            let storage = RendererConfig {
                quad_fetch: Some(QuadFetch::Storage),
                ..vulkan_config(&w2, drew)
            };
            let expected = render(&full, &scene, storage);
            let d = diff(&picture, &expected);
            let dir = out_dir(&format!("backends_content_webgl2_{label}_{t}"));
            picture.save_png(&dir.join("webgl2.png")).unwrap();
            expected.save_png(&dir.join("storage.png")).unwrap();
            eprintln!(
                "{label} {t}: content under WebGL2 limits, max diff {}/255",
                d.max
            );
            assert!(
                d.max <= 1,
                "{label} {t}: {} px off by more than 1/255 (max {}); see {}",
                d.over_one,
                d.max,
                dir.display()
            );
            assert!(distinct_colours(&picture) > 50, "{label} {t}: blank");
            if compared == 0 {
                // The content is there to compare: without it the picture differs.
                let bare = Scene {
                    content: Default::default(),
                    ..scene.clone()
                };
                let without = render(&w2, &bare, technique_config(drew, W, H));
                let seen = diff(&picture, &without).over_one;
                assert!(seen > 500, "{label} {t}: the content covers {seen} px");
            }
            compared += 1;
        }
        assert!(compared > 0, "{label}: nothing compared");
    }
}

/// 4× MSAA on GL falls back to none (its resolve draws black there, see
/// `Capabilities::msaa4`): the picture is GL's without MSAA, not a black one.
#[test]
fn msaa_on_gl_falls_back_to_none() {
    let Some(gl) = tests::gl() else { return };
    let scene = scenes(false).remove(0);
    let config = technique_config(Technique::SortedQuads, W, H);
    let msaa = RendererConfig {
        msaa: true,
        ..config.clone()
    };
    let r = Renderer::new(&gl, scene.world.registry(), msaa.clone()).unwrap();
    assert!(!r.config().msaa);
    let with = render(&gl, &scene, msaa);
    let without = render(&gl, &scene, config);
    tests::assert_close("backends_gl_msaa", &with, &without, 0);
}

/// A registry of any size draws on wgpu's GL backend: the block textures' array never has a
/// layer count GL takes for a cube map (1, or a multiple of 6: 18 layers, the default
/// registry and three more blocks such as `BlockRegistry::with_lights`'s, drew black).
#[test]
fn registries_of_every_size_draw_on_gl() {
    let Some(gl) = tests::gl() else { return };
    for extra in 0..=9 {
        let mut registry = voxel_core::BlockRegistry::default();
        for i in 0..extra {
            let def = voxel_core::BlockDef::new(format!("extra_{i}"), [200, 100, 50], 1.0);
            registry.register(def).unwrap();
        }
        let mut world = voxel_core::World::new(std::sync::Arc::new(registry));
        scene::fill_box(
            &mut world,
            [-8, -1, -8],
            [8, 0, 8],
            voxel_core::blocks::STONE,
        )
        .unwrap();
        let camera = voxel_render::Camera::look_at(
            glam::DVec3::new(0.5, 6.0, 9.0),
            glam::DVec3::new(0.5, 0.0, 0.0),
            60.0,
            0.1,
            100.0,
        )
        .unwrap();
        let scene = Scene::new("registry", world, camera);
        let mut r =
            renderer_for(&gl, &scene, technique_config(Technique::SortedQuads, W, H)).unwrap();
        let target = Offscreen::new(&gl, W, H);
        let img = render_image(&gl, &mut r, &target, &scene.cameras[0]).unwrap();
        let centre = img.pixel(W / 2, H / 2);
        assert!(
            centre[0] > 40,
            "{} blocks: the stone at the centre is {centre:?}",
            13 + extra
        );
    }
}
