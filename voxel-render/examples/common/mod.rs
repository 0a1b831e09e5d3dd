//! What the headless game examples share: their command line, the game's own device, the
//! pool they look into, where the game's things move, and the picture they save. Each
//! example is its own way of drawing the game's things; this is the stage around them.

use std::sync::Arc;

use glam::{DQuat, DVec3};
use voxel_core::{BlockRegistry, World, WorldPos, blocks};
use voxel_render::{Camera, GpuContext, Renderer, RendererConfig, Technique, stages};

/// The picture's size.
pub const SIZE: (u32, u32) = (640, 360);

/// `--frames N` (default 60), `--out FILE` and `--technique NAME` (default `wboit-mrt`).
pub struct Args {
    pub frames: u32,
    pub out: String,
    pub technique: Technique,
}

impl Args {
    /// The command line; `out` is the picture's name without `--out`.
    pub fn parse(out: &str) -> Result<Self, Box<dyn std::error::Error>> {
        let args: Vec<String> = std::env::args().collect();
        let arg = |name: &str| {
            args.iter()
                .position(|a| a == name)
                .and_then(|i| args.get(i + 1).cloned())
        };
        Ok(Self {
            frames: arg("--frames").map_or(Ok(60), |v| v.parse())?.max(1),
            out: arg("--out").unwrap_or_else(|| out.into()),
            technique: match arg("--technique") {
                Some(name) => name.parse::<Technique>()?,
                None => Technique::WboitMrt,
            },
        })
    }
}

/// The game's own device (the renderer draws with whatever device the game has).
pub fn game_device() -> Result<GpuContext, Box<dyn std::error::Error>> {
    // On the backend `WGPU_BACKEND` names (else wgpu's choice), without wgpu's indirect-call
    // validation on GL (`voxel_render::instance_descriptor`).
    let backends = wgpu::Backends::from_env().unwrap_or(wgpu::Backends::all());
    let instance = wgpu::Instance::new(voxel_render::instance_descriptor(backends));
    let adapter = pollster::block_on(instance.request_adapter(&Default::default()))?;
    let (device, queue) = pollster::block_on(voxel_render::request_device(&adapter))?;
    Ok(GpuContext::from_device(&adapter, device, queue))
}

/// A pool of water on sand, walled with stone, a glass wall across one end, meshed into a
/// renderer drawing with `technique`; the game's output texture; the camera looking in.
pub fn pool(
    ctx: &GpuContext,
    technique: Technique,
) -> Result<(Renderer, stages::Target, Camera), Box<dyn std::error::Error>> {
    let mut world = World::new(Arc::new(BlockRegistry::default()));
    for (a, b, id) in [
        ([-10, -8, -10], [10, -8, 10], blocks::SAND),
        ([-11, -8, -11], [11, 0, -11], blocks::STONE),
        ([-11, -8, -11], [-11, 0, 11], blocks::STONE),
        ([11, -8, -11], [11, 0, 11], blocks::STONE),
        ([-10, -7, -10], [10, -1, 10], blocks::WATER),
        ([-10, 0, -10], [10, 3, -10], blocks::GLASS),
    ] {
        let pos = |p: [i32; 3]| WorldPos::new(p[0], p[1], p[2]);
        world.fill_box(pos(a), pos(b), id)?;
    }
    let mut config = RendererConfig {
        width: SIZE.0,
        height: SIZE.1,
        ..RendererConfig::default()
    };
    config.oit.technique = technique;
    let mut renderer = Renderer::new(ctx, world.registry(), config)?;
    for (pos, meshes) in voxel_mesh::mesh_dirty(&mut world)? {
        renderer.upload_chunk(pos, &meshes)?;
    }
    let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
    let format = wgpu::TextureFormat::Rgba8UnormSrgb;
    let output = stages::target(&ctx.device, "game_output", format, usage, SIZE);
    let eye = DVec3::new(1.0, 7.0, 17.0);
    let camera = Camera::look_at(eye, DVec3::new(0.0, -2.0, -2.0), 70.0, 0.1, 300.0)?;
    Ok((renderer, output, camera))
}

/// The crate's centre at `t` seconds: bobbing, half in the water.
pub fn crate_center(t: f64) -> DVec3 {
    DVec3::new(-3.0, 0.1 + 0.08 * (t * 1.7).sin(), 1.0)
}

/// The glass cube's centre and turn at `t` seconds: through the water surface.
pub fn cube_pose(t: f64) -> (DVec3, DQuat) {
    let turn = DQuat::from_euler(glam::EulerRot::YXZ, t * 0.7, 0.6, 0.2);
    (DVec3::new(2.5, 0.2 * (t * 0.9).sin(), -1.0), turn)
}

/// Bubble `i`'s centre and half size at `t` seconds: a fixed scatter (a hash of the
/// index) and a rise that wraps at the surface.
pub fn bubble(i: u64, t: f64) -> (DVec3, f64) {
    let h = |k: u64| {
        let mut z = (i << 8 | k).wrapping_mul(0x9e37_79b9_7f4a_7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        (z ^ (z >> 31)) as f64 / u64::MAX as f64
    };
    let rise = (h(1) * 6.0 + t * (0.5 + h(2))).rem_euclid(6.0);
    let center = DVec3::new(h(3) * 10.0 - 5.0, rise - 6.0, h(4) * 8.0 - 4.0);
    (center, 0.08 + 0.1 * h(5))
}

/// Reads the game's output back, saves it where `args` says and says so, naming `what`
/// was drawn.
pub fn save(
    ctx: &GpuContext,
    output: &stages::Target,
    args: &Args,
    what: &str,
) -> voxel_render::Result<()> {
    let rgba = voxel_render::readback::read_texture(ctx, &output.texture, 4)?;
    let (width, height) = SIZE;
    let image = voxel_render::Image {
        width,
        height,
        rgba,
    };
    image.save_png(std::path::Path::new(&args.out))?;
    let (out, frames, technique) = (&args.out, args.frames, args.technique.name());
    println!("wrote {out}: {frames} frames of {technique} {what}");
    Ok(())
}
