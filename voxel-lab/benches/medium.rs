//! What translucent volumes cost (`voxel_render::medium`), GPU ms per pass, median of
//! several frames. Under water: the eye in the water (the medium's boundary depth and fog,
//! and the technique drawing both sides) against the same camera treated as if it were in
//! air (back faces culled, no extra pass). From above: the deep and shallow lake with its
//! water absorbing along the path (the opaque depth copied for the volumes, each
//! technique's colour reading it) against the same lake of a water that is a thin surface
//! (same colour and opacity, absorption 0). Prints figures; asserts nothing about time.
//! `cargo bench -p voxel-lab --bench medium`.

use std::path::Path;

use voxel_lab::headless::{self, Offscreen};
use voxel_lab::scene::Scene;
use voxel_render::{Camera, GpuPass, NoGame, RendererConfig, Technique};

/// A bench's errors: the lab's, wgpu's, and its own messages.
type Result<T, E = Box<dyn std::error::Error>> = std::result::Result<T, E>;

const FRAMES: usize = 15;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

const TECHNIQUES: [Technique; 3] = [
    Technique::WboitMrt,
    Technique::SortedQuads,
    Technique::DepthPeeling,
];

/// Median GPU ms of `camera`'s frames: translucent work, medium passes, the whole frame.
fn times(
    renderer: &mut voxel_render::Renderer,
    target: &Offscreen,
    camera: &Camera,
) -> Result<[f64; 3]> {
    let (mut work, mut medium, mut total) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..FRAMES + 2 {
        renderer.render_and_submit(&target.view, camera, &mut NoGame)?;
        let t = renderer.gpu_times_blocking();
        if i >= 2 {
            work.push(t.translucent_work());
            medium.push(t.get(GpuPass::Medium).unwrap_or(0.0));
            total.push(t.iter().map(|(_, ms)| ms).sum());
        }
    }
    Ok([median(work), median(medium), median(total)])
}

fn config(technique: Technique, (width, height): (u32, u32)) -> RendererConfig {
    let mut config = RendererConfig {
        width,
        height,
        ..RendererConfig::default()
    };
    config.oit.technique = technique;
    config
}

fn main() -> Result<()> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let ctx = headless::context()?;
    let (w, h) = (640, 360);
    under_water(&ctx, &dir, (w, h))?;
    from_above(&ctx, &dir, (w, h))
}

/// The deep and shallow lake seen from above, its water a volume and a thin surface.
fn from_above(ctx: &voxel_render::GpuContext, dir: &Path, (w, h): (u32, u32)) -> Result<()> {
    let text = std::fs::read_to_string(dir.join("lake_depths.toml"))?;
    let volume = voxel_lab::scene::parse(&text)?;
    let registry = volume.world.registry();
    let water = registry.get(voxel_core::blocks::WATER)?;
    let [r, g, b] = water.color;
    let thin = format!(
        "{}\n[[blocks]]\nname = \"thin_water\"\ncolor = [{r}, {g}, {b}]\nopacity = {}\nclass = \"translucent\"\n",
        text.replace("block = \"water\"", "block = \"thin_water\""),
        water.opacity,
    );
    let thin = voxel_lab::scene::parse(&thin)?;
    println!(
        "\nlake_depths scene (from above), {w}x{h}, {}, median of {FRAMES} frames (volume = the water absorbing along the path; thin = a water of the same colour and opacity that is a thin surface)",
        ctx.caps.adapter_name
    );
    println!("| technique | water | translucent + composite ms | medium ms | frame total ms |");
    println!("|---|---|---|---|---|");
    for technique in TECHNIQUES {
        for (name, scene) in [("volume", &volume), ("thin", &thin)] {
            let mut renderer = headless::renderer_for(ctx, scene, config(technique, (w, h)))?;
            let target = Offscreen::new(ctx, w, h);
            let [work, medium, total] = times(&mut renderer, &target, &scene.cameras[0])?;
            println!("| {technique} | {name} | {work:.3} | {medium:.3} | {total:.3} |");
        }
    }
    Ok(())
}

/// The eye under water, and the same camera treated as if it were in air.
fn under_water(ctx: &voxel_render::GpuContext, dir: &Path, (w, h): (u32, u32)) -> Result<()> {
    let scene = Scene::load(&dir.join("under_water.toml"))?;
    println!(
        "under_water scene, {w}x{h}, {}, median of {FRAMES} frames (inside = the eye in the water; air = the same camera with no medium)",
        ctx.caps.adapter_name
    );
    println!("| technique | camera | translucent + composite ms | medium ms | frame total ms |");
    println!("|---|---|---|---|---|");
    for technique in TECHNIQUES {
        let mut renderer = headless::renderer_for(ctx, &scene, config(technique, (w, h)))?;
        let target = Offscreen::new(ctx, w, h);
        let inside = scene.cameras[0];
        let air = Camera {
            medium: None,
            ..inside
        };
        for (name, camera) in [("inside", inside), ("air", air)] {
            let [work, medium, total] = times(&mut renderer, &target, &camera)?;
            println!("| {technique} | {name} | {work:.3} | {medium:.3} | {total:.3} |");
        }
    }
    Ok(())
}
