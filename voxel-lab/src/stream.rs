//! The streaming run: a fixed flight over generated terrain with a [`ChunkStreamer`]
//! feeding the renderer, measuring per frame the CPU time of streaming and recording, the
//! GPU time, the uploads, and the memory the chunks take (`demo stream`).
//!
//! The eye starts 40 blocks above the ground at the origin, looks along +x pitched 0.25
//! rad down, and flies along +x at a constant height. Before the first frame the view
//! distance is loaded until the streamer is idle (`prefill_ms`), so that the frames measure
//! the steady streaming of a flight, not the first load.

use crate::{Error, Result};

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use glam::DVec3;
use serde::Serialize;
use voxel_core::{BlockRegistry, TerrainConfig, TerrainGenerator};
use voxel_render::low_level::MAX_VIEW_DISTANCE;
use voxel_render::{
    Camera, ChunkStreamer, DrawMode, GpuContext, NoGame, Renderer, RendererConfig, StreamConfig,
};

use crate::charts::{self, Series};
use crate::headless::Offscreen;
use crate::progress::Progress;
use crate::summary::write_json;

/// What `demo stream` runs.
#[derive(Clone, Debug)]
pub struct StreamOptions {
    /// Horizontal view distance in chunks (1 to [`MAX_VIEW_DISTANCE`]).
    pub view_distance: u32,
    /// Vertical view distance in chunks (0 to [`MAX_VIEW_DISTANCE`]).
    pub vertical_distance: u32,
    /// Frames flown (and measured), at least 1.
    pub frames: usize,
    /// Blocks flown per frame (0 hovers; at most 1024).
    pub speed: f64,
    /// How chunk meshes are drawn.
    pub draw: DrawMode,
    /// Picture size.
    pub size: (u32, u32),
    /// Terrain seed.
    pub seed: u32,
    /// At this frame the eye jumps 10 000 chunks (along +z) and flies on from there.
    pub teleport_at: Option<usize>,
    /// Chunks lit as they stream ([`ChunkStreamer::set_light`]), with the light
    /// sources' registry.
    pub light: bool,
    /// Output folder.
    pub out: PathBuf,
}

/// How far a teleport jumps, in chunks.
pub const TELEPORT_CHUNKS: f64 = 10_000.0;

impl Default for StreamOptions {
    fn default() -> Self {
        Self {
            view_distance: 8,
            vertical_distance: 4,
            frames: 600,
            speed: 4.0,
            draw: DrawMode::Indirect,
            size: (640, 360),
            seed: 1,
            teleport_at: None,
            light: false,
            out: PathBuf::from("stream-out"),
        }
    }
}

impl StreamOptions {
    /// Checks the options a user gives (the streamer checks its own configuration too).
    pub fn validate(&self) -> Result<()> {
        if !(1..=MAX_VIEW_DISTANCE).contains(&self.view_distance) {
            return Err(Error::option(
                "--view-distance",
                format!(
                    "{}: it must be from 1 to {MAX_VIEW_DISTANCE}",
                    self.view_distance
                ),
            ));
        }
        if self.vertical_distance > MAX_VIEW_DISTANCE {
            return Err(Error::option(
                "vertical distance",
                format!(
                    "{}: it must be from 0 to {MAX_VIEW_DISTANCE}",
                    self.vertical_distance
                ),
            ));
        }
        if self.frames == 0 {
            return Err(Error::option("--frames", "must be at least 1"));
        }
        if let Some(t) = self.teleport_at
            && t >= self.frames
        {
            return Err(Error::option(
                "--teleport-at",
                format!(
                    "{t}: it must be a frame of the flight (0 to {})",
                    self.frames - 1
                ),
            ));
        }
        if !(self.speed.is_finite() && (0.0..=1024.0).contains(&self.speed)) {
            return Err(Error::option(
                "--speed",
                format!("{}: it must be from 0 to 1024 blocks per frame", self.speed),
            ));
        }
        Ok(())
    }
}

/// Median, 95th percentile and largest value.
#[derive(Clone, Copy, Debug, Default, Serialize, PartialEq)]
pub struct Spread {
    /// Median.
    pub p50: f64,
    /// 95th percentile (nearest rank).
    pub p95: f64,
    /// Largest.
    pub max: f64,
}

impl Spread {
    /// Of `values` (all zero when empty).
    pub fn of(values: &[f64]) -> Self {
        if values.is_empty() {
            return Self::default();
        }
        let mut v = values.to_vec();
        v.sort_by(f64::total_cmp);
        let at = |p: f64| v[((v.len() - 1) as f64 * p).round() as usize];
        Self {
            p50: at(0.5),
            p95: at(0.95),
            max: v[v.len() - 1],
        }
    }
}

/// One frame of the flight.
#[derive(Clone, Copy, Debug, Default, Serialize, PartialEq)]
pub struct StreamFrameRecord {
    /// CPU ms of the frame: streaming, recording and submitting.
    pub cpu_ms: f64,
    /// CPU ms of [`ChunkStreamer::update`].
    pub stream_ms: f64,
    /// CPU ms of [`Renderer::render`] (recording).
    pub record_ms: f64,
    /// CPU ms of submitting the frame.
    pub submit_ms: f64,
    /// GPU ms of the frame's passes, when timed.
    pub gpu_ms: Option<f64>,
    /// Bytes of quads uploaded.
    pub upload_bytes: u64,
    /// Chunks uploaded.
    pub uploads: usize,
    /// Chunks unloaded.
    pub unloads: usize,
    /// Chunks drawn (with at least one mesh in view).
    pub chunks_drawn: usize,
    /// Whether the streamer had everything within the view distance drawn.
    pub idle: bool,
    /// Draw calls recorded.
    pub draw_calls: usize,
}

/// What `demo stream` writes to `stream.json`.
#[derive(Clone, Debug, Serialize)]
pub struct StreamReport {
    /// Adapter.
    pub adapter: String,
    /// Whether chunks were lit as they streamed.
    pub light: bool,
    /// Bytes of the light of the resident chunks at the end (0 without light).
    pub light_bytes: u64,
    /// Meshes made per chunk meshed (at the end): above 1 where chunks were meshed again
    /// (light that changed as neighbours came in, chunks that unloaded and came back).
    pub meshes_per_chunk: f64,
    /// Horizontal view distance in chunks.
    pub view_distance: u32,
    /// Vertical view distance in chunks.
    pub vertical_distance: u32,
    /// Frames flown.
    pub frames: usize,
    /// Blocks per frame.
    pub speed: f64,
    /// `indirect` or `per-chunk` (what the adapter allowed).
    pub draw: String,
    /// Picture size.
    pub size: (u32, u32),
    /// Milliseconds to load the view distance before the first frame.
    pub prefill_ms: f64,
    /// Chunks held in memory at the end (uniform air is not stored).
    pub chunks_resident: usize,
    /// Chunks on the GPU at the end.
    pub chunks_on_gpu: usize,
    /// Median of chunks drawn per frame.
    pub chunks_drawn_p50: f64,
    /// Median of draw calls per frame.
    pub draw_calls_p50: f64,
    /// CPU ms per frame: streaming, recording and submitting.
    pub cpu_frame_ms: Spread,
    /// Of that, the streamer's update.
    pub stream_ms: Spread,
    /// Of that, recording the frame ([`Renderer::render`]).
    pub record_ms: Spread,
    /// Of that, submitting it.
    pub submit_ms: Spread,
    /// Median GPU ms per frame (`null` without timestamp queries).
    pub gpu_frame_ms_p50: Option<f64>,
    /// 95th percentile of quad bytes uploaded per frame.
    pub upload_bytes_per_frame_p95: f64,
    /// GPU bytes of the chunks: quad arena pages, chunk records, indirect commands.
    pub gpu_buffer_bytes: u64,
    /// Of the arena, bytes holding quads.
    pub gpu_quad_bytes: u64,
    /// Quads on the GPU (8 bytes each).
    pub quads: u64,
    /// Bytes of the chunks' blocks in memory (resident, and edited ones unloaded).
    pub chunk_storage_bytes: u64,
    /// What the same chunks would take as packed-index palettes.
    pub packed_index_bytes: u64,
    /// Resident set of the process (Linux; `null` elsewhere).
    pub rss_bytes: Option<u64>,
    /// Frames whose CPU time is over twice the median.
    pub hitches: usize,
    /// Chunks the streamer could not mesh or upload.
    pub failed: usize,
    /// With a teleport: what followed it.
    pub teleport: Option<TeleportReport>,
}

/// What followed a teleport of [`TELEPORT_CHUNKS`].
#[derive(Clone, Copy, Debug, Serialize, PartialEq)]
pub struct TeleportReport {
    /// The frame of the jump.
    pub frame: usize,
    /// Frames until the new view distance was drawn and the old one gone (`null`: not
    /// within the flight).
    pub frames_to_reload: Option<usize>,
    /// The longest frame from the jump on (CPU ms).
    pub max_cpu_ms: f64,
    /// The longest streamer update from the jump on (CPU ms).
    pub max_stream_ms: f64,
    /// The most chunks unloaded in one frame.
    pub max_unloads: usize,
}

/// Resident set size of this process, from `/proc/self/statm` (Linux).
pub fn rss_bytes() -> Option<u64> {
    let statm = std::fs::read_to_string("/proc/self/statm").ok()?;
    let pages: u64 = statm.split_whitespace().nth(1)?.parse().ok()?;
    // The page size of every Linux target we run on.
    Some(pages * 4096)
}

/// The eye at `frame`: 40 blocks above the ground at the origin, flying along +x.
fn camera_at(generator: &TerrainGenerator, opts: &StreamOptions, frame: usize) -> Result<Camera> {
    let y = generator.height_at(0, 0) as f64 + 40.0;
    let z = match opts.teleport_at {
        Some(t) if frame >= t => TELEPORT_CHUNKS * 32.0,
        _ => 0.0,
    };
    let eye = DVec3::new(0.5 + opts.speed * frame as f64, y, 0.5 + z);
    let far = (f64::from(opts.view_distance) * 32.0 * 1.5).max(200.0);
    Camera::from_yaw_pitch(eye, std::f64::consts::FRAC_PI_2, -0.25, 70.0, 0.1, far)
        .map_err(Error::Render)
}

/// Flies `opts` and writes `stream.json`, `frames.json` and the `cpu_ms` chart into
/// `opts.out`.
pub fn run(ctx: &GpuContext, opts: &StreamOptions) -> Result<StreamReport> {
    opts.validate()?;
    std::fs::create_dir_all(&opts.out).map_err(Error::io(&opts.out))?;
    let registry = Arc::new(if opts.light {
        BlockRegistry::with_lights()
    } else {
        BlockRegistry::default()
    });
    let generator = TerrainGenerator::new(TerrainConfig {
        seed: opts.seed,
        ..TerrainConfig::default()
    });
    let config = StreamConfig {
        view_distance: opts.view_distance,
        vertical_distance: opts.vertical_distance,
        ..StreamConfig::default()
    };
    let mut streamer = ChunkStreamer::new(registry.clone(), generator.clone(), config)?;
    streamer.set_light(opts.light);
    let (w, h) = opts.size;
    let mut renderer = Renderer::new(
        ctx,
        &registry,
        RendererConfig {
            width: w,
            height: h,
            draw: opts.draw,
            ..RendererConfig::default()
        },
    )?;
    let target = Offscreen::new(ctx, w, h);
    let mut failed = 0;

    // The first load, untimed per frame.
    let start = Instant::now();
    let first = camera_at(&generator, opts, 0)?;
    let (mut meshed, mut chunks_meshed) = (0, std::collections::HashSet::new());
    while !streamer.is_idle() {
        let f = streamer.update(first.eye, &mut renderer)?;
        failed += f.failed.len();
        meshed += f.uploaded.len();
        chunks_meshed.extend(f.uploaded.iter().copied());
        std::thread::sleep(std::time::Duration::from_micros(500));
    }
    let prefill_ms = start.elapsed().as_secs_f64() * 1e3;

    let mut progress = Progress::new(opts.frames);
    let mut records = Vec::with_capacity(opts.frames);
    for i in 0..opts.frames {
        let camera = camera_at(&generator, opts, i)?;
        let t0 = Instant::now();
        let f = streamer.update(camera.eye, &mut renderer)?;
        let stream_ms = t0.elapsed().as_secs_f64() * 1e3;
        failed += f.failed.len();
        meshed += f.uploaded.len();
        chunks_meshed.extend(f.uploaded.iter().copied());
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("stream_frame"),
            });
        let stats = renderer.render(&mut encoder, &target.view, &camera, &mut NoGame)?;
        let t1 = Instant::now();
        ctx.queue.submit([encoder.finish()]);
        let submit_ms = t1.elapsed().as_secs_f64() * 1e3;
        let cpu_ms = t0.elapsed().as_secs_f64() * 1e3;
        // Wait for the GPU outside the timed part, so frames do not pile up.
        let times = renderer.gpu_times_blocking();
        let gpu_ms = (!times.is_empty()).then(|| times.iter().map(|(_, ms)| ms).sum());
        records.push(StreamFrameRecord {
            cpu_ms,
            stream_ms,
            record_ms: stats.cpu_ms,
            submit_ms,
            gpu_ms,
            upload_bytes: f.upload_bytes,
            uploads: f.uploads,
            unloads: f.unloads,
            chunks_drawn: stats.meshes_drawn.iter().copied().max().unwrap_or(0),
            idle: streamer.is_idle(),
            draw_calls: stats.draw_calls,
        });
        progress.step(&format!("frame {i}"));
    }
    progress.finish();

    let col = |f: fn(&StreamFrameRecord) -> f64| records.iter().map(f).collect::<Vec<f64>>();
    let cpu = col(|r| r.cpu_ms);
    let cpu_spread = Spread::of(&cpu);
    let gpu: Vec<f64> = records.iter().filter_map(|r| r.gpu_ms).collect();
    let memory = renderer.chunk_memory();
    let world = streamer.world();
    let report = StreamReport {
        adapter: ctx.caps.adapter_name.clone(),
        light: opts.light,
        light_bytes: streamer.light_bytes() as u64,
        meshes_per_chunk: meshed as f64 / chunks_meshed.len().max(1) as f64,
        view_distance: opts.view_distance,
        vertical_distance: opts.vertical_distance,
        frames: opts.frames,
        speed: opts.speed,
        draw: renderer.config().draw.name().to_owned(),
        size: opts.size,
        prefill_ms,
        chunks_resident: world.len(),
        chunks_on_gpu: voxel_render::low_level::chunks(&renderer).len(),
        chunks_drawn_p50: Spread::of(&col(|r| r.chunks_drawn as f64)).p50,
        draw_calls_p50: Spread::of(&col(|r| r.draw_calls as f64)).p50,
        cpu_frame_ms: cpu_spread,
        stream_ms: Spread::of(&col(|r| r.stream_ms)),
        record_ms: Spread::of(&col(|r| r.record_ms)),
        submit_ms: Spread::of(&col(|r| r.submit_ms)),
        gpu_frame_ms_p50: (!gpu.is_empty()).then(|| Spread::of(&gpu).p50),
        upload_bytes_per_frame_p95: Spread::of(&col(|r| r.upload_bytes as f64)).p95,
        gpu_buffer_bytes: memory.arena_bytes
            + memory.record_bytes
            + memory.indirect_bytes
            + memory.light_bytes,
        gpu_quad_bytes: memory.quad_bytes,
        quads: memory.quad_bytes / voxel_render::low_level::QUAD_BYTES,
        chunk_storage_bytes: streamer.memory_bytes() as u64,
        packed_index_bytes: world.packed_index_bytes() as u64,
        rss_bytes: rss_bytes(),
        hitches: cpu.iter().filter(|&&c| c > 2.0 * cpu_spread.p50).count(),
        failed,
        teleport: opts.teleport_at.map(|t| {
            let after = &records[t..];
            TeleportReport {
                frame: t,
                frames_to_reload: after.iter().position(|r| r.idle).map(|n| n + 1),
                max_cpu_ms: after.iter().map(|r| r.cpu_ms).fold(0.0, f64::max),
                max_stream_ms: after.iter().map(|r| r.stream_ms).fold(0.0, f64::max),
                max_unloads: after.iter().map(|r| r.unloads).max().unwrap_or(0),
            }
        }),
    };
    write_json(&opts.out.join("stream.json"), &report)?;
    write_json(&opts.out.join("frames.json"), &records)?;
    chart(&opts.out.join("cpu_ms"), &report, &records)?;
    Ok(report)
}

/// CPU ms per frame over the flight: the whole frame, the streamer and the recording.
fn chart(path: &Path, report: &StreamReport, records: &[StreamFrameRecord]) -> Result<()> {
    let line = |name: &str, f: fn(&StreamFrameRecord) -> f64| Series {
        name: name.to_owned(),
        points: records
            .iter()
            .enumerate()
            .map(|(i, r)| (i as f64, f(r)))
            .collect(),
    };
    charts::line_chart(
        path,
        &format!(
            "CPU per frame, view distance {}, {} draws, {} blocks/frame ({})",
            report.view_distance, report.draw, report.speed, report.adapter
        ),
        ("frame", "CPU ms"),
        false,
        &[
            line("frame (stream + record + submit)", |r| r.cpu_ms),
            line("streamer update", |r| r.stream_ms),
            line("record (Renderer::render)", |r| r.record_ms),
            line("submit", |r| r.submit_ms),
        ],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_is_nearest_rank() {
        let v: Vec<f64> = (1..=100).map(f64::from).collect();
        let s = Spread::of(&v);
        assert_eq!((s.p50, s.p95, s.max), (51.0, 95.0, 100.0));
        assert_eq!(Spread::of(&[]), Spread::default());
    }

    #[test]
    fn options_out_of_range_are_errors() {
        let ok = StreamOptions::default();
        assert!(ok.validate().is_ok());
        for bad in [
            StreamOptions {
                view_distance: 0,
                ..ok.clone()
            },
            StreamOptions {
                view_distance: MAX_VIEW_DISTANCE + 1,
                ..ok.clone()
            },
            StreamOptions {
                frames: 0,
                ..ok.clone()
            },
            StreamOptions {
                speed: f64::NAN,
                ..ok.clone()
            },
            StreamOptions {
                speed: -1.0,
                ..ok.clone()
            },
            StreamOptions {
                teleport_at: Some(600),
                ..ok.clone()
            },
        ] {
            assert!(bad.validate().is_err(), "{bad:?}");
        }
    }

    #[test]
    fn rss_is_read_on_linux() {
        if cfg!(target_os = "linux") {
            assert!(rss_bytes().is_some_and(|b| b > 0));
        }
    }
}
