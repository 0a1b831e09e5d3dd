//! The page (wasm32): picks the backend (`?backend=webgpu` or `webgl2`; by default WebGPU
//! where the browser has an adapter, else WebGL2), builds the default scene and draws it
//! every animation frame with the technique picked, flying with the keys and the mouse.
//! With `?test=1` it draws every technique once into a texture and posts what came of
//! each to the server that served it ([`crate::check`]).

use std::cell::{Cell, RefCell};
use std::collections::HashSet;
use std::rc::Rc;
use std::sync::{Arc, Mutex, PoisonError};

use voxel_core::World;
use voxel_mesh::ChunkMeshes;
use voxel_render::{
    Camera, GpuContext, NoGame, OitConfig, Renderer, RendererConfig, Technique, stages,
};
use wasm_bindgen::JsCast;
use wasm_bindgen::prelude::*;
use wasm_bindgen_futures::JsFuture;
use web_sys::{HtmlCanvasElement, HtmlOptionElement, HtmlSelectElement};

use crate::check::{self, Kind, Report, TEST_FRAMES, TEST_RADIUS, TEST_SEED, TEST_SIZE};
use crate::fly::{FlyCamera, Movement};
use crate::scene::{PAGE_RADIUS, default_scene};

/// The format of the test's pictures: what the native test reads back too.
const TEST_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
/// How long a readback may take before the test run gives up, milliseconds.
const READBACK_TIMEOUT_MS: f64 = 60_000.0;

thread_local! {
    /// Errors logged (by the renderer, by wgpu) and GPU errors wgpu reported to no one.
    static ERRORS: RefCell<Vec<String>> = const { RefCell::new(Vec::new()) };
    /// Whether the page runs the test (a panic is then posted too).
    static TESTING: Cell<bool> = const { Cell::new(false) };
}

/// The backend asked for in the URL.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Choice {
    /// WebGPU where the browser has an adapter, else WebGL2.
    Auto,
    /// WebGPU only.
    WebGpu,
    /// WebGL2 only.
    WebGl2,
}

/// What the URL asks for.
#[derive(Debug)]
struct Options {
    backend: Choice,
    test: bool,
    radius: i32,
    technique: Option<Technique>,
}

impl Options {
    fn from_url() -> Result<Self, String> {
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
            .map(|t| Technique::from_name(&t).map_err(|e| e.to_string()))
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

/// The page's entry point, run when the module loads.
#[wasm_bindgen(start)]
pub fn start() {
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
            .is_some_and(|q| q.split(['?', '&']).any(|p| p == "test=1")),
    );
    if log::set_logger(&LOGGER).is_ok() {
        log::set_max_level(log::LevelFilter::Info);
    }
    wasm_bindgen_futures::spawn_local(async {
        if let Err(e) = run().await {
            log::error!("{e}");
            show(&format!("error: {e}"));
            if TESTING.get() {
                let _ = post("/done", format!("error: {e}\n").as_bytes()).await;
            }
        }
    });
}

async fn run() -> Result<(), String> {
    let options = Options::from_url()?;
    let canvas: HtmlCanvasElement = element("view")?;
    if options.test {
        canvas.set_width(TEST_SIZE.0);
        canvas.set_height(TEST_SIZE.1);
    }
    show("starting the GPU…");
    let gpu = Gpu::new(options.backend, canvas.clone()).await?;
    set_text("backend", &gpu.ctx.caps.adapter_name);
    show("generating and meshing the world…");
    // Let the page paint the message before the single thread is busy.
    sleep(0).await;
    let seed = if options.test { TEST_SEED } else { 1 };
    let scene = default_scene(seed, options.radius).map_err(|e| e.to_string())?;
    let positions: Vec<_> = scene.world.iter().map(|(p, _)| p).collect();
    let meshes = voxel_mesh::mesh_chunks(&scene.world, &positions).map_err(|e| e.to_string())?;
    if options.test {
        return test(&gpu, &scene.world, &meshes, &scene.camera).await;
    }
    interactive(gpu, scene.world, meshes, scene.camera, options.technique)
}

/// The device and the canvas's surface.
struct Gpu {
    ctx: GpuContext,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    backend: &'static str,
}

impl Gpu {
    async fn new(choice: Choice, canvas: HtmlCanvasElement) -> Result<Self, String> {
        let (w, h) = (canvas.width().max(1), canvas.height().max(1));
        let backends = match choice {
            Choice::Auto => wgpu::Backends::BROWSER_WEBGPU | wgpu::Backends::GL,
            Choice::WebGpu => wgpu::Backends::BROWSER_WEBGPU,
            Choice::WebGl2 => wgpu::Backends::GL,
        };
        let desc = voxel_render::instance_descriptor(backends);
        if choice == Choice::WebGpu && !wgpu::util::is_browser_webgpu_supported().await {
            return Err("this browser gives no WebGPU adapter".into());
        }
        // Auto: without a WebGPU adapter the instance is WebGL2's.
        let instance = wgpu::util::new_instance_with_webgpu_detection(desc).await;
        let surface = instance
            .create_surface(wgpu::SurfaceTarget::Canvas(canvas))
            .map_err(|e| format!("no surface on the canvas: {e}"))?;
        let adapter = instance
            .request_adapter(&wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::HighPerformance,
                compatible_surface: Some(&surface),
                ..Default::default()
            })
            .await
            .map_err(|e| format!("no adapter: {e}"))?;
        let backend = match adapter.get_info().backend {
            wgpu::Backend::BrowserWebGpu => "WebGPU",
            wgpu::Backend::Gl => "WebGL2",
            _ => "?",
        };
        let (device, queue) = voxel_render::request_device(&adapter)
            .await
            .map_err(|e| e.to_string())?;
        // Whatever wgpu reports to no one fails the test and shows in the console.
        device.on_uncaptured_error(Arc::new(|error: wgpu::Error| {
            log::error!("uncaptured GPU error: {error}");
        }));
        let ctx = GpuContext::from_device(&adapter, device, queue);
        let mut config = surface
            .get_default_config(&adapter, w, h)
            .ok_or("the canvas offers no format")?;
        // The renderer draws into the formats of `OUTPUT_FORMATS`; prefer the first the
        // canvas offers.
        let formats = surface.get_capabilities(&adapter).formats;
        if let Some(f) = formats
            .iter()
            .find(|f| voxel_render::OUTPUT_FORMATS.contains(f))
        {
            config.format = *f;
        }
        surface.configure(&ctx.device, &config);
        Ok(Self {
            ctx,
            surface,
            config,
            backend,
        })
    }

    /// Draws a frame of `renderer` into the canvas.
    fn draw(&self, renderer: &mut Renderer, camera: &Camera) -> Result<(), String> {
        let wgpu::CurrentSurfaceTexture::Success(frame) = self.surface.get_current_texture() else {
            // Lost or outdated: configured again, drawn next frame.
            self.surface.configure(&self.ctx.device, &self.config);
            return Ok(());
        };
        let view = frame.texture.create_view(&Default::default());
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        renderer
            .render(&mut encoder, &view, camera, &mut NoGame)
            .map_err(|e| e.to_string())?;
        self.ctx.queue.submit([encoder.finish()]);
        self.ctx.queue.present(frame);
        renderer.after_submit();
        Ok(())
    }
}

/// A renderer of `config` with `meshes` uploaded.
fn renderer(
    ctx: &GpuContext,
    world: &World,
    meshes: &[(voxel_core::ChunkPos, ChunkMeshes)],
    config: RendererConfig,
) -> voxel_render::Result<Renderer> {
    let mut r = Renderer::new(ctx, world.registry(), config)?;
    for (pos, m) in meshes {
        r.upload_chunk(*pos, m)?;
    }
    Ok(r)
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
        gpu.backend,
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
    gpu.draw(&mut r, camera).map_err(Drawn::Failed)?;
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

/// What the interactive page keeps between frames.
struct App {
    gpu: Gpu,
    renderer: Renderer,
    world: World,
    fly: FlyCamera,
    keys: HashSet<String>,
    dragging: bool,
    last_ms: f64,
}

impl App {
    fn frame(&mut self, now_ms: f64) -> Result<(), String> {
        let seconds = ((now_ms - self.last_ms) / 1000.0).clamp(0.0, 0.25);
        self.last_ms = now_ms;
        self.fly.fly(
            Movement::from_keys(self.keys.iter().map(String::as_str)),
            seconds,
        );
        let medium = self.world.medium_at(self.fly.eye.to_array());
        let camera = self.fly.camera(medium).map_err(|e| e.to_string())?;
        self.gpu.draw(&mut self.renderer, &camera)
    }
}

/// The picker, the fly camera and the frame loop.
fn interactive(
    gpu: Gpu,
    world: World,
    meshes: Vec<(voxel_core::ChunkPos, ChunkMeshes)>,
    camera: Camera,
    asked: Option<Technique>,
) -> Result<(), String> {
    let caps = &gpu.ctx.caps;
    let supported = Technique::supported(caps);
    let best = Technique::best_available(caps).map_err(|e| e.to_string())?;
    let first = asked.unwrap_or(best);
    let config = RendererConfig {
        width: gpu.config.width,
        height: gpu.config.height,
        output_format: gpu.config.format,
        oit: OitConfig::with(first),
        ..RendererConfig::default()
    };
    let renderer = renderer(&gpu.ctx, &world, &meshes, config).map_err(|e| e.to_string())?;
    let select: HtmlSelectElement = element("technique")?;
    let document = window()?.document().ok_or("no document")?;
    for t in supported
        .iter()
        .copied()
        .filter(|t| !t.stalls())
        .chain(asked)
    {
        if select
            .query_selector(&format!("option[value='{t}']"))
            .map_err(js)?
            .is_some()
        {
            continue;
        }
        let option: HtmlOptionElement = document
            .create_element("option")
            .map_err(js)?
            .dyn_into()
            .map_err(|_| "not an option")?;
        option.set_value(t.name());
        option.set_text(t.name());
        select.append_child(&option).map_err(js)?;
    }
    select.set_value(renderer.config().oit.technique.name());
    show(&format!(
        "{} · {} chunks · WASD, Space, Shift and a mouse drag to fly",
        gpu.backend,
        meshes.len()
    ));
    let app = Rc::new(RefCell::new(App {
        gpu,
        renderer,
        world,
        fly: FlyCamera::from_camera(&camera),
        keys: HashSet::new(),
        dragging: false,
        last_ms: now(),
    }));
    listen(&select, "change", {
        let (app, select) = (Rc::clone(&app), select.clone());
        move |_: web_sys::Event| {
            let Ok(t) = Technique::from_name(&select.value()) else {
                return;
            };
            match app.borrow_mut().renderer.set_technique(t) {
                Ok(drew) => show(&format!("drawing with {drew}")),
                Err(e) => show(&format!("{t}: {e}")),
            }
        }
    })?;
    let w = window()?;
    listen(&w, "keydown", {
        let app = Rc::clone(&app);
        move |e: web_sys::KeyboardEvent| {
            if Movement::from_keys([e.code().as_str()]) != Movement::default() {
                e.prevent_default();
                app.borrow_mut().keys.insert(e.code());
            }
        }
    })?;
    listen(&w, "keyup", {
        let app = Rc::clone(&app);
        move |e: web_sys::KeyboardEvent| {
            app.borrow_mut().keys.remove(&e.code());
        }
    })?;
    // A window losing focus never sees its keys go up.
    listen(&w, "blur", {
        let app = Rc::clone(&app);
        move |_: web_sys::Event| app.borrow_mut().keys.clear()
    })?;
    let canvas: HtmlCanvasElement = element("view")?;
    listen(&canvas, "mousedown", {
        let app = Rc::clone(&app);
        move |_: web_sys::MouseEvent| app.borrow_mut().dragging = true
    })?;
    listen(&w, "mouseup", {
        let app = Rc::clone(&app);
        move |_: web_sys::MouseEvent| app.borrow_mut().dragging = false
    })?;
    listen(&w, "mousemove", {
        let app = Rc::clone(&app);
        move |e: web_sys::MouseEvent| {
            let mut app = app.borrow_mut();
            if app.dragging {
                app.fly
                    .turn(f64::from(e.movement_x()), f64::from(e.movement_y()));
            }
        }
    })?;
    // The frame loop: each frame asks for the next.
    let next: Rc<RefCell<Option<FrameCallback>>> = Rc::new(RefCell::new(None));
    let first_frame = Rc::clone(&next);
    *first_frame.borrow_mut() = Some(Closure::new(move |now_ms: f64| {
        if let Err(e) = app.borrow_mut().frame(now_ms) {
            log::error!("{e}");
            show(&format!("error: {e}"));
            return;
        }
        if let (Ok(w), Some(f)) = (window(), next.borrow().as_ref()) {
            let _ = w.request_animation_frame(f.as_ref().unchecked_ref());
        }
    }));
    if let Some(f) = first_frame.borrow().as_ref() {
        w.request_animation_frame(f.as_ref().unchecked_ref())
            .map_err(js)?;
    }
    Ok(())
}

/// What `requestAnimationFrame` calls: the time of the frame, milliseconds.
type FrameCallback = Closure<dyn FnMut(f64)>;

/// Calls `f` on every `event` of `target`, for the life of the page.
fn listen<E: JsCast + 'static>(
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
async fn post(path: &str, body: &[u8]) -> Result<(), String> {
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
async fn sleep(ms: i32) {
    let promise = js_sys::Promise::new(&mut |resolve, _| {
        if let Some(w) = web_sys::window() {
            let _ = w.set_timeout_with_callback_and_timeout_and_arguments_0(&resolve, ms);
        }
    });
    let _ = JsFuture::from(promise).await;
}

fn now() -> f64 {
    web_sys::window()
        .and_then(|w| w.performance())
        .map_or(0.0, |p| p.now())
}

fn window() -> Result<web_sys::Window, String> {
    web_sys::window().ok_or_else(|| "no window".to_owned())
}

/// The page's element `id`, as `T`.
fn element<T: JsCast>(id: &str) -> Result<T, String> {
    window()?
        .document()
        .and_then(|d| d.get_element_by_id(id))
        .ok_or_else(|| format!("the page has no #{id}"))?
        .dyn_into()
        .map_err(|_| format!("#{id} is not the element expected"))
}

/// Sets the text of element `id`, if the page has it.
fn set_text(id: &str, text: &str) {
    if let Some(e) = web_sys::window()
        .and_then(|w| w.document())
        .and_then(|d| d.get_element_by_id(id))
    {
        e.set_text_content(Some(text));
    }
}

/// Shows `text` in the status line (and the console).
fn show(text: &str) {
    web_sys::console::log_1(&JsValue::from_str(text));
    set_text("status", text);
}

/// A JavaScript exception's text.
fn js(e: JsValue) -> String {
    e.as_string().unwrap_or_else(|| format!("{e:?}"))
}
