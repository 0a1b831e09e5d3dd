//! Runs of the lab: every scene of a suite rendered with every technique and with both
//! exact methods; error and cost per picture, as [`Record`]s.

use crate::{Error, Result};

use std::path::Path;

use voxel_render::low_level::{self, FrameCost};
use voxel_render::{
    Camera, FrameStats, GpuContext, GpuTimes, Image, OitConfig, RendererConfig, Technique,
    WeightFunction,
};

use crate::edges::{self, Edges};
use crate::headless::{Offscreen, SceneRenderer, renderer_for};
use crate::metrics::{self, Metrics, thumbnail};
use crate::progress::Progress;
use crate::raymarch;
use crate::scene::Scene;
use crate::summary::{
    Checks, CostRecord, EvalOptions, RayMarchSummary, Record, ReferenceCheck, SceneFeatures,
    Summary,
};

/// A renderer for measurements, sized `size`.
pub fn make_renderer(ctx: &GpuContext, scene: &Scene, size: (u32, u32)) -> Result<SceneRenderer> {
    let config = RendererConfig {
        width: size.0,
        height: size.1,
        ..RendererConfig::default()
    };
    renderer_for(ctx, scene, config)
}

/// What [`measure`] returns: the last picture, its HDR non-finite count, the frame stats.
#[derive(Debug)]
pub struct Measured {
    /// The last frame.
    pub image: Image,
    /// Median GPU ms of the translucent work (the technique's passes and composites).
    pub gpu_ms: Option<f64>,
    /// Median CPU ms per frame.
    pub cpu_ms: f64,
    /// Median CPU ms per frame ordering the game's objects (`FrameStats::game_sort_ms`).
    pub game_sort_ms: f64,
    /// Non-finite HDR pixels of the last frame.
    pub nan_px: usize,
    /// Stats of the last frame.
    pub stats: FrameStats,
    /// What the technique's frame asked of the GPU, counted in one more frame after the
    /// timed ones (`None` when the frame could not be counted).
    pub cost: Option<FrameCost>,
}

fn median(mut v: Vec<f64>) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    Some(v[v.len() / 2])
}

/// Renders `warmup + frames` frames of `camera` with `config` and returns the last picture
/// with the median timings.
pub fn measure(
    ctx: &GpuContext,
    renderer: &mut SceneRenderer,
    target: &Offscreen,
    camera: &Camera,
    config: &OitConfig,
    warmup: usize,
    frames: usize,
) -> Result<Measured> {
    renderer.set_oit_config(config.clone())?;
    let mut gpu = Vec::new();
    let mut cpu = Vec::new();
    let mut sort = Vec::new();
    for i in 0..warmup + frames.max(1) {
        let stats = renderer.render_and_submit(&target.view, camera)?;
        let times = renderer.gpu_times_blocking();
        if i >= warmup {
            cpu.push(stats.cpu_ms);
            sort.push(stats.game_sort_ms);
            if !times.is_empty() {
                gpu.push(times.translucent_work());
            }
        }
    }
    finish(ctx, renderer, target, camera, gpu, cpu, sort)
}

/// Rounds the timed frames of [`measure_runs`] are spread over (at most).
const ROUNDS: usize = 3;

/// Wall-clock time the warm-up of [`measure_runs`] lasts at least: a GPU that idled while
/// the CPU worked (building the renderer, the last scene's checks) raises its clocks over
/// some tens of milliseconds of work.
const WARM_UP: std::time::Duration = std::time::Duration::from_millis(250);

/// Warm-up rounds of [`measure_runs`] at most.
const MAX_WARM_UP_ROUNDS: usize = 64;

/// Measures every configuration of `configs` on one scene, as [`measure`] does each, with
/// the real-time ones timed in turns: all of them built first; `warmup` rounds of one
/// frame each (and more until `WARM_UP` has passed, so that the GPU's clocks have risen);
/// then the timed frames in up to `ROUNDS` rounds, each run's block of them after one
/// untimed frame that settles its switch (sorted-quads sorts again after `sorted` drew the
/// mesher's order). Whatever the GPU's state does over the scene (clocks, memory freed
/// before) then weighs on every technique alike. Each run's picture and counted frame
/// follow its last block. The exact techniques (which wait for the GPU inside a frame)
/// are measured alone afterwards.
pub fn measure_runs(
    ctx: &GpuContext,
    renderer: &mut SceneRenderer,
    target: &Offscreen,
    camera: &Camera,
    configs: &[OitConfig],
    warmup: usize,
    frames: usize,
) -> Result<Vec<Measured>> {
    let real: Vec<usize> = (0..configs.len())
        .filter(|&i| !configs[i].technique.stalls())
        .collect();
    let mut out: Vec<Option<Measured>> = (0..configs.len()).map(|_| None).collect();
    for &i in &real {
        renderer.prebuild_technique(configs[i].technique)?;
    }
    let frame = |renderer: &mut SceneRenderer, i: usize| -> Result<(FrameStats, GpuTimes)> {
        renderer.set_oit_config(configs[i].clone())?;
        let stats = renderer.render_and_submit(&target.view, camera)?;
        Ok((stats, renderer.gpu_times_blocking()))
    };
    let start = std::time::Instant::now();
    let mut round = 0;
    while !real.is_empty()
        && (round < warmup || (start.elapsed() < WARM_UP && round < MAX_WARM_UP_ROUNDS))
    {
        for &i in &real {
            frame(renderer, i)?;
        }
        round += 1;
    }
    let frames = frames.max(1);
    let rounds = frames.min(ROUNDS);
    let mut timed: Vec<(Vec<f64>, Vec<f64>, Vec<f64>)> = vec![Default::default(); configs.len()];
    for r in 0..rounds {
        let block = frames / rounds + usize::from(r < frames % rounds);
        for &i in &real {
            // The switch settles.
            frame(renderer, i)?;
            for _ in 0..block {
                let (stats, times) = frame(renderer, i)?;
                let (g, c, s) = &mut timed[i];
                if !times.is_empty() {
                    g.push(times.translucent_work());
                }
                c.push(stats.cpu_ms);
                s.push(stats.game_sort_ms);
            }
            if r + 1 == rounds {
                let (g, c, s) = std::mem::take(&mut timed[i]);
                out[i] = Some(finish(ctx, renderer, target, camera, g, c, s)?);
            }
        }
    }
    for &i in &real {
        renderer.release_technique(configs[i].technique);
    }
    for (i, config) in configs.iter().enumerate() {
        if out[i].is_none() {
            out[i] = Some(measure(
                ctx, renderer, target, camera, config, warmup, frames,
            )?);
        }
    }
    Ok(out.into_iter().flatten().collect())
}

/// A counted frame of the technique in force, its picture and HDR colour, with the
/// timings gathered before.
fn finish(
    ctx: &GpuContext,
    renderer: &mut SceneRenderer,
    target: &Offscreen,
    camera: &Camera,
    gpu: Vec<f64>,
    cpu: Vec<f64>,
    sort: Vec<f64>,
) -> Result<Measured> {
    // Counted in a frame of its own: its queries stay out of the timed frames. The picture
    // is the same (a still camera).
    low_level::count_next_frame(renderer);
    let stats = renderer.render_and_submit(&target.view, camera)?;
    let cost = low_level::frame_cost(renderer)?;
    let image = target.read(ctx)?;
    let hdr = read_hdr(ctx, renderer.scene_color())?;
    Ok(Measured {
        image,
        gpu_ms: median(gpu),
        cpu_ms: median(cpu).unwrap_or(0.0),
        game_sort_ms: median(sort).unwrap_or(0.0),
        nan_px: metrics::non_finite_pixels(&hdr),
        stats,
        cost,
    })
}

/// The HDR scene colour as f32 RGBA.
pub fn read_hdr(ctx: &GpuContext, texture: &wgpu::Texture) -> Result<Vec<[f32; 4]>> {
    let bytes = voxel_render::readback::read_texture(ctx, texture, 8)?;
    Ok(bytes
        .chunks_exact(8)
        .map(|p| {
            let h =
                |i: usize| voxel_render::readback::f16_to_f32(u16::from_le_bytes([p[i], p[i + 1]]));
            [h(0), h(2), h(4), h(6)]
        })
        .collect())
}

/// The default WBOIT weight.
pub fn default_weight() -> WeightFunction {
    voxel_render::WboitSettings::default().weight
}

/// The default configuration drawing with `technique` and WBOIT weight `weight`.
pub fn oit_config(technique: Technique, weight: WeightFunction) -> OitConfig {
    let mut c = OitConfig::with(technique);
    c.wboit.weight = weight;
    c
}

/// Both exact methods on one scene: the reference picture, and whether it is exact.
#[derive(Debug)]
pub struct Reference {
    /// The A-buffer's picture.
    pub image: Image,
    /// The check of the two methods against each other.
    pub check: ReferenceCheck,
}

/// Renders `camera` of `renderer`'s scene with both exact methods and checks them against
/// each other and against the CPU ray march of `world` (at the size `checks` asks for;
/// none when it asks for none).
pub fn reference(
    ctx: &GpuContext,
    renderer: &mut SceneRenderer,
    target: &Offscreen,
    camera: &Camera,
    scene: &Scene,
    name: &str,
    checks: &Checks,
) -> Result<(Reference, Option<RayMarchCheck>)> {
    let weight = default_weight();
    let abuffer = measure(
        ctx,
        renderer,
        target,
        camera,
        &oit_config(Technique::Reference, weight),
        0,
        1,
    )?;
    let peel = measure(
        ctx,
        renderer,
        target,
        camera,
        &oit_config(Technique::PeelReference, weight),
        0,
        1,
    )?;
    let agreement = metrics::compare_without_flip(&abuffer.image, &peel.image).max_abs_err;
    let r = abuffer.stats.technique.reference.unwrap_or_default();
    let peeled = peel.stats.technique.peeling.unwrap_or_default();
    let size = match checks.raymarch_width {
        None => Some(renderer.size()),
        Some(0) => None,
        Some(w) => {
            let (fw, fh) = renderer.size();
            // The run's aspect at `w` pixels wide (never wider than the run).
            let w = w.min(fw);
            Some((
                w,
                (u64::from(fh) * u64::from(w) / u64::from(fw)).max(1) as u32,
            ))
        }
    };
    let (raymarch, unsettled, ray) = match size {
        // No ray march: the two GPU methods, which share the mesh and the rasteriser,
        // vouch for each other alone. Nothing sides with either picture: every pixel they
        // differ at past the agreement is unsettled (the peeled picture stands in for the
        // ray march), so the reference is exact where they agree within `GPU_AGREEMENT`.
        None => (
            RayMarchSummary::default(),
            unsettled_pixels(&abuffer.image, &peel.image, &peel.image, &abuffer.image),
            None,
        ),
        Some(size) => {
            let ray = raymarch_check(ctx, scene, camera, size)?;
            let c = &ray.comparison;
            let raymarch = RayMarchSummary {
                differing: c.differing,
                max_abs_err_off_edges: c.max_abs_err_off_edges,
                differing_on_edges: c.differing_on_edges,
                translucent_seams: c.translucent_seams,
                cracks: c.cracks,
                worst: c
                    .worst
                    .iter()
                    .map(|p| {
                        format!(
                            "pixel ({}, {}): ray march {:?}, A-buffer {:?} ({}/255), {}",
                            p.x, p.y, p.ray, p.gpu, p.diff, p.surface
                        )
                    })
                    .collect(),
                seconds: ray.seconds,
            };
            let unsettled = unsettled_pixels(&abuffer.image, &peel.image, &ray.ray.image, &ray.gpu);
            (raymarch, unsettled, Some(ray))
        }
    };
    let agrees = raymarch.differing == 0 && raymarch.cracks == 0 && unsettled == 0;
    Ok((
        Reference {
            image: abuffer.image,
            check: ReferenceCheck {
                scene: name.to_owned(),
                max_abs_err: agreement,
                unsettled,
                exact: agrees && r.exact(),
                raymarch,
                lost_fragments: r.lost_fragments,
                capped_pixels: r.capped_pixels,
                capped_visible_pixels: r.capped_visible_pixels,
                depth_complexity: peeled.layers.unwrap_or(0),
            },
        },
        ray,
    ))
}

/// The most the two GPU methods (the A-buffer and peel-to-convergence) may differ at a
/// pixel, in 1/255, before the ray march must decide which is right there: the same
/// fragments blended in another order round differently by a step or two.
pub const GPU_AGREEMENT: u8 = 2;

/// The pixels nobody settles: where the A-buffer's picture (`abuffer`) and
/// peel-to-convergence's (`peeled`) differ by more than [`GPU_AGREEMENT`] in some channel,
/// and the ray march (`ray`) does not side with the A-buffer there (its flat-texture picture
/// `abuffer_flat` within 1/255 of the ray march's). Where the ray march agrees with the
/// A-buffer it decides for it (peeling keeps one of two fragments at exactly equal depth);
/// where it cannot (an edge or a seam passes within reach of the pixel's centre, where the
/// rasteriser decides) nothing says which picture is right. A ray march smaller than the
/// pictures (`--raymarch-width`) settles each pixel by the pixel of its own picture that
/// covers it; pictures of other sizes (the two GPU ones apart, or the two of the ray march's
/// check apart) leave every pixel unsettled.
pub fn unsettled_pixels(
    abuffer: &Image,
    peeled: &Image,
    ray: &Image,
    abuffer_flat: &Image,
) -> usize {
    let pixels = abuffer.rgba.len() / 4;
    let same = |a: &Image, b: &Image| {
        (a.width, a.height) == (b.width, b.height) && a.rgba.len() == b.rgba.len()
    };
    let (w, h) = (abuffer.width as usize, abuffer.height as usize);
    if !same(abuffer, peeled) || !same(ray, abuffer_flat) || w * h != pixels || ray.width == 0 {
        return pixels;
    }
    let (rw, rh) = (ray.width as usize, ray.height as usize);
    if rw * rh != ray.rgba.len() / 4 {
        return pixels;
    }
    let differ = |a: &Image, i: usize, b: &Image, j: usize| {
        (0..3)
            .map(|c| a.rgba[i * 4 + c].abs_diff(b.rgba[j * 4 + c]))
            .max()
            .unwrap_or(0)
    };
    // The ray march's pixel over pixel `i` of the pictures.
    let covering = |i: usize| {
        let (x, y) = (i % w, i / w);
        (y * rh / h).min(rh - 1) * rw + (x * rw / w).min(rw - 1)
    };
    (0..pixels)
        .filter(|&i| {
            differ(abuffer, i, peeled, i) > GPU_AGREEMENT && {
                let j = covering(i);
                differ(ray, j, abuffer_flat, j) > 1
            }
        })
        .count()
}

/// The A-buffer reference against the CPU ray march, both in flat-texture mode (each block
/// one colour, which both draw the same): the comparison, the ray-marched picture and the
/// A-buffer's.
#[derive(Debug)]
pub struct RayMarchCheck {
    /// Where they differ off geometric edges, and the cracks.
    pub comparison: raymarch::Comparison,
    /// The ray march's picture.
    pub ray: raymarch::RayMarched,
    /// The A-buffer's picture (flat textures).
    pub gpu: Image,
    /// Seconds the ray march took.
    pub seconds: f64,
}

/// Renders `camera` of `scene` at `size` with the A-buffer reference and flat textures,
/// ray-marches the same picture on the CPU, and compares them (see [`raymarch`]).
pub fn raymarch_check(
    ctx: &GpuContext,
    scene: &Scene,
    camera: &Camera,
    size: (u32, u32),
) -> Result<RayMarchCheck> {
    let config = RendererConfig {
        width: size.0,
        height: size.1,
        flat_textures: true,
        oit: oit_config(Technique::Reference, default_weight()),
        ..RendererConfig::default()
    };
    let shading = raymarch::Shading::of(&config);
    let mut renderer = renderer_for(ctx, scene, config)?;
    let target = Offscreen::new(ctx, size.0, size.1);
    renderer.render_and_submit(&target.view, camera)?;
    let gpu = target.read(ctx)?;
    // Copied on Vulkan, through a pass on GL (which copies no depth texture to a buffer).
    let depth = voxel_render::readback::read_depth(ctx, renderer.scene_depth())?;
    let drawn = renderer.drawn_camera(camera);
    let start = std::time::Instant::now();
    let mut marcher = raymarch::RayMarcher::with_content(&scene.world, &scene.content);
    if scene.light {
        let field = voxel_core::LightField::new(&scene.world);
        marcher = marcher.with_light(std::sync::Arc::new(field));
    }
    if crate::headless::sun_region(scene).is_some() {
        marcher = marcher.with_sun_shadows(scene.world.registry());
    }
    let ray = marcher.render(&drawn, size.0, size.1, &shading);
    let seconds = start.elapsed().as_secs_f64();
    let comparison = marcher.compare(&ray, &drawn, &shading, &gpu, Some(&depth));
    Ok(RayMarchCheck {
        comparison,
        ray,
        gpu,
        seconds,
    })
}

/// The runs of one scene: each technique at the default weight, then `wboit-mrt` with each
/// of `weights`.
fn runs(opts: &EvalOptions) -> Vec<(String, OitConfig)> {
    let default = default_weight();
    let mut runs: Vec<(String, OitConfig)> = opts
        .techniques
        .iter()
        .map(|t| (t.name().to_owned(), oit_config(*t, default)))
        .collect();
    for w in &opts.weights {
        runs.push((
            format!("wboit-mrt/{}", w.name()),
            oit_config(Technique::WboitMrt, *w),
        ));
    }
    runs
}

/// Checked here, above [`crate::scene`], since it reads the scene files.
impl EvalOptions {
    /// Checks what the run asks for against the documented caps ([`crate::limits`]) and
    /// reads every scene file (parsing it and checking the size it asks for), so that
    /// nothing is rendered or written when any of it is wrong. The error names the option
    /// or the file.
    pub fn validate(&self) -> Result<()> {
        use crate::limits::{self, check_range};
        if let Some(size) = self.size {
            limits::check_size("--size", size)?;
        }
        check_range("--frames", self.frames as u64, 1, limits::MAX_FRAMES.into())?;
        check_range("--warmup", self.warmup as u64, 0, limits::MAX_WARMUP.into())?;
        if let Some(w) = self.heatmap_width {
            check_range(
                "--heatmap-width",
                w.into(),
                limits::MIN_HEATMAP_WIDTH.into(),
                limits::MAX_SIDE.into(),
            )?;
        }
        if self.stability {
            check_range(
                "--flicker-frames",
                self.flicker_frames as u64,
                2,
                limits::MAX_FLICKER_FRAMES.into(),
            )?;
            check_range(
                "--sweep-points",
                self.sweep_points as u64,
                limits::MIN_SWEEP_POINTS.into(),
                limits::MAX_SWEEP_POINTS.into(),
            )?;
        }
        if self.random.is_none() {
            if self.scenes.is_empty() {
                return Err(Error::NoScenes { dir: None });
            }
            for path in &self.scenes {
                // Parsing checks a scene's own size against the same caps.
                Scene::load(path)?;
            }
        }
        Ok(())
    }
}

/// Output size when neither the command nor the scene gives one.
pub const DEFAULT_SIZE: (u32, u32) = (640, 360);

/// The progress steps [`scene_records`] makes for a scene of `runs` runs: the runs
/// measured, the exact references, then one per run compared.
fn scene_steps(runs: usize) -> usize {
    runs + 2
}

/// Measures every run of `opts` on `scene` (named `stem`) against its reference; with
/// `heatmaps`, saves the reference picture and one heat map per run under
/// `out/heatmaps/`.
fn scene_records(
    ctx: &GpuContext,
    opts: &EvalOptions,
    stem: &str,
    scene: &Scene,
    heatmaps: bool,
    progress: &mut Progress,
) -> Result<(Vec<Record>, ReferenceCheck)> {
    let stem = stem.to_owned();
    let size = opts.size.or(scene.size).unwrap_or(DEFAULT_SIZE);
    let mut renderer = make_renderer(ctx, scene, size)?;
    let target = Offscreen::new(ctx, size.0, size.1);
    let camera = scene.cameras[0];
    let dir = opts.out.join("heatmaps");

    // The techniques first, before the exact references fill the GPU's memory (the
    // A-buffer of a deep stack at 1080p takes gigabytes) and the ray march leaves it idle.
    let runs = runs(opts);
    progress.step(&format!("{stem}: {} runs in rounds", runs.len()));
    let configs: Vec<OitConfig> = runs.iter().map(|(_, c)| c.clone()).collect();
    let measured = measure_runs(
        ctx,
        &mut renderer,
        &target,
        &camera,
        &configs,
        opts.warmup,
        opts.frames,
    )?;

    progress.step(&format!("{stem}: exact references and the ray march"));
    let checks = &opts.checks;
    let heatmaps = heatmaps && checks.heatmaps && checks.flip;
    let (reference, ray) = reference(ctx, &mut renderer, &target, &camera, scene, &stem, checks)?;
    if heatmaps {
        let mut pictures = vec![(&reference.image, "reference")];
        if let Some(ray) = &ray {
            pictures.push((&ray.ray.image, "raymarch_flat"));
            pictures.push((&ray.gpu, "reference_flat"));
        }
        for (image, what) in pictures {
            save(
                &thumbnail(image, opts.heatmap_width),
                &dir.join(format!("{stem}__{what}.png")),
            )?;
        }
    }

    let mut records = Vec::new();
    let mut quad_edges = None;
    let mut overlaps = None;
    for ((name, config), m) in runs.into_iter().zip(measured) {
        progress.step(&format!("{stem}: {name}"));
        let (metrics, heat) = if checks.flip {
            let (m, heat) = metrics::compare(&reference.image, &m.image);
            (m, Some(heat))
        } else {
            (
                metrics::compare_without_flip(&reference.image, &m.image),
                None,
            )
        };
        let heatmap = match heat.filter(|_| heatmaps) {
            Some(heat) => {
                let file = format!("{stem}__{}.png", name.replace('/', "_"));
                save(&thumbnail(&heat, opts.heatmap_width), &dir.join(&file))?;
                format!("heatmaps/{file}")
            }
            None => String::new(),
        };
        let Metrics {
            rmse,
            psnr,
            flip_mean,
            max_abs_err,
            frac_bad_px,
        } = metrics;
        let report = &m.stats.technique;
        // An exact order's error off the quad edges (sub-pixel snapping decides the rest),
        // seen from where the renderer drew (an eye on a face plane is moved off it).
        let off_edges = report.sort.map(|_| {
            let drawn = renderer.drawn_camera(&camera);
            let e = quad_edges.get_or_insert_with(|| Edges::new(&scene.world, &drawn, size));
            let o = overlaps
                .get_or_insert_with(|| crate::overlaps::object_mask(&scene.content, &drawn, size));
            edges::error_off_edges(e, o, &reference.image, &m.image)
        });
        records.push(Record {
            scene: stem.clone(),
            technique: name,
            weight: report.wboit.as_ref().map(|w| w.weight.name().to_owned()),
            width: size.0,
            height: size.1,
            gpu_ms: m.gpu_ms,
            cpu_ms: m.cpu_ms,
            game_sort_ms: (config.technique.sorts() && !scene.content.is_empty())
                .then_some(m.game_sort_ms),
            rmse,
            psnr,
            flip_mean,
            max_abs_err,
            frac_bad_px,
            nan_px: m.nan_px,
            layers: report.peeling.and_then(|p| p.layers),
            lost_fragments: report.reference.map(|r| r.lost_fragments),
            capped_pixels: report.reference.map(|r| r.capped_pixels),
            reference_exact: reference.check.exact,
            sort_cycles: report.sort.map(|s| s.cycles),
            quads_in_cycles: report.sort.map(|s| s.quads_in_cycles),
            max_abs_err_off_edges: off_edges.map(|e| e.max),
            edge_px: off_edges.map(|e| e.on_edges),
            overlap_px: off_edges.map(|e| e.on_overlaps),
            near_px: off_edges.map(|e| e.on_near),
            heatmap,
            cost: m.cost.as_ref().map(CostRecord::of),
        });
    }
    Ok((records, reference.check))
}

fn save(image: &Image, path: &Path) -> Result<()> {
    image.save_png(path).map_err(Error::Render)
}

/// Measures every scene of `opts` with every technique against its reference.
pub fn run_suite(ctx: &GpuContext, opts: &EvalOptions) -> Result<Summary> {
    let dir = if opts.random.is_some() {
        opts.out.clone()
    } else {
        opts.out.join("heatmaps")
    };
    std::fs::create_dir_all(&dir).map_err(Error::io(&dir))?;
    let count = opts.random.map_or(opts.scenes.len(), |r| r.count);
    let mut progress = Progress::new(count * scene_steps(runs(opts).len()));
    let mut records = Vec::new();
    let mut checks = Vec::new();
    let mut features = Vec::new();
    let mut skipped = Vec::new();
    let start = std::time::Instant::now();
    for i in 0..count {
        if opts
            .checks
            .time_budget
            .is_some_and(|b| start.elapsed().as_secs_f64() > b)
        {
            skipped.extend((i..count).map(|j| match opts.random {
                Some(set) => set.scene(j, opts.size.unwrap_or(DEFAULT_SIZE)).name,
                None => opts.scenes[j].display().to_string(),
            }));
            log::warn!(
                "time budget spent after {i} of {count} scenes: {} left out",
                count - i
            );
            break;
        }
        let (r, check) = match opts.random {
            Some(set) => {
                // Parsed from its text like a scene file, so that the text replays it.
                let generated = set.scene(i, opts.size.unwrap_or(DEFAULT_SIZE));
                let scene =
                    crate::scene::parse(&generated.text).map_err(|e| e.in_file(&generated.name))?;
                features.push(SceneFeatures {
                    scene: generated.name.clone(),
                    features: generated.features,
                });
                scene_records(ctx, opts, &generated.name, &scene, false, &mut progress)?
            }
            None => {
                let path = &opts.scenes[i];
                let stem = path
                    .file_stem()
                    .map_or("scene".into(), |s| s.to_string_lossy().into_owned());
                let scene = Scene::load(path)?;
                scene_records(ctx, opts, &stem, &scene, true, &mut progress)?
            }
        };
        if !check.exact {
            log::warn!(
                "{}: the A-buffer differs from the ray march on {} pixels off edges with {} cracks, the GPU methods differ where the ray march does not settle it on {} pixels (or capped pixels): its errors are not scored",
                check.scene,
                check.raymarch.differing,
                check.raymarch.cracks,
                check.unsettled
            );
        }
        records.extend(r);
        checks.push(check);
    }
    progress.finish();
    Ok(Summary {
        skipped,
        adapter: ctx.caps.adapter_name.clone(),
        records,
        reference_checks: checks,
        features,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(pixels: &[[u8; 3]]) -> Image {
        Image {
            width: pixels.len() as u32,
            height: 1,
            rgba: pixels
                .iter()
                .flat_map(|p| [p[0], p[1], p[2], 255])
                .collect(),
        }
    }

    #[test]
    fn the_ray_march_settles_where_the_gpu_methods_disagree() {
        // Pixel 0: the GPU methods agree within 2/255 (the ray march need not decide).
        // Pixel 1: they differ by 8/255, the ray march sides with the A-buffer: settled.
        // Pixel 2: they differ by 8/255, the ray march does not side with the A-buffer
        // (an edge there): unsettled. Pixel 3: they differ by 3/255, the ray march is off
        // by 2/255 from the A-buffer: unsettled.
        let abuffer = image(&[[100, 100, 100], [100, 100, 100], [50, 60, 70], [10, 10, 10]]);
        let peeled = image(&[[102, 98, 100], [108, 100, 100], [50, 68, 70], [10, 13, 10]]);
        let abuffer_flat = image(&[[1, 1, 1], [30, 40, 50], [30, 40, 50], [9, 9, 9]]);
        let ray = image(&[[200, 0, 0], [31, 40, 49], [30, 45, 50], [9, 11, 9]]);
        assert_eq!(unsettled_pixels(&abuffer, &peeled, &ray, &abuffer_flat), 2);
        // Agreement everywhere: nothing to settle, whatever the ray march says.
        assert_eq!(unsettled_pixels(&abuffer, &abuffer, &ray, &abuffer_flat), 0);
        // The ray march on the A-buffer's side everywhere: all settled.
        assert_eq!(
            unsettled_pixels(&abuffer, &peeled, &abuffer_flat, &abuffer_flat),
            0
        );
        // GPU pictures of two sizes settle nothing.
        let small = image(&[[100, 100, 100]]);
        assert_eq!(unsettled_pixels(&abuffer, &small, &ray, &abuffer_flat), 4);
        // A ray march of half the width: pixels 0 and 1 are settled by its pixel 0 (on the
        // A-buffer's side), 2 and 3 by its pixel 1 (not): pixels 2 and 3 stay unsettled.
        let ray_half = image(&[[30, 40, 50], [0, 0, 0]]);
        let flat_half = image(&[[30, 40, 50], [9, 9, 9]]);
        assert_eq!(
            unsettled_pixels(&abuffer, &peeled, &ray_half, &flat_half),
            2
        );
        let flat_agreeing = image(&[[30, 40, 50], [0, 0, 0]]);
        assert_eq!(
            unsettled_pixels(&abuffer, &peeled, &ray_half, &flat_agreeing),
            0
        );
    }
}
