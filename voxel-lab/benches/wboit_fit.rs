//! CPU cost of the fitted WBOIT weight (`oit::wboit::fit`, run in the technique's
//! `prepare`) on the record bench's worlds (`record.rs`: generated terrain within VD chunks,
//! the camera 40 blocks above the ground): per frame, `wboit-mrt` with the fitted weight
//! against the same renderer with the flat weight (no fit), frames alternating between the
//! two. Reports the median of the technique's `prepare_ms` and of `Renderer::render`'s CPU
//! ms. Prints figures; asserts nothing about time.
//! `cargo bench -p voxel-lab --bench wboit_fit` (FIT_VD=8,32 picks view distances).

use voxel_lab::Result;
use voxel_lab::eval::oit_config;
use voxel_lab::headless::{self, Offscreen};
use voxel_render::{NoGame, Technique, WeightFunction};

#[path = "common/record_world.rs"]
mod record_world;
use record_world::{H, LAYERS, SEED, W, camera, renderer};

const WARMUP: usize = 4;
const FRAMES: usize = 40;

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let ctx = headless::context()?;
    let vds: Vec<i32> = std::env::var("FIT_VD")
        .ok()
        .map(|v| v.split(',').filter_map(|x| x.trim().parse().ok()).collect())
        .unwrap_or_else(|| vec![8, 16, 32]);
    println!(
        "# Fitted WBOIT weight, CPU (cargo bench -p voxel-lab --bench wboit_fit)\n\n\
         {} at {W}x{H}, the record bench's worlds (terrain seed {SEED}, layers y {}..={}) and camera; `wboit-mrt`, frames alternating \
         between the fitted and the flat weight; median of {FRAMES} frames each after {WARMUP} \
         warm-up frames. prepare = the technique's CPU work before recording (the fit, the \
         uniform's upload); render = `Renderer::render`.\n",
        ctx.caps.adapter_name,
        LAYERS.start(),
        LAYERS.end(),
    );
    println!(
        "| VD | translucent meshes | prepare fitted ms | prepare flat ms | fit ms (difference) | render fitted ms | render flat ms |"
    );
    println!("|---:|---:|---:|---:|---:|---:|---:|");
    for vd in vds {
        let mut renderer = renderer(&ctx, vd, Technique::WboitMrt)?;
        let target = Offscreen::new(&ctx, W, H);
        let camera = camera(vd)?;
        let weights = [WeightFunction::Fitted, WeightFunction::Flat];
        let mut prepare: [Vec<f64>; 2] = Default::default();
        let mut render: [Vec<f64>; 2] = Default::default();
        let mut meshes = 0;
        for i in 0..WARMUP + FRAMES {
            let order = if i % 2 == 0 { [0, 1] } else { [1, 0] };
            for m in order {
                renderer.set_oit_config(oit_config(Technique::WboitMrt, weights[m]))?;
                let mut encoder = ctx
                    .device
                    .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
                let s = renderer.render(&mut encoder, &target.view, &camera, &mut NoGame)?;
                ctx.queue.submit([encoder.finish()]);
                ctx.device.poll(wgpu::PollType::wait_indefinitely())?;
                if i >= WARMUP {
                    prepare[m].push(s.technique.prepare_ms);
                    render[m].push(s.cpu_ms);
                }
                meshes = s.meshes_drawn[2];
            }
        }
        let [pf, pl] = prepare.each_mut().map(|v| median(v));
        let [rf, rl] = render.each_mut().map(|v| median(v));
        println!(
            "| {vd} | {meshes} | {pf:.3} | {pl:.3} | {:.3} | {rf:.3} | {rl:.3} |",
            pf - pl
        );
    }
    Ok(())
}
