//! What drawing the world without storage buffers costs (`voxel_render::QuadFetch`): GPU
//! ms per pass of the default scene with quads pulled from storage buffers (indirect
//! draws, today's path; and one draw per mesh, which shows the machine's noise) against
//! quads as instance attributes (the chunk record a uniform, the block layers a texture),
//! three renderers on one device drawing the same frames in turn, each first in turn, so
//! that a busy machine slows all alike. Prints the medians and the medians of the
//! frame-by-frame ratios; asserts nothing about time.
//! `cargo bench -p voxel-lab --bench quad_fetch` (`-- --size 640x360 --frames 31`).

use voxel_lab::headless::{self, Offscreen, SceneRenderer};
use voxel_render::{DrawMode, GpuPass, GpuTimes, QuadFetch, RendererConfig, Technique};

/// A bench's errors: the lab's, wgpu's, and its own messages.
type Result<T, E = Box<dyn std::error::Error>> = std::result::Result<T, E>;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The GPU ms of the world's passes (opaque, cutout) and of the rest (the technique's
/// passes, tonemap).
fn split(t: &GpuTimes) -> (f64, f64) {
    let world: f64 = [GpuPass::Opaque, GpuPass::Cutout]
        .iter()
        .filter_map(|&p| t.get(p))
        .sum();
    let total: f64 = t.iter().map(|(_, ms)| ms).sum();
    (world, total - world)
}

fn arg(name: &str) -> Option<String> {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1).cloned())
}

fn main() -> Result<()> {
    let (w, h) = arg("--size")
        .and_then(|s| {
            let (a, b) = s.split_once('x')?;
            Some((a.parse().ok()?, b.parse().ok()?))
        })
        .unwrap_or((1280, 720));
    let frames: usize = arg("--frames").and_then(|s| s.parse().ok()).unwrap_or(9);
    let scene = voxel_lab::scene::default_scene(1)?;
    let ctx = headless::context()?;
    if !ctx.caps.timestamps() {
        return Err(format!("{} has no timestamp queries", ctx.caps.adapter_name).into());
    }
    println!(
        "default scene (seed 1), {w}x{h}, {}, {frames} frames each after 2 untimed, the ways in turn",
        ctx.caps.adapter_name
    );
    println!(
        "| technique | fetch | opaque + cutout ms | technique + tonemap ms | frame ms | frame ratio to storage, indirect (median of frame pairs) |"
    );
    println!("|---|---|---:|---:|---:|---:|");
    let camera = scene.cameras[0];
    let target = Offscreen::new(&ctx, w, h);
    // Frame-pair ratios to storage with indirect draws, of every technique, per way.
    let mut pooled: Vec<Vec<f64>> = Vec::new();
    for technique in [
        Technique::OpaqueOnly,
        Technique::Stipple,
        Technique::SortedQuads,
        Technique::WboitMrt,
    ] {
        let make = |fetch, draw| -> voxel_lab::Result<SceneRenderer> {
            let mut config = RendererConfig {
                width: w,
                height: h,
                quad_fetch: Some(fetch),
                draw,
                ..RendererConfig::default()
            };
            config.oit.technique = technique;
            headless::renderer_for(&ctx, &scene, config)
        };
        // Today's path (indirect draws), the same one draw per mesh (as the instanced
        // path draws), and the instanced path.
        let ways = [
            (QuadFetch::Storage, DrawMode::Indirect),
            (QuadFetch::Storage, DrawMode::PerChunk),
            (QuadFetch::Instanced, DrawMode::PerChunk),
        ];
        let mut renderers = ways
            .iter()
            .map(|&(f, d)| make(f, d))
            .collect::<Result<Vec<_>, _>>()?;
        let mut times: Vec<Vec<(f64, f64)>> = vec![Vec::new(); ways.len()];
        for i in 0..frames + 2 {
            // Each goes first in turn.
            for j in 0..ways.len() {
                let k = (i + j) % ways.len();
                let r = &mut renderers[k];
                r.render_and_submit(&target.view, &camera)?;
                let g = r.gpu_times_blocking();
                if i >= 2 {
                    times[k].push(split(&g));
                }
            }
        }
        for (k, ((fetch, draw), t)) in ways.iter().zip(&times).enumerate() {
            let world = median(t.iter().map(|x| x.0).collect());
            let rest = median(t.iter().map(|x| x.1).collect());
            let frame = median(t.iter().map(|x| x.0 + x.1).collect());
            let ratios: Vec<f64> = times[0]
                .iter()
                .zip(t)
                .map(|(s, i)| (i.0 + i.1) / (s.0 + s.1))
                .collect();
            if pooled.len() <= k {
                pooled.push(Vec::new());
            }
            pooled[k].extend(&ratios);
            let ratio = median(ratios);
            let r = if k == 0 {
                String::new()
            } else {
                format!("{ratio:.3}")
            };
            println!(
                "| {technique} | {}, {} | {world:.2} | {rest:.2} | {frame:.2} | {r} |",
                fetch.name(),
                draw.name()
            );
        }
    }
    // Storage drawn one mesh per draw is today's path drawn another way: its ratio is what
    // the machine's noise alone gives.
    println!();
    for (k, name) in ["storage, per-chunk (the noise)", "instanced, per-chunk"]
        .iter()
        .enumerate()
    {
        let r = pooled[k + 1].clone();
        println!(
            "every technique, {name}: frame ratio to storage, indirect: median {:.3} of {} frame pairs",
            median(r.clone()),
            r.len()
        );
    }
    Ok(())
}
