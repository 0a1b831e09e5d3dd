//! What seeing translucent volumes from inside costs (`voxel_render::medium`): GPU ms per
//! pass with the eye under water (the medium's boundary depth and fog, and the technique
//! drawing both sides), against the same camera treated as if it were in air (what every
//! frame cost before: back faces culled, no extra pass). Prints figures; asserts nothing
//! about time. `cargo bench -p voxel-lab --bench medium`.

use std::path::Path;

use voxel_lab::headless::{self, Offscreen};
use voxel_lab::scene::Scene;
use voxel_render::{Camera, GpuPass, RendererConfig, Technique};

const FRAMES: usize = 15;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() -> Result<(), String> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/under_water.toml");
    let scene = Scene::load(&path)?;
    let ctx = headless::context()?;
    let (w, h) = (640, 360);
    println!(
        "under_water scene, {w}x{h}, {}, median of {FRAMES} frames (inside = the eye in the water; air = the same camera with no medium)",
        ctx.caps.adapter_name
    );
    println!("| technique | camera | translucent + composite ms | medium ms | frame total ms |");
    println!("|---|---|---|---|---|");
    for technique in [
        Technique::WboitMrt,
        Technique::SortedQuads,
        Technique::DepthPeeling,
    ] {
        let mut config = RendererConfig {
            width: w,
            height: h,
            ..RendererConfig::default()
        };
        config.oit.technique = technique;
        let mut renderer = headless::renderer_for(&ctx, &scene, config)?;
        let target = Offscreen::new(&ctx, w, h);
        let inside = scene.cameras[0];
        let air = Camera {
            medium: None,
            ..inside
        };
        for (name, camera) in [("inside", inside), ("air", air)] {
            let (mut work, mut medium, mut total) = (Vec::new(), Vec::new(), Vec::new());
            for i in 0..FRAMES + 2 {
                renderer
                    .render_and_submit(&target.view, &camera)
                    .map_err(|e| voxel_lab::chain(&e))?;
                let t = renderer.gpu_times_blocking();
                if i >= 2 {
                    work.push(t.translucent_work());
                    medium.push(t.get(GpuPass::Medium).unwrap_or(0.0));
                    total.push(t.iter().map(|(_, ms)| ms).sum());
                }
            }
            println!(
                "| {technique} | {name} | {:.3} | {:.3} | {:.3} |",
                median(work),
                median(medium),
                median(total)
            );
        }
    }
    Ok(())
}
