//! The backend × technique table (`demo backends`): every technique of the default scene
//! on Vulkan, on wgpu's GL backend, and on both with WebGL2's limits; whether it runs (as
//! itself or as its replacement) or which capability it lacks, its error against the
//! Vulkan picture, its GPU time.

use crate::{Error, Result};

use std::path::{Path, PathBuf};

use voxel_render::{GpuContext, Image, OitConfig, Renderer, RendererConfig, Technique};

use crate::headless::{self, Offscreen, renderer_for};
use crate::metrics;
use crate::scene::{self, Scene};

/// What the table is made of.
#[derive(Clone, Debug)]
pub struct Options {
    /// Picture size.
    pub size: (u32, u32),
    /// Timed frames per picture (after one untimed): the median is reported.
    pub frames: u32,
    /// Folder of `report.md` and the pictures.
    pub out: PathBuf,
}

/// One device of the table.
#[derive(Debug)]
pub struct Device {
    /// Its name in the table.
    pub name: String,
    /// The context, or why it could not be made.
    pub ctx: Result<GpuContext>,
}

/// The four devices: Vulkan, GL, and both with WebGL2's limits and no optional feature but
/// timestamp queries (which WebGL2 lacks; asked for here only to time the passes). A device
/// that cannot be made is one too, with its error: the table goes on with the others.
pub fn devices() -> Vec<Device> {
    let vulkan = headless::Device {
        backends: wgpu::Backends::VULKAN,
        limits: voxel_render::LimitsPreset::Adapter,
    };
    let gl = headless::Device {
        backends: wgpu::Backends::GL,
        ..vulkan
    };
    vec![
        Device {
            name: "Vulkan".into(),
            ctx: vulkan.context(),
        },
        Device {
            name: "GL".into(),
            ctx: gl.context(),
        },
        Device {
            name: "Vulkan, WebGL2 limits".into(),
            ctx: webgl2_timed(wgpu::Backends::VULKAN),
        },
        Device {
            name: "GL, WebGL2 limits".into(),
            ctx: webgl2_timed(wgpu::Backends::GL),
        },
    ]
}

/// A device of `backends` with WebGL2's limits and timestamp queries (when the adapter has
/// them).
fn webgl2_timed(backends: wgpu::Backends) -> Result<GpuContext> {
    let instance = wgpu::Instance::new(voxel_render::instance_descriptor(backends));
    pollster::block_on(async {
        let adapter = instance
            .request_adapter(&Default::default())
            .await
            .map_err(|source| Error::NoAdapter { backends, source })?;
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("webgl2_limits_timed"),
                required_features: adapter.features() & wgpu::Features::TIMESTAMP_QUERY,
                required_limits: wgpu::Limits::downlevel_webgl2_defaults(),
                ..Default::default()
            })
            .await
            .map_err(Error::NoWebGl2Device)?;
        Ok(GpuContext::from_device(&adapter, device, queue))
    })
}

/// What a technique did on a device.
#[derive(Clone, Debug)]
pub enum Outcome {
    /// It drew (as `drew`: itself, or its replacement on this device).
    Runs {
        /// The technique that drew.
        drew: Technique,
        /// How the world's quads were fetched.
        fetch: &'static str,
        /// Mean |difference| to the Vulkan picture, 1/255 steps (`None` on Vulkan).
        mean: Option<f64>,
        /// Largest channel difference to it, 1/255 steps.
        max: u32,
        /// Median GPU ms of a frame (`None` without timestamps).
        gpu_ms: Option<f64>,
    },
    /// It was refused: the error's message.
    Unsupported(String),
    /// It failed otherwise (the device could not be made, was lost, or the renderer
    /// failed): the error's message.
    Failed(String),
}

/// One cell of the table.
#[derive(Clone, Debug)]
pub struct Row {
    /// The device's name.
    pub device: String,
    /// The technique asked for (`None`: the device could not be made).
    pub technique: Option<Technique>,
    /// What happened.
    pub outcome: Outcome,
}

/// The settings that draw what `technique` draws on `ctx`, on another device: MBOIT's
/// moments in 16 bits where `ctx` cannot blend 32-bit floats.
fn config_like(ctx: &GpuContext, technique: Technique, (w, h): (u32, u32)) -> RendererConfig {
    let mut oit = OitConfig::with(technique);
    oit.mboit.half_precision = !voxel_render::low_level::single_precision(&ctx.caps, &oit.mboit);
    RendererConfig {
        width: w,
        height: h,
        oit,
        ..RendererConfig::default()
    }
}

/// What [`draw`] gives: the technique that drew, the picture, the renderer's quad fetch,
/// the median GPU ms.
type Drawn = (Technique, Image, &'static str, Option<f64>);

/// Draws `scene` with `config` on `ctx` ([`Drawn`]).
fn draw(ctx: &GpuContext, scene: &Scene, config: RendererConfig, frames: u32) -> Result<Drawn> {
    let (w, h) = (config.width, config.height);
    let mut r = renderer_for(ctx, scene, config)?;
    let target = Offscreen::new(ctx, w, h);
    let mut ms = Vec::new();
    for i in 0..=frames {
        r.render_and_submit(&target.view, &scene.cameras[0])?;
        let t = r.gpu_times_blocking();
        if i > 0 && !t.is_empty() {
            ms.push(t.iter().map(|(_, ms)| ms).sum::<f64>());
        }
    }
    ms.sort_by(f64::total_cmp);
    let image = target.read(ctx)?;
    let fetch = r.config().quad_fetch.map_or("?", |f| f.name());
    Ok((
        r.config().oit.technique,
        image,
        fetch,
        ms.get(ms.len() / 2).copied(),
    ))
}

/// Runs every technique on every device of [`devices`] and writes `report.md` and the
/// pictures into `opts.out`; returns the rows. A device that cannot be made, or a
/// technique that fails on one, is a row with its error and the table goes on; it is an
/// error ([`Error::NoDeviceRuns`], after the report is written) only when no device draws.
pub fn run(opts: &Options) -> Result<Vec<Row>> {
    let scene = scene::default_scene(1)?;
    let devices = devices();
    // The pictures are compared with the first device's (Vulkan), when it exists.
    let reference = devices.first().and_then(|d| d.ctx.as_ref().ok());
    let mut rows = Vec::new();
    for d in &devices {
        let ctx = match &d.ctx {
            Ok(ctx) => ctx,
            Err(e) => {
                let outcome = Outcome::Failed(format!("no device: {}", crate::chain(e)));
                eprintln!("{}: {outcome:?}", d.name);
                rows.push(Row {
                    device: d.name.clone(),
                    technique: None,
                    outcome,
                });
                continue;
            }
        };
        let dir = opts
            .out
            .join(d.name.replace([',', ' '], "_").replace("__", "_"));
        std::fs::create_dir_all(&dir).map_err(Error::io(&dir))?;
        let compare_with = reference.filter(|r| !std::ptr::eq(*r, ctx));
        for t in Technique::ALL {
            let outcome = match technique(ctx, compare_with, &scene, t, opts, &dir) {
                Ok(outcome) => outcome,
                Err(Error::Render(e @ voxel_render::Error::Unsupported(_))) => {
                    Outcome::Unsupported(e.to_string())
                }
                Err(e) => Outcome::Failed(crate::chain(&e)),
            };
            eprintln!("{}: {t}: {outcome:?}", d.name);
            rows.push(Row {
                device: d.name.clone(),
                technique: Some(t),
                outcome,
            });
        }
    }
    let report = markdown(&rows, &devices, opts);
    let path = opts.out.join("report.md");
    std::fs::write(&path, report).map_err(Error::io(&path))?;
    if !rows
        .iter()
        .any(|r| matches!(r.outcome, Outcome::Runs { .. }))
    {
        let devices = devices
            .iter()
            .map(|d| {
                let why = rows
                    .iter()
                    .filter(|r| r.device == d.name)
                    .find_map(|r| match &r.outcome {
                        Outcome::Failed(why) | Outcome::Unsupported(why) => Some(why.as_str()),
                        Outcome::Runs { .. } => None,
                    })
                    .unwrap_or("nothing drew");
                format!("{}: {why}", d.name)
            })
            .collect::<Vec<_>>()
            .join("; ");
        return Err(Error::NoDeviceRuns { devices });
    }
    Ok(rows)
}

/// Draws `t` on `ctx` (refused before anything is made when the device cannot run it),
/// saves the picture into `dir` and compares it with `compare_with`'s picture of what drew.
fn technique(
    ctx: &GpuContext,
    compare_with: Option<&GpuContext>,
    scene: &Scene,
    t: Technique,
    opts: &Options,
    dir: &Path,
) -> Result<Outcome> {
    let config = config_like(ctx, t, opts.size);
    Renderer::new(ctx, scene.world.registry(), config.clone())?;
    let (drew, image, fetch, gpu_ms) = draw(ctx, scene, config, opts.frames)?;
    save(&image, &dir.join(format!("{t}.png")))?;
    let (mean, max) = match compare_with {
        None => (None, 0),
        Some(reference) => {
            let config = config_like(ctx, drew, opts.size);
            let (_, expected, _, _) = draw(reference, scene, config, 0)?;
            let (m, _) = metrics::compare(&expected, &image);
            (
                Some(metrics::mean_abs_diff(&expected, &image)),
                m.max_abs_err,
            )
        }
    };
    Ok(Outcome::Runs {
        drew,
        fetch,
        mean,
        max,
        gpu_ms,
    })
}

fn save(image: &Image, path: &Path) -> Result<()> {
    image.save_png(path).map_err(Error::Render)
}

/// The table as Markdown, with the devices it was made on.
pub fn markdown(rows: &[Row], devices: &[Device], opts: &Options) -> String {
    let (w, h) = opts.size;
    let mut s = format!(
        "# Backend × technique\n\nThe default scene (seed 1) at {w}×{h}, every technique on each device; \
         error against the Vulkan picture (mean and largest channel difference, 1/255 steps; \
         MBOIT compared with Vulkan's 16-bit moments where the device cannot blend 32-bit \
         floats); GPU ms the median of {} frames after one untimed (all passes). Made by \
         `cargo run --release -p demo -- backends --size {w}x{h} --frames {} --out {}`.\n\n",
        opts.frames,
        opts.frames,
        opts.out.display()
    );
    for d in devices {
        match &d.ctx {
            Ok(ctx) => s += &format!("- {}: {}\n", d.name, ctx.caps.adapter_name),
            Err(e) => s += &format!("- {}: could not be made ({})\n", d.name, crate::chain(e)),
        }
    }
    s += "\n| device | technique | runs | quads | error vs Vulkan (mean / max) | GPU ms |\n|---|---|---|---|---|---:|\n";
    for r in rows {
        let technique = r.technique.map_or("(all)".to_owned(), |t| format!("`{t}`"));
        match &r.outcome {
            Outcome::Runs {
                drew,
                fetch,
                mean,
                max,
                gpu_ms,
            } => {
                let runs = if Some(*drew) == r.technique {
                    "yes".to_owned()
                } else {
                    format!("as `{drew}`")
                };
                let err = match mean {
                    Some(m) => format!("{m:.4} / {max}"),
                    None if devices.first().is_some_and(|d| d.name == r.device) => {
                        "(the reference picture)".to_owned()
                    }
                    None => "(no Vulkan picture)".to_owned(),
                };
                let ms = gpu_ms.map_or("n/a".to_owned(), |v| format!("{v:.1}"));
                s += &format!(
                    "| {} | {technique} | {runs} | {fetch} | {err} | {ms} |\n",
                    r.device
                );
            }
            Outcome::Unsupported(why) => {
                s += &format!(
                    "| {} | {technique} | unsupported: {} | | | |\n",
                    r.device,
                    why.replace('|', "/")
                );
            }
            Outcome::Failed(why) => {
                s += &format!(
                    "| {} | {technique} | failed: {} | | | |\n",
                    r.device,
                    why.replace(['|', '\n'], " ")
                );
            }
        }
    }
    s
}
