//! Streaming at view distances 8, 16, 24 and 32 with both draw paths, from one run: the
//! flight of `demo stream` (4 blocks per frame: one chunk per 8 frames) for each, then a
//! teleport of 10 000 chunks at view distance 16. Prints a table and writes it with every
//! `stream.json` under `target/stream-bench/` (`results/stream-bench.md` is a copy of the
//! table). Prints figures; asserts nothing about time.
//!
//! `cargo bench -p voxel-lab --bench stream` (about 10 minutes on 2 cores with lavapipe).
//! `STREAM_FRAMES` changes the frames per flight (default 240).

use std::fmt::Write as _;
use std::path::PathBuf;
use voxel_lab::Result;

use voxel_lab::headless;
use voxel_lab::stream::{StreamOptions, StreamReport, run};
use voxel_render::DrawMode;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let frames: usize = std::env::var("STREAM_FRAMES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(240);
    let ctx = headless::context()?;
    let out = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../target/stream-bench");
    let mut table = String::new();
    let mib = |b: u64| b as f64 / f64::from(1 << 20);
    let _ = writeln!(
        table,
        "Flight of {frames} frames at 4 blocks per frame (one chunk per 8 frames), 640x360, vertical distance 4, {}; CPU ms per frame (streamer update + recording + submit), medians unless named.\n",
        ctx.caps.adapter_name
    );
    let _ = writeln!(
        table,
        "| view distance | draw | chunks held | on GPU | drawn p50 | draw calls p50 | record ms p50 | record ratio | stream ms p50 | frame ms p50 | p95 | p95/p50 | max | hitches | upload KiB/frame p95 | GPU MiB (quads) | GPU bytes over 8/quad + 64/chunk | blocks MiB | blocks / packed-index |"
    );
    let _ = writeln!(
        table,
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    for vd in [8, 16, 24, 32] {
        let mut reports: Vec<StreamReport> = Vec::new();
        for draw in [DrawMode::PerChunk, DrawMode::Indirect] {
            let opts = StreamOptions {
                view_distance: vd,
                frames,
                draw,
                out: out.join(format!("vd{vd}-{}", draw.name())),
                ..StreamOptions::default()
            };
            eprintln!("view distance {vd}, {} draws", draw.name());
            reports.push(run(&ctx, &opts)?);
        }
        let per_chunk = reports[0].record_ms.p50;
        for r in &reports {
            let bound = 8 * r.quads + 64 * r.chunks_on_gpu as u64;
            let _ = writeln!(
                table,
                "| {} | {} | {} | {} | {:.0} | {:.0} | {:.3} | {:.2} | {:.3} | {:.3} | {:.3} | {:.2} | {:.2} | {} | {:.0} | {:.1} ({:.1}) | {:.1} MiB | {:.1} | {:.2} |",
                r.view_distance,
                r.draw,
                r.chunks_resident,
                r.chunks_on_gpu,
                r.chunks_drawn_p50,
                r.draw_calls_p50,
                r.record_ms.p50,
                r.record_ms.p50 / per_chunk,
                r.stream_ms.p50,
                r.cpu_frame_ms.p50,
                r.cpu_frame_ms.p95,
                r.cpu_frame_ms.p95 / r.cpu_frame_ms.p50,
                r.cpu_frame_ms.max,
                r.hitches,
                r.upload_bytes_per_frame_p95 / 1024.0,
                mib(r.gpu_buffer_bytes),
                mib(r.gpu_quad_bytes),
                mib(r.gpu_buffer_bytes.saturating_sub(bound)),
                mib(r.chunk_storage_bytes),
                r.chunk_storage_bytes as f64 / r.packed_index_bytes.max(1) as f64,
            );
        }
    }
    // A teleport: the eye jumps 10 000 chunks halfway through the flight.
    let opts = StreamOptions {
        view_distance: 16,
        frames,
        teleport_at: Some(frames / 4),
        out: out.join("vd16-teleport"),
        ..StreamOptions::default()
    };
    eprintln!("view distance 16, teleport");
    let r = run(&ctx, &opts)?;
    if let Some(t) = r.teleport {
        let _ = writeln!(
            table,
            "\nTeleport of 10 000 chunks at frame {} (view distance 16, indirect): everything reloaded after {} frames; the longest frame from the jump on took {:.3} ms (streamer update {:.3} ms), against a flight median of {:.3} ms; at most {} chunks unloaded per frame.",
            t.frame,
            t.frames_to_reload
                .map_or("more than the remaining".to_owned(), |n| n.to_string()),
            t.max_cpu_ms,
            t.max_stream_ms,
            r.cpu_frame_ms.p50,
            t.max_unloads
        );
    }
    println!("{table}");
    std::fs::create_dir_all(&out)?;
    std::fs::write(out.join("stream-bench.md"), &table)?;
    Ok(())
}
