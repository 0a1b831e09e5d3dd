//! GL contexts as real drivers give them, made here with Mesa's overrides, and
//! `demo backends` going on past a device that cannot be made.
//!
//! NVIDIA's EGL gives wgpu a desktop GL 3.3 context whose shading language (GLSL 3.30)
//! cannot compile storage buffers or compute shaders, while the driver lists the extensions
//! that offer both. Mesa gives the same with `MESA_GL_VERSION_OVERRIDE=3.3` and
//! `MESA_GLSL_VERSION_OVERRIDE=330` (its extension list keeps `GL_ARB_compute_shader`), and a
//! 3.3 context without compute with `MESA_EXTENSION_OVERRIDE=-GL_ARB_compute_shader` too.
//! (`MESA_GLES_VERSION_OVERRIDE` changes nothing here: where EGL offers desktop GL, wgpu
//! takes it.)
//!
//! Without a Vulkan or GL adapter the tests skip with a loud message, unless `CI` is set:
//! then they fail. On a GL adapter that is not Mesa's the overrides do nothing, and the GL
//! tests skip.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use voxel_render::Image;

/// NVIDIA's kind of context: desktop GL 3.3, GLSL 3.30, compute listed as an extension.
const GL33_WITH_COMPUTE_EXTENSION: &[(&str, &str)] = &[
    ("MESA_GL_VERSION_OVERRIDE", "3.3"),
    ("MESA_GLSL_VERSION_OVERRIDE", "330"),
];

/// The same without the compute extension: a GL 3.3 device as the GL 3.3 standard has it.
const GL33: &[(&str, &str)] = &[
    ("MESA_GL_VERSION_OVERRIDE", "3.3"),
    ("MESA_GLSL_VERSION_OVERRIDE", "330"),
    ("MESA_EXTENSION_OVERRIDE", "-GL_ARB_compute_shader"),
];

/// No EGL vendor library: every GL device fails to be made.
const NO_GL: &[(&str, &str)] = &[("__EGL_VENDOR_LIBRARY_FILENAMES", "/nonexistent.json")];

/// No Vulkan driver either.
const NO_GL_NOR_VULKAN: &[(&str, &str)] = &[
    ("__EGL_VENDOR_LIBRARY_FILENAMES", "/nonexistent.json"),
    ("VK_ICD_FILENAMES", "/nonexistent.json"),
    ("VK_DRIVER_FILES", "/nonexistent.json"),
];

fn out_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../target/test-output/backends")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn demo(env: &[(&str, &str)], args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_demo"))
        .args(args)
        .envs(env.iter().copied())
        .env_remove("WGPU_BACKEND")
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap()
}

/// Runs the demo, expects success; returns what it printed.
fn succeeds(env: &[(&str, &str)], args: &[&str]) -> String {
    let out = demo(env, args);
    let log =
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "demo {args:?} with {env:?} failed: {}\n{log}",
        out.status
    );
    log
}

/// Both adapters, and the GL one Mesa's (whose overrides these tests use); `false` (after
/// the loud message of [`tests::gpu`] or [`tests::gl`], or of a GL adapter that is not
/// Mesa's) when a test cannot run here.
fn mesa_gl_and_vulkan() -> bool {
    if tests::gpu().is_none() {
        return false;
    }
    let Some(gl) = tests::gl() else {
        return false;
    };
    let name = &gl.caps.adapter_name;
    if !name.contains("llvmpipe") && !name.contains("softpipe") {
        eprintln!(
            "\n!!!! SKIPPING: the GL adapter {name} is not Mesa's: its overrides do nothing !!!!\n"
        );
        return false;
    }
    true
}

fn backends(env: &[(&str, &str)], out: &Path) -> Output {
    demo(
        env,
        &[
            "backends",
            "--size",
            "64x36",
            "--frames",
            "1",
            "--out",
            out.to_str().unwrap(),
        ],
    )
}

/// The table's rows of `device` (the text after the device's cell).
fn rows<'a>(report: &'a str, device: &str) -> Vec<&'a str> {
    let prefix = format!("| {device} | ");
    report
        .lines()
        .filter_map(|l| l.strip_prefix(prefix.as_str()))
        .collect()
}

/// On NVIDIA's kind of GL context the device is made (wgpu's indirect-call validation,
/// whose compute pipeline that GLSL cannot compile, is not asked for), and every technique
/// is refused with the reason (wgpu 30 binds every resource to slot 0 there: drawing would
/// give a blank picture), not lost with the device before the first frame.
#[test]
fn gl_whose_shading_language_lacks_compute_starts_and_refuses_cleanly() {
    if !mesa_gl_and_vulkan() {
        return;
    }
    let out = out_dir("gl33_compute_extension");
    let run = backends(GL33_WITH_COMPUTE_EXTENSION, &out);
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{}\n{err}", run.status);
    assert!(!err.contains("device is lost"), "{err}");
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(report.contains("- GL: llvmpipe"), "{report}");
    for device in ["GL", "GL, WebGL2 limits"] {
        let gl = rows(&report, device);
        assert_eq!(gl.len(), voxel_render::Technique::ALL.len(), "{report}");
        for row in gl {
            assert!(
                row.contains("unsupported:") && row.contains("resources bound"),
                "{device}: {row}"
            );
        }
    }
    let vulkan = rows(&report, "Vulkan");
    assert!(vulkan.iter().all(|r| r.contains("| yes |")), "{report}");
}

/// On a GL 3.3 context without compute (no storage buffers in GLSL 3.30, no indirect
/// draws) the world is drawn with instanced quads and direct draws, as on Vulkan.
#[test]
fn gl_3_3_without_compute_draws_like_vulkan() {
    if !mesa_gl_and_vulkan() {
        return;
    }
    let out = out_dir("gl33");
    let (gl, vulkan) = (out.join("gl.png"), out.join("vulkan.png"));
    let render = |env, backend, path: &Path| {
        succeeds(
            env,
            &[
                "render",
                "--backend",
                backend,
                "--size",
                "160x90",
                "--out",
                path.to_str().unwrap(),
            ],
        )
    };
    let log = render(GL33, "gl", &gl);
    assert!(log.contains("quads fetched by instanced"), "{log}");
    render(&[], "vulkan", &vulkan);
    let (gl, vulkan) = (
        Image::load_png(&gl).unwrap(),
        Image::load_png(&vulkan).unwrap(),
    );
    assert!(tests::distinct_colours(&gl) > 100, "a blank picture");
    let mean = voxel_lab::metrics::mean_abs_diff(&vulkan, &gl);
    // GL 4.5 on llvmpipe is within 0.01/255 of lavapipe's picture of this scene on the
    // mean (docs/measurements.md); 0.5/255 leaves room for rasterisation differences
    // while a missing pass or a wrong binding costs tens.
    assert!(mean < 0.5, "mean difference {mean}/255");
}

/// A device that cannot be made is a row with its error, and the table goes on; only
/// when no device draws is the command a failure (the report is written all the same).
#[test]
fn backends_writes_a_row_for_a_device_that_cannot_be_made() {
    if tests::gpu().is_none() {
        return;
    }
    let out = out_dir("no_gl");
    let run = backends(NO_GL, &out);
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{}\n{err}", run.status);
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    for device in ["GL", "GL, WebGL2 limits"] {
        let gl = rows(&report, device);
        assert_eq!(gl.len(), 1, "{report}");
        assert!(gl[0].starts_with("(all) | failed: no device"), "{}", gl[0]);
    }
    for device in ["Vulkan", "Vulkan, WebGL2 limits"] {
        let vulkan = rows(&report, device);
        assert_eq!(vulkan.len(), voxel_render::Technique::ALL.len());
        assert!(
            vulkan
                .iter()
                .all(|r| r.contains("| yes |") || r.contains("| as `"))
        );
    }

    let out = out_dir("no_device");
    let run = backends(NO_GL_NOR_VULKAN, &out);
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success(), "{err}");
    assert!(err.contains("no device drew a technique"), "{err}");
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert_eq!(report.matches("| (all) | failed: no device").count(), 4);
}
