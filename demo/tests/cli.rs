//! The command line on bad input: every mistake is an error that names the input, found
//! before any rendering starts (no GPU is needed for these).

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

mod common;

use common::demo;

/// Runs `args`, expects a failure whose stderr contains every one of `words`.
fn fails_saying(args: &[&str], words: &[&str]) {
    let out = demo(args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{args:?} succeeded");
    for w in words {
        assert!(err.contains(w), "{args:?}: {w:?} not in {err}");
    }
}

#[test]
fn unknown_options_and_values_are_named() {
    fails_saying(
        &["render", "--bar", "--out", "x.png"],
        &["unexpected argument", "--bar"],
    );
    fails_saying(&["--bar"], &["unexpected argument", "--bar"]);
    fails_saying(
        &["render", "--technique", "nope", "--out", "x.png"],
        &["nope", "wboit-mrt"],
    );
    fails_saying(
        &["render", "--weight", "eq11", "--out", "x.png"],
        &["eq11", "fitted"],
    );
    fails_saying(&["render", "--bayer", "3", "--out", "x.png"], &["3", "16"]);
    fails_saying(
        &["render", "--size", "0x10", "--out", "x.png"],
        &["--size", "\"0\""],
    );
    fails_saying(&["render"], &["--out"]);
    fails_saying(
        &["eval", "--techniques", "wboit,sorted", "--out", "x"],
        &["wboit", "known"],
    );
    fails_saying(
        &["window", "--view-distance", "513"],
        &["--view-distance", "513"],
    );
}

#[test]
fn peel_layers_beyond_the_limit_are_refused_before_rendering() {
    fails_saying(
        &[
            "render",
            "--technique",
            "depth-peeling",
            "--layers",
            "8194",
            "--out",
            "x.png",
        ],
        &["8194", "512"],
    );
}

#[test]
fn an_output_that_cannot_be_written_is_refused_before_rendering() {
    let dir = std::env::temp_dir().join(format!("demo-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("a_file");
    std::fs::write(&file, b"x").unwrap();
    let under_file = file.join("x.png");
    fails_saying(
        &["render", "--out", under_file.to_str().unwrap()],
        &["is a file, not a folder", "a_file"],
    );
    fails_saying(
        &["render", "--out", dir.to_str().unwrap()],
        &["is a folder"],
    );
    // /proc refuses new files even to root.
    fails_saying(
        &["render", "--out", "/proc/voxel-oit/x.png"],
        &["/proc/voxel-oit"],
    );
    fails_saying(
        &["eval", "--out", under_file.to_str().unwrap()],
        &["is a file"],
    );
    fails_saying(
        &["showcase", "--full", "--out", under_file.to_str().unwrap()],
        &["is a file"],
    );
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn help_comes_from_clap_for_every_command() {
    for args in [
        &["--help"][..],
        &["eval", "--help"],
        &["render", "--help"],
        &["showcase", "--help"],
    ] {
        let out = demo(args);
        assert!(out.status.success(), "{args:?}");
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(text.contains("Usage: demo"), "{args:?}: {text}");
    }
    // Every technique in `Technique::ALL` order, however many there are (clap may wrap).
    let text = String::from_utf8_lossy(&demo(&["--help"]).stdout).into_owned();
    let words = text.split_whitespace().collect::<Vec<_>>().join(" ");
    let want = format!(
        "techniques: {}",
        voxel_render::Technique::ALL
            .map(voxel_render::Technique::name)
            .join(", ")
    );
    assert!(words.contains(&want), "no `{want}` in:\n{text}");
    let text = String::from_utf8_lossy(&demo(&["showcase", "--help"]).stdout).into_owned();
    assert!(text.contains("--full"), "{text}");
}

#[test]
fn bad_random_draws_are_refused_before_rendering() {
    fails_saying(
        &["eval", "--random", "0", "--out", "x"],
        &["--random", "at least 1 scene"],
    );
    fails_saying(
        &["eval", "--random", "100001", "--out", "x"],
        &["--random", "100001", "at most 100000"],
    );
    fails_saying(
        &["eval", "--random", "99999999999999999999999", "--out", "x"],
        &[
            "--random",
            "99999999999999999999999 random scenes",
            "at most 100000",
        ],
    );
    fails_saying(
        &["eval", "--random", "ten", "--out", "x"],
        &["--random", "\"ten\"", "not a number of scenes"],
    );
    fails_saying(&["eval", "--random", "-3", "--out", "x"], &["--random"]);
    fails_saying(
        &["eval", "--random", "5", "--seed", "abc", "--out", "x"],
        &["--seed", "\"abc\"", "not a seed"],
    );
    fails_saying(
        &["eval", "--random", "5", "--seed", "-1", "--out", "x"],
        &["--seed", "\"-1\"", "not a seed"],
    );
    fails_saying(
        &[
            "eval",
            "--random",
            "5",
            "--seed",
            "18446744073709551616",
            "--out",
            "x",
        ],
        &["--seed", "not a seed", "18446744073709551615"],
    );
    fails_saying(&["eval", "--seed", "3", "--out", "x"], &["--random"]);
    fails_saying(
        &["eval", "--random", "3", "--scenes", "scenes", "--out", "x"],
        &["--random", "--scenes", "cannot be used with"],
    );
}

#[test]
fn bad_stream_runs_are_refused_before_rendering() {
    fails_saying(
        &[
            "stream",
            "--view-distance",
            "0",
            "--frames",
            "5",
            "--out",
            "x",
        ],
        &["--view-distance", "0"],
    );
    fails_saying(
        &[
            "stream",
            "--view-distance",
            "65",
            "--frames",
            "5",
            "--out",
            "x",
        ],
        &["--view-distance", "65", "1..=64"],
    );
    fails_saying(
        &[
            "stream",
            "--view-distance",
            "4",
            "--frames",
            "0",
            "--out",
            "x",
        ],
        &["--frames", "0"],
    );
    for speed in ["NaN", "-1", "2000", "inf"] {
        fails_saying(
            &[
                "stream",
                "--view-distance",
                "4",
                "--frames",
                "5",
                "--speed",
                speed,
                "--out",
                "x",
            ],
            &["--speed", "0 to 1024"],
        );
    }
    fails_saying(
        &[
            "stream",
            "--view-distance",
            "4",
            "--frames",
            "5",
            "--draw",
            "bindless",
            "--out",
            "x",
        ],
        &["--draw", "bindless", "indirect or per-chunk"],
    );
    fails_saying(
        &["stream", "--frames", "5", "--out", "x"],
        &["--view-distance"],
    );
}

/// Writes `text` as `name` in a fresh temporary folder and returns its path.
fn scene_file(name: &str, text: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("demo-cli-scenes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// A one-box scene; `camera_extra` is added to its camera.
fn small_scene(boxes_max: &str, camera_extra: &str) -> String {
    format!(
        "name = \"small\"\n[[boxes]]\nblock = \"red_glass\"\nmin = [0, 0, 0]\nmax = {boxes_max}\n\
         [[cameras]]\neye = [0.5, 1.0, 10.0]\ntarget = [0.5, 1.0, 0.0]\n{camera_extra}\n"
    )
}

/// Sizes, frame counts, warm-up frames, flicker frames and sweep points past
/// their documented caps are errors naming the flag and the cap, before anything runs
/// (these used to panic, fail to allocate, or run for ever).
#[test]
fn counts_and_sizes_past_their_caps_are_refused_before_rendering() {
    fails_saying(
        &["eval", "--size", "16384x16384", "--out", "x"],
        &["--size", "8192"],
    );
    fails_saying(
        &["render", "--size", "8192x8192", "--out", "x.png"],
        &["--size", "33177600 pixels"],
    );
    fails_saying(
        &["render", "--frames", "4294967295", "--out", "x.png"],
        &["--frames", "4294967295", "1..=1000"],
    );
    fails_saying(
        &["eval", "--frames", "1001", "--out", "x"],
        &["--frames", "1..=1000"],
    );
    fails_saying(
        &["eval", "--warmup", "4294967295", "--out", "x"],
        &["--warmup", "0..=100"],
    );
    fails_saying(
        &["eval", "--flicker-frames", "100000000", "--out", "x"],
        &["--flicker-frames", "100000000", "2..=240"],
    );
    for points in ["1", "10"] {
        fails_saying(
            &["eval", "--sweep-points", points, "--out", "x"],
            &["--sweep-points", "2..=9"],
        );
    }
    fails_saying(
        &[
            "stream",
            "--view-distance",
            "4",
            "--frames",
            "5",
            "--size",
            "9000x10",
            "--out",
            "x",
        ],
        &["--size", "8192"],
    );
}

/// Scene files are read with a size limit (an endless device is an error after
/// 1 MiB, naming it), boxes that touch too many chunks are an error (20 M blocks in one
/// row passed the block count), and a `path_to` no camera can take is refused by
/// `render` as by `eval`: all before any GPU work.
#[test]
fn bad_scene_files_are_refused_before_rendering() {
    for endless in ["/dev/zero", "/dev/urandom"] {
        fails_saying(
            &["render", "--scene", endless, "--out", "x.png"],
            &[endless, "larger than 1048576 bytes"],
        );
    }
    let row = scene_file("row.toml", &small_scene("[19999999, 0, 0]", ""));
    fails_saying(
        &["render", "--scene", row.to_str().unwrap(), "--out", "x.png"],
        &["row.toml", "boxes", "16384 chunks"],
    );
    let big = scene_file(
        "big.toml",
        &format!("size = [16384, 16384]\n{}", small_scene("[3, 3, 0]", "")),
    );
    // eval makes its output folder first: a temporary one.
    let out = std::env::temp_dir().join(format!("demo-cli-out-{}", std::process::id()));
    let out = out.to_str().unwrap();
    for (args, target) in [
        (&["render", "--scene"][..], "x.png"),
        (&["eval", "--techniques", "opaque-only", "--scenes"], out),
    ] {
        let mut a = args.to_vec();
        a.extend([big.to_str().unwrap(), "--out", target]);
        fails_saying(&a, &["big.toml", "size", "8192"]);
    }
    let nan = scene_file(
        "nan_path.toml",
        &small_scene("[3, 3, 0]", "path_to = [nan, 1.0, 10.0]"),
    );
    for (args, target) in [
        (&["render", "--scene"][..], "x.png"),
        (&["eval", "--techniques", "opaque-only", "--scenes"], out),
    ] {
        let mut a = args.to_vec();
        a.extend([nan.to_str().unwrap(), "--out", target]);
        fails_saying(&a, &["nan_path.toml", "cameras.path_to", "finite"]);
    }
    assert!(
        std::fs::read_dir(out).unwrap().next().is_none(),
        "nothing written"
    );
    let _ = std::fs::remove_dir_all(out);
}

#[test]
fn a_broken_vox_model_is_named_before_rendering() {
    let dir = std::env::temp_dir().join(format!("demo-cli-vox-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("broken.vox");
    // "VOX ", version 200, then a MAIN chunk declaring more children than the file holds.
    let mut bytes = b"VOX \xc8\0\0\0MAIN".to_vec();
    bytes.extend([0, 0, 0, 0, 0, 0, 1, 0]);
    std::fs::write(&bad, &bytes).unwrap();
    let out = dir.join("x.png");
    let (bad_s, out_s) = (bad.to_str().unwrap(), out.to_str().unwrap());
    fails_saying(
        &["render", "--scene", bad_s, "--out", out_s],
        &["broken.vox", "chunk MAIN", "past the end"],
    );
    fails_saying(
        &["window", "--scene", bad_s, "--frames", "1"],
        &["broken.vox", "past the end"],
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `demo render --scene X.vox` draws a bare MagicaVoxel model from its default camera (on
/// lavapipe; skipped loudly without an adapter unless `CI` is set).
#[test]
fn a_bare_vox_model_renders_from_its_default_camera() {
    if tests::gpu().is_none() {
        return;
    }
    let dir = std::env::temp_dir().join(format!("demo-cli-vox-ok-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let png = dir.join("chapel.png");
    let model = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/vox/chapel.vox");
    let out = demo(&[
        "render",
        "--scene",
        model,
        "--technique",
        "sorted-quads",
        "--size",
        "160x90",
        "--out",
        png.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("scene: chapel"), "{stdout}");
    let img = voxel_render::Image::load_png(&png).unwrap();
    // The model is in the frame: pixels far from the sky's colour (11 % when this test was
    // written: the camera frames the bounding box, whose garden corner is mostly empty).
    let sky = img.pixel(0, 0);
    let model_px = (0..img.height)
        .flat_map(|y| (0..img.width).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            let p = img.pixel(x, y);
            (0..3).any(|c| p[c].abs_diff(sky[c]) > 40)
        })
        .count();
    let share = model_px as f64 / f64::from(img.width * img.height);
    assert!(share > 0.08, "the model covers {share:.2} of the picture");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The showcase (what `bash scripts/run.sh` runs without a display): every technique's
/// picture of the default scene, the cathedral window lit, then the chart of a few suite scenes, and where the whole
/// suite is (on lavapipe; skipped loudly without an adapter unless `CI` is set).
#[test]
fn the_showcase_draws_every_technique_and_a_small_chart() {
    if tests::gpu().is_none() {
        return;
    }
    let dir = std::env::temp_dir().join(format!("demo-cli-showcase-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = demo(&[
        "showcase",
        "--size",
        "160x90",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    for t in voxel_render::Technique::ALL {
        let img = voxel_render::Image::load_png(&dir.join(format!("{}.png", t.name()))).unwrap();
        assert_eq!((img.width, img.height), (160, 90), "{}", t.name());
    }
    // The cathedral window, lit: not a black picture.
    let lit = voxel_render::Image::load_png(&dir.join("light.png")).unwrap();
    assert_eq!((lit.width, lit.height), (160, 90));
    assert!(tests::distinct_colours(&lit) > 20, "light.png is a picture");
    assert!(dir.join("eval/speed_vs_accuracy.png").is_file());
    let summary = std::fs::read_to_string(dir.join("eval/summary.json")).unwrap();
    let records: Vec<serde_json::Value> = serde_json::from_str(&summary).unwrap();
    let mut scenes: Vec<&str> = records
        .iter()
        .map(|r| r["scene"].as_str().unwrap())
        .collect();
    scenes.dedup();
    assert_eq!(scenes.len(), 6, "a few scenes, not the suite: {scenes:?}");
    assert!(
        records
            .iter()
            .all(|r| r["width"] == 320 && r["height"] == 180),
        "at a small size"
    );
    assert!(stdout.contains("showcase --full"), "{stdout}");
    let _ = std::fs::remove_dir_all(dir);
}
