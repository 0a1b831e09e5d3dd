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
    /// The context.
    pub ctx: GpuContext,
}

/// The four devices: Vulkan, GL, and both with WebGL2's limits and no optional feature but
/// timestamp queries (which WebGL2 lacks; asked for here only to time the passes).
pub fn devices() -> Result<Vec<Device>> {
    let vulkan = headless::Device {
        backends: wgpu::Backends::VULKAN,
        limits: voxel_render::LimitsPreset::Adapter,
    };
    let gl = headless::Device {
        backends: wgpu::Backends::GL,
        ..vulkan
    };
    Ok(vec![
        Device {
            name: "Vulkan".into(),
            ctx: vulkan.context()?,
        },
        Device {
            name: "GL".into(),
            ctx: gl.context()?,
        },
        Device {
            name: "Vulkan, WebGL2 limits".into(),
            ctx: webgl2_timed(wgpu::Backends::VULKAN)?,
        },
        Device {
            name: "GL, WebGL2 limits".into(),
            ctx: webgl2_timed(wgpu::Backends::GL)?,
        },
    ])
}

/// A device of `backends` with WebGL2's limits and timestamp queries (when the adapter has
/// them).
fn webgl2_timed(backends: wgpu::Backends) -> Result<GpuContext> {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = backends;
    let instance = wgpu::Instance::new(desc);
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
}

/// One cell of the table.
#[derive(Clone, Debug)]
pub struct Row {
    /// The device's name.
    pub device: String,
    /// The technique asked for.
    pub technique: Technique,
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
/// pictures into `opts.out`; returns the rows.
pub fn run(opts: &Options) -> Result<Vec<Row>> {
    let scene = scene::default_scene(1)?;
    let devices = devices()?;
    let vulkan = &devices[0].ctx;
    let mut rows = Vec::new();
    for d in &devices {
        let dir = opts
            .out
            .join(d.name.replace([',', ' '], "_").replace("__", "_"));
        std::fs::create_dir_all(&dir).map_err(Error::io(&dir))?;
        for t in Technique::ALL {
            let config = config_like(&d.ctx, t, opts.size);
            // Refused before anything is made when the device cannot run it.
            let outcome = match Renderer::new(&d.ctx, scene.world.registry(), config.clone()) {
                Err(e @ voxel_render::Error::Unsupported(_)) => Outcome::Unsupported(e.to_string()),
                Err(source) => {
                    return Err(Error::Technique {
                        device: d.name.clone(),
                        technique: t,
                        source: Box::new(source),
                    });
                }
                Ok(_) => {
                    let (drew, image, fetch, gpu_ms) = draw(&d.ctx, &scene, config, opts.frames)?;
                    save(&image, &dir.join(format!("{t}.png")))?;
                    let (mean, max) = if std::ptr::eq(d, &devices[0]) {
                        (None, 0)
                    } else {
                        let config = config_like(&d.ctx, drew, opts.size);
                        let (_, expected, _, _) = draw(vulkan, &scene, config, 0)?;
                        let (m, _) = metrics::compare(&expected, &image);
                        (
                            Some(metrics::mean_abs_diff(&expected, &image)),
                            m.max_abs_err,
                        )
                    };
                    Outcome::Runs {
                        drew,
                        fetch,
                        mean,
                        max,
                        gpu_ms,
                    }
                }
            };
            eprintln!("{}: {t}: {outcome:?}", d.name);
            rows.push(Row {
                device: d.name.clone(),
                technique: t,
                outcome,
            });
        }
    }
    let report = markdown(&rows, &devices, opts);
    let path = opts.out.join("report.md");
    std::fs::write(&path, report).map_err(Error::io(&path))?;
    Ok(rows)
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
        s += &format!("- {}: {}\n", d.name, d.ctx.caps.adapter_name);
    }
    s += "\n| device | technique | runs | quads | error vs Vulkan (mean / max) | GPU ms |\n|---|---|---|---|---|---:|\n";
    for r in rows {
        match &r.outcome {
            Outcome::Runs {
                drew,
                fetch,
                mean,
                max,
                gpu_ms,
            } => {
                let runs = if *drew == r.technique {
                    "yes".to_owned()
                } else {
                    format!("as `{drew}`")
                };
                let err = mean.map_or("(the reference picture)".to_owned(), |m| {
                    format!("{m:.4} / {max}")
                });
                let ms = gpu_ms.map_or("n/a".to_owned(), |v| format!("{v:.1}"));
                s += &format!(
                    "| {} | `{}` | {runs} | {fetch} | {err} | {ms} |\n",
                    r.device, r.technique
                );
            }
            Outcome::Unsupported(why) => {
                s += &format!(
                    "| {} | `{}` | unsupported: {} | | | |\n",
                    r.device,
                    r.technique,
                    why.replace('|', "/")
                );
            }
        }
    }
    s
}
