//! Every file the tools write is checked: a failed write (a full disk, a folder
//! in the way) is an error naming the file and a failing exit, never "wrote". And `render`
//! and `eval` accept the same scene files. Needs a Vulkan adapter (lavapipe); without one
//! it skips loudly, unless `CI` is set: then it fails.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use common::demo;

/// A Vulkan adapter is there (else the test skips loudly, or fails under `CI`).
fn have_gpu() -> bool {
    tests::gpu().is_some()
}

fn dir(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Two glass sheets over stone, a camera with a flicker path: small and quick.
const SCENE: &str = r#"
name = "tiny"
[[boxes]]
block = "stone"
min = [-4, -1, -6]
max = [4, -1, 0]
[[boxes]]
block = "red_glass"
min = [-2, 0, -4]
max = [2, 3, -4]
[[boxes]]
block = "blue_glass"
min = [-1, 0, -2]
max = [3, 2, -2]
[[cameras]]
eye = [0.5, 1.5, 6.0]
target = [0.5, 1.0, -3.0]
path_to = [1.5, 1.5, 6.0]
"#;

fn scene(dir: &Path) -> String {
    let path = dir.join("tiny.toml");
    std::fs::write(&path, SCENE).unwrap();
    path.to_str().unwrap().to_owned()
}

/// `demo eval` of `scene` at 32×24, one frame and no warm-up, writing into `out`, with
/// the options `more`.
fn eval(scene: &str, out: &str, more: &[&str]) -> Output {
    let mut args = vec![
        "eval", "--scenes", scene, "--size", "32x24", "--frames", "1", "--warmup", "0",
    ];
    args.extend_from_slice(more);
    args.extend(["--out", out]);
    demo(&args)
}

fn failed_naming(out: &Output, words: &[&str]) {
    let err = String::from_utf8_lossy(&out.stderr);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(!out.status.success(), "succeeded: {stdout}");
    assert!(!stdout.contains("wrote"), "{stdout}");
    for w in words {
        assert!(err.contains(w), "{w:?} not in {err}");
    }
}

#[test]
fn a_png_that_cannot_be_written_is_an_error() {
    if !have_gpu() {
        return;
    }
    let d = dir("writes-render");
    let scene = scene(&d);
    let base = ["render", "--scene", &scene, "--size", "48x32"];
    let mut args = base.to_vec();
    args.extend(["--out", "/dev/full"]);
    failed_naming(&demo(&args), &["/dev/full"]);
    // And the same command with a real file works and says so.
    let png = d.join("tiny.png");
    let mut args = base.to_vec();
    args.extend(["--out", png.to_str().unwrap()]);
    let out = demo(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("wrote"));
    assert!(std::fs::metadata(&png).unwrap().len() > 100);
}

/// `eval` with one of its files blocked by a folder of that name: the JSON summary, the
/// chart, a heat map, the report. Each run fails naming that file.
#[test]
fn eval_files_that_cannot_be_written_are_errors() {
    if !have_gpu() {
        return;
    }
    for blocked in [
        "summary.json",
        "speed_vs_accuracy.png",
        "speed_vs_accuracy.svg",
        "heatmaps/tiny__opaque-only.png",
        "report.md",
    ] {
        let d = dir(&format!("writes-eval-{}", blocked.replace('/', "_")));
        let scene = scene(&d);
        let out = d.join("out");
        std::fs::create_dir_all(out.join(blocked)).unwrap();
        let run = eval(
            &scene,
            out.to_str().unwrap(),
            &[
                "--techniques",
                "opaque-only",
                "--weights",
                "none",
                "--no-stability",
            ],
        );
        let name = Path::new(blocked).file_name().unwrap().to_str().unwrap();
        failed_naming(&run, &[name]);
    }
}

/// The scene file `render` draws, `eval` evaluates (flicker path included).
#[test]
fn render_and_eval_accept_the_same_scene_files() {
    if !have_gpu() {
        return;
    }
    let d = dir("writes-same-scene");
    let scene = scene(&d);
    let png = d.join("r.png");
    let r = demo(&[
        "render",
        "--scene",
        &scene,
        "--size",
        "32x24",
        "--out",
        png.to_str().unwrap(),
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let out = d.join("eval");
    let e = eval(
        &scene,
        out.to_str().unwrap(),
        &[
            "--techniques",
            "sorted-quads",
            "--weights",
            "none",
            "--flicker-frames",
            "3",
            "--sweep-points",
            "2",
        ],
    );
    assert!(e.status.success(), "{}", String::from_utf8_lossy(&e.stderr));
    assert!(out.join("stability/stability.json").exists());
}

/// A write that fails part way (the file size limit of the process: what a full disk does
/// to a file) leaves no partial file behind, and fails naming it.
#[test]
fn a_write_that_fails_part_way_leaves_no_partial_file() {
    if !have_gpu() {
        return;
    }
    let d = dir("writes-partial");
    let scene = scene(&d);
    let png = d.join("big.png");
    // Files of this process may not pass 1 KiB; the signal that limit raises is ignored,
    // so the write fails with an error instead.
    let cmd = format!(
        "trap '' XFSZ; ulimit -f 1; exec '{}' render --scene '{scene}' --size 320x200 --out '{}'",
        env!("CARGO_BIN_EXE_demo"),
        png.display()
    );
    let out = Command::new("bash")
        .args(["-c", &cmd])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    failed_naming(&out, &["big.png"]);
    assert!(!png.exists(), "a partial file was left behind");
}

/// `--heatmap-width` below what can be shrunk to is refused before anything renders.
#[test]
fn a_heat_map_too_narrow_is_refused_before_rendering() {
    let d = dir("writes-heatmap-width");
    let scene = scene(&d);
    let out = d.join("out");
    let run = eval(
        &scene,
        out.to_str().unwrap(),
        &["--no-stability", "--heatmap-width", "1"],
    );
    failed_naming(&run, &["heatmap-width"]);
    assert!(!out.exists(), "something was written");
}
