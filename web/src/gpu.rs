//! The page's GPU (wasm32): a device on WebGPU or WebGL2 with the canvas's surface, made
//! and checked step by step, falling back to WebGL2 where WebGPU fails at any step
//! (no `navigator.gpu`, no adapter, no device, a surface that cannot be configured or
//! cannot present, a device lost or erring during start-up); the canvas's size followed.

use std::sync::{Arc, Mutex, PoisonError};

use voxel_render::{Camera, GameStages, GpuContext, Renderer};
use wasm_bindgen::JsCast;
use web_sys::HtmlCanvasElement;

use crate::page::{element, sleep, window};

/// The backend asked for in the URL.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Choice {
    /// WebGPU, falling back to WebGL2 where WebGPU fails at any step.
    Auto,
    /// WebGPU only (a failure is the page's error).
    WebGpu,
    /// WebGL2 only.
    WebGl2,
}

/// One of the browser's two APIs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Api {
    WebGpu,
    WebGl2,
}

impl Api {
    pub(crate) fn name(self) -> &'static str {
        match self {
            Api::WebGpu => "WebGPU",
            Api::WebGl2 => "WebGL2",
        }
    }
}

/// How long the start-up's probe frame may take to finish before WebGPU counts as
/// failed, milliseconds (SwiftShader's first frame takes about 100 ms here).
const PROBE_TIMEOUT_MS: f64 = 10_000.0;

/// The canvas's element id.
pub(crate) const CANVAS: &str = "view";

/// The device and the canvas's surface.
pub(crate) struct Gpu {
    pub(crate) ctx: GpuContext,
    pub(crate) surface: wgpu::Surface<'static>,
    pub(crate) config: wgpu::SurfaceConfiguration,
    pub(crate) api: Api,
    /// GPU errors wgpu reported to no one on this device.
    pub(crate) uncaptured: Arc<Mutex<Vec<String>>>,
    /// Kept as long as the device: WebGPU rejects what is still pending on a device
    /// whose instance is gone (an error in the console).
    _instance: wgpu::Instance,
}

thread_local! {
    /// Devices that failed or were lost, kept for the page's life (a few at most: one per
    /// failed start or loss) so that what is pending on them settles quietly instead of
    /// being rejected as their instance goes.
    static RETIRED: std::cell::RefCell<Vec<Gpu>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// Keeps `gpu` for the page's life (see `RETIRED`).
pub(crate) fn retire(gpu: Gpu) {
    RETIRED.with_borrow_mut(|r| r.push(gpu));
}

impl Gpu {
    /// A device for `choice` on the canvas; for [`Choice::Auto`] WebGL2 where WebGPU
    /// fails, with why WebGPU failed (to be said on the page).
    pub(crate) async fn start(choice: Choice) -> Result<(Self, Option<String>), String> {
        match choice {
            Choice::WebGl2 => Ok((Self::new(Api::WebGl2).await?, None)),
            Choice::WebGpu => Ok((Self::new(Api::WebGpu).await?, None)),
            Choice::Auto => match Self::new(Api::WebGpu).await {
                Ok(gpu) => Ok((gpu, None)),
                Err(why) => {
                    log::warn!("WebGPU failed ({why}); falling back to WebGL2");
                    let gpu = Self::new(Api::WebGl2).await.map_err(|e| {
                        format!("WebGPU failed ({why}), and WebGL2 failed too ({e})")
                    })?;
                    Ok((gpu, Some(why)))
                }
            },
        }
    }

    /// A device on `api` drawing into the canvas, checked by drawing and presenting one
    /// frame; an error names the step that failed.
    pub(crate) async fn new(api: Api) -> Result<Self, String> {
        // A canvas that ever gave a context of one kind gives no other: a fresh one.
        let canvas = fresh_canvas()?;
        let (w, h) = fit(&canvas, 8192);
        let backends = match api {
            Api::WebGpu => {
                let navigator = window()?.navigator();
                let has_gpu = js_sys::Reflect::get(&navigator, &"gpu".into())
                    .is_ok_and(|g| !g.is_undefined() && !g.is_null());
                if !has_gpu {
                    return Err("this browser has no WebGPU (no navigator.gpu)".into());
                }
                wgpu::Backends::BROWSER_WEBGPU
            }
            Api::WebGl2 => wgpu::Backends::GL,
        };
        let instance = wgpu::Instance::new(voxel_render::instance_descriptor(backends));
        let surface = instance
            .create_surface(wgpu::SurfaceTarget::Canvas(canvas.clone()))
            .map_err(|e| format!("no {} surface on the canvas: {e}", api.name()))?;
        let adapter = instance
            .request_adapter(&wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::HighPerformance,
                compatible_surface: Some(&surface),
                ..Default::default()
            })
            .await
            .map_err(|e| format!("no {} adapter: {e}", api.name()))?;
        let (device, queue) = voxel_render::request_device(&adapter)
            .await
            .map_err(|e| format!("no {} device: {e}", api.name()))?;
        let uncaptured = Arc::new(Mutex::new(Vec::new()));
        let errors = Arc::clone(&uncaptured);
        device.on_uncaptured_error(Arc::new(move |error: wgpu::Error| {
            log::error!("uncaptured GPU error: {error}");
            errors
                .lock()
                .unwrap_or_else(PoisonError::into_inner)
                .push(error.to_string());
        }));
        let ctx = GpuContext::from_device(&adapter, device, queue);
        let (w, h) = {
            let max = ctx.device.limits().max_texture_dimension_2d;
            (w.min(max), h.min(max))
        };
        let mut config = surface
            .get_default_config(&adapter, w, h)
            .ok_or("the canvas's surface offers no configuration")?;
        // The renderer draws into the formats of `OUTPUT_FORMATS`; prefer the first the
        // canvas offers.
        let formats = surface.get_capabilities(&adapter).formats;
        if let Some(f) = formats
            .iter()
            .find(|f| voxel_render::OUTPUT_FORMATS.contains(f))
        {
            config.format = *f;
        }
        let gpu = Self {
            ctx,
            surface,
            config,
            api,
            uncaptured,
            _instance: instance,
        };
        if let Err(e) = gpu.probe().await {
            retire(gpu);
            return Err(e);
        }
        Ok(gpu)
    }

    /// Configures the surface and presents one cleared frame, then waits for the GPU to
    /// finish it: a surface that cannot be configured or present, a device lost, or a GPU
    /// error on the way is an error naming the step.
    async fn probe(&self) -> Result<(), String> {
        let device = &self.ctx.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        self.surface.configure(device, &self.config);
        let frame = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(frame) => frame,
            other => {
                let _ = scope.pop().await;
                return Err(format!(
                    "the canvas gives no frame to draw into ({other:?})"
                ));
            }
        };
        let view = frame.texture.create_view(&Default::default());
        let mut encoder = device.create_command_encoder(&Default::default());
        drop(encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("probe"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            ..Default::default()
        }));
        // Four bytes copied after the frame and mapped: the map is done when the frame is
        // (WebGPU's `onSubmittedWorkDone` would log an error where the device is lost).
        let buffer = |label, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: 4,
                usage,
                mapped_at_creation: false,
            })
        };
        let src = buffer("probe_src", wgpu::BufferUsages::COPY_SRC);
        let dst = buffer(
            "probe_dst",
            wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        );
        encoder.copy_buffer_to_buffer(&src, 0, &dst, 0, 4);
        self.ctx.queue.submit([encoder.finish()]);
        self.ctx.queue.present(frame);
        if let Some(error) = scope.pop().await {
            return Err(format!("configuring and presenting the canvas: {error}"));
        }
        let done = Arc::new(Mutex::new(None));
        let flag = Arc::clone(&done);
        dst.slice(..).map_async(wgpu::MapMode::Read, move |result| {
            *flag.lock().unwrap_or_else(PoisonError::into_inner) = Some(result.is_ok());
        });
        let start = crate::page::now();
        loop {
            self.ctx
                .check_device()
                .map_err(|e| format!("presenting the first frame: {e}"))?;
            if let Some(e) = self.first_uncaptured() {
                return Err(format!("presenting the first frame: {e}"));
            }
            let _ = self.ctx.device.poll(wgpu::PollType::Poll);
            match *done.lock().unwrap_or_else(PoisonError::into_inner) {
                Some(true) => break,
                Some(false) => {
                    self.ctx
                        .check_device()
                        .map_err(|e| format!("presenting the first frame: {e}"))?;
                    return Err("the first frame's work failed on the GPU".into());
                }
                None => {}
            }
            if crate::page::now() - start > PROBE_TIMEOUT_MS {
                return Err("the first frame did not finish within 10 s".into());
            }
            sleep(5).await;
        }
        // A swap chain without a backing loses the device a moment after the frame.
        sleep(100).await;
        self.ctx
            .check_device()
            .map_err(|e| format!("presenting the first frame: {e}"))?;
        Ok(())
    }

    /// The first GPU error reported to no one, if any.
    pub(crate) fn first_uncaptured(&self) -> Option<String> {
        self.uncaptured
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .first()
            .cloned()
    }

    /// Follows the canvas's size on the page: the surface configured again and `true`
    /// when its drawing buffer's size changed.
    pub(crate) fn follow_size(&mut self) -> Result<bool, String> {
        let canvas: HtmlCanvasElement = element(CANVAS)?;
        let (w, h) = fit(&canvas, self.ctx.device.limits().max_texture_dimension_2d);
        if (w, h) == (self.config.width, self.config.height) {
            return Ok(false);
        }
        self.config.width = w;
        self.config.height = h;
        self.surface.configure(&self.ctx.device, &self.config);
        Ok(true)
    }
}

impl Gpu {
    /// Draws a frame of `renderer` (with `game`'s stages) into the canvas. A surface lost
    /// or outdated is configured again and drawn next frame.
    pub(crate) fn draw(
        &self,
        renderer: &mut Renderer,
        camera: &Camera,
        game: &mut dyn GameStages,
    ) -> voxel_render::Result<()> {
        let wgpu::CurrentSurfaceTexture::Success(frame) = self.surface.get_current_texture() else {
            self.ctx.check_device()?;
            self.surface.configure(&self.ctx.device, &self.config);
            return Ok(());
        };
        let view = frame.texture.create_view(&Default::default());
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        renderer.render(&mut encoder, &view, camera, game)?;
        self.ctx.queue.submit([encoder.finish()]);
        self.ctx.queue.present(frame);
        renderer.after_submit();
        Ok(())
    }
}

/// Replaces the canvas with a fresh one of the same id and attributes (a canvas that
/// gave a WebGPU context cannot give a WebGL2 one), returning it.
fn fresh_canvas() -> Result<HtmlCanvasElement, String> {
    let old: HtmlCanvasElement = element(CANVAS)?;
    let fresh: HtmlCanvasElement = old
        .clone_node()
        .map_err(crate::page::js)?
        .dyn_into()
        .map_err(|_| "the canvas's copy is not a canvas")?;
    old.replace_with_with_node_1(&fresh)
        .map_err(crate::page::js)?;
    Ok(fresh)
}

thread_local! {
    /// A drawing-buffer size that does not follow the page (the test's pictures).
    static FIXED: std::cell::Cell<Option<(u32, u32)>> = const { std::cell::Cell::new(None) };
}

/// Keeps the canvas's drawing buffer at `size` instead of following the page.
pub(crate) fn fix_size(size: (u32, u32)) {
    FIXED.set(Some(size));
}

/// Sets the canvas's drawing buffer to its size on the page in device pixels (at least
/// 1, at most `max` each way; or the size [`fix_size`] fixed) and returns it.
pub(crate) fn fit(canvas: &HtmlCanvasElement, max: u32) -> (u32, u32) {
    let ratio = web_sys::window().map_or(1.0, |w| w.device_pixel_ratio());
    let px = |css: i32| ((f64::from(css.max(1)) * ratio).round() as u32).clamp(1, max);
    let (w, h) = FIXED
        .get()
        .unwrap_or_else(|| (px(canvas.client_width()), px(canvas.client_height())));
    if (canvas.width(), canvas.height()) != (w, h) {
        canvas.set_width(w);
        canvas.set_height(h);
    }
    (w, h)
}
