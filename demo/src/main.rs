//! The demo and headless tools of the voxel OIT renderer.
//!
//! - `demo [window] [--seed N] [--size WxH] [--technique NAME] [--view-distance N]
//!   [--heatmap] [--frames N] [--screenshot FILE] [--cycle DIR] [--edit] [--resize]`: the
//!   interactive demo (a window); the last five script it for tests. Without a display,
//!   `demo` runs the showcase instead.
//! - `demo showcase [--out DIR] [--size WxH]`: every technique rendered for the default scene
//!   into `DIR` (default `out/`), and a quick speed/accuracy evaluation with its chart.
//! - `demo stats [--seed N] [--chunks N]`: generate and mesh a world, print statistics.
//! - `demo render [--technique NAME] [--weight NAME] [--bayer 2|4|8|16] [--layers N]
//!   [--scene FILE] [--size WxH] [--seed N] [--msaa] [--frames N] --out FILE.png`: render a
//!   scene file (or the default generated scene) headlessly.

use std::sync::Arc;
use std::time::Instant;

const USAGE: &str = "\
usage: demo [COMMAND] [OPTIONS]

commands:
  (none)     the interactive window; without a display, the showcase
  window     [--seed N] [--size WxH] [--technique NAME] [--view-distance N] [--heatmap]
             [--frames N] [--screenshot FILE] [--cycle DIR] [--edit] [--resize]
  showcase   [--out DIR] [--size WxH]: every technique for the default scene, and a quick
             speed/accuracy evaluation with its chart
  stats      [--seed N] [--chunks N]: generate and mesh a world, print statistics
  render     [--technique NAME] [--weight NAME] [--bayer 2|4|8|16] [--layers N] [--scene FILE]
             [--size WxH] [--seed N] [--msaa] [--frames N] --out FILE.png
  eval       [--scenes PATH...] [--techniques all|LIST] [--weights all|none|LIST] [--size WxH]
             [--frames N] [--warmup N] [--no-stability] [--flicker-frames N]
             [--sweep-points N] [--heatmap-width W] --out DIR
";

use demo::args::{self, Args};
use voxel_core::{BlockRegistry, ChunkPos, TerrainConfig, TerrainGenerator};

fn main() {
    let argv: Vec<String> = std::env::args().skip(1).collect();
    if argv.first().is_some_and(|a| a == "help") || argv.iter().any(|a| a == "--help" || a == "-h")
    {
        use voxel_render::{Technique, WeightFunction};
        print!("{USAGE}");
        println!(
            "\ntechniques: {}\nweights: {} (default {})",
            Technique::ALL.map(Technique::name).join(", "),
            WeightFunction::ALL.map(WeightFunction::name).join(", "),
            WeightFunction::Fitted.name()
        );
        return;
    }
    let (cmd, rest) = match argv.first().map(String::as_str) {
        Some(c) if !c.starts_with("--") => (c, &argv[1..]),
        _ => ("", &argv[..]),
    };
    let result = match cmd {
        "" if demo::app::have_display() => window(rest),
        "" => {
            eprintln!(
                "no display (neither DISPLAY nor WAYLAND_DISPLAY is set): running the headless showcase instead"
            );
            showcase(rest)
        }
        "window" => window(rest),
        "showcase" => showcase(rest),
        "stats" => stats(rest),
        "render" => render(rest),
        "eval" => eval(rest),
        other => Err(format!(
            "unknown command {other:?}; commands: window, showcase, stats, render, eval"
        )),
    };
    if let Err(e) = result {
        eprintln!("error: {e}");
        std::process::exit(2);
    }
}

/// Generates and meshes a world, then prints what it holds and how long it took.
fn stats(argv: &[String]) -> Result<(), String> {
    let a = Args::parse(argv, &[], &[])?;
    a.reject_unknown(&["seed", "chunks"])?;
    let seed: u32 = a.parse_or("seed", 1)?;
    let n: i32 = a.parse_or("chunks", 32)?;
    if !(1..=256).contains(&n) {
        return Err(format!(
            "--chunks {n}: must be in 1..=256 (the world is N x 2 x N chunks)"
        ));
    }
    let registry = Arc::new(BlockRegistry::default());
    let generator = TerrainGenerator::new(TerrainConfig {
        seed,
        ..TerrainConfig::default()
    });
    let half = n / 2;
    let t = Instant::now();
    let mut world = generator
        .generate_world(
            registry.clone(),
            ChunkPos::new(-half, 0, -half),
            ChunkPos::new(n - half - 1, 1, n - half - 1),
        )
        .map_err(|e| e.to_string())?;
    let gen_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let meshes = voxel_mesh::mesh_dirty(&mut world).map_err(|e| e.to_string())?;
    let mesh_s = t.elapsed().as_secs_f64();

    let uniform = world
        .iter()
        .filter(|(_, c)| c.as_uniform().is_some())
        .count();
    let sum =
        |f: fn(&voxel_mesh::ChunkMeshes) -> usize| meshes.iter().map(|(_, m)| f(m)).sum::<usize>();
    let (opaque, cutout, translucent) = (
        sum(|m| m.opaque.len()),
        sum(|m| m.cutout.len()),
        sum(|m| m.translucent.len()),
    );
    let extent = i64::from(n) * 32;
    let sites = generator.sites_in(
        -i64::from(half) * 32,
        -i64::from(half) * 32,
        extent / 2,
        extent / 2,
    );
    println!("world seed {seed}: {n} x 2 x {n} chunks ({extent} x 64 x {extent} blocks)");
    println!(
        "generated in {:.0} ms, meshed in {:.0} ms on {} threads",
        gen_s * 1e3,
        mesh_s * 1e3,
        rayon::current_num_threads()
    );
    println!("chunks: {} ({uniform} uniform)", world.len());
    println!(
        "quads: {} opaque, {cutout} cutout (leaves), {translucent} translucent (water, glass); {:.1} MiB of quads",
        opaque,
        (opaque + cutout + translucent) as f64 * 8.0 / (1 << 20) as f64
    );
    println!(
        "glass structures: {} greenhouses, {} stained-glass pavilions",
        sites
            .iter()
            .filter(|s| s.kind == voxel_core::SiteKind::Greenhouse)
            .count(),
        sites
            .iter()
            .filter(|s| s.kind == voxel_core::SiteKind::Pavilion)
            .count()
    );
    Ok(())
}

/// Renders the default scene headlessly to a PNG and prints GPU times per pass.
fn render(argv: &[String]) -> Result<(), String> {
    use voxel_render::{RendererConfig, Technique, WeightFunction};
    let a = Args::parse(argv, &["msaa"], &[])?;
    a.reject_unknown(&[
        "technique",
        "weight",
        "bayer",
        "layers",
        "size",
        "seed",
        "scene",
        "msaa",
        "frames",
        "out",
    ])?;

    let out = a.get("out").ok_or("--out FILE.png is required")?;
    let (width, height) = args::parse_size(a.get("size").unwrap_or("1280x720"))?;
    let seed: u32 = a.parse_or("seed", 1)?;
    let frames: usize = a.parse_or("frames", 1)?;
    if frames == 0 {
        return Err("--frames must be at least 1".into());
    }
    let technique = Technique::from_name(a.get("technique").unwrap_or("wboit-mrt"))
        .map_err(|e| e.to_string())?;
    let mut config = RendererConfig {
        width,
        height,
        msaa: a.flag("msaa"),
        ..RendererConfig::default()
    };
    config.oit.technique = technique;
    if let Some(w) = a.get("weight") {
        config.oit.weight = WeightFunction::from_name(w).map_err(|e| e.to_string())?;
    }
    if let Some(b) = a.get("bayer") {
        let side = b
            .parse()
            .map_err(|_| format!("--bayer {b:?}: expected 2, 4, 8 or 16"))?;
        config.oit.bayer = voxel_render::BayerSize::from_side(side).map_err(|e| e.to_string())?;
    }
    config.oit.peel_layers = a.parse_or("layers", config.oit.peel_layers)?;
    if config.oit.peel_layers < 2 || !config.oit.peel_layers.is_multiple_of(2) {
        return Err(format!(
            "--layers {}: dual depth peeling takes an even number of layers, at least 2",
            config.oit.peel_layers
        ));
    }
    let t = Instant::now();
    let scene = match a.get("scene") {
        Some(path) => demo::scene::Scene::load(std::path::Path::new(path))?,
        None => demo::scene::default_scene(seed)?,
    };

    println!(
        "scene: {} ({} chunks) built in {:.0} ms",
        scene.name,
        scene.world.len(),
        t.elapsed().as_secs_f64() * 1e3
    );
    let ctx = demo::headless::context()?;
    println!("adapter: {}", ctx.caps.adapter_name);
    let mut renderer = demo::headless::renderer_for(&ctx, &scene, config)?;
    let target = demo::headless::Offscreen::new(&ctx, width, height);
    let camera = scene.cameras[0];
    let mut per_pass: Vec<(&'static str, Vec<f64>)> = Vec::new();
    let mut stats = None;
    let mut cpu = Vec::new();
    let mut first_sort = (0.0, 0);
    // The first frame warms up (pipeline and target creation); it is not timed.
    for i in 0..=frames {
        let s = renderer
            .render_and_submit(&target.view, &camera)
            .map_err(|e| e.to_string())?;
        if i == 0 {
            first_sort = (s.sort_ms, s.chunks_resorted);
        } else {
            cpu.push(s.cpu_ms);
        }
        stats = Some(s);
        let times = renderer.gpu_times_blocking();
        if i > 0 {
            for (label, ms) in times {
                match per_pass.iter_mut().find(|(l, _)| *l == label) {
                    Some((_, v)) => v.push(ms),
                    None => per_pass.push((label, vec![ms])),
                }
            }
        }
    }
    let image = target.read(&ctx)?;
    image
        .save_png(std::path::Path::new(out))
        .map_err(|e| e.to_string())?;
    let stats = stats.ok_or("no frame rendered")?;
    println!(
        "technique {technique}: drew {} opaque, {} cutout, {} translucent chunk meshes ({} translucent quads)",
        stats.meshes_drawn[0],
        stats.meshes_drawn[1],
        stats.meshes_drawn[2],
        stats.translucent_quads
    );
    if let Some(layers) = stats.technique.layers {
        println!("layers peeled: {layers}");
    }
    cpu.sort_by(f64::total_cmp);
    let cpu_median = cpu.get(cpu.len() / 2).copied().unwrap_or(0.0);
    println!("CPU ms to record a frame, median of {frames}: {cpu_median:.3}");
    if technique == Technique::SortedQuads {
        println!(
            "quad sort: first frame {:.3} ms for all {} visible translucent chunks; a still camera re-sorts nothing",
            first_sort.0, first_sort.1
        );
    }
    if let Some(overflow) = stats.technique.overflow {
        println!("reference overflow: {overflow} fragments");
    }
    if per_pass.is_empty() {
        println!("GPU times: unavailable (no timestamp queries on this adapter)");
    } else {
        let median = |v: &mut Vec<f64>| {
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        let line: Vec<String> = per_pass
            .iter_mut()
            .map(|(l, v)| format!("{l} {:.3}", median(v)))
            .collect();
        println!(
            "GPU ms per pass, median of {frames} frames at {width}x{height}: {}",
            line.join(", ")
        );
    }
    println!("wrote {out}");
    Ok(())
}

/// The scene files named on the command line (files or folders), or the `scenes/` folder.
fn scene_paths(given: &[String]) -> Result<Vec<std::path::PathBuf>, String> {
    let given: Vec<std::path::PathBuf> = if given.is_empty() {
        let local = std::path::PathBuf::from("scenes");
        let repo = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
        vec![if local.is_dir() { local } else { repo }]
    } else {
        given.iter().map(std::path::PathBuf::from).collect()
    };
    let mut out = Vec::new();
    for p in given {
        if p.is_dir() {
            out.extend(demo::eval::scene_files(&p)?);
        } else if p.is_file() {
            out.push(p);
        } else {
            return Err(format!("{}: no such scene file or folder", p.display()));
        }
    }
    Ok(out)
}

/// Renders every scene with every technique and the exact reference; writes the summary,
/// charts, heat maps, stability sweeps and report.
fn eval(argv: &[String]) -> Result<(), String> {
    use voxel_render::{Technique, WeightFunction};
    let a = Args::parse(
        argv,
        &["no-stability"],
        &["scenes", "techniques", "weights"],
    )?;
    a.reject_unknown(&[
        "scenes",
        "techniques",
        "weights",
        "size",
        "frames",
        "warmup",
        "no-stability",
        "flicker-frames",
        "sweep-points",
        "heatmap-width",
        "out",
    ])?;

    let out = std::path::PathBuf::from(a.get("out").ok_or("--out DIR is required")?);
    let list = |name: &str| -> Vec<String> {
        a.all(name)
            .iter()
            .flat_map(|v| v.split(','))
            .map(|s| s.trim().to_owned())
            .filter(|s| !s.is_empty())
            .collect()
    };
    let techniques = match list("techniques").as_slice() {
        [] => Technique::ALL.to_vec(),
        [all] if all == "all" => Technique::ALL.to_vec(),
        names => names
            .iter()
            .map(|n| Technique::from_name(n))
            .collect::<Result<_, _>>()
            .map_err(|e| e.to_string())?,
    };
    let weights = match list("weights").as_slice() {
        [] => WeightFunction::ALL.to_vec(),
        [all] if all == "all" => WeightFunction::ALL.to_vec(),
        [none] if none == "none" => Vec::new(),
        names => names
            .iter()
            .map(|n| WeightFunction::from_name(n))
            .collect::<Result<_, _>>()
            .map_err(|e| e.to_string())?,
    };
    let opts = demo::eval::EvalOptions {
        scenes: scene_paths(a.all("scenes"))?,
        techniques,
        weights,
        size: a.get("size").map(args::parse_size).transpose()?,
        frames: a.parse_or("frames", 10)?,
        warmup: a.parse_or("warmup", 2)?,
        out: out.clone(),
        stability: !a.flag("no-stability"),
        flicker_frames: a.parse_or("flicker-frames", 60)?,
        sweep_points: a.parse_or("sweep-points", 9)?,
        command: std::iter::once("demo eval".to_owned())
            .chain(argv.iter().cloned())
            .collect::<Vec<_>>()
            .join(" "),
        heatmap_width: a
            .get("heatmap-width")
            .map(str::parse)
            .transpose()
            .map_err(|e| format!("--heatmap-width: {e}"))?,
    };

    if opts.frames == 0 {
        return Err("--frames must be at least 1".into());
    }
    let ctx = demo::headless::context()?;
    eprintln!(
        "adapter: {}; {} scenes x {} techniques + {} weights",
        ctx.caps.adapter_name,
        opts.scenes.len(),
        opts.techniques.len(),
        opts.weights.len()
    );
    let t = Instant::now();
    let summary = demo::eval::run(&ctx, &opts)?;
    let worst = summary
        .reference_checks
        .iter()
        .map(|c| c.max_abs_err)
        .max()
        .unwrap_or(0);
    println!(
        "{} records in {:.0} s; exact methods agree within {worst}/255; wrote {}",
        summary.records.len(),
        t.elapsed().as_secs_f64(),
        out.join("report.md").display()
    );
    Ok(())
}

/// Opens the interactive demo.
fn window(argv: &[String]) -> Result<(), String> {
    let a = Args::parse(argv, &["heatmap", "edit", "resize"], &[])?;
    a.reject_unknown(&[
        "seed",
        "size",
        "technique",
        "view-distance",
        "heatmap",
        "frames",
        "screenshot",
        "cycle",
        "edit",
        "resize",
    ])?;
    let defaults = demo::app::DemoOptions::default();
    let opts = demo::app::DemoOptions {
        seed: a.parse_or("seed", defaults.seed)?,
        size: a
            .get("size")
            .map(args::parse_size)
            .transpose()?
            .unwrap_or(defaults.size),
        technique: match a.get("technique") {
            Some(t) => voxel_render::Technique::from_name(t).map_err(|e| e.to_string())?,
            None => defaults.technique,
        },
        view_distance: a.parse_or("view-distance", defaults.view_distance)?,
        frames: a
            .get("frames")
            .map(str::parse)
            .transpose()
            .map_err(|e| format!("--frames: {e}"))?,
        screenshot: a.get("screenshot").map(std::path::PathBuf::from),
        cycle: a.get("cycle").map(std::path::PathBuf::from),
        heatmap: a.flag("heatmap"),
        edit: a.flag("edit"),
        resize: a.flag("resize"),
    };
    if !(1..=16).contains(&opts.view_distance) {
        return Err(format!(
            "--view-distance {}: must be in 1..=16 chunks",
            opts.view_distance
        ));
    }
    if (opts.screenshot.is_some() || opts.cycle.is_some() || opts.edit || opts.resize)
        && opts.frames.is_none()
    {
        return Err(
            "--screenshot, --cycle, --edit and --resize script a run: give --frames N too".into(),
        );
    }
    demo::app::run(opts)
}

/// Without a display: every technique's picture of the default scene, and a quick
/// evaluation of the suite with its speed/accuracy chart.
fn showcase(argv: &[String]) -> Result<(), String> {
    use voxel_render::{RendererConfig, Technique};
    let a = Args::parse(argv, &[], &[])?;
    a.reject_unknown(&["out", "size"])?;
    let out = std::path::PathBuf::from(a.get("out").unwrap_or("out"));
    let (w, h) = args::parse_size(a.get("size").unwrap_or("1280x720"))?;
    let ctx = demo::headless::context()?;
    println!("adapter: {}", ctx.caps.adapter_name);
    let scene = demo::scene::default_scene(1)?;
    let mut renderer = demo::headless::renderer_for(
        &ctx,
        &scene,
        RendererConfig {
            width: w,
            height: h,
            ..RendererConfig::default()
        },
    )?;
    let target = demo::headless::Offscreen::new(&ctx, w, h);
    for t in Technique::ALL {
        renderer.set_technique(t);
        // One frame to settle (adaptive peeling), one to keep.
        renderer
            .render_and_submit(&target.view, &scene.cameras[0])
            .map_err(|e| e.to_string())?;
        let img = demo::headless::render_image(&ctx, &mut renderer, &target, &scene.cameras[0])?;
        let path = out.join(format!("{}.png", t.name()));
        img.save_png(&path).map_err(|e| e.to_string())?;
        println!("wrote {}", path.display());
    }
    let eval_out = out.join("eval");
    let opts = demo::eval::EvalOptions {
        scenes: scene_paths(&[])?,
        techniques: Technique::ALL.to_vec(),
        weights: Vec::new(),
        size: Some((480, 270)),
        frames: 3,
        warmup: 1,
        out: eval_out.clone(),
        stability: false,
        flicker_frames: 0,
        sweep_points: 0,
        command: "demo showcase".into(),
        heatmap_width: Some(240),
    };
    let summary = demo::eval::run(&ctx, &opts)?;
    println!(
        "evaluated {} scenes x {} techniques: {}",
        summary.reference_checks.len(),
        opts.techniques.len(),
        eval_out.join("speed_vs_accuracy.png").display()
    );
    println!("report: {}", eval_out.join("report.md").display());
    Ok(())
}
