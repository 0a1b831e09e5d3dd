//! The interactive page (wasm32): a [`GamePage`] drawn every animation frame with the
//! technique picker and the fly camera; the canvas follows the window; streamed chunks
//! are made within the streamer's budget each frame; a device lost makes a new device
//! and renderer by itself (WebGL2 where WebGPU will not come back).

use std::cell::RefCell;
use std::collections::HashSet;
use std::rc::Rc;

use voxel_core::ChunkPos;
use voxel_mesh::ChunkMeshes;
use voxel_render::content::{Content, ContentStages};
use voxel_render::{OitConfig, Renderer, RendererConfig, Technique};
use wasm_bindgen::JsCast;
use wasm_bindgen::prelude::*;
use web_sys::{HtmlCanvasElement, HtmlOptionElement, HtmlSelectElement};

use crate::fly::{FlyCamera, Movement};
use crate::game::{Blocks, GamePage, OnFrame, Tick};
use crate::gpu::{Api, CANVAS, Choice, Gpu};
use crate::page::{
    ERRORS, FrameCallback, Options, element, fallback_notice, js, listen, now, post, set_text,
    show, window,
};

/// Frames drawn after a start or a new device before the page reports its state
/// (`?report=1`).
const REPORT_AFTER_FRAMES: u64 = 5;
/// Frames between the page's reports after the first.
const REPORT_EVERY: u64 = 15;

/// What the page keeps between frames.
struct App {
    gpu: Gpu,
    renderer: Renderer,
    stages: ContentStages,
    blocks: Blocks,
    /// The whole world's meshes ([`Blocks::World`]), kept for a new renderer.
    meshes: Vec<(ChunkPos, ChunkMeshes)>,
    content: Content,
    on_frame: Option<OnFrame>,
    fly: FlyCamera,
    keys: HashSet<String>,
    dragging: bool,
    start_ms: f64,
    last_ms: f64,
    options: Options,
    /// Why WebGPU failed, where WebGL2 draws instead.
    fell_back: Option<String>,
    /// Frames drawn on this device.
    frames: u64,
    /// Frames drawn in all.
    total_frames: u64,
    /// New devices made after a loss.
    rebuilt: u32,
    /// Whether a new device is on its way (no frame is drawn meanwhile).
    rebuilding: bool,
    /// Whether `?lose=N` destroyed a device already.
    lost_once: bool,
    /// Failures of streamed chunks, in all.
    failed_chunks: usize,
}

/// A renderer drawing `technique` (else the best the device runs) with `blocks` uploaded
/// and `content`'s stages.
fn build(
    gpu: &Gpu,
    blocks: &Blocks,
    meshes: &[(ChunkPos, ChunkMeshes)],
    technique: Option<Technique>,
    content: &Content,
) -> Result<(Renderer, ContentStages), String> {
    let best = Technique::best_available(&gpu.ctx.caps).map_err(|e| e.to_string())?;
    let config = RendererConfig {
        width: gpu.config.width,
        height: gpu.config.height,
        output_format: gpu.config.format,
        oit: OitConfig::with(technique.unwrap_or(best)),
        ..RendererConfig::default()
    };
    let world = blocks.world();
    let mut renderer =
        crate::page::renderer(&gpu.ctx, world, meshes, config).map_err(|e| e.to_string())?;
    if let Blocks::Stream(streamer) = blocks {
        // A new renderer holds none of what the streamer uploaded: mesh it again.
        let positions: Vec<ChunkPos> = streamer.uploaded().collect();
        for (pos, m) in voxel_mesh::mesh_chunks(world, &positions).map_err(|e| e.to_string())? {
            renderer.upload_chunk(pos, &m).map_err(|e| e.to_string())?;
        }
    }
    let stages = ContentStages::new(&renderer, content.clone()).map_err(|e| e.to_string())?;
    Ok((renderer, stages))
}

/// Starts the page: the picker, the fly camera, the listeners and the frame loop.
pub(crate) fn run(
    gpu: Gpu,
    fell_back: Option<String>,
    page: GamePage,
    options: Options,
) -> Result<(), String> {
    if !page.title.is_empty() {
        set_text("title", &page.title);
        if let Some(d) = window()?.document() {
            d.set_title(&page.title);
        }
    }
    let meshes = match &page.blocks {
        Blocks::World(world) => {
            crate::scene::mesh_world(world, page.light).map_err(|e| e.to_string())?
        }
        Blocks::Stream(_) => Vec::new(),
    };
    let (renderer, stages) = build(
        &gpu,
        &page.blocks,
        &meshes,
        options.technique,
        &page.content,
    )?;
    fill_picker(&gpu, &renderer, options.technique)?;
    let start = now();
    let app = Rc::new(RefCell::new(App {
        gpu,
        renderer,
        stages,
        blocks: page.blocks,
        meshes,
        content: page.content,
        on_frame: page.on_frame,
        fly: FlyCamera::from_camera(&page.camera),
        keys: HashSet::new(),
        dragging: false,
        start_ms: start,
        last_ms: start,
        options,
        fell_back,
        frames: 0,
        total_frames: 0,
        rebuilt: 0,
        rebuilding: false,
        lost_once: false,
        failed_chunks: 0,
    }));
    app.borrow().show_drawing();
    listeners(&app)?;
    // The frame loop: each frame asks for the next.
    let next: Rc<RefCell<Option<FrameCallback>>> = Rc::new(RefCell::new(None));
    let first_frame = Rc::clone(&next);
    *first_frame.borrow_mut() = Some(Closure::new(move |now_ms: f64| {
        if let Err(e) = App::frame(&app, now_ms) {
            log::error!("{e}");
            show(&format!("error: {e}"));
            return;
        }
        if let (Ok(w), Some(f)) = (window(), next.borrow().as_ref()) {
            let _ = w.request_animation_frame(f.as_ref().unchecked_ref());
        }
    }));
    if let Some(f) = first_frame.borrow().as_ref() {
        window()?
            .request_animation_frame(f.as_ref().unchecked_ref())
            .map_err(js)?;
    }
    Ok(())
}

impl App {
    /// The status line: what draws, and how to fly.
    fn show_drawing(&self) {
        let chunks = match &self.blocks {
            Blocks::World(_) => format!("{} chunks", self.meshes.len()),
            Blocks::Stream(s) => format!("streaming ({} chunks drawn)", s.uploaded().count()),
        };
        let mut line = format!(
            "{} · {} · {chunks} · WASD, Space, Shift and a mouse drag to fly",
            self.gpu.api.name(),
            self.renderer.config().oit.technique,
        );
        if self.rebuilt > 0 {
            line = format!(
                "the GPU device was lost; drawing on a new one ({} since the start) · {line}",
                self.rebuilt
            );
        }
        show(&line);
        set_text(
            "notice",
            &self
                .fell_back
                .as_deref()
                .map(fallback_notice)
                .unwrap_or_default(),
        );
    }

    fn frame(app: &Rc<RefCell<App>>, now_ms: f64) -> Result<(), String> {
        let mut this = app.borrow_mut();
        if this.rebuilding {
            return Ok(());
        }
        if this.gpu.ctx.is_lost() {
            drop(this);
            Self::rebuild(app);
            return Ok(());
        }
        match this.draw(now_ms) {
            Ok(()) => {}
            Err(voxel_render::Error::DeviceLost { reason }) => {
                log::warn!("the GPU device was lost ({reason}): making a new one");
                drop(this);
                Self::rebuild(app);
                return Ok(());
            }
            Err(e) => return Err(e.to_string()),
        }
        this.frames += 1;
        this.total_frames += 1;
        if this.options.lose_after == Some(this.total_frames) && !this.lost_once {
            // `?lose=N`: the device destroyed, as a driver reset or the browser would.
            this.lost_once = true;
            log::warn!(
                "?lose: destroying the device after {} frames",
                this.total_frames
            );
            this.gpu.ctx.device.destroy();
        }
        let f = this.frames;
        if this.options.report && (f == REPORT_AFTER_FRAMES || f.is_multiple_of(REPORT_EVERY)) {
            let (state, picture) = this.state();
            wasm_bindgen_futures::spawn_local(async move {
                let _ = post("/picture", picture.as_bytes()).await;
                let _ = post("/status", state.as_bytes()).await;
            });
        }
        if this.frames.is_multiple_of(60) {
            this.show_drawing();
        }
        Ok(())
    }

    /// One frame: the size followed, the camera moved, chunks streamed, things moved,
    /// the picture drawn.
    fn draw(&mut self, now_ms: f64) -> voxel_render::Result<()> {
        if self
            .gpu
            .follow_size()
            .map_err(voxel_render::Error::InvalidSetting)?
        {
            self.renderer
                .resize(self.gpu.config.width, self.gpu.config.height)?;
        }
        let dt = ((now_ms - self.last_ms) / 1000.0).clamp(0.0, 0.25);
        self.last_ms = now_ms;
        self.fly.fly(
            Movement::from_keys(self.keys.iter().map(String::as_str)),
            dt,
        );
        let eye = self.fly.eye;
        if let Blocks::Stream(streamer) = &mut self.blocks {
            let frame = streamer.update(eye, &mut self.renderer)?;
            for (pos, why) in &frame.failed {
                log::warn!("chunk {pos:?}: {why}");
            }
            self.failed_chunks += frame.failed.len();
        }
        if let Some(f) = &mut self.on_frame {
            let tick = Tick {
                seconds: (now_ms - self.start_ms) / 1000.0,
                dt,
                eye,
            };
            if let Some(content) = f(tick, &self.content) {
                self.stages.set_content(&self.gpu.ctx, content.clone())?;
                self.content = content;
            }
        }
        // A lit world's sun shadows follow the eye (the page's world is wider than their
        // volume; nothing is read while the eye stays in its chunk).
        if let Blocks::World(world) = &self.blocks {
            self.renderer
                .follow_sun_shadows(world, voxel_core::WorldPos::containing(eye.to_array()));
        }
        let medium = self.blocks.world().medium_at(eye.to_array());
        let camera = self.fly.camera(medium)?;
        self.gpu.draw(&mut self.renderer, &camera, &mut self.stages)
    }

    /// Makes a new device and renderer on the event loop (WebGL2 where the lost device
    /// was WebGPU's and WebGPU does not come back, unless WebGPU was asked for).
    fn rebuild(app: &Rc<RefCell<App>>) {
        let (api, choice) = {
            let mut this = app.borrow_mut();
            this.rebuilding = true;
            (this.gpu.api, this.options.backend)
        };
        show("the GPU device was lost; making a new device and renderer…");
        let app = Rc::clone(app);
        wasm_bindgen_futures::spawn_local(async move {
            let gpu = match Gpu::new(api).await {
                Ok(gpu) => Ok((gpu, None)),
                Err(why) if api == Api::WebGpu && choice == Choice::Auto => {
                    log::warn!("WebGPU did not come back ({why}); falling back to WebGL2");
                    Gpu::new(Api::WebGl2).await.map(|g| (g, Some(why)))
                }
                Err(why) => Err(why),
            };
            let result = gpu.and_then(|(gpu, fell_back)| {
                let this = app.borrow();
                let technique = Some(this.renderer.config().oit.technique);
                let built = build(&gpu, &this.blocks, &this.meshes, technique, &this.content)?;
                Ok((gpu, fell_back, built))
            });
            let mut this = app.borrow_mut();
            match result {
                Ok((gpu, fell_back, (renderer, stages))) => {
                    if let Some(why) = fell_back {
                        this.fell_back = Some(why);
                    }
                    if let Err(e) = fill_picker(&gpu, &renderer, None) {
                        log::error!("{e}");
                    }
                    set_text("backend", &gpu.ctx.caps.adapter_name);
                    let old = std::mem::replace(&mut this.gpu, gpu);
                    crate::gpu::retire(old);
                    this.renderer = renderer;
                    this.stages = stages;
                    this.rebuilt += 1;
                    this.frames = 0;
                    this.rebuilding = false;
                    this.show_drawing();
                }
                Err(e) => {
                    log::error!("no new device after a loss: {e}");
                    show(&format!(
                        "error: the GPU device was lost and no new one could be made: {e}"
                    ));
                }
            }
        });
    }

    /// The page's state, for the browser tests (`?report=1`), and what the canvas shows
    /// (a PNG data URL).
    fn state(&self) -> (String, String) {
        let (iw, ih, sw, sh) = window()
            .ok()
            .and_then(|w| {
                let root = w.document()?.document_element()?;
                let inner = |v: Result<JsValue, JsValue>| {
                    v.ok().and_then(|v| v.as_f64()).unwrap_or(0.0) as i32
                };
                Some((
                    inner(w.inner_width()),
                    inner(w.inner_height()),
                    root.scroll_width(),
                    root.scroll_height(),
                ))
            })
            .unwrap_or_default();
        let canvas: Option<HtmlCanvasElement> = element(CANVAS).ok();
        let (cw, ch) = canvas
            .as_ref()
            .map_or((0, 0), |c| (c.client_width(), c.client_height()));
        let text = |id: &str| {
            window()
                .ok()
                .and_then(|w| w.document())
                .and_then(|d| d.get_element_by_id(id))
                .and_then(|e| e.text_content())
                .unwrap_or_default()
        };
        let (colours, picture) = canvas.as_ref().map_or((0, String::new()), canvas_picture);
        let errors = ERRORS.with(|e| e.borrow().clone());
        let chunks = match &self.blocks {
            Blocks::World(_) => self.meshes.len(),
            Blocks::Stream(s) => s.uploaded().count(),
        };
        let mut out = format!(
            "backend: {}\nadapter: {}\ntechnique: {}\nstatus: {}\nnotice: {}\nframes: {}\n\
             rebuilt: {}\ndrawing buffer: {}x{}\ncanvas: {cw}x{ch}\nwindow: {iw}x{ih}\n\
             scroll: {sw}x{sh}\ncolours: {colours}\nchunks: {chunks}\nfailed chunks: {}\n\
             things: {}\nidle: {}\nerrors: {}\n",
            self.gpu.api.name(),
            self.gpu.ctx.caps.adapter_name,
            self.renderer.config().oit.technique,
            text("status"),
            text("notice"),
            self.total_frames,
            self.rebuilt,
            self.gpu.config.width,
            self.gpu.config.height,
            self.failed_chunks,
            self.content.particles.len() + self.content.entities.len(),
            match &self.blocks {
                Blocks::World(_) => true,
                Blocks::Stream(s) => s.is_idle(),
            },
            errors.len(),
        );
        for e in errors {
            out += &format!("error: {e}\n");
        }
        (out, picture)
    }
}

/// Distinct colours of what the canvas shows now (drawn into a 2D canvas and read
/// back: a blank or white box has one or two), and that picture as a PNG data URL.
fn canvas_picture(canvas: &HtmlCanvasElement) -> (usize, String) {
    let count = || -> Option<(usize, String)> {
        let document = window().ok()?.document()?;
        let copy: HtmlCanvasElement = document.create_element("canvas").ok()?.dyn_into().ok()?;
        let (w, h) = (canvas.width().min(512), canvas.height().min(512));
        copy.set_width(w);
        copy.set_height(h);
        let ctx: web_sys::CanvasRenderingContext2d =
            copy.get_context("2d").ok()??.dyn_into().ok()?;
        ctx.draw_image_with_html_canvas_element_and_dw_and_dh(canvas, 0.0, 0.0, w.into(), h.into())
            .ok()?;
        let data = ctx
            .get_image_data(0.0, 0.0, w.into(), h.into())
            .ok()?
            .data();
        let colours: HashSet<[u8; 4]> = data
            .chunks_exact(4)
            .map(|p| [p[0], p[1], p[2], p[3]])
            .collect();
        Some((colours.len(), copy.to_data_url().ok()?))
    };
    count().unwrap_or_default()
}

/// The picker: the techniques the device runs without stalling (and `asked`), the
/// renderer's selected.
fn fill_picker(gpu: &Gpu, renderer: &Renderer, asked: Option<Technique>) -> Result<(), String> {
    let select: HtmlSelectElement = element("technique")?;
    let document = window()?.document().ok_or("no document")?;
    select.set_inner_html("");
    let supported = Technique::supported(&gpu.ctx.caps);
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
    Ok(())
}

/// The picker, the keys and the mouse.
fn listeners(app: &Rc<RefCell<App>>) -> Result<(), String> {
    let select: HtmlSelectElement = element("technique")?;
    listen(&select, "change", {
        let (app, select) = (Rc::clone(app), select.clone());
        move |_: web_sys::Event| {
            let Ok(t) = select.value().parse::<Technique>() else {
                return;
            };
            let mut app = app.borrow_mut();
            match app.renderer.set_technique(t) {
                Ok(_) => app.show_drawing(),
                Err(e) => show(&format!("{t}: {e}")),
            }
        }
    })?;
    let w = window()?;
    listen(&w, "keydown", {
        let app = Rc::clone(app);
        move |e: web_sys::KeyboardEvent| {
            if Movement::from_keys([e.code().as_str()]) != Movement::default() {
                e.prevent_default();
                app.borrow_mut().keys.insert(e.code());
            }
        }
    })?;
    listen(&w, "keyup", {
        let app = Rc::clone(app);
        move |e: web_sys::KeyboardEvent| {
            app.borrow_mut().keys.remove(&e.code());
        }
    })?;
    // A window losing focus never sees its keys go up.
    listen(&w, "blur", {
        let app = Rc::clone(app);
        move |_: web_sys::Event| app.borrow_mut().keys.clear()
    })?;
    // On the window, not the canvas: a fallback or a new device replaces the canvas.
    listen(&w, "mousedown", {
        let app = Rc::clone(app);
        move |e: web_sys::MouseEvent| {
            let on_canvas = e
                .target()
                .and_then(|t| t.dyn_into::<web_sys::Element>().ok())
                .is_some_and(|t| t.id() == CANVAS);
            if on_canvas {
                app.borrow_mut().dragging = true;
            }
        }
    })?;
    listen(&w, "mouseup", {
        let app = Rc::clone(app);
        move |_: web_sys::MouseEvent| app.borrow_mut().dragging = false
    })?;
    listen(&w, "mousemove", {
        let app = Rc::clone(app);
        move |e: web_sys::MouseEvent| {
            let mut app = app.borrow_mut();
            if app.dragging {
                app.fly
                    .turn(f64::from(e.movement_x()), f64::from(e.movement_y()));
            }
        }
    })?;
    Ok(())
}
