//! CPU cost of `sorted-quads` along camera paths: the default scene (walking sideways past
//! the greenhouse) and the stained-glass corridor (walking through its twelve panes). Each
//! frame is rendered by the real renderer; the technique's report gives the CPU time of
//! building orders and sorting, and the chunks re-sorted. Prints figures; asserts nothing
//! about time. `cargo bench -p voxel-lab --bench sort_path`.

use std::path::Path;

use glam::DVec3;
use voxel_lab::headless::{self, Offscreen};
use voxel_lab::scene::{Scene, default_scene};
use voxel_render::{Camera, RendererConfig, Technique};

/// A bench's errors: the lab's, wgpu's, and its own messages.
type Result<T, E = Box<dyn std::error::Error>> = std::result::Result<T, E>;

const FRAMES: usize = 120;

fn percentile(v: &[f64], p: f64) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * p).round() as usize]
}

fn walk(name: &str, scene: &Scene, to: DVec3) -> Result<()> {
    let ctx = headless::context()?;
    let (w, h) = (640, 360);
    let mut config = RendererConfig {
        width: w,
        height: h,
        ..RendererConfig::default()
    };
    config.oit.technique = Technique::SortedQuads;
    let mut renderer = headless::renderer_for(&ctx, scene, config)?;
    let target = Offscreen::new(&ctx, w, h);
    let start = scene.cameras[0];
    let mut ms = Vec::new();
    let mut resorted = Vec::new();
    let mut first = None;
    let mut cycles = 0;
    for i in 0..FRAMES {
        let camera = Camera {
            eye: start.eye.lerp(to, i as f64 / (FRAMES - 1) as f64),
            ..start
        };
        let stats = renderer.render_and_submit(&target.view, &camera)?;
        let sort = stats.technique.sort.ok_or("no sort report")?;
        cycles = cycles.max(sort.cycles);
        if i == 0 {
            first = Some((sort.ms, sort.chunks_built, stats.meshes_drawn[2]));
        } else {
            ms.push(sort.ms);
            resorted.push(sort.chunks_resorted as f64);
        }
    }
    let (first_ms, built, visible) = first.ok_or("no frame")?;
    let still = resorted.iter().filter(|&&n| n == 0.0).count();
    println!(
        "{name}: {:.1} blocks in {FRAMES} frames; first frame {first_ms:.3} ms (built and sorted {built} of {visible} visible translucent chunks)",
        start.eye.distance(to)
    );
    println!(
        "  then per frame: sort ms mean {:.4}, p50 {:.4}, p95 {:.4}, max {:.4}; chunks re-sorted mean {:.2}, max {}; {still} of {} frames sorted nothing; cycles {cycles}",
        ms.iter().sum::<f64>() / ms.len() as f64,
        percentile(&ms, 0.5),
        percentile(&ms, 0.95),
        percentile(&ms, 1.0),
        resorted.iter().sum::<f64>() / resorted.len() as f64,
        percentile(&resorted, 1.0),
        ms.len()
    );
    // A still camera sorts nothing.
    let again = renderer.render_and_submit(&target.view, &Camera { eye: to, ..start })?;
    println!(
        "  still camera: {} chunks re-sorted",
        again.technique.sort.map_or(0, |s| s.chunks_resorted)
    );
    Ok(())
}

fn main() -> Result<()> {
    let default = default_scene(1)?;
    let cam = default.cameras[0];
    let side = default.paths[0].unwrap_or(cam.eye) - cam.eye;
    // Five times the flicker path: 30 blocks sideways past the greenhouse.
    walk("default scene", &default, cam.eye + side * 5.0)?;
    let corridor = Scene::load(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/stained_glass_corridor.toml"),
    )?;
    let eye = corridor.cameras[0].eye;
    // Down the corridor through all twelve panes (z from 7 to -38).
    walk(
        "stained-glass corridor",
        &corridor,
        DVec3::new(eye.x, eye.y, -38.0),
    )?;
    Ok(())
}
