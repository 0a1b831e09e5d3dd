//! The web page in a real browser: headless Chromium loads it on WebGPU (SwiftShader) and on
//! WebGL2 (ANGLE on SwiftShader), the page draws the default scene with every technique at
//! a small fixed size and camera and posts each picture (or the renderer's refusal) to a
//! server this test runs; each picture is compared with the same technique's native picture
//! on lavapipe (Vulkan), same scene, size and camera: mean and largest channel difference,
//! as the backend table of docs/measurements.md.
//!
//! The page is built first (`bash scripts/web.sh build`: wasm32, wasm-bindgen, into
//! target/test-output/web-page). Without Chromium or a Vulkan adapter the test skips with a loud message,
//! unless `CI` is set: then it fails. The pictures and `report.md` (the browser ×
//! technique table) are written into target/test-output/browser.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use std::collections::{BTreeMap, HashMap};
mod common;

use std::path::Path;
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant};

use common::{Browser, Post, build_page, chromium, out_dir, root, serve, skip};

use voxel_lab::metrics;
use voxel_render::{
    GpuContext, Image, NoGame, OitConfig, Renderer, RendererConfig, Technique, readback, stages,
};
use voxel_web::check::{
    Kind, Report, TEST_FRAMES, TEST_LIGHT, TEST_RADIUS, TEST_SEED, TEST_SIZE, parse_report_path,
};

/// Mean difference to the native picture a technique may show, in 1/255 steps: the target
/// of docs/browser.md. The browser's GPUs (SwiftShader) and lavapipe rasterise, filter and
/// round differently; a missing pass or a wrong binding costs tens.
const MAX_MEAN: f64 = 3.0;
/// Most pixels that may differ from the native picture by more than 3/255 in a channel:
/// about 1 % do, nearly all on an edge of the geometry, where the two rasterisers
/// cover a pixel differently; a layer drawn wrong would cover far more.
const MAX_OFF: f64 = 0.03;
/// How long one backend's run may take (about 10 s here; the first start of a profile
/// and SwiftShader's shader compiles on a loaded machine take longer).
const RUN_TIMEOUT: Duration = Duration::from_secs(300);
/// Fewest distinct colours of a picture that is not blank (a default-scene picture at
/// 160×90 has thousands).
const MIN_COLOURS: usize = 100;

/// What one backend's run gave.
#[derive(Debug, Default)]
struct Run {
    reports: BTreeMap<&'static str, (Report, Vec<u8>)>,
    summary: String,
}

/// Runs the page on `backend` until it posts its summary or a panic.
fn run_page(binary: &Path, port: u16, backend: &str, posts: &Receiver<Post>, out: &Path) -> Run {
    let url = format!("http://127.0.0.1:{port}/index.html?test=1&backend={backend}");
    let _browser = Browser::open(binary, &url, &out.join(format!("profile-{backend}")));
    let start = Instant::now();
    let mut run = Run::default();
    loop {
        let left = RUN_TIMEOUT.saturating_sub(start.elapsed());
        let post = posts.recv_timeout(left).unwrap_or_else(|_| {
            panic!(
                "{backend}: no summary within {RUN_TIMEOUT:?} (reports so far: {:?}); browser log: {}",
                run.reports.keys().collect::<Vec<_>>(),
                out.join(format!("profile-{backend}.log")).display()
            )
        });
        let text = String::from_utf8_lossy(&post.body).into_owned();
        eprintln!("{backend}: {} ({} bytes)", post.path, post.body.len());
        match post.path.as_str() {
            "/panic" => panic!("{backend}: the page panicked: {text}"),
            "/done" => {
                run.summary = text;
                eprintln!(
                    "{backend}: {} s\n{}",
                    start.elapsed().as_secs(),
                    run.summary
                );
                return run;
            }
            path => {
                let report = parse_report_path(path)
                    .unwrap_or_else(|| panic!("{backend}: an unknown post {path}: {text}"));
                let old = run
                    .reports
                    .insert(report.technique.name(), (report, post.body));
                assert!(old.is_none(), "{backend}: {path} twice");
            }
        }
    }
}

/// The native picture of `technique` (with 32-bit MBOIT moments when `single`), drawn as
/// the page draws it.
fn native(ctx: &GpuContext, technique: Technique, single: bool) -> Image {
    let scene = voxel_web::scene::default_scene(TEST_SEED, TEST_RADIUS).unwrap();
    let (w, h) = TEST_SIZE;
    let mut oit = OitConfig::with(technique);
    oit.mboit.half_precision = !single;
    let config = RendererConfig {
        width: w,
        height: h,
        oit,
        ..RendererConfig::default()
    };
    let mut r = Renderer::new(ctx, scene.world.registry(), config).unwrap();
    let meshes = voxel_web::scene::mesh_world(&scene.world, TEST_LIGHT).unwrap();
    for (pos, meshes) in &meshes {
        r.upload_chunk(*pos, meshes).unwrap();
    }
    voxel_web::scene::sun_shadows(&mut r, &scene.world, &meshes).unwrap();
    let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
    let format = wgpu::TextureFormat::Rgba8UnormSrgb;
    let target = stages::target(&ctx.device, "native", format, usage, (w, h));
    for _ in 0..TEST_FRAMES {
        r.render_and_submit(&target.view, &scene.camera, &mut NoGame)
            .unwrap();
        r.after_submit();
    }
    assert_eq!(r.config().oit.technique, technique, "native drew another");
    readback::read_image(ctx, &target.texture).unwrap()
}

/// One cell of the browser × technique table.
#[derive(Debug)]
enum Cell {
    Drew {
        drew: Technique,
        mean: f64,
        max: u32,
        /// Share of the pixels off by more than 3/255.
        off: f64,
    },
    Refused(String),
}

#[test]
fn the_page_draws_like_native_on_webgpu_and_webgl2() {
    let Some(binary) = chromium() else {
        skip("no chromium (install it: bash scripts/test.sh does, as root)");
        return;
    };
    let Some(ctx) = tests::gpu() else {
        return;
    };
    let out = out_dir("browser");
    // The page into the target folder: nothing written into the checkout.
    let page = root().join("target/test-output/web-page");
    build_page(None, &page, &[]);
    let (tx, posts) = channel();
    let port = serve(page, tx);
    let (w, h) = TEST_SIZE;
    let mut natives: HashMap<(Technique, bool), Image> = HashMap::new();
    let mut table = format!(
        "# Browser × technique\n\nThe default scene (seed {TEST_SEED}, {TEST_RADIUS} chunks each way, lit: {TEST_LIGHT}) at {w}×{h} in headless Chromium, each technique's picture against the native one on lavapipe (Vulkan): mean and largest channel difference, 1/255 steps. Made by `cargo test --release -p voxel-web --test browser`.\n\n| browser | technique | runs | error vs native (mean / max) | pixels off by > 3/255 |\n|---|---|---|---|---:|\n"
    );
    let mut failures = Vec::new();
    for backend in ["webgpu", "webgl2"] {
        let run = run_page(&binary, port, backend, &posts, &out);
        let summary = &run.summary;
        assert!(
            !summary.starts_with("error:"),
            "{backend}: the page failed: {summary}"
        );
        assert!(
            summary.contains("errors: 0\n"),
            "{backend}: errors logged or reported by the GPU: {summary}"
        );
        let field = |name: &str| {
            summary
                .lines()
                .find_map(|l| l.strip_prefix(name))
                .unwrap_or_else(|| panic!("{backend}: no {name} in {summary}"))
                .to_owned()
        };
        let browser = match field("backend: ").as_str() {
            "WebGPU" => "Chromium, WebGPU",
            "WebGL2" => "Chromium, WebGL2",
            other => panic!("{backend}: the page ran on {other}"),
        };
        let supported: Vec<Technique> = field("supported: ")
            .split(',')
            .map(|t| t.parse::<Technique>().unwrap())
            .collect();
        table += &format!(
            "| {browser} | adapter: {}; {} | | | |\n",
            field("adapter: "),
            field("drawn with: ")
        );
        let dir = out.join(backend);
        std::fs::create_dir_all(&dir).unwrap();
        for t in Technique::ALL {
            let (report, body) = run
                .reports
                .get(t.name())
                .unwrap_or_else(|| panic!("{backend}: no report of {t}"));
            let text = String::from_utf8_lossy(body);
            let cell = match report.kind {
                Kind::Failed => panic!("{backend}: {t} failed: {text}"),
                Kind::Refused => {
                    // `Error::Unsupported`, and only for what the device does not run.
                    assert!(
                        text.starts_with("not supported on this device: "),
                        "{backend}: {t} refused with another error: {text}"
                    );
                    assert!(
                        !supported.contains(&t),
                        "{backend}: {t} refused but listed as supported"
                    );
                    Cell::Refused(text.into_owned())
                }
                Kind::Drew => {
                    let drew = report.drew.unwrap();
                    assert!(
                        drew == t || !supported.contains(&t),
                        "{backend}: {t} drew as {drew} though the device runs it"
                    );
                    assert_eq!(body.len(), (4 * w * h) as usize, "{backend}: {t}");
                    let image = Image {
                        width: w,
                        height: h,
                        rgba: body.clone(),
                    };
                    image.save_png(&dir.join(format!("{t}.png"))).unwrap();
                    let colours = tests::distinct_colours(&image);
                    assert!(
                        colours >= MIN_COLOURS,
                        "{backend}: {t}: a blank picture ({colours} colours)"
                    );
                    let single = report.single_precision_moments;
                    let expected = natives
                        .entry((drew, single))
                        .or_insert_with(|| native(&ctx, drew, single));
                    expected
                        .save_png(&out.join(format!("native-{drew}-{single}.png")))
                        .unwrap();
                    let mean = metrics::mean_abs_diff(expected, &image);
                    let (m, _) = metrics::compare(expected, &image);
                    let off = expected
                        .rgba
                        .chunks_exact(4)
                        .zip(image.rgba.chunks_exact(4))
                        .filter(|(p, q)| (0..3).any(|c| p[c].abs_diff(q[c]) > 3))
                        .count() as f64
                        / f64::from(w * h);
                    Cell::Drew {
                        drew,
                        mean,
                        max: m.max_abs_err,
                        off,
                    }
                }
            };
            match &cell {
                Cell::Drew {
                    drew,
                    mean,
                    max,
                    off,
                } => {
                    let runs = if *drew == t {
                        "yes".to_owned()
                    } else {
                        format!("as `{drew}`")
                    };
                    let off = 100.0 * off;
                    table += &format!(
                        "| {browser} | `{t}` | {runs} | {mean:.3} / {max} | {off:.2} % |\n"
                    );
                }
                Cell::Refused(why) => {
                    table += &format!(
                        "| {browser} | `{t}` | refused: {} | | |\n",
                        why.replace('|', "/")
                    );
                }
            }
            // The targets: on WebGPU every real-time technique as itself; on WebGL2 at
            // least stipple and the sorted ones; each within MAX_MEAN of native.
            let required = match backend {
                "webgpu" => !t.stalls(),
                _ => matches!(
                    t,
                    Technique::Stipple | Technique::Sorted | Technique::SortedQuads
                ),
            };
            match cell {
                Cell::Drew { mean, .. } if mean > MAX_MEAN => {
                    failures.push(format!("{backend}: {t}: mean {mean:.3}/255"));
                }
                Cell::Drew { off, .. } if off > MAX_OFF => {
                    failures.push(format!(
                        "{backend}: {t}: {:.2} % of the pixels off by more than 3/255",
                        100.0 * off
                    ));
                }
                Cell::Drew { drew, .. } if required && drew != t => {
                    failures.push(format!("{backend}: {t} drew as {drew}"));
                }
                Cell::Refused(why) if required => {
                    failures.push(format!("{backend}: {t} refused: {why}"));
                }
                _ => {}
            }
        }
    }
    std::fs::write(out.join("report.md"), &table).unwrap();
    eprintln!("{table}");
    assert!(
        failures.is_empty(),
        "{}\n(pictures in {})",
        failures.join("\n"),
        out.display()
    );
}
