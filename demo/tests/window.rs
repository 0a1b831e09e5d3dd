//! The real demo window under Xvfb on lavapipe: the scripted demo steps through every
//! technique, edits a block, resizes, and saves screenshots with its panel, which must not be
//! blank and must differ between techniques where they should.
//!
//! Without Xvfb or a Vulkan adapter the test skips with a loud message, unless `CI` is set:
//! then it fails.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use std::path::{Path, PathBuf};

use tests::{Xvfb, skip_or_fail};
use voxel_render::{GpuContext, Image, Technique};

/// `target/test-output/<name>/`, emptied and created.
fn out_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../target/test-output")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A Vulkan adapter and an Xvfb server, or `None` after [`skip_or_fail`] said which is missing.
fn vulkan_and_xvfb() -> Option<Xvfb> {
    if GpuContext::headless(wgpu::Backends::VULKAN).is_err() {
        skip_or_fail("no Vulkan adapter (install mesa-vulkan-drivers)");
        return None;
    }
    let x = Xvfb::start();
    if x.is_none() {
        skip_or_fail("Xvfb could not be started (install xvfb)");
    }
    x
}

fn demo(x: &Xvfb, args: &[&str]) {
    let out = x
        .command(env!("CARGO_BIN_EXE_demo"))
        .args(args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "demo {args:?} failed: {}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A 640 × 360 screenshot of the terrain at `view_distance` after 3 frames, saved at
/// `path`, with `extra` arguments.
fn terrain_shot(x: &Xvfb, path: &Path, view_distance: &str, extra: &[&str]) -> Image {
    let mut args = vec![
        "--size",
        "640x360",
        "--frames",
        "3",
        "--view-distance",
        view_distance,
        "--screenshot",
        path.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    demo(x, &args);
    Image::load_png(path).unwrap()
}

/// Where the panel ends: the first column whose mean brightness is that of the scene (sky,
/// grass, water), not of the dark panel with its text.
fn panel_edge(img: &Image) -> u32 {
    let mean = |x: u32| {
        (0..img.height)
            .map(|y| {
                let p = img.pixel(x, y);
                (u32::from(p[0]) + u32::from(p[1]) + u32::from(p[2])) / 3
            })
            .sum::<u32>()
            / img.height
    };
    (0..img.width)
        .find(|&x| mean(x) > 100)
        .unwrap_or(img.width / 2)
}

/// The 3D view right of the panel.
fn view(img: &Image) -> Vec<[u8; 3]> {
    let mut v = Vec::new();
    let edge = panel_edge(img) + 4;
    assert!(
        edge > 100 && edge < img.width / 2 + 60,
        "panel edge at {edge}"
    );
    for y in 0..img.height {
        for x in edge..img.width {
            let p = img.pixel(x, y);
            v.push([p[0], p[1], p[2]]);
        }
    }
    v
}

fn max_diff(a: &[[u8; 3]], b: &[[u8; 3]]) -> u8 {
    a.iter()
        .zip(b)
        .flat_map(|(p, q)| (0..3).map(move |c| p[c].abs_diff(q[c])))
        .max()
        .unwrap_or(0)
}

fn distinct(v: &[[u8; 3]]) -> usize {
    let mut v = v.to_vec();
    v.sort_unstable();
    v.dedup();
    v.len()
}

#[test]
fn the_window_runs_every_technique_under_xvfb() {
    let Some(x) = vulkan_and_xvfb() else { return };
    let dir = out_dir("window");
    demo(
        &x,
        &[
            "--size",
            "640x360",
            "--frames",
            "3",
            "--cycle",
            dir.to_str().unwrap(),
        ],
    );

    let shots: Vec<(Technique, Image)> = Technique::ALL
        .iter()
        .map(|t| {
            (
                *t,
                Image::load_png(&dir.join(format!("{}.png", t.name()))).unwrap(),
            )
        })
        .collect();
    for (t, img) in &shots {
        assert_eq!((img.width, img.height), (640, 360), "{t}");
        // Not blank: terrain, water, glass and the panel's text.
        assert!(
            distinct(&view(img)) > 200,
            "{t}: {} colours",
            distinct(&view(img))
        );
        // The egui panel is drawn on the left: its dark background.
        let p = img.pixel(4, 300);
        assert!(
            p[0] < 60 && p[1] < 60 && p[2] < 60,
            "{t}: no panel at the left edge ({p:?})"
        );
    }
    let get = |t: Technique| view(&shots.iter().find(|s| s.0 == t).unwrap().1);
    let reference = get(Technique::Reference);
    // Same maths: the same picture up to rounding.
    assert!(max_diff(&get(Technique::PeelReference), &reference) <= 1);
    assert!(max_diff(&get(Technique::WboitTwoPass), &get(Technique::WboitMrt)) <= 1);
    // sorted-quads: within 2/255 but on a few edge pixels, where the water meets the
    // shore and the volume's depth is read across the edge.
    let off = get(Technique::SortedQuads)
        .iter()
        .zip(&reference)
        .filter(|(p, q)| (0..3).any(|c| p[c].abs_diff(q[c]) > 2))
        .count();
    assert!(
        off <= 10,
        "sorted-quads: {off} pixels off by more than 2/255"
    );
    // Different methods: visibly different pictures.
    for t in [
        Technique::OpaqueOnly,
        Technique::WboitMrt,
        Technique::Stipple,
    ] {
        assert!(
            max_diff(&get(t), &reference) > 8,
            "{t} should differ from the reference"
        );
    }

    // Resizing, a zero size and back: the last picture has the window's size again. A
    // block placed on frame 1 is remeshed in the background and shows in the last frame.
    let resized = dir.join("resized.png");
    demo(
        &x,
        &[
            "--size",
            "640x360",
            "--frames",
            "8",
            "--resize",
            "--edit",
            "--screenshot",
            resized.to_str().unwrap(),
        ],
    );
    let img = Image::load_png(&resized).unwrap();
    assert_eq!((img.width, img.height), (640, 360));
    assert!(distinct(&view(&img)) > 200);
    // The run above with the technique the window starts with (its panel shows the same
    // settings).
    let default = voxel_render::OitConfig::default().technique;
    let before = &shots.iter().find(|s| s.0 == default).unwrap().1;
    assert!(
        max_diff(&view(&img), &view(before)) > 8,
        "the placed block shows"
    );
    // The panel's settings (everything above its statistics, which change from run to
    // run) look the same after the resize: frames skipped for an outdated surface did not
    // lose egui's font-texture updates (glyphs went missing when they did).
    let settings = |img: &Image| -> Vec<[u8; 3]> {
        let edge = panel_edge(img) - 8;
        (0..300)
            .flat_map(|y| (0..edge).map(move |x| (x, y)))
            .map(|(x, y)| {
                let p = img.pixel(x, y);
                [p[0], p[1], p[2]]
            })
            .collect()
    };
    assert_eq!(
        max_diff(&settings(&img), &settings(before)),
        0,
        "the panel's text changed after the resize"
    );
}

#[test]
fn the_window_opens_a_vox_model() {
    let Some(x) = vulkan_and_xvfb() else { return };
    let dir = out_dir("window-vox");
    let shot = dir.join("harbour.png");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/vox/harbour.toml");
    demo(
        &x,
        &[
            "--size",
            "640x360",
            "--frames",
            "3",
            "--technique",
            "sorted-quads",
            "--scene",
            scene.to_str().unwrap(),
            "--screenshot",
            shot.to_str().unwrap(),
        ],
    );
    let img = Image::load_png(&shot).unwrap();
    let v = view(&img);
    assert!(distinct(&v) > 100, "{} colours", distinct(&v));
    // The harbour, not terrain: its red sail and lighthouse bands (200+ red, little else),
    // which generated terrain does not hold, and sky around it.
    let red = v
        .iter()
        .filter(|p| p[0] > 150 && p[1] < 90 && p[2] < 90)
        .count();
    assert!(red > 50, "{red} red pixels");
    let top_left_sky = v[0];
    assert!(
        top_left_sky[2] > 200 && top_left_sky[2] > top_left_sky[0],
        "sky above the model: {top_left_sky:?}"
    );
}

/// The window under WebGL2's limits (no storage buffers in the vertex stage) draws its game
/// content, on as by default in an interactive run, from vertex buffers: on Vulkan and on
/// GL it starts, draws and saves its screenshot, and the content is in it (the picture
/// differs from the one without it).
#[test]
fn the_window_draws_its_game_content_under_webgl2_limits() {
    let Some(x) = Xvfb::start() else {
        return skip_or_fail("Xvfb could not be started (install xvfb)");
    };
    let dir = out_dir("window-webgl2");
    for (backend, backends) in [
        ("vulkan", wgpu::Backends::VULKAN),
        ("gl", wgpu::Backends::GL),
    ] {
        if GpuContext::headless(backends).is_err() {
            skip_or_fail(&format!("no {backend} adapter"));
            continue;
        }
        let shot = |game: &str| {
            let path = dir.join(format!("{backend}_game_{game}.png"));
            demo(
                &x,
                &[
                    "--backend",
                    backend,
                    "--limits",
                    "webgl2",
                    "--size",
                    "640x360",
                    "--frames",
                    "3",
                    "--game",
                    game,
                    "--screenshot",
                    path.to_str().unwrap(),
                ],
            );
            view(&Image::load_png(&path).unwrap())
        };
        let (with, without) = (shot("true"), shot("false"));
        assert!(
            distinct(&with) > 200,
            "{backend}: {} colours",
            distinct(&with)
        );
        let differing = with.iter().zip(&without).filter(|(a, b)| a != b).count();
        assert!(
            differing > 50,
            "{backend}: the game content changes {differing} pixels"
        );
    }
}

/// Past 32 chunks the window draws the terrain in levels of detail (a far field): the far
/// picture shows ground where the streamed one ends, and an edit in a far view goes through.
#[test]
fn the_window_draws_a_far_view_past_the_streamed_distance() {
    let Some(x) = vulkan_and_xvfb() else { return };
    let dir = out_dir("window-far");
    let shot = |vd: &str, extra: &[&str]| {
        let path = dir.join(format!("view-distance-{vd}.png"));
        terrain_shot(&x, &path, vd.trim_end_matches("-bands"), extra)
    };
    let near = shot("4", &[]);
    let far = shot("64", &["--edit"]);
    let (a, b) = (view(&near), view(&far));
    assert!(distinct(&b) > 200, "{} colours", distinct(&b));
    // Where the near view shows sky past its 4 chunks, the far view shows land and sea.
    let changed = a
        .iter()
        .zip(&b)
        .filter(|(p, q)| (0..3).any(|c| p[c].abs_diff(q[c]) > 16))
        .count();
    assert!(
        changed * 50 > a.len(),
        "the far view differs from the near one on {changed} of {} pixels; see {}",
        a.len(),
        dir.display()
    );
    // With the levels as bands, level 1 (past 32 chunks) is drawn darker: the picture is
    // darker where it differs, and only there (level 0 is the same).
    let banded = view(&shot("64-bands", &["--level-bands"]));
    let (mut darker, mut lighter) = (0, 0);
    for (p, q) in b.iter().zip(&banded) {
        let sum = |p: &[u8; 3]| p.iter().map(|&c| u32::from(c)).sum::<u32>();
        if sum(q) + 12 < sum(p) {
            darker += 1;
        } else if sum(q) > sum(p) + 12 {
            lighter += 1;
        }
    }
    println!("with bands: {darker} pixels darker, {lighter} lighter");
    // Level 1 is the strip at the horizon of this view (459 pixels at 640 × 360).
    assert!(darker > 200, "level 1 not darker: {darker} pixels");
    assert!(lighter * 10 < darker, "{lighter} pixels lighter with bands");
}

/// A lit scene (`light = true`) opened in the window is drawn with its light and its sun
/// shadows (docs/light.md): the cathedral's hall is dark where no light reaches (a fifth of
/// the view and more; unlit, daylight would fill it), and without sun shadows
/// (`sun_shadows = false`) the picture differs wherever the sun's light falls or is hidden.
#[test]
fn the_window_draws_a_lit_scene_with_its_light_and_sun_shadows() {
    let Some(x) = vulkan_and_xvfb() else { return };
    let dir = out_dir("window-light");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/light/cathedral.toml");
    let text = std::fs::read_to_string(&scene).unwrap();
    assert!(text.contains("\nlight = true\n"), "a lit scene");
    let flat = dir.join("cathedral_no_sun_shadows.toml");
    std::fs::write(
        &flat,
        text.replace("\nlight = true\n", "\nlight = true\nsun_shadows = false\n"),
    )
    .unwrap();
    let shot = |scene: &Path, name: &str| {
        let path = dir.join(name);
        demo(
            &x,
            &[
                "--size",
                "960x540",
                "--frames",
                "3",
                "--scene",
                scene.to_str().unwrap(),
                "--screenshot",
                path.to_str().unwrap(),
            ],
        );
        // The view right of the panel (the hall is too dark for `panel_edge`).
        let img = Image::load_png(&path).unwrap();
        let mut v = Vec::new();
        for y in 0..img.height {
            for x in img.width * 2 / 5..img.width {
                let p = img.pixel(x, y);
                v.push([p[0], p[1], p[2]]);
            }
        }
        v
    };
    let lit = shot(&scene, "cathedral.png");
    let no_shadows = shot(&flat, "cathedral_no_sun_shadows.png");
    assert!(distinct(&lit) > 100, "{} colours", distinct(&lit));
    let dark = lit.iter().filter(|p| p.iter().all(|&c| c < 40)).count();
    assert!(
        dark * 5 > lit.len(),
        "lit: {dark} of {} pixels dark",
        lit.len()
    );
    let differ = lit
        .iter()
        .zip(&no_shadows)
        .filter(|(p, q)| (0..3).any(|c| p[c].abs_diff(q[c]) > 8))
        .count();
    assert!(
        differ * 20 > lit.len(),
        "sun shadows: {differ} of {} pixels differ",
        lit.len()
    );
}

/// `--light` lights the generated terrain as it streams (on the streamer's workers): the
/// scripted frames wait for the light as for the meshes, and the picture is the unlit
/// one where the open sky lights everything alike, darker where the sky's light is
/// dimmed (the sea floor under the water, the ground under trees and overhangs).
#[test]
fn the_window_lights_the_terrain_as_it_streams() {
    let Some(x) = vulkan_and_xvfb() else { return };
    let dir = out_dir("window-lit-terrain");
    let shot = |name: &str, extra: &[&str]| view(&terrain_shot(&x, &dir.join(name), "4", extra));
    let unlit = shot("unlit.png", &[]);
    let lit = shot("lit.png", &["--light"]);
    assert!(distinct(&lit) > 100, "{} colours", distinct(&lit));
    let sum = |p: &[u8; 3]| p.iter().map(|&c| u32::from(c)).sum::<u32>();
    let (mut darker, mut lighter) = (0, 0);
    for (p, q) in unlit.iter().zip(&lit) {
        if sum(q) + 12 < sum(p) {
            darker += 1;
        } else if sum(q) > sum(p) + 12 {
            lighter += 1;
        }
    }
    println!(
        "lit: {darker} pixels darker, {lighter} lighter of {}",
        lit.len()
    );
    assert!(darker * 100 > lit.len(), "only {darker} pixels darker lit");
    assert!(lighter * 20 < lit.len(), "{lighter} pixels lighter lit");
    // Not a view gone dark (chunks drawn unlit or not at all).
    assert!(
        darker * 2 < lit.len(),
        "{darker} of {} pixels darker",
        lit.len()
    );
}
