//! CPU cost of ordering a game's translucent objects among the chunks (what the sorted
//! techniques do in `Renderer::render`, reported as `FrameStats::game_sort_ms`),
//! beside a plain `sort_unstable_by` of the same objects' view depths in the same run.
//!
//! The world is a sea: every chunk column within a circle of radius VD chunks around the
//! origin holds sand below y = 0 and water from 0 to 23 (its surface at y = 24), and every
//! third column in x and z a glass dome on the sea floor (a hollow 16 × 10 × 16 box of
//! air). Objects are scattered in the water in front of the camera within the view
//! distance: bubbles (radius 0.1) and one fish in a hundred (radius 1.2, near the domes).
//! The camera hovers 6 blocks above the surface looking along +x, pitched down 0.3 rad.
//! Each frame is waited for on the GPU before the next one is recorded. Medians of
//! `FRAMES` frames; the plain sort is timed as many times on a fresh copy of the depths.
//! Prints a table (and writes it to `results/object-order.md`); asserts nothing about time.
//! `cargo bench -p voxel-lab --bench object_order` (`ORDER_VD=8,16` and
//! `ORDER_OBJECTS=1000,10000` choose rows).

use std::ops::Range;
use std::sync::Arc;
use std::time::Instant;
use voxel_lab::Result;

use glam::DVec3;
use voxel_core::{BlockId, BlockRegistry, Chunk, ChunkPos, World, blocks};
use voxel_lab::headless::{self, Offscreen};

use voxel_render::stages::{GameFrame, Stages};
use voxel_render::{
    Camera, GameStages, GpuContext, NoGame, Renderer, Technique, TranslucentObject,
};

#[path = "common/report.rs"]
mod report;
#[path = "common/setup.rs"]
mod setup;
use report::{Report, list, median};

const W: u32 = 640;
const H: u32 = 360;
const WARMUP: usize = 3;
const FRAMES: usize = 15;
/// The sea's surface: water fills y = 0 to 23.
const SURFACE: i32 = 24;

/// Whether column (cx, cz) holds a dome.
fn dome(cx: i32, cz: i32) -> bool {
    cx.rem_euclid(3) == 1 && cz.rem_euclid(3) == 1
}

/// The sea of radius `vd` chunks, meshed and uploaded into a renderer of `technique`.
fn renderer(ctx: &GpuContext, vd: i32, technique: Technique) -> Result<Renderer> {
    let registry = Arc::new(BlockRegistry::default());
    let mut sea = Chunk::default();
    let mut domed = Chunk::default();
    for x in 0..32 {
        for z in 0..32 {
            for y in 0..SURFACE as usize {
                let _ = sea.set(x, y, z, blocks::WATER);
                let inside = (8..24).contains(&x) && (8..24).contains(&z) && y < 10;
                let shell = inside && (x == 8 || x == 23 || z == 8 || z == 23 || y == 9);
                let id = match (inside, shell) {
                    (_, true) => blocks::GLASS,
                    (true, false) => BlockId::AIR,
                    _ => blocks::WATER,
                };
                let _ = domed.set(x, y, z, id);
            }
        }
    }
    let mut world = World::new(registry.clone());
    let mut positions = Vec::new();
    for cx in -vd..=vd {
        for cz in -vd..=vd {
            if cx * cx + cz * cz > vd * vd {
                continue;
            }
            let floor = ChunkPos::new(cx, -1, cz);
            let water = ChunkPos::new(cx, 0, cz);
            world.insert_chunk(floor, Chunk::uniform(blocks::SAND))?;
            let c = if dome(cx, cz) {
                domed.clone()
            } else {
                sea.clone()
            };
            world.insert_chunk(water, c)?;
            positions.extend([floor, water]);
        }
    }
    setup::renderer_of(ctx, &world, &positions, technique, (W, H))
}

fn camera(vd: i32) -> Result<Camera> {
    let eye = DVec3::new(0.5, f64::from(SURFACE) + 6.0, 0.5);
    let pitch: f64 = -0.3;
    let dir = DVec3::new(pitch.cos(), pitch.sin(), 0.0);
    Camera::look_at(eye, eye + dir, 70.0, 0.1, f64::from(vd) * 32.0 * 1.5)
        .map_err(voxel_lab::Error::Render)
}

/// `n` objects in the water in front of the camera, within the view distance.
fn objects(n: usize, vd: i32) -> Vec<TranslucentObject> {
    let mut next = report::numbers(0x9e37_79b9_7f4a_7c15u64 ^ n as u64);
    let reach = f64::from(vd) * 32.0;
    (0..n)
        .map(|i| {
            let x = 4.0 + next() * (reach - 4.0);
            let z = (next() - 0.5) * 1.4 * x;
            let y = 0.5 + next() * (f64::from(SURFACE) - 1.0);
            if i % 100 == 0 {
                // A fish by the nearest dome.
                let c = |v: f64| ((v / 32.0).floor() / 3.0).floor() * 96.0 + 48.0;
                TranslucentObject::ball(
                    DVec3::new(c(x) + (next() - 0.5) * 30.0, 3.0 + next() * 12.0, c(z)),
                    1.2,
                )
            } else {
                TranslucentObject::ball(DVec3::new(x, y, z), 0.1)
            }
        })
        .collect()
}

/// A game with translucent objects that draws nothing: only their order is measured.
struct Orderer {
    objects: Vec<TranslucentObject>,
    contract: Option<u64>,
}

impl GameStages for Orderer {
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

    fn prepare(&mut self, _: &GpuContext, _: &GameFrame<'_>) {}

    fn translucent(
        &self,
        _: &mut wgpu::RenderPass<'_>,
        _: &GameFrame<'_>,
        _: usize,
        _: Range<usize>,
    ) {
    }
}

/// Median ordering ms and render CPU ms over `FRAMES` frames, and the runs of objects.
fn measure(
    ctx: &GpuContext,
    renderer: &mut Renderer,
    game: &mut Orderer,
    camera: &Camera,
) -> Result<(f64, f64)> {
    let target = Offscreen::new(ctx, W, H);
    game.contract = Some(renderer.translucent_contract()?.id);
    let (mut order, mut cpu) = (Vec::new(), Vec::new());
    for i in 0..WARMUP + FRAMES {
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        let stats = renderer.render(&mut encoder, &target.view, camera, game)?;
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
fn plain_sort(objects: &[TranslucentObject], camera: &Camera) -> f64 {
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
    median(&mut ms[WARMUP..])
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let ctx = headless::context()?;
    let vds = list("ORDER_VD", &[8, 16, 32]);
    let counts = list("ORDER_OBJECTS", &[1_000, 2_000, 10_000, 100_000]);
    let mut out = Report::new("object_order", &ctx.caps.adapter_name, "");
    out.line("| VD | translucent chunks in view | objects | order, sorted-quads ms | order, sorted ms | plain depth sort ms | sorted-quads / plain | render CPU ms (sorted-quads) |");
    out.line("|---:|---:|---:|---:|---:|---:|---:|---:|");
    for &vd in &vds {
        let vd = vd as i32;
        let camera = camera(vd)?;
        let mut quads = renderer(&ctx, vd, Technique::SortedQuads)?;
        let mut chunks = renderer(&ctx, vd, Technique::Sorted)?;
        for &n in &counts {
            let mut game = Orderer {
                objects: objects(n, vd),
                contract: None,
            };
            let (q, cpu) = measure(&ctx, &mut quads, &mut game, &camera)?;
            let (s, _) = measure(&ctx, &mut chunks, &mut game, &camera)?;
            let plain = plain_sort(&game.objects, &camera);
            let visible = {
                let target = Offscreen::new(&ctx, W, H);
                let stats = quads.render_and_submit(&target.view, &camera, &mut NoGame)?;
                stats.meshes_drawn[2]
            };
            out.line(&format!(
                "| {vd} | {visible} | {n} | {q:.3} | {s:.3} | {plain:.3} | {:.2} | {cpu:.3} |",
                q / plain
            ));
        }
    }
    out.write("object-order.md")?;
    Ok(())
}
