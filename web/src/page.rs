//! The page (wasm32): the backend picked and checked ([`crate::gpu`]: WebGPU falling back to
//! WebGL2), then the default scene (the crate's own page) or a game's [`GamePage`]
//! ([`run`]) drawn every animation frame ([`crate::app`]). With `?test=1` the crate's page
//! draws every technique once into a texture and posts what came of each to the server
//! that served it ([`crate::check`]).
//!
//! The URL's parameters: `?backend=webgpu|webgl2|auto` (default `auto`: WebGPU, WebGL2
//! where WebGPU fails), `?technique=NAME`, `?radius=N` (the crate's page), `?test=1` (the
//! browser test's run), `?report=1` (the page posts its state to the server that served it,
//! for the browser tests), `?lose=N` (the device is destroyed after N frames: a loss to
//! recover from, for the browser tests).

use std::cell::{Cell, RefCell};

use voxel_core::World;
use voxel_mesh::ChunkMeshes;
use voxel_render::{GpuContext, Renderer, RendererConfig, Technique};
use wasm_bindgen::JsCast;
use wasm_bindgen::prelude::*;
use wasm_bindgen_futures::JsFuture;

use crate::check::{TEST_RADIUS, TEST_SIZE};
use crate::game::GamePage;
use crate::gpu::{Choice, Gpu};
use crate::scene::PAGE_RADIUS;

thread_local! {
    /// Errors logged (by the renderer, by wgpu) and GPU errors wgpu reported to no one.
    pub(crate) static ERRORS: RefCell<Vec<String>> = const { RefCell::new(Vec::new()) };
    /// Whether the page runs the test (a panic is then posted too).
    static TESTING: Cell<bool> = const { Cell::new(false) };
}

/// What the URL asks for.
#[derive(Debug)]
pub(crate) struct Options {
    pub(crate) backend: Choice,
    pub(crate) test: bool,
    #[cfg_attr(not(feature = "page"), allow(dead_code))]
    pub(crate) radius: i32,
    pub(crate) technique: Option<Technique>,
    /// Post the page's state to the server (`?report=1`).
    pub(crate) report: bool,
    /// Destroy the device after this many frames (`?lose=N`).
    pub(crate) lose_after: Option<u64>,
    /// Draw the world with its light field (`?light=0` turns it off; default on).
    pub(crate) light: bool,
}

impl Options {
    pub(crate) fn from_url() -> Result<Self, String> {
        let search = window()?.location().search().map_err(js)?;
        let params = web_sys::UrlSearchParams::new_with_str(&search).map_err(js)?;
        let backend = match params.get("backend").as_deref() {
            None | Some("auto") => Choice::Auto,
            Some("webgpu") => Choice::WebGpu,
            Some("webgl2") => Choice::WebGl2,
            Some(other) => {
                return Err(format!(
                    "backend {other:?}: expected webgpu, webgl2 or auto"
                ));
            }
        };
        let test = params.get("test").is_some_and(|v| v == "1");
        let radius = match params.get("radius") {
            None => PAGE_RADIUS,
            Some(r) => r
                .parse::<i32>()
                .ok()
                .filter(|r| (1..=16).contains(r))
                .ok_or_else(|| format!("radius {r:?}: expected 1 to 16 chunks"))?,
        };
        let technique = params
            .get("technique")
            .map(|t| t.parse::<Technique>().map_err(|e| e.to_string()))
            .transpose()?;
        let lose_after = params
            .get("lose")
            .map(|n| {
                n.parse::<u64>()
                    .map_err(|_| format!("lose {n:?}: expected a number of frames"))
            })
            .transpose()?;
        Ok(Self {
            backend: if test && backend == Choice::Auto {
                Choice::WebGpu
            } else {
                backend
            },
            test,
            radius: if test { TEST_RADIUS } else { radius },
            technique,
            report: params.get("report").is_some_and(|v| v == "1"),
            lose_after,
            light: params.get("light").is_none_or(|v| v != "0"),
        })
    }
}

/// Logs to the browser's console; errors are kept for the test's summary.
struct PageLogger;

impl log::Log for PageLogger {
    fn enabled(&self, meta: &log::Metadata<'_>) -> bool {
        // wgpu's own info is a line per pipeline: warnings and errors only.
        let max = if meta.target().starts_with("wgpu") || meta.target().starts_with("naga") {
            log::Level::Warn
        } else {
            log::Level::Info
        };
        meta.level() <= max
    }

    fn log(&self, record: &log::Record<'_>) {
        if !self.enabled(record.metadata()) {
            return;
        }
        let line = format!(
            "[{}] {}: {}",
            record.level(),
            record.target(),
            record.args()
        );
        let value = JsValue::from_str(&line);
        match record.level() {
            log::Level::Error => {
                web_sys::console::error_1(&value);
                ERRORS.with(|e| e.borrow_mut().push(line));
            }
            log::Level::Warn => web_sys::console::warn_1(&value),
            _ => web_sys::console::log_1(&value),
        }
    }

    fn flush(&self) {}
}

static LOGGER: PageLogger = PageLogger;

/// Runs a game's page: starts the GPU (WebGPU, or WebGL2 where WebGPU fails, said on
/// the page), calls `make` for what the page shows, and draws it every animation frame
/// with the technique picker and the fly camera, making a new device and renderer
/// after a loss and following the canvas's size. Call it once, from the game's
/// `#[wasm_bindgen(start)]` function; `make` runs after the GPU is up (its world
/// generation then shows as a step on the page). Errors are shown on the page.
pub fn run(make: impl FnOnce() -> Result<GamePage, String> + 'static) {
    install_hooks();
    wasm_bindgen_futures::spawn_local(async move {
        let result = async {
            let options = Options::from_url()?;
            let (gpu, fell_back) = start_gpu(&options).await?;
            show("making the world…");
            sleep(0).await;
            let page = make()?;
            crate::app::run(gpu, fell_back, page, options)
        }
        .await;
        if let Err(e) = result {
            fail(&e).await;
        }
    });
}

/// The panic hook, the logger and whether this is the test's run.
pub(crate) fn install_hooks() {
    std::panic::set_hook(Box::new(|info| {
        let message = format!("panic: {info}");
        web_sys::console::error_1(&JsValue::from_str(&message));
        show(&message);
        // The module cannot run on after a panic: a beacon is sent without waiting.
        if TESTING.get()
            && let Some(w) = web_sys::window()
        {
            let _ = w
                .navigator()
                .send_beacon_with_opt_str("/panic", Some(&message));
        }
    }));
    // Known before anything can fail, so that a failed test run says so.
    TESTING.set(
        web_sys::window()
            .and_then(|w| w.location().search().ok())
            .is_some_and(|q| {
                q.split(['?', '&'])
                    .any(|p| p == "test=1" || p == "report=1")
            }),
    );
    if log::set_logger(&LOGGER).is_ok() {
        log::set_max_level(log::LevelFilter::Info);
    }
}

/// Shows `e` on the page (and posts it in a test's run).
pub(crate) async fn fail(e: &str) {
    log::error!("{e}");
    show(&format!("error: {e}"));
    if TESTING.get() {
        let _ = post("/done", format!("error: {e}\n").as_bytes()).await;
    }
}

/// The GPU the options ask for; the note on the page says where WebGPU failed.
pub(crate) async fn start_gpu(options: &Options) -> Result<(Gpu, Option<String>), String> {
    if options.test {
        crate::gpu::fix_size(TEST_SIZE);
    }
    show("starting the GPU…");
    let (gpu, fell_back) = Gpu::start(options.backend).await?;
    set_text("backend", &gpu.ctx.caps.adapter_name);
    if let Some(why) = &fell_back {
        set_text("notice", &fallback_notice(why));
    }
    Ok((gpu, fell_back))
}

/// What the page says when WebGPU failed and WebGL2 draws.
pub(crate) fn fallback_notice(why: &str) -> String {
    format!("WebGPU failed ({why}): drawing with WebGL2 instead")
}

/// A renderer of `config` with `meshes` uploaded.
pub(crate) fn renderer(
    ctx: &GpuContext,
    world: &World,
    meshes: &[(voxel_core::ChunkPos, ChunkMeshes)],
    config: RendererConfig,
) -> voxel_render::Result<Renderer> {
    let mut r = Renderer::new(ctx, world.registry(), config)?;
    for (pos, m) in meshes {
        r.upload_chunk(*pos, m)?;
    }
    crate::scene::sun_shadows(&mut r, world, meshes)?;
    Ok(r)
}

/// What `requestAnimationFrame` calls: the time of the frame, milliseconds.
pub(crate) type FrameCallback = Closure<dyn FnMut(f64)>;

/// Calls `f` on every `event` of `target`, for the life of the page.
pub(crate) fn listen<E: JsCast + 'static>(
    target: &web_sys::EventTarget,
    event: &str,
    mut f: impl FnMut(E) + 'static,
) -> Result<(), String> {
    let closure = Closure::<dyn FnMut(web_sys::Event)>::new(move |e: web_sys::Event| {
        if let Ok(e) = e.dyn_into::<E>() {
            f(e);
        }
    });
    target
        .add_event_listener_with_callback(event, closure.as_ref().unchecked_ref())
        .map_err(js)?;
    // The listener lives as long as the page.
    closure.forget();
    Ok(())
}

/// Posts `body` to `path` on the server that served the page.
pub(crate) async fn post(path: &str, body: &[u8]) -> Result<(), String> {
    let init = web_sys::RequestInit::new();
    init.set_method("POST");
    init.set_body(&js_sys::Uint8Array::from(body).into());
    let response = JsFuture::from(window()?.fetch_with_str_and_init(path, &init))
        .await
        .map_err(js)?;
    let response: web_sys::Response = response.dyn_into().map_err(js)?;
    if response.ok() {
        Ok(())
    } else {
        Err(format!("posting {path}: HTTP {}", response.status()))
    }
}

/// Waits `ms` milliseconds on the event loop.
pub(crate) async fn sleep(ms: i32) {
    let promise = js_sys::Promise::new(&mut |resolve, _| {
        if let Some(w) = web_sys::window() {
            let _ = w.set_timeout_with_callback_and_timeout_and_arguments_0(&resolve, ms);
        }
    });
    let _ = JsFuture::from(promise).await;
}

pub(crate) fn now() -> f64 {
    web_sys::window()
        .and_then(|w| w.performance())
        .map_or(0.0, |p| p.now())
}

pub(crate) fn window() -> Result<web_sys::Window, String> {
    web_sys::window().ok_or_else(|| "no window".to_owned())
}

/// The page's element `id`, as `T`.
pub(crate) fn element<T: JsCast>(id: &str) -> Result<T, String> {
    window()?
        .document()
        .and_then(|d| d.get_element_by_id(id))
        .ok_or_else(|| format!("the page has no #{id}"))?
        .dyn_into()
        .map_err(|_| format!("#{id} is not the element expected"))
}

/// Sets the text of element `id`, if the page has it.
pub(crate) fn set_text(id: &str, text: &str) {
    if let Some(e) = web_sys::window()
        .and_then(|w| w.document())
        .and_then(|d| d.get_element_by_id(id))
    {
        e.set_text_content(Some(text));
    }
}

/// Shows `text` in the status line (and the console).
pub(crate) fn show(text: &str) {
    web_sys::console::log_1(&JsValue::from_str(text));
    set_text("status", text);
}

/// A JavaScript exception's text.
pub(crate) fn js(e: JsValue) -> String {
    e.as_string().unwrap_or_else(|| format!("{e:?}"))
}
