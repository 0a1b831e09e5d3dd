//! Where WBOIT's GPU time goes, pass by pass, against `sorted-quads` on the scene suite
//! (`scenes/*.toml`, each scene's first camera, as the lab): per scene the median GPU ms
//! of the translucent passes (accumulation, the targets' clears included) and of the
//! composite, for `sorted-quads`, `wboit-mrt` with the fitted weight, `wboit-mrt` with the
//! flat weight (no table read: the difference is the fitted weight's cost) and
//! `wboit-two-pass`; and the cost of clearing WBOIT's two targets alone (an empty pass with
//! the same load ops). One renderer per mode, frames interleaved across the modes so that
//! drift of the shared machine hits all alike. Prints figures; asserts nothing about time.
//! `cargo bench -p voxel-lab --bench wboit_passes` (WBOIT_PASSES_FRAMES overrides the
//! frame count, WBOIT_PASSES_SIZE the size, e.g. `1920x1080`).

use std::path::Path;

use voxel_lab::eval::oit_config;
use voxel_lab::headless::{self, Offscreen, SceneRenderer};
use voxel_lab::scene::{Scene, scene_files};
use voxel_render::low_level::REVEALAGE_FORMAT;
use voxel_render::{GpuContext, GpuPass, OitConfig, RendererConfig, Technique, WeightFunction};

/// A bench's errors: the lab's, wgpu's, and its own messages.
type Result<T, E = Box<dyn std::error::Error>> = std::result::Result<T, E>;

const WARMUP: usize = 3;

fn frames() -> usize {
    std::env::var("WBOIT_PASSES_FRAMES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(15)
}

fn size() -> (u32, u32) {
    std::env::var("WBOIT_PASSES_SIZE")
        .ok()
        .and_then(|v| {
            let (w, h) = v.split_once('x')?;
            Some((w.parse().ok()?, h.parse().ok()?))
        })
        .unwrap_or((640, 360))
}

fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The configurations compared, with their column names.
fn modes() -> Vec<(&'static str, OitConfig)> {
    vec![
        (
            "sorted-quads",
            oit_config(Technique::SortedQuads, WeightFunction::Fitted),
        ),
        (
            "wboit-mrt",
            oit_config(Technique::WboitMrt, WeightFunction::Fitted),
        ),
        (
            "wboit-mrt flat",
            oit_config(Technique::WboitMrt, WeightFunction::Flat),
        ),
        (
            "wboit-two-pass",
            oit_config(Technique::WboitTwoPass, WeightFunction::Fitted),
        ),
    ]
}

/// Median GPU ms of an empty render pass that clears WBOIT's accumulation (RGBA16F) and
/// revealage targets, as the accumulation pass's load ops do.
fn clear_ms(ctx: &GpuContext, (w, h): (u32, u32)) -> Result<f64> {
    use wgpu::TextureUsages as U;
    let usage = U::RENDER_ATTACHMENT | U::TEXTURE_BINDING;
    let target = |format| {
        ctx.device
            .create_texture(&wgpu::TextureDescriptor {
                label: Some("bench_clear"),
                size: wgpu::Extent3d {
                    width: w,
                    height: h,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
            .create_view(&wgpu::TextureViewDescriptor::default())
    };
    let accum = target(wgpu::TextureFormat::Rgba16Float);
    let reveal = target(REVEALAGE_FORMAT);
    let queries = ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
        label: Some("bench_clear"),
        ty: wgpu::QueryType::Timestamp,
        count: 2,
    });
    let resolve = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("bench_clear_resolve"),
        size: 16,
        usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let read = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("bench_clear_read"),
        size: 16,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let period = f64::from(ctx.queue.get_timestamp_period());
    let mut ms = Vec::new();
    for i in 0..WARMUP + frames() {
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        let clear = |view, color| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(color),
                    store: wgpu::StoreOp::Store,
                },
            })
        };
        drop(encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("bench_clear"),
            color_attachments: &[
                clear(&accum, wgpu::Color::TRANSPARENT),
                clear(&reveal, wgpu::Color::WHITE),
            ],
            depth_stencil_attachment: None,
            timestamp_writes: Some(wgpu::RenderPassTimestampWrites {
                query_set: &queries,
                beginning_of_pass_write_index: Some(0),
                end_of_pass_write_index: Some(1),
            }),
            occlusion_query_set: None,
            multiview_mask: None,
        }));
        encoder.resolve_query_set(&queries, 0..2, &resolve, 0);
        encoder.copy_buffer_to_buffer(&resolve, 0, &read, 0, 16);
        ctx.queue.submit([encoder.finish()]);
        read.slice(..).map_async(wgpu::MapMode::Read, |_| {});
        ctx.device.poll(wgpu::PollType::wait_indefinitely())?;
        let t: [u64; 2] = {
            let view = read.slice(..).get_mapped_range()?;
            bytemuck::pod_read_unaligned(&view)
        };
        read.unmap();
        if i >= WARMUP {
            ms.push(t[1].saturating_sub(t[0]) as f64 * period * 1e-6);
        }
    }
    Ok(median(&mut ms))
}

fn main() -> Result<()> {
    let ctx = headless::context()?;
    if !ctx.caps.timestamps() {
        return Err("this adapter has no timestamp queries: nothing to measure".into());
    }
    let size = size();
    let (w, h) = size;
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let modes = modes();
    println!(
        "# WBOIT pass by pass (cargo bench -p voxel-lab --bench wboit_passes)\n\n\
         {} at {w}x{h}; each scene's first camera; median of {} frames after {WARMUP} warm-up \
         frames, the modes' frames interleaved. acc = the technique's translucent passes \
         (the accumulation, its targets' clears included; both passes of two-pass), comp = \
         the composite; ms of GPU time from timestamp queries.\n",
        ctx.caps.adapter_name,
        frames()
    );
    let mut header = String::from("| scene |");
    let mut rule = String::from("|---|");
    for (name, _) in &modes {
        header += &format!(" {name} acc | {name} comp | {name} total |");
        rule += "---:|---:|---:|";
    }
    println!("{header}\n{rule}");
    let mut sums = vec![[0.0f64; 3]; modes.len()];
    let mut scenes = 0usize;
    // WBOIT_PASSES_SCENES=deep_stack,under_water picks scenes by file stem.
    let only: Option<Vec<String>> = std::env::var("WBOIT_PASSES_SCENES")
        .ok()
        .map(|v| v.split(',').map(|s| s.trim().to_owned()).collect());
    for path in scene_files(&dir)? {
        let stem = path
            .file_stem()
            .map_or("scene".into(), |s| s.to_string_lossy().into_owned());
        if only.as_ref().is_some_and(|o| !o.contains(&stem)) {
            continue;
        }
        let scene = Scene::load(&path)?;
        let camera = scene.cameras[0];
        let mut renderers: Vec<SceneRenderer> = Vec::new();
        for (_, oit) in &modes {
            let mut config = RendererConfig {
                width: w,
                height: h,
                ..RendererConfig::default()
            };
            config.oit = oit.clone();
            renderers.push(headless::renderer_for(&ctx, &scene, config)?);
        }
        let target = Offscreen::new(&ctx, w, h);
        let mut times = vec![[Vec::new(), Vec::new()]; modes.len()];
        for i in 0..WARMUP + frames() {
            // Rotate the order so that no mode always follows the same one.
            for k in 0..modes.len() {
                let m = (i + k) % modes.len();
                let r = &mut renderers[m];
                r.render_and_submit(&target.view, &camera)?;
                let t = r.gpu_times_blocking();
                if i >= WARMUP {
                    times[m][0].push(t.get(GpuPass::Translucent).unwrap_or(0.0));
                    times[m][1].push(t.get(GpuPass::Composite).unwrap_or(0.0));
                }
            }
        }
        let mut line = format!("| {stem} |");
        for (m, [acc, comp]) in times.iter_mut().enumerate() {
            let totals: Vec<f64> = acc.iter().zip(comp.iter()).map(|(a, c)| a + c).collect();
            let row = [median(acc), median(comp), median(&mut totals.clone())];
            for (s, v) in sums[m].iter_mut().zip(row) {
                *s += v;
            }
            line += &format!(" {:.3} | {:.3} | {:.3} |", row[0], row[1], row[2]);
        }
        println!("{line}");
        scenes += 1;
    }
    let n = scenes.max(1) as f64;
    let mut line = String::from("| **mean** |");
    for s in &sums {
        line += &format!(" {:.3} | {:.3} | {:.3} |", s[0] / n, s[1] / n, s[2] / n);
    }
    println!("{line}\n");
    let sq = sums[0][2];
    for (m, (name, _)) in modes.iter().enumerate().skip(1) {
        println!(
            "{name}: total / sorted-quads total = {:.2} (suite mean)",
            sums[m][2] / sq
        );
    }
    println!(
        "\nclearing the accumulation (RGBA16F) and revealage ({:?}) in an empty pass: {:.3} ms",
        REVEALAGE_FORMAT,
        clear_ms(&ctx, size)?
    );
    Ok(())
}
