//! The demo and headless tools of the voxel OIT renderer. `demo --help` lists the
//! commands, `demo <command> --help` their options.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};
use demo::{Error, Result};
use voxel_lab::headless;
use voxel_render::{BayerSize, Technique, WeightFunction};

mod commands;
use commands::{backends, eval, far, gallery, render, showcase, stats, stream, window};

/// The voxel OIT renderer's demo: a window when there is a display, else the headless
/// showcase.
#[derive(Parser, Debug)]
#[command(name = "demo", after_help = names_help())]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    /// Options of the window, when no command is given.
    #[command(flatten)]
    window: WindowArgs,
    /// The device every command draws with.
    #[command(flatten)]
    device: DeviceArgs,
}

/// Which device to draw with.
#[derive(Args, Debug, Clone, Copy)]
struct DeviceArgs {
    /// Graphics backend: vulkan, gl, metal or dx12 (default: WGPU_BACKEND; unset, Vulkan
    /// for the headless commands and the primary backends for the window).
    #[arg(long, global = true, value_parser = headless::backend)]
    backend: Option<wgpu::Backends>,
    /// Device limits: adapter (all the adapter has) or webgl2 (WebGL2's limits and no
    /// optional feature, on any adapter).
    #[arg(long, global = true, value_parser = limits_preset, default_value = "adapter")]
    limits: voxel_render::LimitsPreset,
}

impl DeviceArgs {
    /// The headless device: `--backend`, else `WGPU_BACKEND`, else Vulkan.
    fn headless(&self) -> headless::Device {
        let env = headless::Device::from_env();
        headless::Device {
            backends: self.backend.unwrap_or(env.backends),
            limits: self.limits,
        }
    }
}

fn quad_fetch(s: &str) -> Result<voxel_render::QuadFetch> {
    Ok(s.parse::<voxel_render::QuadFetch>()?)
}

/// An hour of the day, 0 to 24.
fn hour(s: &str) -> Result<f32> {
    s.trim()
        .parse::<f32>()
        .ok()
        .filter(|h| (0.0..=24.0).contains(h))
        .ok_or_else(|| Error::NotA {
            value: s.to_owned(),
            what: "an hour from 0 to 24 (e.g. 12 or 22.5)".to_owned(),
        })
}

fn limits_preset(s: &str) -> Result<voxel_render::LimitsPreset> {
    Ok(s.parse::<voxel_render::LimitsPreset>()?)
}

#[derive(Subcommand, Debug)]
enum Command {
    /// The interactive window (scripted with --frames for tests and screenshots).
    Window(WindowArgs),
    /// Every technique rendered for the default scene, and a speed/accuracy chart of a few
    /// suite scenes at a small size (--full: of the whole suite).
    Showcase(ShowcaseArgs),
    /// Generates and meshes a world, prints what it holds and how long it took.
    Stats(StatsArgs),
    /// Renders a scene file (or the default generated scene) headlessly to a PNG, with GPU
    /// times per pass.
    Render(RenderArgs),
    /// The lab: every scene × technique against the exact reference; summary, charts,
    /// heat maps, stability sweeps and report.
    Eval(EvalArgs),
    /// Flies over generated terrain with chunk streaming; writes stream.json (CPU and GPU
    /// time per frame, uploads, memory), frames.json and a chart of CPU ms per frame.
    Stream(StreamArgs),
    /// The default terrain to a far view distance in levels of detail: a picture per
    /// technique, GPU memory and quads per level, build time (--compare: scored against
    /// full detail of the same view); far.json.
    Far(FarArgs),
    /// One scene (a scene file or a .vox model) under every technique: each picture, its
    /// FLIP error map against the reference, and gallery.png with all of them.
    Gallery(GalleryArgs),
    /// Every technique of the default scene on Vulkan, on wgpu's GL backend, and on both
    /// with WebGL2's limits: runs or which capability it lacks, error against the Vulkan
    /// picture, GPU ms; report.md and the pictures (ignores --backend and --limits).
    Backends(BackendsArgs),
}

#[derive(Args, Debug)]
struct BackendsArgs {
    /// Picture size.
    #[arg(long, value_parser = size, default_value = "640x360")]
    size: (u32, u32),
    /// Timed frames per picture (after one untimed), 1 to 1000; the median is reported.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=i64::from(voxel_lab::limits::MAX_FRAMES)), default_value_t = 5)]
    frames: u32,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
}

#[derive(Args, Debug)]
struct GalleryArgs {
    /// Scene file or MagicaVoxel .vox model.
    #[arg(long)]
    scene: PathBuf,
    /// Picture size of each technique.
    #[arg(long, value_parser = size, default_value = "480x270")]
    size: (u32, u32),
    /// Tiles per row of gallery.png.
    #[arg(long, default_value_t = 3)]
    columns: usize,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
}

/// How chunk meshes are drawn: `indirect` or `per-chunk`.
fn draw_mode(s: &str) -> Result<voxel_render::DrawMode> {
    use voxel_render::DrawMode;
    [DrawMode::Indirect, DrawMode::PerChunk]
        .into_iter()
        .find(|m| m.name() == s)
        .ok_or_else(|| Error::Expected {
            value: s.to_owned(),
            expected: "indirect or per-chunk",
        })
}

#[derive(Args, Debug)]
struct FarArgs {
    /// Full detail to this many chunks from the eye (even, 2 to 64).
    #[arg(long, default_value_t = 32)]
    full_detail: u32,
    /// View distance in chunks (the full detail to 2048): rings of levels 2x, 4x, ...
    /// coarser reach it.
    #[arg(long, default_value_t = 512)]
    view_distance: u32,
    /// Techniques: all, or a comma-separated list.
    #[arg(long, num_args = 1.., value_delimiter = ',', default_value = "sorted-quads")]
    techniques: Vec<String>,
    /// Also render full detail to the view distance (at most 64) and score the levels.
    #[arg(long)]
    compare: bool,
    /// Frames flown at 20 blocks a second once the view is built (0 to 100000), each
    /// frame's far-field update timed.
    #[arg(long, default_value_t = 600)]
    fly_frames: usize,
    /// Picture size.
    #[arg(long, value_parser = size, default_value = "1280x720")]
    size: (u32, u32),
    /// Terrain seed.
    #[arg(long, default_value_t = 1)]
    seed: u32,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
}

#[derive(Args, Debug)]
struct StreamArgs {
    /// Chunks loaded each way horizontally (1 to 64).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=i64::from(voxel_render::low_level::MAX_VIEW_DISTANCE)))]
    view_distance: u32,
    /// Chunks loaded above and below the eye (0 to 64).
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=i64::from(voxel_render::low_level::MAX_VIEW_DISTANCE)), default_value_t = 4)]
    vertical_distance: u32,
    /// Frames flown and measured (after loading the view distance).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    frames: u32,
    /// Blocks flown per frame (0 to 1024; 4 is one chunk per 8 frames).
    #[arg(long, default_value_t = 4.0, allow_negative_numbers = true)]
    speed: f64,
    /// How chunk meshes are drawn: indirect or per-chunk.
    #[arg(long, value_parser = draw_mode, default_value = "indirect")]
    draw: voxel_render::DrawMode,
    /// Picture size.
    #[arg(long, value_parser = size, default_value = "640x360")]
    size: (u32, u32),
    /// Terrain seed.
    #[arg(long, default_value_t = 1)]
    seed: u32,
    /// At this frame the eye jumps 10 000 chunks away and flies on (bad-input check of
    /// the streamer: it drops and reloads within its per-frame budgets).
    #[arg(long, value_name = "FRAME")]
    teleport_at: Option<usize>,
    /// Light the chunks as they stream (sky light, light sources; on the streamer's
    /// workers).
    #[arg(long)]
    light: bool,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
}

fn names_help() -> String {
    format!(
        "techniques: {}\nweights: {} (default {})",
        Technique::ALL.map(Technique::name).join(", "),
        WeightFunction::ALL.map(WeightFunction::name).join(", "),
        voxel_render::WboitSettings::default().weight.name()
    )
}

/// `WxH`, each side 1 to [`voxel_lab::limits::MAX_SIDE`], at most
/// [`voxel_lab::limits::MAX_PIXELS`] in all.
fn size(s: &str) -> Result<(u32, u32)> {
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| Error::NotA {
        value: s.to_owned(),
        what: "WxH (e.g. 1280x720)".to_owned(),
    })?;
    let max = voxel_lab::limits::MAX_SIDE;
    let side = |v: &str| {
        v.trim()
            .parse::<u32>()
            .ok()
            .filter(|n| (1..=max).contains(n))
            .ok_or_else(|| Error::NotA {
                value: v.to_owned(),
                what: format!("a whole number from 1 to {max}"),
            })
    };
    let size = (side(w)?, side(h)?);
    voxel_lab::limits::check_size("size", size)?;
    Ok(size)
}

/// A number of random scenes: 1 to [`voxel_lab::random::MAX_SCENES`].
fn random_count(s: &str) -> Result<usize> {
    let max = voxel_lab::random::MAX_SCENES;
    let t = s.trim();
    if !t.is_empty() && t.bytes().all(|b| b.is_ascii_digit()) {
        // Too many digits for a usize is still "too many", not "not a number".
        return match t.parse::<usize>() {
            Ok(n) => Ok(voxel_lab::random::RandomSet::new(n, 0)?.count),
            Err(_) => Err(voxel_lab::random::too_many(t).into()),
        };
    }
    Err(Error::NotA {
        value: s.to_owned(),
        what: format!("a number of scenes: a whole number from 1 to {max}"),
    })
}

/// A seed: any whole number from 0 to 2^64 - 1.
fn random_seed(s: &str) -> Result<u64> {
    s.trim().parse().map_err(|_| Error::NotA {
        value: s.to_owned(),
        what: format!("a seed: a whole number from 0 to {}", u64::MAX),
    })
}

fn time_budget(s: &str) -> Result<f64> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(Error::NotA {
            value: s.to_owned(),
            what: "a time budget: a number of seconds above 0".into(),
        }),
    }
}

fn technique(s: &str) -> Result<Technique> {
    Ok(s.parse::<Technique>()?)
}

fn weight(s: &str) -> Result<WeightFunction> {
    Ok(s.parse::<WeightFunction>()?)
}

fn bayer(s: &str) -> Result<BayerSize> {
    let side = s.parse().map_err(|_| Error::Expected {
        value: s.to_owned(),
        expected: "2, 4, 8 or 16",
    })?;
    Ok(BayerSize::from_side(side)?)
}

#[derive(Args, Debug, Clone)]
struct WindowArgs {
    /// World seed.
    #[arg(long, default_value_t = 1)]
    seed: u32,
    /// Window size.
    #[arg(long, value_parser = size, default_value = "1280x720")]
    size: (u32, u32),
    /// Technique to start with.
    #[arg(long, value_parser = technique, default_value = "sorted-quads")]
    technique: Technique,
    /// Chunks of terrain drawn around the eye, each way (1 to 512); to 32 they stream in
    /// full detail as the camera flies, past 32 the terrain is drawn in levels of detail
    /// (full detail to 32).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=i64::from(demo::app::MAX_DEMO_VIEW_DISTANCE)), default_value_t = 8)]
    view_distance: u32,
    /// Start with the error map against the reference on.
    #[arg(long)]
    heatmap: bool,
    /// Start with the levels of detail shown as bands (odd levels darker; the L key).
    #[arg(long)]
    level_bands: bool,
    /// Show the game content (3 000 bubbles rising through the water, a turning glass
    /// cube crossing its surface, a boat) from the start: `true` or `false`. Default: on
    /// in an interactive run, off with --frames. The panel toggles each.
    #[arg(long)]
    game: Option<bool>,
    /// Scripted: quit after N frames (per technique with --cycle).
    #[arg(long)]
    frames: Option<u64>,
    /// Scripted: save the last frame, panel included.
    #[arg(long, requires = "frames")]
    screenshot: Option<PathBuf>,
    /// Scripted: step through every technique, saving DIR/<technique>.png for each.
    #[arg(long, requires = "frames")]
    cycle: Option<PathBuf>,
    /// Light the generated terrain as it streams (sky light through glass and water,
    /// light sources; docs/light.md), to view distance 32. A scene is lit by its own
    /// `light = true`.
    #[arg(long)]
    light: bool,
    /// Scripted: place a block in front of the camera on the second frame.
    #[arg(long, requires = "frames")]
    edit: bool,
    /// Scripted: halve the window, get a zero size, restore it (frames 1 to 3).
    #[arg(long, requires = "frames")]
    resize: bool,
    /// A scene file or a MagicaVoxel .vox model to show instead of generated terrain.
    #[arg(long)]
    scene: Option<PathBuf>,
}

#[derive(Args, Debug)]
struct ShowcaseArgs {
    /// Output folder.
    #[arg(long, default_value = "out")]
    out: PathBuf,
    /// Picture size.
    #[arg(long, value_parser = size, default_value = "1280x720")]
    size: (u32, u32),
    /// Chart the whole suite (every scene at 480x270: many minutes on a CPU driver)
    /// instead of a few scenes at 320x180.
    #[arg(long)]
    full: bool,
}

/// The suite scenes the quick chart measures: water and glass, leaves behind glass, the
/// eye under water, a game's bubbles and fish in the sea, a corridor of stained glass, and
/// a game's things around a glass dome on the sea floor (each a few seconds at
/// [`QUICK_SIZE`] on a CPU driver, every one scored there; `deep_stack` alone takes
/// minutes).
const QUICK_SCENES: [&str; 6] = [
    "water_through_glass",
    "leaves_behind_glass",
    "under_water",
    "game_sea",
    "stained_glass_corridor",
    "game_base",
];
/// Picture size of the quick chart.
const QUICK_SIZE: (u32, u32) = (320, 180);

#[derive(Args, Debug)]
struct StatsArgs {
    /// World seed.
    #[arg(long, default_value_t = 1)]
    seed: u32,
    /// The world is N x 2 x N chunks (1 to 256).
    #[arg(long, value_parser = clap::value_parser!(i32).range(1..=256), default_value_t = 32)]
    chunks: i32,
}

#[derive(Args, Debug)]
struct RenderArgs {
    /// Technique.
    #[arg(long, value_parser = technique, default_value = "sorted-quads")]
    technique: Technique,
    /// WBOIT weight (default: the renderer's).
    #[arg(long, value_parser = weight)]
    weight: Option<WeightFunction>,
    /// Stipple's Bayer pattern: 2, 4, 8 or 16.
    #[arg(long, value_parser = bayer)]
    bayer: Option<BayerSize>,
    /// Layers of dual depth peeling (even, 2 to 512).
    #[arg(long)]
    layers: Option<u32>,
    /// Scene file or MagicaVoxel .vox model (default: the generated default scene).
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Picture size.
    #[arg(long, value_parser = size, default_value = "1280x720")]
    size: (u32, u32),
    /// Seed of the default scene.
    #[arg(long, default_value_t = 1)]
    seed: u32,
    /// 4x MSAA for the opaque and cutout passes.
    #[arg(long)]
    msaa: bool,
    /// Ambient-occlusion strength, 0 (off) to 1.
    #[arg(long, default_value_t = 1.0)]
    ao_strength: f32,
    /// Every block one flat colour (what the lab compares with its CPU ray march).
    #[arg(long)]
    flat_textures: bool,
    /// The lighting of this hour, 0 to 24 (`Lighting::daytime`: night is moonlit; default:
    /// the renderer's default daylight).
    #[arg(long, value_parser = hour)]
    hour: Option<f32>,
    /// Draw the world with its light field (sky light through glass and water, the light
    /// of torches, lava and glowing glass: docs/light.md), as a scene file's `light = true`
    /// does.
    #[arg(long)]
    light: bool,
    /// With light: no sun shadows (the sky light stands for the sun's; docs/light.md),
    /// as a scene file's `sun_shadows = false` does.
    #[arg(long)]
    no_sun_shadows: bool,
    /// How quads reach the vertex shader: storage or instanced (default: the first the
    /// device can).
    #[arg(long, value_parser = quad_fetch)]
    quad_fetch: Option<voxel_render::QuadFetch>,
    /// Timed frames (after one untimed), 1 to 1000; the medians are printed.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=i64::from(voxel_lab::limits::MAX_FRAMES)), default_value_t = 1)]
    frames: u32,
    /// Output PNG.
    #[arg(long)]
    out: PathBuf,
}

#[derive(Args, Debug)]
struct EvalArgs {
    /// Scene files (.toml), MagicaVoxel models (.vox) or folders of them (default: the
    /// suite in scenes/).
    #[arg(long, num_args = 1..)]
    scenes: Vec<PathBuf>,
    /// Random scenes instead of scene files: N scenes (1 to 100000) drawn from --seed;
    /// writes distribution.json, scenes.json, worst/<technique>.toml and distribution
    /// charts besides the usual files (no heat maps per scene).
    #[arg(long, value_name = "N", value_parser = random_count, conflicts_with = "scenes", allow_negative_numbers = true)]
    random: Option<usize>,
    /// Seed of the random scenes (0 to 2^64-1; default 1): the same N and seed give the
    /// same scenes on every machine.
    #[arg(long, value_name = "S", value_parser = random_seed, requires = "random", allow_negative_numbers = true)]
    seed: Option<u64>,
    /// Techniques: all, or a comma-separated list.
    #[arg(long, num_args = 1.., value_delimiter = ',', default_value = "all")]
    techniques: Vec<String>,
    /// WBOIT weights compared in extra wboit-mrt runs: all, none, or a list.
    #[arg(long, num_args = 1.., value_delimiter = ',', default_value = "all")]
    weights: Vec<String>,
    /// Picture size (default: each scene's own, else 640x360).
    #[arg(long, value_parser = size)]
    size: Option<(u32, u32)>,
    /// Timed frames per picture, 1 to 1000 (the median is reported).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=i64::from(voxel_lab::limits::MAX_FRAMES)), default_value_t = 10)]
    frames: u32,
    /// Untimed frames first, 0 to 100.
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=i64::from(voxel_lab::limits::MAX_WARMUP)), default_value_t = 2)]
    warmup: u32,
    /// Skip the stability sweeps and flicker paths.
    #[arg(long)]
    no_stability: bool,
    /// Frames of the flicker camera path, 2 to 240.
    #[arg(long, value_parser = clap::value_parser!(u32).range(2..=i64::from(voxel_lab::limits::MAX_FLICKER_FRAMES)), default_value_t = 60)]
    flicker_frames: u32,
    /// Points per stability sweep, 2 to 9.
    #[arg(long, value_parser = clap::value_parser!(u32).range(i64::from(voxel_lab::limits::MIN_SWEEP_POINTS)..=i64::from(voxel_lab::limits::MAX_SWEEP_POINTS)), default_value_t = 9)]
    sweep_points: u32,
    /// Width of the saved heat maps (downscaled; default full size), 16 to 8192.
    #[arg(long, value_parser = clap::value_parser!(u32).range(i64::from(voxel_lab::limits::MIN_HEATMAP_WIDTH)..=i64::from(voxel_lab::limits::MAX_SIDE)))]
    heatmap_width: Option<u32>,
    /// Skip FLIP (the lab's dearest step per run at large sizes): no mean FLIP, no heat
    /// maps; the other errors (largest, share of pixels off) stay.
    #[arg(long)]
    no_flip: bool,
    /// Save no heat maps or reference pictures.
    #[arg(long)]
    no_heatmaps: bool,
    /// Width of the CPU ray march checking each scene's reference (default: the run's
    /// size; 0: none, the two GPU exact methods then vouch for each other), 0 to 8192.
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=i64::from(voxel_lab::limits::MAX_SIDE)))]
    raymarch_width: Option<u32>,
    /// Start no scene after this many seconds (the scenes done are written out, those
    /// left named in the report).
    #[arg(long, value_name = "SECONDS", value_parser = time_budget)]
    time_budget: Option<f64>,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
}

fn main() {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let cli = Cli::parse();
    let (device, d) = (cli.device.headless(), cli.device);
    let result = match cli.command {
        None if demo::app::have_display() => window(cli.window, d),
        None => {
            eprintln!(
                "no display (neither DISPLAY nor WAYLAND_DISPLAY is set): running the headless showcase instead"
            );
            showcase(
                ShowcaseArgs {
                    out: "out".into(),
                    size: (1280, 720),
                    full: false,
                },
                &device,
            )
        }
        Some(Command::Window(a)) => window(a, d),
        Some(Command::Showcase(a)) => showcase(a, &device),
        Some(Command::Stats(a)) => stats(a),
        Some(Command::Render(a)) => render(a, &device),
        Some(Command::Eval(a)) => eval(a, &device),
        Some(Command::Stream(a)) => stream(a, &device),
        Some(Command::Far(a)) => far(a, &device),
        Some(Command::Gallery(a)) => gallery(a, &device),
        Some(Command::Backends(a)) => backends(a),
    };
    if let Err(e) = result {
        eprintln!("error: {e}");
        std::process::exit(2);
    }
}
