//! The crate's own page (wasm32, the `page` feature): the default scene, drawn by
//! [`crate::app`] as a game's page is, or with `?test=1` every technique drawn once into a
//! texture and what came of each posted to the server that served the page
//! ([`crate::check`]).

use std::sync::{Arc, Mutex, PoisonError};

use voxel_core::World;
use voxel_mesh::ChunkMeshes;
use voxel_render::{Camera, GpuContext, NoGame, OitConfig, RendererConfig, Technique, stages};
use wasm_bindgen::prelude::*;

use crate::check::{self, Kind, Report, TEST_FRAMES, TEST_SEED, TEST_SIZE};
use crate::game::{Blocks, GamePage};
use crate::gpu::Gpu;
use crate::page::{
    ERRORS, Options, fail, install_hooks, now, post, renderer, show, sleep, start_gpu,
};
use crate::scene::default_scene;

/// The format of the test's pictures: what the native test reads back too.
const TEST_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
/// How long a readback may take before the test run gives up, milliseconds.
const READBACK_TIMEOUT_MS: f64 = 60_000.0;

/// The crate's own page: the default scene (wasm32 with the `page` feature, on by
/// default; a game's crate turns it off and calls [`run`]).
#[wasm_bindgen(start)]
pub fn start() {
    install_hooks();
    wasm_bindgen_futures::spawn_local(async {
        if let Err(e) = own_page().await {
            fail(&e).await;
        }
    });
}

/// The crate's own page: the default scene, or the test's run.
async fn own_page() -> Result<(), String> {
    let options = Options::from_url()?;
    let (gpu, fell_back) = start_gpu(&options).await?;
    show("generating and meshing the world…");
    // Let the page paint the message before the single thread is busy.
    sleep(0).await;
    let seed = if options.test { TEST_SEED } else { 1 };
    let scene = default_scene(seed, options.radius).map_err(|e| e.to_string())?;
    if options.test {
        let meshes = crate::scene::mesh_world(&scene.world, crate::check::TEST_LIGHT)
            .map_err(|e| e.to_string())?;
        return test(&gpu, &scene.world, &meshes, &scene.camera).await;
    }
    let mut page = GamePage::new("voxel-oit", Blocks::World(scene.world), scene.camera)
        .with_light(options.light);
    page.title = String::new();
    crate::app::run(gpu, fell_back, page, options)
}

/// Every technique into a texture, each picture or refusal posted; then the summary.
async fn test(
    gpu: &Gpu,
    world: &World,
    meshes: &[(voxel_core::ChunkPos, ChunkMeshes)],
    camera: &Camera,
) -> Result<(), String> {
    let ctx = &gpu.ctx;
    let (w, h) = TEST_SIZE;
    let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
    let target = stages::target(&ctx.device, "test_output", TEST_FORMAT, usage, (w, h));
    let single = voxel_render::low_level::single_precision(&ctx.caps, &Default::default());
    // How the renderers drew the world (the same for every technique).
    let mut drawn_with = String::new();
    for technique in Technique::ALL {
        show(&format!("drawing {technique}…"));
        let config = RendererConfig {
            width: w,
            height: h,
            output_format: TEST_FORMAT,
            oit: OitConfig::with(technique),
            ..RendererConfig::default()
        };
        let mut report = Report {
            technique,
            kind: Kind::Drew,
            drew: None,
            single_precision_moments: single,
        };
        let body = match draw_and_read(gpu, world, meshes, config, &target, camera).await {
            Ok((drew, rgba, how)) => {
                report.drew = Some(drew);
                drawn_with = how;
                rgba
            }
            Err(Drawn::Refused(why)) => {
                report.kind = Kind::Refused;
                why.into_bytes()
            }
            Err(Drawn::Failed(why)) => {
                report.kind = Kind::Failed;
                why.into_bytes()
            }
        };
        post(&check::report_path(&report), &body).await?;
    }
    let supported: Vec<_> = Technique::supported(&ctx.caps)
        .iter()
        .map(|t| t.name())
        .collect();
    let best = Technique::best_available(&ctx.caps)
        .map_or_else(|e| e.to_string(), |t| t.name().to_owned());
    // Errors reported late (WebGPU answers error scopes on the event loop) arrive first.
    sleep(200).await;
    let errors = ERRORS.with(|e| e.borrow().clone());
    let caps = &ctx.caps;
    let mut summary = format!(
        "backend: {}\nadapter: {}\nsupported: {}\nbest: {best}\ndrawn with: {drawn_with}\n\
         float32 blending: {}\nmsaa4: {}\ntimestamps: {}\nerrors: {}\n",
        gpu.api.name(),
        caps.adapter_name,
        supported.join(","),
        caps.features.contains(wgpu::Features::FLOAT32_BLENDABLE),
        caps.msaa4,
        caps.timestamps(),
        errors.len()
    );
    for e in errors {
        summary += &format!("error: {e}\n");
    }
    post("/done", summary.as_bytes()).await?;
    show(&format!("done: {}", supported.join(", ")));
    Ok(())
}

/// Why a technique has no picture.
enum Drawn {
    Refused(String),
    Failed(String),
}

/// Draws [`TEST_FRAMES`] frames of `config` into `target` and into the canvas, and reads
/// `target` back: the technique that drew, the picture, and how the world's quads were
/// fetched and drawn.
async fn draw_and_read(
    gpu: &Gpu,
    world: &World,
    meshes: &[(voxel_core::ChunkPos, ChunkMeshes)],
    config: RendererConfig,
    target: &stages::Target,
    camera: &Camera,
) -> Result<(Technique, Vec<u8>, String), Drawn> {
    let ctx = &gpu.ctx;
    let failed = |e: voxel_render::Error| match e {
        voxel_render::Error::Unsupported(_) => Drawn::Refused(e.to_string()),
        e => Drawn::Failed(e.to_string()),
    };
    let mut r = renderer(ctx, world, meshes, config).map_err(failed)?;
    for _ in 0..TEST_FRAMES {
        r.render_and_submit(&target.view, camera, &mut NoGame)
            .map_err(failed)?;
        r.after_submit();
    }
    let rgba = read_rgba(ctx, &target.texture)
        .await
        .map_err(Drawn::Failed)?;
    // The canvas shows what was drawn (its own format: the tonemap is made for it).
    gpu.draw(&mut r, camera, &mut NoGame)
        .map_err(|e| Drawn::Failed(e.to_string()))?;
    let c = r.config();
    let how = format!(
        "{} quads, {} draws",
        c.quad_fetch.map_or("?", |f| f.name()),
        c.draw.name()
    );
    Ok((c.oit.technique, rgba, how))
}

/// Reads an RGBA8 texture back without blocking (the page's thread must not): the map is
/// awaited on the event loop, polling the device (WebGL2 maps at a poll).
async fn read_rgba(ctx: &GpuContext, texture: &wgpu::Texture) -> Result<Vec<u8>, String> {
    let copy = voxel_render::readback::copy_texture(ctx, texture, 4)
        .map_err(|e| format!("copying the picture: {e}"))?;
    let buffer = &copy.buffer;
    let mapped = Arc::new(Mutex::new(None));
    let done = Arc::clone(&mapped);
    buffer.slice(..).map_async(wgpu::MapMode::Read, move |r| {
        *done.lock().unwrap_or_else(PoisonError::into_inner) = Some(r);
    });
    let start = now();
    loop {
        let _ = ctx.device.poll(wgpu::PollType::Poll);
        let result = mapped.lock().unwrap_or_else(PoisonError::into_inner).take();
        if let Some(result) = result {
            result.map_err(|e| format!("mapping the picture: {e}"))?;
            break;
        }
        if now() - start > READBACK_TIMEOUT_MS {
            return Err("the picture was not mapped within a minute".into());
        }
        sleep(2).await;
    }
    let view = buffer
        .slice(..)
        .get_mapped_range()
        .map_err(|e| format!("reading the picture: {e}"))?;
    let out = copy.rows(&view);
    drop(view);
    buffer.unmap();
    Ok(out)
}
