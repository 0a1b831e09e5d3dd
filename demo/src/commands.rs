//! The demo's commands, one function each; `main.rs` holds their arguments (clap) and
//! dispatches to them.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use demo::{Error, Result};
use voxel_core::{BlockRegistry, ChunkPos, TerrainConfig, TerrainGenerator};
use voxel_lab::{EvalOptions, chain, headless, scene};
use voxel_render::{RendererConfig, Technique};

use super::*;

/// Fails early, before any rendering, when `dir` cannot be created or written to.
pub(crate) fn writable_dir(dir: &Path) -> Result<()> {
    if let Some(file) = dir.ancestors().find(|a| a.is_file()) {
        return Err(Error::NotAFolder {
            dir: dir.to_owned(),
            file: file.to_owned(),
        });
    }
    std::fs::create_dir_all(dir).map_err(voxel_lab::Error::io(dir))?;
    let probe = dir.join(format!(".write-test-{}", std::process::id()));
    std::fs::write(&probe, b"").map_err(|error| Error::NotWritable {
        dir: dir.to_owned(),
        error,
    })?;
    let _ = std::fs::remove_file(probe);
    Ok(())
}

/// [`writable_dir`] for the folder of an output file, which must not be a folder itself.
pub(crate) fn writable_file(path: &Path) -> Result<()> {
    if path.is_dir() {
        return Err(Error::IsAFolder {
            path: path.to_owned(),
        });
    }
    match path.parent().filter(|p| !p.as_os_str().is_empty()) {
        Some(dir) => writable_dir(dir),
        None => writable_dir(Path::new(".")),
    }
}

/// Generates and meshes a world, then prints what it holds and how long it took.
pub(crate) fn stats(a: StatsArgs) -> Result<()> {
    let (seed, n) = (a.seed, a.chunks);
    let registry = Arc::new(BlockRegistry::default());
    let generator = TerrainGenerator::new(TerrainConfig {
        seed,
        ..TerrainConfig::default()
    });
    let half = n / 2;
    let t = Instant::now();
    let mut world = generator.generate_world(
        registry.clone(),
        ChunkPos::new(-half, 0, -half),
        ChunkPos::new(n - half - 1, 1, n - half - 1),
    )?;
    let gen_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let meshes = voxel_mesh::mesh_dirty(&mut world)?;
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
        "quads: {opaque} opaque, {cutout} cutout (leaves), {translucent} translucent (water, glass); {:.1} MiB of quads",
        (opaque + cutout + translucent) as f64 * 8.0 / (1 << 20) as f64
    );
    let count = |kind| sites.iter().filter(|s| s.kind == kind).count();
    println!(
        "glass structures: {} greenhouses, {} stained-glass pavilions",
        count(voxel_core::SiteKind::Greenhouse),
        count(voxel_core::SiteKind::Pavilion)
    );
    Ok(())
}

/// Renders the default scene (or a scene file) headlessly to a PNG and prints GPU times
/// per pass.
pub(crate) fn render(a: RenderArgs, device: &headless::Device) -> Result<()> {
    writable_file(&a.out)?;
    let (width, height) = a.size;
    let mut config = RendererConfig {
        width,
        height,
        msaa: a.msaa,
        ao_strength: a.ao_strength,
        flat_textures: a.flat_textures,
        quad_fetch: a.quad_fetch,
        ..RendererConfig::default()
    };
    config.oit.technique = a.technique;
    if let Some(hour) = a.hour {
        let l = voxel_render::Lighting::daytime(hour);
        (config.sun_dir, config.ambient) = (l.sun_dir, l.ambient);
        (config.brightness, config.sky) = (l.brightness, l.sky);
    }
    if let Some(w) = a.weight {
        config.oit.wboit.weight = w;
    }
    if let Some(b) = a.bayer {
        config.oit.stipple.bayer = b;
    }
    if let Some(l) = a.layers {
        config.oit.peeling.layers = l;
    }
    config
        .oit
        .validate()
        .map_err(|e| Error::from(e).in_option("--layers"))?;

    let t = Instant::now();
    let mut scene = match &a.scene {
        Some(path) => scene::Scene::load(path)?,
        None => scene::default_scene(a.seed)?,
    };
    scene.light |= a.light;
    scene.sun_shadows &= !a.no_sun_shadows;
    println!(
        "scene: {} ({} chunks{}) built in {:.0} ms",
        scene.name,
        scene.world.len(),
        match (scene.light, scene.sun_shadows) {
            (false, _) => "",
            (true, false) => ", lit",
            (true, true) => ", lit, sun shadows",
        },
        t.elapsed().as_secs_f64() * 1e3
    );
    let ctx = device.context()?;
    println!("adapter: {} ({})", ctx.caps.adapter_name, device.name());
    let mut renderer = headless::renderer_for(&ctx, &scene, config)?;
    println!(
        "quads fetched by {}; techniques this device runs: {}",
        renderer.config().quad_fetch.map_or("?", |f| f.name()),
        Technique::supported(&ctx.caps)
            .into_iter()
            .map(Technique::name)
            .collect::<Vec<_>>()
            .join(", ")
    );
    if let Some(r) = renderer.sun_region() {
        println!(
            "sun shadows over {} x {} x {} chunks from chunk ({}, {}, {})",
            r.chunks[0], r.chunks[1], r.chunks[2], r.min.x, r.min.y, r.min.z
        );
    }
    let target = headless::Offscreen::new(&ctx, width, height);
    let camera = scene.cameras[0];
    let frames = a.frames as usize;
    let mut per_pass: Vec<(voxel_render::GpuPass, Vec<f64>)> = Vec::new();
    let mut stats = None;
    let mut cpu = Vec::new();
    let mut first_sort = None;
    // The first frame warms up (pipeline and target creation); it is not timed.
    for i in 0..=frames {
        let s = renderer.render_and_submit(&target.view, &camera)?;
        if i == 0 {
            first_sort = s.technique.sort;
        } else {
            cpu.push(s.cpu_ms);
        }
        stats = Some(s);
        let times = renderer.gpu_times_blocking();
        if i > 0 {
            for (pass, ms) in times.iter() {
                match per_pass.iter_mut().find(|(p, _)| *p == pass) {
                    Some((_, v)) => v.push(ms),
                    None => per_pass.push((pass, vec![ms])),
                }
            }
        }
    }
    let image = target.read(&ctx)?;
    image.save_png(&a.out)?;
    let stats = stats.ok_or(Error::NoFrame)?;
    println!(
        "technique {}: drew {} opaque, {} cutout, {} translucent chunk meshes ({} translucent quads)",
        renderer.config().oit.technique,
        stats.meshes_drawn[0],
        stats.meshes_drawn[1],
        stats.meshes_drawn[2],
        stats.translucent_quads
    );
    let memory = renderer.chunk_memory();
    let mib = |b: u64| b as f64 / (1024.0 * 1024.0);
    println!(
        "chunk memory: {:.2} MiB of quads in {:.2} MiB of arena pages, {:.2} MiB of light",
        mib(memory.quad_bytes),
        mib(memory.arena_bytes),
        mib(memory.light_bytes)
    );
    let report = &stats.technique;
    if let Some(layers) = report.peeling.and_then(|p| p.layers) {
        println!("layers peeled: {layers}");
    }
    cpu.sort_by(f64::total_cmp);
    let cpu_median = cpu.get(cpu.len() / 2).copied().unwrap_or(0.0);
    println!("CPU ms to record a frame, median of {frames}: {cpu_median:.3}");
    if let Some(sort) = first_sort {
        println!(
            "quad sort: first frame {:.3} ms for all {} visible translucent chunks; a still camera re-sorts nothing",
            sort.ms, sort.chunks_resorted
        );
    }
    if let Some(r) = report.reference {
        println!(
            "reference: {} fragments lost, {} pixels capped ({} visibly), {}x{} tiles",
            r.lost_fragments, r.capped_pixels, r.capped_visible_pixels, r.tiles, r.tiles
        );
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
            .map(|(p, v)| format!("{p} {:.3}", median(v)))
            .collect();
        println!(
            "GPU ms per pass, median of {frames} frames at {width}x{height}: {}",
            line.join(", ")
        );
    }
    println!("wrote {}", a.out.display());
    Ok(())
}

/// The `scenes/` folder: the working directory's, else the repository's.
fn scenes_dir() -> PathBuf {
    let local = PathBuf::from("scenes");
    if local.is_dir() {
        local
    } else {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes")
    }
}

/// The scene files named on the command line (files or folders), or the `scenes/` folder.
pub(crate) fn scene_paths(given: &[PathBuf]) -> Result<Vec<PathBuf>> {
    let given: Vec<PathBuf> = if given.is_empty() {
        vec![scenes_dir()]
    } else {
        given.to_vec()
    };
    let mut out = Vec::new();
    for p in given {
        if p.is_dir() {
            out.extend(scene::scene_files(&p)?);
        } else if p.is_file() {
            out.push(p);
        } else {
            return Err(Error::NoSuchScene { path: p });
        }
    }
    Ok(out)
}

/// `all`, `none` (when allowed) or a list of names.
pub(crate) fn names<T: Copy>(
    given: &[String],
    all: &[T],
    none_ok: bool,
    parse: impl Fn(&str) -> Result<T>,
) -> Result<Vec<T>> {
    let given: Vec<&str> = given
        .iter()
        .map(|s| s.trim())
        .filter(|s| !s.is_empty())
        .collect();
    match given.as_slice() {
        [] | ["all"] => Ok(all.to_vec()),
        ["none"] if none_ok => Ok(Vec::new()),
        list => list.iter().map(|n| parse(n)).collect(),
    }
}

/// Renders every scene with every technique and the exact reference; writes the summary,
/// charts, heat maps, stability sweeps and report.
pub(crate) fn eval(a: EvalArgs, device: &headless::Device) -> Result<()> {
    writable_dir(&a.out)?;
    let random = a
        .random
        .map(|n| voxel_lab::random::RandomSet::new(n, a.seed.unwrap_or(1)))
        .transpose()?;
    let opts = EvalOptions {
        scenes: if random.is_some() {
            Vec::new()
        } else {
            scene_paths(&a.scenes)?
        },
        techniques: names(&a.techniques, &Technique::ALL, false, technique)
            .map_err(|e| e.in_option("--techniques"))?,
        weights: names(&a.weights, &WeightFunction::ALL, true, weight)
            .map_err(|e| e.in_option("--weights"))?,
        size: a.size,
        frames: a.frames as usize,
        warmup: a.warmup as usize,
        out: a.out.clone(),
        stability: !a.no_stability,
        flicker_frames: a.flicker_frames as usize,
        sweep_points: a.sweep_points as usize,
        command: std::iter::once("demo".to_owned())
            .chain(std::env::args().skip(1))
            .collect::<Vec<_>>()
            .join(" "),
        heatmap_width: a.heatmap_width,
        random,
        checks: voxel_lab::summary::Checks {
            flip: !a.no_flip,
            heatmaps: !a.no_heatmaps,
            raymarch_width: a.raymarch_width,
            time_budget: a.time_budget,
        },
    };
    // Before the GPU: a broken scene or an option past its cap is the first thing said.
    opts.validate()?;
    let ctx = device.context()?;
    eprintln!(
        "adapter: {}; {} scenes x {} techniques + {} weights",
        ctx.caps.adapter_name,
        random.map_or(opts.scenes.len(), |r| r.count),
        opts.techniques.len(),
        opts.weights.len()
    );
    let t = Instant::now();
    let summary = voxel_lab::evaluate(&ctx, &opts)?;
    println!(
        "{} records in {:.0} s; exact methods agree within {}/255; wrote {}",
        summary.records.len(),
        t.elapsed().as_secs_f64(),
        summary.worst_reference_disagreement(),
        a.out.join("report.md").display()
    );
    Ok(())
}

/// Flies over streamed terrain and writes what it measured.
pub(crate) fn stream(a: StreamArgs, device: &headless::Device) -> Result<()> {
    let opts = voxel_lab::stream::StreamOptions {
        view_distance: a.view_distance,
        vertical_distance: a.vertical_distance,
        frames: a.frames as usize,
        speed: a.speed,
        draw: a.draw,
        size: a.size,
        seed: a.seed,
        teleport_at: a.teleport_at,
        light: a.light,
        out: a.out.clone(),
    };
    opts.validate()?;
    writable_dir(&a.out)?;
    let ctx = device.context()?;
    eprintln!(
        "adapter: {}; view distance {}, {} frames at {} blocks per frame, {} draws",
        ctx.caps.adapter_name,
        a.view_distance,
        a.frames,
        a.speed,
        a.draw.name()
    );
    let r = voxel_lab::stream::run(&ctx, &opts)?;
    let mib = |b: u64| b as f64 / f64::from(1 << 20);
    println!(
        "loaded {} chunks ({} on the GPU) in {:.0} ms; per frame CPU p50 {:.3} ms, p95 {:.3}, max {:.3} \
         (record p50 {:.3}, stream p50 {:.3}); GPU p50 {}; {} hitches",
        r.chunks_resident,
        r.chunks_on_gpu,
        r.prefill_ms,
        r.cpu_frame_ms.p50,
        r.cpu_frame_ms.p95,
        r.cpu_frame_ms.max,
        r.record_ms.p50,
        r.stream_ms.p50,
        r.gpu_frame_ms_p50
            .map_or("n/a".to_owned(), |g| format!("{g:.2} ms")),
        r.hitches
    );
    println!(
        "memory: GPU {:.1} MiB ({} quads), blocks {:.1} MiB ({:.2}x a packed-index palette), \
         light {:.1} MiB; {:.2} meshes per chunk; wrote {}",
        mib(r.gpu_buffer_bytes),
        r.quads,
        mib(r.chunk_storage_bytes),
        r.chunk_storage_bytes as f64 / r.packed_index_bytes.max(1) as f64,
        mib(r.light_bytes),
        r.meshes_per_chunk,
        a.out.join("stream.json").display()
    );
    if let Some(t) = r.teleport {
        println!(
            "teleport at frame {}: reloaded in {} frames; longest frame after it {:.3} ms (streamer {:.3} ms), at most {} unloads per frame",
            t.frame,
            t.frames_to_reload
                .map_or("more than the remaining".to_owned(), |n| n.to_string()),
            t.max_cpu_ms,
            t.max_stream_ms,
            t.max_unloads
        );
    }
    Ok(())
}

/// The default terrain to a far view distance in levels of detail (`voxel_lab::far`).
pub(crate) fn far(a: FarArgs, device: &headless::Device) -> Result<()> {
    let opts = voxel_lab::far::FarOptions {
        full_detail: a.full_detail,
        view_distance: a.view_distance,
        size: a.size,
        seed: a.seed,
        techniques: names(&a.techniques, &Technique::ALL, false, technique)
            .map_err(|e| e.in_option("--techniques"))?,
        compare: a.compare,
        fly_frames: a.fly_frames,
        out: a.out.clone(),
    };
    opts.validate()?;
    writable_dir(&a.out)?;
    let ctx = device.context()?;
    eprintln!("adapter: {}", ctx.caps.adapter_name);
    let r = voxel_lab::far::run(&ctx, &opts)?;
    let mib = |b: u64| b as f64 / f64::from(1 << 20);
    println!(
        "view distance {} chunks (full detail to {}, levels to {}): the horizon (coarsest level) \
         drawn after {:.0} ms, the finished view after {:.0} ms ({} views, coarse first); GPU \
         {:.1} MiB of buffers ({:.1} MiB of quads)",
        r.view_distance,
        r.full_detail,
        r.coarsest,
        r.horizon_ms,
        r.built_ms,
        r.views,
        mib(r.gpu_buffer_bytes),
        mib(r.gpu_quad_bytes)
    );
    if r.flight_frames > 0 {
        println!(
            "flight of {} frames at {} blocks/s: update p50 {:.3} ms, p95 {:.3}, max {:.3} on the frame's thread; {} views swapped in, at most {} chunks missing",
            r.flight_frames,
            voxel_lab::far::FLIGHT_SPEED,
            r.flight_update_ms.p50,
            r.flight_update_ms.p95,
            r.flight_update_ms.max,
            r.flight_swaps,
            r.flight_most_missing
        );
    }
    println!(
        "| level | cell (blocks) | chunks from..to | chunks (drawn) | quads opaque / cutout / translucent | MiB | KiB per chunk of distance |"
    );
    println!("|---|---|---|---|---|---|---|");
    for l in &r.levels {
        println!(
            "| {} | {} | {}..{} | {} ({}) | {} / {} / {} | {:.1} | {:.1} |",
            l.level,
            l.cell_blocks,
            l.from_chunks,
            l.to_chunks,
            l.chunks,
            l.chunks_drawn,
            l.quads[0],
            l.quads[1],
            l.quads[2],
            mib(l.bytes),
            l.bytes_per_chunk_of_distance / 1024.0
        );
    }
    if let Some(c) = &r.compare {
        println!(
            "against full detail: holes {:.4} % of pixels, skyline differs on {:.4} %; far pixels \
             {:.1} %, far water {:.2} % (levels {:.2} %); far water mean step {:.2}/255, far \
             ground {:.2}/255; far mean |error| {:.2}/255",
            c.holes * 100.0,
            c.skyline * 100.0,
            c.far_pixels * 100.0,
            c.far_water_pixels * 100.0,
            c.far_water_pixels_levels * 100.0,
            c.water_step(),
            c.ground_step(),
            c.far_mean_abs
        );
    }
    println!("wrote {}", a.out.join("far.json").display());
    Ok(())
}

/// Renders one scene with every technique and writes the pictures, error maps and sheet.
pub(crate) fn gallery(a: GalleryArgs, device: &headless::Device) -> Result<()> {
    writable_dir(&a.out)?;
    let scene = scene::Scene::load(&a.scene)?;
    let ctx = device.context()?;
    println!("adapter: {}; scene: {}", ctx.caps.adapter_name, scene.name);
    let entries = voxel_lab::gallery::render(&ctx, &scene, a.size)?;
    voxel_lab::gallery::write(&a.out, &entries, a.columns)?;
    for e in &entries {
        println!(
            "{:<16} FLIP {:.4}  max error {}/255",
            e.technique.name(),
            e.metrics.flip_mean,
            e.metrics.max_abs_err
        );
    }
    println!("wrote {}", a.out.join("gallery.png").display());
    Ok(())
}

/// The backend × technique table.
pub(crate) fn backends(a: BackendsArgs) -> Result<()> {
    writable_dir(&a.out)?;
    let opts = voxel_lab::backends::Options {
        size: a.size,
        frames: a.frames,
        out: a.out,
    };
    voxel_lab::backends::run(&opts)?;
    println!("wrote {}", opts.out.join("report.md").display());
    Ok(())
}

/// Opens the interactive demo.
pub(crate) fn window(a: WindowArgs, device: DeviceArgs) -> Result<()> {
    demo::app::run(demo::app::DemoOptions {
        backends: device.backend,
        limits: device.limits,
        seed: a.seed,
        size: a.size,
        technique: a.technique,
        view_distance: a.view_distance,
        frames: a.frames,
        screenshot: a.screenshot,
        cycle: a.cycle,
        heatmap: a.heatmap,
        level_bands: a.level_bands,
        edit: a.edit,
        resize: a.resize,
        // Read before the window opens: a broken file is an error, not an empty window.
        scene: a.scene.as_deref().map(scene::Scene::load).transpose()?,
        game: a.game,
        light: a.light,
    })
}

/// Without a display: every technique's picture of the default scene, then the
/// speed/accuracy chart of [`QUICK_SCENES`] at [`QUICK_SIZE`] (with `full`, of the whole
/// suite at 480x270), each with a progress bar.
pub(crate) fn showcase(a: ShowcaseArgs, device: &headless::Device) -> Result<()> {
    writable_dir(&a.out)?;
    let suite = scene_paths(&[])?;
    let suite_len = suite.len();
    let scenes = if a.full {
        suite
    } else {
        QUICK_SCENES
            .iter()
            .map(|name| {
                suite
                    .iter()
                    .find(|p| p.file_stem().is_some_and(|s| s == *name))
                    .cloned()
                    .ok_or_else(|| Error::NoSuchScene {
                        path: PathBuf::from("scenes").join(format!("{name}.toml")),
                    })
            })
            .collect::<Result<Vec<_>>>()?
    };
    let start = Instant::now();
    let (w, h) = a.size;
    let ctx = device.context()?;
    println!("adapter: {}", ctx.caps.adapter_name);
    let scene = scene::default_scene(1)?;
    let config = RendererConfig {
        width: w,
        height: h,
        ..RendererConfig::default()
    };
    let mut renderer = headless::renderer_for(&ctx, &scene, config.clone())?;
    let target = headless::Offscreen::new(&ctx, w, h);
    println!(
        "every technique's picture of the default scene ({w}x{h}) into {}:",
        a.out.display()
    );
    let mut progress = voxel_lab::progress::Progress::new(Technique::ALL.len());
    let mut wrote = Vec::new();
    for t in Technique::ALL {
        if let Err(e) = renderer.set_technique(t) {
            progress.step(&format!("{t}: skipped"));
            wrote.push(format!("skipped {t}: {}", chain(&e)));
            continue;
        }
        // One frame to settle (adaptive peeling), one to keep.
        renderer.render_and_submit(&target.view, &scene.cameras[0])?;
        let img = headless::render_image(&ctx, &mut renderer, &target, &scene.cameras[0])?;
        let path = a.out.join(format!("{}.png", t.name()));
        img.save_png(&path)?;
        progress.step(t.name());
        wrote.push(format!("wrote {}", path.display()));
    }
    progress.finish();
    for line in wrote {
        println!("{line}");
    }
    // Light through stained glass (docs/light.md): the cathedral window scene, lit.
    let lit = scene::Scene::load(&scenes_dir().join("light/cathedral.toml"))?;
    let mut lit_renderer = headless::renderer_for(&ctx, &lit, config)?;
    let img = headless::render_image(&ctx, &mut lit_renderer, &target, &lit.cameras[0])?;
    let path = a.out.join("light.png");
    img.save_png(&path)?;
    println!("wrote {} ({}, lit)", path.display(), lit.name);
    let eval_out = a.out.join("eval");
    let size = if a.full { (480, 270) } else { QUICK_SIZE };
    println!(
        "the speed/accuracy chart: {} scenes x {} techniques at {}x{} against the exact reference:",
        scenes.len(),
        Technique::ALL.len(),
        size.0,
        size.1
    );
    let opts = EvalOptions {
        scenes,
        techniques: Technique::ALL.to_vec(),
        weights: Vec::new(),
        size: Some(size),
        frames: 3,
        warmup: 1,
        out: eval_out.clone(),
        stability: false,
        flicker_frames: 0,
        sweep_points: 0,
        command: if a.full {
            "demo showcase --full".into()
        } else {
            "demo showcase".into()
        },
        heatmap_width: Some(240),
        random: None,
        checks: Default::default(),
    };
    let summary = voxel_lab::evaluate(&ctx, &opts)?;
    println!(
        "evaluated {} scenes x {} techniques: {}",
        summary.reference_checks.len(),
        opts.techniques.len(),
        eval_out.join("speed_vs_accuracy.png").display()
    );
    println!("report: {}", eval_out.join("report.md").display());
    println!("took {:.0} s", start.elapsed().as_secs_f64());
    if !a.full {
        println!(
            "the whole suite ({suite_len} scenes at 480x270, many minutes): bash scripts/run.sh showcase --full (or demo eval, docs/lab.md)"
        );
    }
    Ok(())
}
