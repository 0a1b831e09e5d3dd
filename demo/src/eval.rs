//! The lab: every scene of a suite rendered with every technique and with the exact
//! reference; error and cost per picture; a speed-against-accuracy chart; stability
//! sweeps where methods fail; a report.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;
use voxel_render::{
    GpuContext, Image, OitConfig, Renderer, RendererConfig, Technique, WeightFunction,
};

use crate::charts::{self, Series};
use crate::headless::{Offscreen, renderer_for};
use crate::metrics::{self, Metrics};
use crate::scene::Scene;

/// What to run.
#[derive(Clone, Debug)]
pub struct EvalOptions {
    /// Scene files, in order.
    pub scenes: Vec<PathBuf>,
    /// Techniques to measure (the exact reference is always rendered too).
    pub techniques: Vec<Technique>,
    /// WBOIT weights compared in extra `wboit-mrt` runs (empty: none).
    pub weights: Vec<WeightFunction>,
    /// Output size; `None`: each scene's own, else 640×360.
    pub size: Option<(u32, u32)>,
    /// Timed frames per picture (the median is reported).
    pub frames: usize,
    /// Untimed frames first (pipelines, targets, adaptive peeling settle).
    pub warmup: usize,
    /// Output folder.
    pub out: PathBuf,
    /// Run the stability sweeps too.
    pub stability: bool,
    /// Frames of the flicker camera path.
    pub flicker_frames: usize,
    /// Points per sweep (the parameter lists are cut to this many, spread over their range).
    pub sweep_points: usize,
    /// The command line, for the report.
    pub command: String,
    /// Width of the saved heat maps and reference pictures (downscaled, to keep results
    /// small); `None`: full size.
    pub heatmap_width: Option<u32>,
}

/// `img` scaled down (box filter) to `width` pixels wide, or as it is if not wider.
pub fn thumbnail(img: &Image, width: Option<u32>) -> Image {
    let Some(w) = width.filter(|w| *w > 0 && *w < img.width) else {
        return img.clone();
    };
    let f = img.width.div_ceil(w);
    let (nw, nh) = (img.width / f, img.height / f);
    let mut rgba = Vec::with_capacity((nw * nh * 4) as usize);
    for y in 0..nh {
        for x in 0..nw {
            let mut acc = [0u32; 4];
            for dy in 0..f {
                for dx in 0..f {
                    let p = img.pixel(x * f + dx, y * f + dy);
                    for c in 0..4 {
                        acc[c] += u32::from(p[c]);
                    }
                }
            }
            rgba.extend(acc.map(|v| (v / (f * f)) as u8));
        }
    }
    Image {
        width: nw,
        height: nh,
        rgba,
    }
}

/// One scene × technique measurement (the keys of `summary.json`).
#[derive(Clone, Debug, Serialize)]
pub struct Record {
    /// Scene file stem.
    pub scene: String,
    /// Technique name (with `/weight` for the weight comparison runs).
    pub technique: String,
    /// WBOIT weight in force, for WBOIT techniques.
    pub weight: Option<String>,
    /// Picture width.
    pub width: u32,
    /// Picture height.
    pub height: u32,
    /// Median GPU ms of the translucent work per frame (passes labelled translucent and
    /// composite); `null` without timestamp queries.
    pub gpu_ms: Option<f64>,
    /// Median CPU ms to record a frame (quad sorting and the exact methods' waits included).
    pub cpu_ms: f64,
    /// Root mean square error, [0, 1] units.
    pub rmse: f64,
    /// PSNR in dB (100: identical).
    pub psnr: f64,
    /// Mean FLIP.
    pub flip_mean: f64,
    /// Largest channel error in 1/255 steps.
    pub max_abs_err: u32,
    /// Share of pixels off by more than 1/255.
    pub frac_bad_px: f64,
    /// Pixels of the HDR scene colour holding NaN or inf.
    pub nan_px: usize,
    /// Depth peeling: layers found.
    pub layers: Option<u32>,
    /// Reference: fragments that did not fit.
    pub overflow: Option<u64>,
    /// The FLIP heat map, relative to the output folder.
    pub heatmap: String,
}

/// The exact methods against each other, per scene.
#[derive(Clone, Debug, Serialize)]
pub struct ReferenceCheck {
    /// Scene file stem.
    pub scene: String,
    /// Largest channel difference between the A-buffer and peel-to-convergence pictures.
    pub max_abs_err: u32,
    /// A-buffer fragments that did not fit (must be 0).
    pub overflow: u64,
    /// Layers peel-to-convergence found (the scene's depth complexity).
    pub depth_complexity: u32,
}

/// Everything an evaluation produced.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    /// Adapter the pictures were rendered on.
    pub adapter: String,
    /// One record per scene × technique.
    pub records: Vec<Record>,
    /// The exact methods' agreement per scene.
    pub reference_checks: Vec<ReferenceCheck>,
}

/// A progress bar on stderr: redrawn in place on a terminal, one line per 10% elsewhere.
#[derive(Debug)]
pub struct Progress {
    total: usize,
    done: usize,
    last_decile: usize,
    tty: bool,
    start: Instant,
}

impl Progress {
    /// A bar for `total` steps.
    pub fn new(total: usize) -> Self {
        use std::io::IsTerminal;
        Self {
            total: total.max(1),
            done: 0,
            last_decile: 0,
            tty: std::io::stderr().is_terminal(),
            start: Instant::now(),
        }
    }

    /// One step done, doing `what` next.
    pub fn step(&mut self, what: &str) {
        self.done = (self.done + 1).min(self.total);
        let frac = self.done as f64 / self.total as f64;
        let filled = (frac * 30.0).round() as usize;
        let line = format!(
            "[{}{}] {:>4}/{} {:>5.1}s {what}",
            "#".repeat(filled),
            "-".repeat(30 - filled),
            self.done,
            self.total,
            self.start.elapsed().as_secs_f64()
        );
        let mut err = std::io::stderr();
        if self.tty {
            let _ = write!(err, "\r{line:<110}");
            if self.done == self.total {
                let _ = writeln!(err);
            }
        } else if (frac * 10.0) as usize > self.last_decile || self.done == self.total {
            self.last_decile = (frac * 10.0) as usize;
            let _ = writeln!(err, "{line}");
        }
    }
}

/// The scene files of a folder, sorted.
pub fn scene_files(dir: &Path) -> Result<Vec<PathBuf>, String> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| format!("{}: {e}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    v.sort();
    if v.is_empty() {
        return Err(format!("{}: no .toml scene files", dir.display()));
    }
    Ok(v)
}

fn is_wboit(t: Technique) -> bool {
    matches!(t, Technique::WboitMrt | Technique::WboitTwoPass)
}

/// A renderer for measurements, sized `size`.
pub fn make_renderer(
    ctx: &GpuContext,
    scene: &Scene,
    size: (u32, u32),
) -> Result<Renderer, String> {
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
    /// Median GPU ms of translucent + composite passes.
    pub gpu_ms: Option<f64>,
    /// Median CPU ms per frame.
    pub cpu_ms: f64,
    /// Non-finite HDR pixels of the last frame.
    pub nan_px: usize,
    /// Stats of the last frame.
    pub stats: voxel_render::FrameStats,
}

fn median(mut v: Vec<f64>) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    Some(v[v.len() / 2])
}

/// Renders `warmup + frames` frames of `camera` with `config`'s technique and returns the
/// last picture with the median timings.
pub fn measure(
    ctx: &GpuContext,
    renderer: &mut Renderer,
    target: &Offscreen,
    camera: &voxel_render::Camera,
    config: &OitConfig,
    warmup: usize,
    frames: usize,
) -> Result<Measured, String> {
    renderer.set_oit_config(config.clone());
    let mut gpu = Vec::new();
    let mut cpu = Vec::new();
    let mut stats = voxel_render::FrameStats::default();
    for i in 0..warmup + frames.max(1) {
        stats = renderer
            .render_and_submit(&target.view, camera)
            .map_err(|e| e.to_string())?;
        let times = renderer.gpu_times_blocking();
        if i >= warmup {
            cpu.push(stats.cpu_ms);
            if !times.is_empty() {
                gpu.push(
                    times
                        .iter()
                        .filter(|(l, _)| *l == "translucent" || *l == "composite")
                        .map(|(_, ms)| ms)
                        .fold(0.0, |a, b| a + b),
                );
            }
        }
    }
    let image = target.read(ctx)?;
    let hdr = read_hdr(ctx, renderer.scene_color())?;
    Ok(Measured {
        image,
        gpu_ms: median(gpu),
        cpu_ms: median(cpu).unwrap_or(0.0),
        nan_px: metrics::non_finite_pixels(&hdr),
        stats,
    })
}

/// The HDR scene colour as f32 RGBA.
pub fn read_hdr(ctx: &GpuContext, texture: &wgpu::Texture) -> Result<Vec<[f32; 4]>, String> {
    let bytes = voxel_render::readback::read_texture(ctx, texture, 8).map_err(|e| e.to_string())?;
    Ok(bytes
        .chunks_exact(8)
        .map(|p| {
            let h =
                |i: usize| voxel_render::readback::f16_to_f32(u16::from_le_bytes([p[i], p[i + 1]]));
            [h(0), h(2), h(4), h(6)]
        })
        .collect())
}

/// The configuration for `technique` (with `weight` for WBOIT).
pub fn oit_config(technique: Technique, weight: WeightFunction) -> OitConfig {
    OitConfig {
        technique,
        weight,
        ..OitConfig::default()
    }
}

/// Runs the evaluation, writes every file, returns the summary.
pub fn run(ctx: &GpuContext, opts: &EvalOptions) -> Result<Summary, String> {
    let out = &opts.out;
    std::fs::create_dir_all(out.join("heatmaps")).map_err(|e| format!("{}: {e}", out.display()))?;
    let runs_per_scene = opts.techniques.len() + opts.weights.len() + 2;
    let mut progress = Progress::new(opts.scenes.len() * runs_per_scene);
    let mut records = Vec::new();
    let mut checks = Vec::new();
    let default_weight = OitConfig::default().weight;
    for path in &opts.scenes {
        let stem = path
            .file_stem()
            .map_or("scene".into(), |s| s.to_string_lossy().into_owned());
        let scene = Scene::load(path)?;
        let size = opts.size.or(scene.size).unwrap_or((640, 360));
        let mut renderer = make_renderer(ctx, &scene, size)?;
        let target = Offscreen::new(ctx, size.0, size.1);
        let camera = scene.cameras[0];

        progress.step(&format!("{stem}: reference"));
        let reference = measure(
            ctx,
            &mut renderer,
            &target,
            &camera,
            &oit_config(Technique::Reference, default_weight),
            0,
            1,
        )?;
        progress.step(&format!("{stem}: peel-reference"));
        let peel = measure(
            ctx,
            &mut renderer,
            &target,
            &camera,
            &oit_config(Technique::PeelReference, default_weight),
            0,
            1,
        )?;
        let cross = metrics::compare(&reference.image, &peel.image).0;
        checks.push(ReferenceCheck {
            scene: stem.clone(),
            max_abs_err: cross.max_abs_err,
            overflow: reference.stats.technique.overflow.unwrap_or(0),
            depth_complexity: peel.stats.technique.layers.unwrap_or(0),
        });
        thumbnail(&reference.image, opts.heatmap_width)
            .save_png(&out.join("heatmaps").join(format!("{stem}__reference.png")))
            .map_err(|e| e.to_string())?;

        let mut runs: Vec<(String, OitConfig)> = opts
            .techniques
            .iter()
            .map(|t| (t.name().to_owned(), oit_config(*t, default_weight)))
            .collect();
        for w in &opts.weights {
            runs.push((
                format!("wboit-mrt/{}", w.name()),
                oit_config(Technique::WboitMrt, *w),
            ));
        }
        for (name, config) in runs {
            progress.step(&format!("{stem}: {name}"));
            let m = measure(
                ctx,
                &mut renderer,
                &target,
                &camera,
                &config,
                opts.warmup,
                opts.frames,
            )?;
            let (metrics, heat) = metrics::compare(&reference.image, &m.image);
            let file = format!("{stem}__{}.png", name.replace('/', "_"));
            thumbnail(&heat, opts.heatmap_width)
                .save_png(&out.join("heatmaps").join(&file))
                .map_err(|e| e.to_string())?;

            let Metrics {
                rmse,
                psnr,
                flip_mean,
                max_abs_err,
                frac_bad_px,
            } = metrics;
            records.push(Record {
                scene: stem.clone(),
                technique: name,
                weight: is_wboit(config.technique).then(|| config.weight.name().to_owned()),
                width: size.0,
                height: size.1,
                gpu_ms: m.gpu_ms,
                cpu_ms: m.cpu_ms,
                rmse,
                psnr,
                flip_mean,
                max_abs_err,
                frac_bad_px,
                nan_px: m.nan_px,
                layers: m.stats.technique.layers,
                overflow: m.stats.technique.overflow,
                heatmap: format!("heatmaps/{file}"),
            });
        }
    }
    let summary = Summary {
        adapter: ctx.caps.adapter_name.clone(),
        records,
        reference_checks: checks,
    };
    write_json(&out.join("summary.json"), &summary.records)?;
    write_json(
        &out.join("reference_checks.json"),
        &summary.reference_checks,
    )?;
    chart(out, &summary, opts)?;
    let stability = if opts.stability {
        Some(crate::stability::run(ctx, opts)?)
    } else {
        None
    };
    crate::report::write(out, &summary, stability.as_ref(), opts)?;
    Ok(summary)
}

/// Writes `value` as pretty JSON.
pub fn write_json(path: &Path, value: &impl Serialize) -> Result<(), String> {
    let text = serde_json::to_string_pretty(value).map_err(|e| e.to_string())?;
    std::fs::write(path, text + "\n").map_err(|e| format!("{}: {e}", path.display()))
}

/// The techniques of the main chart and tables: the runs without a weight suffix.
pub fn main_techniques(summary: &Summary) -> Vec<String> {
    let mut names: Vec<String> = Vec::new();
    for r in &summary.records {
        if !r.technique.contains('/') && !names.contains(&r.technique) {
            names.push(r.technique.clone());
        }
    }
    names
}

/// Suite means of one technique: (gpu ms, cpu ms, flip, rmse), if every scene has a GPU time.
pub fn suite_mean(summary: &Summary, technique: &str) -> (Option<f64>, f64, f64, f64) {
    let rs: Vec<&Record> = summary
        .records
        .iter()
        .filter(|r| r.technique == technique)
        .collect();
    let n = rs.len().max(1) as f64;
    let gpu = rs
        .iter()
        .map(|r| r.gpu_ms)
        .collect::<Option<Vec<f64>>>()
        .map(|v| v.iter().sum::<f64>() / n);
    (
        gpu,
        rs.iter().map(|r| r.cpu_ms).sum::<f64>() / n,
        rs.iter().map(|r| r.flip_mean).sum::<f64>() / n,
        rs.iter().map(|r| r.rmse).sum::<f64>() / n,
    )
}

/// The speed-against-accuracy chart. `opaque-only` (draws no translucency, costs nothing)
/// stays out of it.
fn chart(out: &Path, summary: &Summary, opts: &EvalOptions) -> Result<(), String> {
    let names: Vec<String> = main_techniques(summary)
        .into_iter()
        .filter(|n| n != "opaque-only")
        .collect();
    // A scene where a technique drew nothing translucent (0 ms: nothing in view to
    // compose) says nothing about it, and would sit at -inf on the log axis.
    let floor = 0.001;
    let per_scene: Vec<Series> = names
        .iter()
        .map(|n| Series {
            name: n.clone(),
            points: summary
                .records
                .iter()
                .filter(|r| &r.technique == n)
                .filter_map(|r| r.gpu_ms.filter(|g| *g > 0.0).map(|g| (g, r.flip_mean)))
                .collect(),
        })
        .collect();
    let means: Vec<Series> = names
        .iter()
        .map(|n| {
            let (gpu, _, flip, _) = suite_mean(summary, n);
            Series {
                name: n.clone(),
                points: gpu.map(|g| vec![(g.max(floor), flip)]).unwrap_or_default(),
            }
        })
        .collect();
    let (w, h) = opts.size.unwrap_or((640, 360));
    charts::speed_vs_accuracy(
        &out.join("speed_vs_accuracy"),
        &format!(
            "Speed vs accuracy, {} scenes, {w}x{h}, {}",
            opts.scenes.len(),
            summary.adapter
        ),
        &per_scene,
        &means,
    )
}
