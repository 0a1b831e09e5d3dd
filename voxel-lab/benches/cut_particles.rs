//! CPU cost of a frame whose game particles are all cut by `sorted-quads` (issue 52: a
//! million cut particles took 41–49 s a frame), beside a plain `sort_unstable_by` of the
//! same particles' view depths in the same run.
//!
//! The world: a glass floor (its top face at y = 1) and a glass layer above it (y = 4 to 5)
//! over 4 × 4 chunks, grass under them. Every particle (a camera-facing square of half side
//! 0.1, ordered as a ball, as `content` orders particles) is centred within 0.05 of the
//! floor's top face, so it reaches through that plane in a chunk no sound test decides
//! (the layer above is beyond it): `sorted-quads` cuts each into two parts, one drawn before
//! the floor's quads and one after; those across a chunk border are cut there too. The
//! camera looks down through the upper layer at an angle. The game draws nothing (only the
//! order and its draw calls into the pass are measured); each frame is waited for on the
//! GPU before the next one is recorded. Medians of `FRAMES` frames.
//!
//! Prints a table (and writes it to `results/cut-particles.md`): per count of particles the
//! parts drawn and the runs of them (draw calls of the game), the ordering ms and the
//! render CPU ms (ordering included), each also per million parts, and the plain sort;
//! asserts nothing about time. `cargo bench -p voxel-lab --bench cut_particles`
//! (`CUT_PARTICLES=10000,1000000` chooses rows).

use std::cell::Cell;
use std::ops::Range;
use std::sync::Arc;
use std::time::Instant;

use glam::DVec3;
use voxel_core::{BlockRegistry, Chunk, ChunkPos, World, blocks};
use voxel_lab::Result;
use voxel_lab::headless::{self, Offscreen};
use voxel_render::stages::{GameFrame, Stages};
use voxel_render::{Camera, GameStages, GpuContext, Renderer, Technique, TranslucentObject};

#[path = "common/report.rs"]
mod report;
#[path = "common/setup.rs"]
mod setup;
use report::{Report, list, median};

const W: u32 = 640;
const H: u32 = 360;
const WARMUP: usize = 2;
const FRAMES: usize = 5;
/// Half side of a particle, blocks.
const HALF: f64 = 0.1;

/// The two glass layers over chunks x, z in -2..=1, meshed and uploaded.
fn renderer(ctx: &GpuContext) -> Result<Renderer> {
    let registry = Arc::new(BlockRegistry::default());
    let mut layers = Chunk::default();
    for x in 0..32 {
        for z in 0..32 {
            let _ = layers.set(x, 0, z, blocks::GLASS);
            let _ = layers.set(x, 4, z, blocks::GLASS);
        }
    }
    let mut world = World::new(registry);
    let mut positions = Vec::new();
    for cx in -2..=1 {
        for cz in -2..=1 {
            let (floor, glass) = (ChunkPos::new(cx, -1, cz), ChunkPos::new(cx, 0, cz));
            world.insert_chunk(floor, Chunk::uniform(blocks::GRASS))?;
            world.insert_chunk(glass, layers.clone())?;
            positions.extend([floor, glass]);
        }
    }
    setup::renderer_of(ctx, &world, &positions, Technique::SortedQuads, (W, H))
}

fn camera() -> Result<Camera> {
    let eye = DVec3::new(0.5, 30.0, 45.0);
    Camera::look_at(eye, DVec3::new(0.0, 0.0, -15.0), 70.0, 0.1, 500.0)
        .map_err(voxel_lab::Error::Render)
}

/// `n` particles through the floor's top face (y = 1), in view.
fn particles(n: usize) -> Vec<TranslucentObject> {
    let mut next = report::numbers(0x51ed_2701_f00d_cafe ^ n as u64);
    (0..n)
        .map(|_| {
            let c = DVec3::new(
                -40.0 + 80.0 * next(),
                0.95 + 0.1 * next(),
                -55.0 + 80.0 * next(),
            );
            TranslucentObject::ball(c, HALF * std::f64::consts::SQRT_2)
        })
        .collect()
}

/// A game of particles that draws nothing: counts the runs it is asked to draw and the
/// positions in them.
struct Particles {
    objects: Vec<TranslucentObject>,
    contract: Option<u64>,
    runs: Cell<usize>,
    drawn: Cell<usize>,
    order_len: usize,
}

impl GameStages for Particles {
    fn stages(&self) -> Stages {
        Stages {
            translucent: true,
            ..Stages::default()
        }
    }

    fn translucent_objects(&self) -> &[TranslucentObject] {
        &self.objects
    }

    fn translucent_contract_id(&self) -> Option<u64> {
        self.contract
    }

    fn prepare(&mut self, _: &GpuContext, frame: &GameFrame<'_>) {
        self.order_len = frame.order.map_or(0, <[u32]>::len);
        self.runs.set(0);
        self.drawn.set(0);
    }

    fn translucent(
        &self,
        _: &mut wgpu::RenderPass<'_>,
        _: &GameFrame<'_>,
        _: usize,
        objects: Range<usize>,
    ) {
        self.runs.set(self.runs.get() + 1);
        self.drawn.set(self.drawn.get() + objects.len());
    }
}

/// Median ordering ms and render CPU ms over `FRAMES` frames.
fn measure(ctx: &GpuContext, renderer: &mut Renderer, game: &mut Particles) -> Result<(f64, f64)> {
    let camera = camera()?;
    let target = Offscreen::new(ctx, W, H);
    game.contract = Some(renderer.translucent_contract()?.id);
    let (mut order, mut cpu) = (Vec::new(), Vec::new());
    for i in 0..WARMUP + FRAMES {
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        let stats = renderer.render(&mut encoder, &target.view, &camera, game)?;
        ctx.queue.submit([encoder.finish()]);
        let _ = ctx.device.poll(wgpu::PollType::wait_indefinitely());
        if i >= WARMUP {
            order.push(stats.game_sort_ms);
            cpu.push(stats.cpu_ms);
        }
    }
    Ok((median(&mut order), median(&mut cpu)))
}

/// Median ms of a plain `sort_unstable_by` of the objects' view depths.
fn plain_sort(objects: &[TranslucentObject]) -> Result<f64> {
    let camera = camera()?;
    let f = camera.unit_forward();
    let depths: Vec<(f64, u32)> = objects
        .iter()
        .enumerate()
        .map(|(i, o)| ((o.center - camera.eye).dot(f), i as u32))
        .collect();
    let mut ms = Vec::new();
    for _ in 0..WARMUP + FRAMES {
        let mut v = depths.clone();
        let start = Instant::now();
        v.sort_unstable_by(|a, b| b.0.total_cmp(&a.0));
        ms.push(start.elapsed().as_secs_f64() * 1e3);
        std::hint::black_box(&v);
    }
    Ok(median(&mut ms[WARMUP..]))
}

fn main() -> std::result::Result<(), Box<dyn std::error::Error>> {
    let ctx = headless::context()?;
    let counts = list("CUT_PARTICLES", &[10_000, 100_000, 1_000_000]);
    let mut out = Report::new("cut_particles", &ctx.caps.adapter_name, "");
    out.line("| particles | order length | parts drawn | runs drawn | order ms | order ms per million parts | render CPU ms | render CPU ms per million parts | plain depth sort ms | order / plain |");
    out.line("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    let mut renderer = renderer(&ctx)?;
    for &n in &counts {
        let mut game = Particles {
            objects: particles(n),
            contract: None,
            runs: Cell::new(0),
            drawn: Cell::new(0),
            order_len: 0,
        };
        let (order, cpu) = measure(&ctx, &mut renderer, &mut game)?;
        let plain = plain_sort(&game.objects)?;
        let parts = game.drawn.get();
        let per_million = |ms: f64| ms * 1e6 / parts.max(1) as f64;
        out.line(&format!(
            "| {n} | {} | {parts} | {} | {order:.1} | {:.0} | {cpu:.1} | {:.0} | {plain:.1} | {:.1} |",
            game.order_len,
            game.runs.get(),
            per_million(order),
            per_million(cpu),
            order / plain
        ));
    }
    out.write("cut-particles.md")?;
    Ok(())
}
