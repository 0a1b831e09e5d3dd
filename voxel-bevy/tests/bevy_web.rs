//! The Bevy example in the browser: `examples/web` (game.rs's world, fly camera, Bevy cube,
//! glass box and sparks, drawn by the plugin into the page's canvas) built for wasm32 by
//! `scripts/web.sh` with voxel-bevy's `webgl2` feature and with its `webgpu` feature (in the
//! `web-test` profile: opt-level 1, no debug info: a third of a release build's CPU), each
//! opened in headless Chromium (WebGL2 on ANGLE over SwiftShader; WebGPU on SwiftShader).
//!
//! The page runs with `?report=1` (examples/web/report.rs): it posts its state and the
//! canvas's picture, read back after Bevy presented the frame, until the picture is steady;
//! then it removes the game's things (the glass box, the sparks, the Bevy cube) and posts
//! until the picture is steady again. The test checks, on each backend: Bevy drew with the
//! backend the feature asks for, the plugin drew frames with a technique, nothing was logged
//! as an error and nothing panicked; the world is drawn (many colours, few dark pixels);
//! where the glass box and the cube are on the canvas the picture changed when they went,
//! the world is seen through the glass (many colours there), and the rest of the picture
//! stayed as it was. The pictures go to `target/test-output/bevy-web/`. Without Chromium the
//! tests skip loudly, unless `CI` is set: then they fail.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

#[path = "../../web/tests/common/mod.rs"]
mod page;

use std::collections::HashSet;
use std::path::Path;
use std::sync::Mutex;
use std::sync::mpsc::channel;
use std::time::{Duration, Instant};

use page::{
    Browser, GPU_FLAGS, Report, build_page, chromium, out_dir, png_of_data_url, root, serve, skip,
};
use voxel_render::Image;

/// How long the page may take to post both steady pictures (about a minute here on a
/// shared machine: SwiftShader compiles Bevy's and the crate's shaders on the CPU).
const TIMEOUT: Duration = Duration::from_secs(300);
/// The browser window (the canvas fills the page in it).
const WINDOW: (u32, u32) = (640, 480);
/// A channel difference that counts as changed (the same frame drawn twice is identical).
const CHANGED: u8 = 8;

/// One Chromium at a time (the two tests would share two cores).
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

#[test]
fn the_web_example_draws_on_webgl2() {
    run("webgl2", "Gl");
}

#[test]
fn the_web_example_draws_on_webgpu() {
    run("webgpu", "BrowserWebGpu");
}

impl Report {
    /// A `x0 y0 x1 y1` rectangle on the canvas, in whole pixels within `size`.
    fn rect(&self, key: &str, size: (u32, u32)) -> [u32; 4] {
        let v: Vec<f32> = self
            .get(key)
            .split(' ')
            .map(|v| v.parse().unwrap())
            .collect();
        let clamp = |v: f32, max: u32| (v.max(0.0) as u32).min(max);
        [
            clamp(v[0], size.0),
            clamp(v[1], size.1),
            clamp(v[2].ceil(), size.0),
            clamp(v[3].ceil(), size.1),
        ]
    }
}

fn run(feature: &str, backend: &str) {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let Some(binary) = chromium() else {
        skip("no chromium (install it: bash scripts/test.sh does, as root)");
        return;
    };
    let out = out_dir(&format!("bevy-web/{feature}"));
    let site = out.join("page");
    let start = Instant::now();
    build_page(
        Some(&root().join("voxel-bevy")),
        &site,
        &[
            ("WEB_EXAMPLE", "web"),
            ("WEB_FEATURES", feature),
            ("WEB_PROFILE", "web-test"),
        ],
    );
    eprintln!(
        "{feature}: page built in {:.0} s",
        start.elapsed().as_secs_f64()
    );
    let (tx, posts) = channel();
    let port = serve(site, tx);
    let url = format!("http://127.0.0.1:{port}/index.html?report=1");
    let start = Instant::now();
    let _browser = Browser::open_with(&binary, &url, &out.join("profile"), GPU_FLAGS, Some(WINDOW));
    let mut with: Option<(Report, Image)> = None;
    let without = loop {
        let left = TIMEOUT.saturating_sub(start.elapsed());
        let post = posts.recv_timeout(left).unwrap_or_else(|_| {
            panic!(
                "{feature}: no steady pictures within {TIMEOUT:?}; browser log: {}",
                out.join("profile.log").display()
            )
        });
        let text = String::from_utf8_lossy(&post.body).into_owned();
        assert_ne!(post.path, "/panic", "{feature}: the page panicked: {text}");
        assert_eq!(post.path, "/status", "{feature}: an unknown post: {text}");
        let report = Report::parse(&text);
        eprintln!(
            "{feature}: {:.0} s: {}",
            start.elapsed().as_secs_f64(),
            text.lines()
                .filter(|l| !l.starts_with("picture: "))
                .collect::<Vec<_>>()
                .join("; ")
        );
        assert_eq!(report.get("errors"), "0", "{feature}: errors: {text}");
        if report.get("steady") != "true" {
            continue;
        }
        let picture = png_of_data_url(report.get("picture")).unwrap();
        let phase = report.get("phase").to_owned();
        let path = out.join(format!("{}.png", phase.replace(' ', "-")));
        std::fs::write(&path, picture).unwrap();
        let image = Image::load_png(&path).unwrap();
        match phase.as_str() {
            "with things" => with = Some((report, image)),
            "without things" if with.is_some() => break image,
            _ => {}
        }
    };
    eprintln!(
        "{feature}: both pictures in {:.0} s",
        start.elapsed().as_secs_f64()
    );
    let (report, with) = with.unwrap();
    check(feature, backend, &report, &with, &without, &out);
}

/// What the two pictures must show (see the module's comment).
fn check(feature: &str, backend: &str, report: &Report, with: &Image, without: &Image, out: &Path) {
    assert_eq!(report.get("backend"), backend, "{feature}: Bevy's backend");
    assert!(
        report.number("voxel frames") > 0,
        "{feature}: the plugin drew nothing"
    );
    assert_ne!(
        report.get("technique"),
        "none",
        "{feature}: no technique drew"
    );
    let size = (with.width, with.height);
    // Headless Chromium's page is not the window's size: a canvas of some size is enough.
    assert!(
        size.0 >= 320 && size.1 >= 160,
        "{feature}: a canvas of {size:?}"
    );
    assert_eq!(size, (without.width, without.height));
    for (name, image) in [("with", with), ("without", without)] {
        let colours: HashSet<&[u8]> = image.rgba.chunks_exact(4).collect();
        let dark = image
            .rgba
            .chunks_exact(4)
            .filter(|p| p[..3].iter().all(|&c| c < 16))
            .count();
        let dark = dark as f64 / f64::from(size.0 * size.1);
        eprintln!(
            "{feature} {name}: {} colours, {:.1} % dark",
            colours.len(),
            dark * 100.0
        );
        assert!(
            colours.len() >= 500,
            "{feature} {name}: {} colours",
            colours.len()
        );
        assert!(
            dark < 0.05,
            "{feature} {name}: {:.1} % of the pixels are dark",
            dark * 100.0
        );
    }
    let pixel = |img: &Image, x: u32, y: u32| {
        let i = ((y * size.0 + x) * 4) as usize;
        [img.rgba[i], img.rgba[i + 1], img.rgba[i + 2]]
    };
    let changed = |x, y| {
        let (a, b) = (pixel(with, x, y), pixel(without, x, y));
        a.iter().zip(b).any(|(a, b)| a.abs_diff(b) > CHANGED)
    };
    let glass = report.rect("glass", size);
    let cube = report.rect("cube", size);
    let inside = |r: [u32; 4], x, y, margin| {
        x + margin >= r[0] && x < r[2] + margin && y + margin >= r[1] && y < r[3] + margin
    };
    let mut diff = Image {
        width: size.0,
        height: size.1,
        rgba: Vec::new(),
    };
    let (mut outside, mut outside_changed) = (0u32, 0u32);
    for y in 0..size.1 {
        for x in 0..size.0 {
            let c = changed(x, y);
            diff.rgba.extend(if c {
                [255, 0, 255, 255]
            } else {
                [0, 0, 0, 255]
            });
            if !inside(glass, x, y, 3) && !inside(cube, x, y, 3) {
                outside += 1;
                outside_changed += u32::from(c);
            }
        }
    }
    diff.save_png(&out.join("changed.png")).unwrap();
    for (name, r) in [("glass box", glass), ("cube", cube)] {
        let area = (r[2] - r[0]) * (r[3] - r[1]);
        assert!(
            area >= 50,
            "{feature}: the {name} covers {r:?} on the canvas"
        );
        let pixels = (r[1]..r[3]).flat_map(|y| (r[0]..r[2]).map(move |x| (x, y)));
        let moved = pixels.clone().filter(|&(x, y)| changed(x, y)).count();
        let share = moved as f64 / f64::from(area);
        eprintln!(
            "{feature}: {name} at {r:?}: {:.0} % of its pixels changed",
            share * 100.0
        );
        assert!(
            share > 0.3,
            "{feature}: the {name} is not drawn ({:.0} %)",
            share * 100.0
        );
        if name == "glass box" {
            // Seen through the glass: the terrain's detail, not a few flat faces.
            let seen: HashSet<[u8; 3]> = pixels
                .filter(|&(x, y)| changed(x, y))
                .map(|(x, y)| pixel(with, x, y))
                .collect();
            assert!(
                seen.len() >= 50,
                "{feature}: {} colours through the glass",
                seen.len()
            );
        }
    }
    let share = f64::from(outside_changed) / f64::from(outside);
    eprintln!("{feature}: {:.2} % of the rest changed", share * 100.0);
    assert!(
        share < 0.01,
        "{feature}: {:.2} % of the picture outside the things changed",
        share * 100.0
    );
}
