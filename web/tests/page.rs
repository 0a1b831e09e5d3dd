//! The page as a visitor meets it, in headless Chromium: WebGPU failing at start-up falls
//! back to WebGL2 and says so (a browser whose WebGPU canvas cannot present, a browser
//! with no WebGPU adapter); a device lost later is replaced by a new one; the canvas
//! fills the window (no scroll bars) at two window sizes; the page opened as a file says
//! what to run; and a game's own page, built from a crate outside the workspace
//! (templates/web-game, its own Cargo.toml depending on the crates by path), streams its
//! chunks on the page's thread and draws its things.
//!
//! Each page runs with `?report=1`: it posts its state (backend, status line, the notice,
//! sizes, the colours of what the canvas shows, errors logged) and the canvas's picture
//! every 15 frames after the 5th; the pictures are written into
//! target/test-output/web-page-tests. Without Chromium the tests skip with a loud message,
//! unless `CI` is set: then they fail.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::mpsc::{Receiver, channel};
use std::sync::{Mutex, OnceLock};
use std::time::{Duration, Instant};

use common::{
    Browser, GPU_FLAGS, Post, Report, build_page, chromium, out_dir, png_of_data_url, root, serve,
    skip,
};

/// How long a page may take to report what a test waits for (a few seconds here; a
/// loaded machine and SwiftShader's shader compiles take longer).
const TIMEOUT: Duration = Duration::from_secs(240);
/// Fewest distinct colours of a canvas that shows the scene (a white or black box has
/// one or two; the scene has thousands).
const MIN_COLOURS: usize = 100;

/// Chromium with WebGPU on SwiftShader but without its own Vulkan: the WebGPU device
/// comes, but the canvas's swap chain has no backing and the device is lost at the first
/// present (issue 53's repro: "the GPU device is lost (Destroyed...)" and a white box).
const NO_VULKAN: &[&str] = &[
    "--enable-unsafe-webgpu",
    "--use-webgpu-adapter=swiftshader",
    "--use-angle=swiftshader",
];
/// Chromium whose WebGPU gives no adapter.
const NO_WEBGPU: &[&str] = &["--disable-features=WebGPU", "--use-angle=swiftshader"];

/// One page build per test binary, shared by the tests (they run one at a time: each
/// starts a browser).
fn page() -> &'static Mutex<PathBuf> {
    static PAGE: OnceLock<Mutex<PathBuf>> = OnceLock::new();
    PAGE.get_or_init(|| {
        let out = root().join("target/test-output/web-page");
        build_page(None, &out, &[]);
        Mutex::new(out)
    })
}

impl Report {
    /// A `WxH` field.
    fn size(&self, key: &str) -> (u32, u32) {
        let (w, h) = self.get(key).split_once('x').unwrap();
        (w.parse().unwrap(), h.parse().unwrap())
    }
}

/// Opens `url` (a path on the server of `dir`) in Chromium with `flags` and a window of
/// `size`, and waits for a report for which `until` holds; saves the canvas's picture
/// of that report as `name.png`. Fails on a panic, an error the page shows, or none
/// within [`TIMEOUT`].
fn visit(
    dir: &Path,
    url: &str,
    flags: &[&str],
    size: (u32, u32),
    name: &str,
    until: impl Fn(&Report) -> bool,
) -> Report {
    let binary = chromium().unwrap();
    let out = out_dir(&format!("web-page-tests/{name}"));
    let (tx, posts): (_, Receiver<Post>) = channel();
    let port = serve(dir.to_owned(), tx);
    let url = format!("http://127.0.0.1:{port}/{url}");
    let _browser = Browser::open_with(&binary, &url, &out.join("profile"), flags, Some(size));
    let start = Instant::now();
    let mut picture = Vec::new();
    let mut seen = Vec::new();
    loop {
        let left = TIMEOUT.saturating_sub(start.elapsed());
        let post = posts.recv_timeout(left).unwrap_or_else(|_| {
            panic!(
                "{name}: no report as wanted within {TIMEOUT:?}; reports: {seen:#?}; browser log: {}",
                out.join("profile.log").display()
            )
        });
        let text = String::from_utf8_lossy(&post.body).into_owned();
        match post.path.as_str() {
            "/panic" => panic!("{name}: the page panicked: {text}"),
            "/done" => panic!("{name}: the page failed: {text}"),
            "/picture" => picture = png_of_data_url(&text).unwrap_or_default(),
            "/status" => {
                eprintln!("{name}: {} s\n{text}", start.elapsed().as_secs());
                let state = Report::parse(&text);
                assert!(
                    !state.get("status").starts_with("error"),
                    "{name}: the page shows an error: {text}"
                );
                if until(&state) {
                    std::fs::write(out.join(format!("{name}.png")), &picture).unwrap();
                    return state;
                }
                seen.push(text);
            }
            other => panic!("{name}: an unknown post {other}: {text}"),
        }
    }
}

/// What every page must show: the scene (not a blank or white box), no error logged,
/// the canvas as wide as the window and as tall as what the header leaves, its drawing
/// buffer its size, and no scroll bars (the document no larger than the window).
fn check_page(name: &str, s: &Report) {
    let colours = s.number("colours") as usize;
    assert!(
        colours >= MIN_COLOURS,
        "{name}: the canvas shows {colours} colours: {s:?}"
    );
    assert_eq!(s.get("errors"), "0", "{name}: errors logged: {s:?}");
    let (ww, wh) = s.size("window");
    let (cw, ch) = s.size("canvas");
    let (sw, sh) = s.size("scroll");
    assert_eq!(
        cw, ww,
        "{name}: the canvas is not as wide as the window: {s:?}"
    );
    assert!(
        ch > wh / 3 && ch < wh,
        "{name}: the canvas does not fill the window below the header: {s:?}"
    );
    assert_eq!(
        (sw, sh),
        (ww, wh),
        "{name}: the document is larger than the window (scroll bars): {s:?}"
    );
    // Headless Chromium's device pixel ratio is 1.
    assert_eq!(
        s.size("drawing buffer"),
        (cw, ch),
        "{name}: the drawing buffer does not follow the canvas: {s:?}"
    );
}

fn have_chromium() -> bool {
    if chromium().is_some() {
        return true;
    }
    skip("no chromium (install it: bash scripts/test.sh does, as root)");
    false
}

/// Issue 53's repro: WebGPU whose canvas cannot present (Chromium without its Vulkan)
/// loses its device at the first frame; the page falls back to WebGL2, says why, and
/// draws the scene (before: "the GPU device is lost" and a white box). At issue 53's
/// 960×600 window, which had scroll bars both ways.
#[test]
fn webgpu_that_cannot_present_falls_back_to_webgl2() {
    if !have_chromium() {
        return;
    }
    let dir = page().lock().unwrap_or_else(|e| e.into_inner());
    let name = "cannot-present";
    let s = visit(
        &dir,
        "index.html?report=1&radius=1",
        NO_VULKAN,
        (960, 600),
        name,
        |_| true,
    );
    assert_eq!(s.get("backend"), "WebGL2", "{s:?}");
    let notice = s.get("notice");
    assert!(
        notice.starts_with("WebGPU failed (") && notice.ends_with("drawing with WebGL2 instead"),
        "{notice}"
    );
    assert!(notice.contains("device is lost"), "{notice}");
    assert!(s.get("status").starts_with("WebGL2 · "), "{s:?}");
    check_page(name, &s);
}

/// A browser whose WebGPU gives no adapter: WebGL2, said on the page; at a second window
/// size, which the canvas follows too.
#[test]
fn no_webgpu_adapter_falls_back_to_webgl2() {
    if !have_chromium() {
        return;
    }
    let dir = page().lock().unwrap_or_else(|e| e.into_inner());
    let name = "no-adapter";
    let s = visit(
        &dir,
        "index.html?report=1&radius=1",
        NO_WEBGPU,
        (640, 480),
        name,
        |_| true,
    );
    assert_eq!(s.get("backend"), "WebGL2", "{s:?}");
    assert!(
        s.get("notice")
            .starts_with("WebGPU failed (no WebGPU adapter"),
        "{s:?}"
    );
    check_page(name, &s);
}

/// Where WebGPU works the page draws with it and says nothing of a fallback; a device
/// destroyed after 6 frames (`?lose=6`, as a driver reset or the browser would) is
/// replaced by a new device and renderer by the page itself, which draws on.
#[test]
fn a_lost_device_is_replaced_by_a_new_one() {
    if !have_chromium() {
        return;
    }
    let dir = page().lock().unwrap_or_else(|e| e.into_inner());
    let name = "lost-later";
    let first = visit(
        &dir,
        "index.html?report=1&radius=1",
        GPU_FLAGS,
        (960, 600),
        "webgpu",
        |_| true,
    );
    assert_eq!(first.get("backend"), "WebGPU", "{first:?}");
    assert_eq!(first.get("notice"), "", "{first:?}");
    check_page("webgpu", &first);
    let s = visit(
        &dir,
        "index.html?report=1&radius=1&lose=6",
        GPU_FLAGS,
        (960, 600),
        name,
        |s| s.number("rebuilt") >= 1,
    );
    assert_eq!(s.get("rebuilt"), "1", "{s:?}");
    assert_eq!(s.get("backend"), "WebGPU", "WebGPU came back: {s:?}");
    assert!(s.number("frames") > 6, "{s:?}");
    assert!(
        s.get("status")
            .starts_with("the GPU device was lost; drawing on a new one"),
        "{s:?}"
    );
    check_page(name, &s);
}

/// G3 (issue 52): opened as a file, the page says what to run instead of staying on
/// "loading…" (browsers load no module from file://).
#[test]
fn the_page_opened_as_a_file_says_what_to_run() {
    if !have_chromium() {
        return;
    }
    let binary = chromium().unwrap();
    let out = out_dir("web-page-tests/file");
    // The page's index.html alone, as a visitor opening it would have it.
    std::fs::copy(root().join("web/index.html"), out.join("index.html")).unwrap();
    let url = format!("file://{}", out.join("index.html").display());
    let dom = Command::new(binary)
        .args(["--headless=new", "--no-sandbox", "--disable-gpu"])
        .arg(format!("--user-data-dir={}", out.join("profile").display()))
        .args(["--dump-dom", &url])
        .output()
        .unwrap();
    let dom = String::from_utf8_lossy(&dom.stdout);
    let status = dom
        .split("<span id=\"status\">")
        .nth(1)
        .and_then(|s| s.split("</span>").next())
        .unwrap_or_else(|| panic!("no status in {dom}"));
    assert!(
        status.contains("cannot run from a file")
            && status.contains("<code>bash scripts/web.sh serve</code>"),
        "{status}"
    );
}

/// A game's own page: templates/web-game copied outside the checkout (its own
/// Cargo.toml, the crates by path), built by `scripts/web.sh` with `WEB_CRATE`,
/// `WEB_OUT` and the target folder from the environment, opened in Chromium: its
/// terrain streams in on the page's thread (chunks drawn, none failed, the streamer
/// idle), its things (40 fireflies and a glass box) drawn and moved, on WebGPU.
#[test]
fn a_games_own_page_builds_outside_the_workspace_and_runs() {
    if !have_chromium() {
        return;
    }
    let _one_at_a_time = page().lock().unwrap_or_else(|e| e.into_inner());
    let work = out_dir("web-page-tests/game-crate");
    let krate = work.join("web-game");
    std::fs::create_dir_all(krate.join("src")).unwrap();
    let template = root().join("templates/web-game");
    let checkout = root().canonicalize().unwrap();
    let manifest = std::fs::read_to_string(template.join("Cargo.toml"))
        .unwrap()
        .replace(
            "path = \"../../",
            &format!("path = \"{}/", checkout.display()),
        );
    assert!(manifest.contains(&format!("{}/web\"", checkout.display())));
    std::fs::write(krate.join("Cargo.toml"), manifest).unwrap();
    for f in ["src/lib.rs", "index.html"] {
        std::fs::copy(template.join(f), krate.join(f)).unwrap();
    }
    // The workspace's versions (wasm-bindgen's must be the CLI's); none downloaded.
    std::fs::copy(root().join("Cargo.lock"), krate.join("Cargo.lock")).unwrap();
    // The workspace's target folder: the game's page shares the build of every dependency
    // with the crate's own page (voxel-web is an rlib; web.sh makes each page's module a
    // cdylib of its own name, so neither overwrites the other).
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| root().join("target"));
    let out = work.join("out");
    build_page(
        Some(&krate),
        &out,
        &[
            ("CARGO_TARGET_DIR", target.to_str().unwrap()),
            ("CARGO_NET_OFFLINE", "true"),
        ],
    );
    for f in ["index.html", "web_game.js", "web_game_bg.wasm"] {
        assert!(out.join(f).is_file(), "{f} not built");
    }
    // Nothing written into the template.
    let mut files: Vec<_> = walk(&template);
    files.sort();
    assert_eq!(
        files,
        ["Cargo.toml", "index.html", "src/lib.rs"],
        "the template's folder changed"
    );
    let name = "game";
    let s = visit(
        &out,
        "index.html?report=1",
        GPU_FLAGS,
        (800, 600),
        name,
        |s| s.get("idle") == "true" && s.number("chunks") > 0,
    );
    assert_eq!(s.get("backend"), "WebGPU", "{s:?}");
    assert_eq!(s.get("failed chunks"), "0", "{s:?}");
    assert_eq!(s.get("things"), "41", "{s:?}");
    assert!(s.number("chunks") >= 20, "{s:?}");
    assert!(s.get("status").contains("streaming"), "{s:?}");
    check_page(name, &s);
}

/// The files under `dir`, relative, with `/`.
fn walk(dir: &Path) -> Vec<String> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        let name = e.file_name().to_string_lossy().into_owned();
        if p.is_dir() {
            out.extend(walk(&p).into_iter().map(|f| format!("{name}/{f}")));
        } else {
            out.push(name);
        }
    }
    out
}
