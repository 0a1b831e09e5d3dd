//! The demo and headless tools of the voxel OIT renderer. `demo --help` lists the
//! commands, `demo <command> --help` their options.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use clap::{Args, Parser, Subcommand};
use demo::{Error, Result};
use voxel_core::{BlockRegistry, ChunkPos, TerrainConfig, TerrainGenerator};
use voxel_lab::{EvalOptions, chain, headless, scene};
use voxel_render::{BayerSize, RendererConfig, Technique, WeightFunction};

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
    Ok(voxel_render::QuadFetch::from_name(s)?)
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
    Ok(voxel_render::LimitsPreset::from_name(s)?)
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
    Ok(Technique::from_name(s)?)
}

fn weight(s: &str) -> Result<WeightFunction> {
    Ok(WeightFunction::from_name(s)?)
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
    /// Chunks of terrain loaded around the eye, each way (1 to 32); they stream in as
    /// the camera flies.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=i64::from(demo::app::MAX_DEMO_VIEW_DISTANCE)), default_value_t = 8)]
    view_distance: u32,
    /// Start with the error map against the reference on.
    #[arg(long)]
    heatmap: bool,
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
        Some(Command::Gallery(a)) => gallery(a, &device),
        Some(Command::Backends(a)) => backends(a),
    };
    if let Err(e) = result {
        eprintln!("error: {e}");
        std::process::exit(2);
    }
}

/// Fails early, before any rendering, when `dir` cannot be created or written to.
fn writable_dir(dir: &Path) -> Result<()> {
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
fn writable_file(path: &Path) -> Result<()> {
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
fn stats(a: StatsArgs) -> Result<()> {
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
fn render(a: RenderArgs, device: &headless::Device) -> Result<()> {
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
    let scene = match &a.scene {
        Some(path) => scene::Scene::load(path)?,
        None => scene::default_scene(a.seed)?,
    };
    println!(
        "scene: {} ({} chunks) built in {:.0} ms",
        scene.name,
        scene.world.len(),
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

/// The scene files named on the command line (files or folders), or the `scenes/` folder.
fn scene_paths(given: &[PathBuf]) -> Result<Vec<PathBuf>> {
    let given: Vec<PathBuf> = if given.is_empty() {
        let local = PathBuf::from("scenes");
        let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
        vec![if local.is_dir() { local } else { repo }]
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
fn names<T: Copy>(
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
fn eval(a: EvalArgs, device: &headless::Device) -> Result<()> {
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
fn stream(a: StreamArgs, device: &headless::Device) -> Result<()> {
    let opts = voxel_lab::stream::StreamOptions {
        view_distance: a.view_distance,
        vertical_distance: a.vertical_distance,
        frames: a.frames as usize,
        speed: a.speed,
        draw: a.draw,
        size: a.size,
        seed: a.seed,
        teleport_at: a.teleport_at,
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
        "memory: GPU {:.1} MiB ({} quads), blocks {:.1} MiB ({:.2}x a packed-index palette); wrote {}",
        mib(r.gpu_buffer_bytes),
        r.quads,
        mib(r.chunk_storage_bytes),
        r.chunk_storage_bytes as f64 / r.packed_index_bytes.max(1) as f64,
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

/// Renders one scene with every technique and writes the pictures, error maps and sheet.
fn gallery(a: GalleryArgs, device: &headless::Device) -> Result<()> {
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
fn backends(a: BackendsArgs) -> Result<()> {
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
fn window(a: WindowArgs, device: DeviceArgs) -> Result<()> {
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
        edit: a.edit,
        resize: a.resize,
        // Read before the window opens: a broken file is an error, not an empty window.
        scene: a.scene.as_deref().map(scene::Scene::load).transpose()?,
        game: a.game,
    })
}

/// Without a display: every technique's picture of the default scene, then the
/// speed/accuracy chart of [`QUICK_SCENES`] at [`QUICK_SIZE`] (with `full`, of the whole
/// suite at 480x270), each with a progress bar.
fn showcase(a: ShowcaseArgs, device: &headless::Device) -> Result<()> {
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
    let mut renderer = headless::renderer_for(&ctx, &scene, config)?;
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
