//! CPU cost of recording a frame (`Renderer::render`: culling, draw lists, the indirect
//! buffer's upload, pass recording; not GPU time) against the view distance, with indirect
//! draws (one `multi_draw_indirect` per page run) and with one draw per chunk mesh.
//!
//! For each view distance VD the world is the generated terrain (default
//! [`TerrainConfig`], seed 1) of every chunk column within a circle of radius VD chunks
//! around the origin chunk, chunk layers y = -2 to 3 (the ground lies in layers 0 and 1,
//! stone fills everything below, air everything above; empty chunks are not uploaded). The
//! camera hovers 40 blocks above the ground at the origin, looking along +x pitched down
//! 0.25 rad, far plane VD × 32 × 1.5 blocks. Each frame is waited for on the GPU before the
//! next one is recorded, so that lavapipe's rasterising threads do not share the CPU with
//! the recording; the two modes alternate frame by frame so that drift of the shared
//! machine hits both alike. Prints figures (and writes them to
//! `results/record-bench.txt`); asserts nothing about time.
//! `cargo bench -p voxel-lab --bench record`.

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use voxel_lab::headless::{self, Offscreen};
use voxel_render::{DrawMode, FrameStats, GpuContext, NoGame, Technique};

/// A bench's errors: the lab's, wgpu's, and its own messages.
type Result<T, E = Box<dyn std::error::Error>> = std::result::Result<T, E>;

#[path = "common/record_world.rs"]
mod record_world;
use record_world::{H, LAYERS, SEED, W, camera, renderer};

const WARMUP: usize = 4;
/// Frames measured per mode (RECORD_FRAMES overrides, for profiling).
fn frames() -> usize {
    std::env::var("RECORD_FRAMES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(40)
}
fn percentile(v: &[f64], p: f64) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * p).round() as usize]
}

/// One row: what a frame drew, and the CPU ms of each mode.
struct Row {
    label: String,
    chunks: usize,
    stats: [FrameStats; 2],
    ms: [Vec<f64>; 2],
    /// `render` plus the encoder's `finish`.
    finish_ms: [Vec<f64>; 2],
}

const MODES: [DrawMode; 2] = [DrawMode::Indirect, DrawMode::PerChunk];

fn measure(ctx: &GpuContext, vd: i32, technique: Technique) -> Result<Row> {
    let mut renderer = renderer(ctx, vd, technique)?;
    let target = Offscreen::new(ctx, W, H);
    let camera = camera(vd)?;
    renderer.set_draw_mode(DrawMode::Indirect);
    if renderer.config().draw != DrawMode::Indirect {
        // The adapter lacks indirect first-instance draws.
        return Err("this adapter cannot draw indirect; nothing to compare".into());
    }
    let mut ms: [Vec<f64>; 2] = Default::default();
    let mut finish_ms: [Vec<f64>; 2] = Default::default();
    let mut stats: [FrameStats; 2] = Default::default();
    for i in 0..WARMUP + frames() {
        // ABBA order: neither mode always follows the other.
        let order = if i % 2 == 0 { [0, 1] } else { [1, 0] };
        for m in order {
            renderer.set_draw_mode(MODES[m]);
            // What `render_and_submit` does, with `finish` timed: wgpu 30 records a pass
            // as a list of commands and validates and encodes them (one by one) only when
            // the encoder is finished.
            let mut encoder = ctx
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
            let s = renderer.render(&mut encoder, &target.view, &camera, &mut NoGame)?;
            let t = Instant::now();
            let commands = encoder.finish();
            let finish = t.elapsed().as_secs_f64() * 1e3;
            ctx.queue.submit([commands]);
            ctx.device.poll(wgpu::PollType::wait_indefinitely())?;
            if i >= WARMUP {
                ms[m].push(s.cpu_ms);
                finish_ms[m].push(s.cpu_ms + finish);
            }
            stats[m] = s;
        }
    }
    Ok(Row {
        label: format!("{vd} {technique}"),
        chunks: voxel_render::low_level::chunks(&renderer).len(),
        stats,
        ms,
        finish_ms,
    })
}

fn main() -> Result<()> {
    let ctx = headless::context()?;
    let mut out = String::new();
    writeln!(
        out,
        "# Frame recording CPU time (cargo bench -p voxel-lab --bench record)\n\
         {} at {W}x{H}; terrain seed {SEED}, chunk columns within a circle of radius VD chunks, layers y {}..={}; \
         camera 40 blocks above the ground at the origin looking along +x pitched down 0.25 rad, fov 70, far VD*48 blocks.\n\
         CPU ms = FrameStats::cpu_ms (Renderer::render only), median (p95) of {} frames per mode after {WARMUP} warm-up frames, modes interleaved; \
         meshes = opaque / cutout / translucent; calls = draw calls of the chunk lists; \
         +finish = render plus CommandEncoder::finish, where wgpu 30 validates and encodes the passes' commands (each draw) for the driver.\n",
        ctx.caps.adapter_name,
        LAYERS.start(),
        LAYERS.end(),
        frames()
    )?;
    writeln!(
        out,
        "| VD technique | chunks | meshes | calls indirect | calls per-chunk | CPU ms indirect | CPU ms per-chunk | indirect / per-chunk | +finish indirect | +finish per-chunk | ratio +finish |\n|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|"
    )?;
    print!("{out}");
    // RECORD_VD=32 (a comma list) runs only those view distances (for profiling).
    let only: Option<Vec<i32>> = std::env::var("RECORD_VD")
        .ok()
        .map(|v| v.split(',').filter_map(|x| x.trim().parse().ok()).collect());
    let runs = [8, 16, 24, 32]
        .map(|vd| (vd, Technique::WboitMrt))
        .into_iter()
        .chain([
            (16, Technique::SortedQuads),
            (32, Technique::SortedQuads),
            (32, Technique::Sorted),
        ])
        .filter(|(vd, _)| only.as_ref().is_none_or(|o| o.contains(vd)));
    for (vd, technique) in runs {
        let r = measure(&ctx, vd, technique)?;
        let [i, p] = &r.ms;
        let [fi, fp] = &r.finish_ms;
        let m = r.stats[0].meshes_drawn;
        let line = format!(
            "| {} | {} | {} / {} / {} | {} | {} | {:.3} ({:.3}) | {:.3} ({:.3}) | {:.3} | {:.3} ({:.3}) | {:.3} ({:.3}) | {:.3} |",
            r.label,
            r.chunks,
            m[0],
            m[1],
            m[2],
            r.stats[0].draw_calls,
            r.stats[1].draw_calls,
            percentile(i, 0.5),
            percentile(i, 0.95),
            percentile(p, 0.5),
            percentile(p, 0.95),
            percentile(i, 0.5) / percentile(p, 0.5),
            percentile(fi, 0.5),
            percentile(fi, 0.95),
            percentile(fp, 0.5),
            percentile(fp, 0.95),
            percentile(fi, 0.5) / percentile(fp, 0.5),
        );
        println!("{line}");
        writeln!(out, "{line}")?;
    }
    if only.is_some() {
        return Ok(());
    }
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../results/record-bench.txt");
    std::fs::write(&path, out).map_err(voxel_lab::Error::io(&path))?;
    println!("written to {}", path.display());
    Ok(())
}
