//! The interactive demo: a winit window with a wgpu surface, generated terrain drawn by the
//! voxel renderer, an egui side panel to switch techniques and settings, a fly camera,
//! block edits remeshed in the background, live GPU timings and a live error map against
//! the exact reference.
//!
//! A frame is drawn into an sRGB offscreen target (the scene, then the panel), which is
//! blitted to the surface: one picture for the window and for screenshots.

use std::collections::{HashMap, HashSet};
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::mpsc::{Receiver, Sender, channel};
use std::time::Instant;

use glam::DVec3;
use voxel_core::{BlockId, ChunkPos, RenderClass, World, WorldPos};
use voxel_mesh::{ChunkMeshes, Mesher};
use voxel_render::{
    BayerSize, Camera, GpuContext, Image, OitConfig, Renderer, RendererConfig, Technique,
    WeightFunction, readback,
};
use winit::application::ApplicationHandler;
use winit::event::{DeviceEvent, ElementState, MouseButton, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

use crate::scene;

/// The format frames are drawn in before they reach the surface.
const FRAME_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;

/// How the demo starts, and what a scripted run does.
#[derive(Clone, Debug)]
pub struct DemoOptions {
    /// World seed.
    pub seed: u32,
    /// Initial window size.
    pub size: (u32, u32),
    /// Initial technique.
    pub technique: Technique,
    /// Chunks of terrain around the start, each way.
    pub view_distance: i32,
    /// Scripted: quit after this many frames (per technique with `cycle`).
    pub frames: Option<u64>,
    /// Scripted: save the last frame (with the panel) here.
    pub screenshot: Option<PathBuf>,
    /// Scripted: step through every technique, saving `DIR/<technique>.png` for each.
    pub cycle: Option<PathBuf>,
    /// Start with the error map on.
    pub heatmap: bool,
    /// Scripted: place a block in front of the camera on the second frame (remeshing test).
    pub edit: bool,
    /// Scripted: on frames 1 to 3, halve the window, get a zero size (what a minimised
    /// window reports), then restore the size (resize test).
    pub resize: bool,
}

impl Default for DemoOptions {
    fn default() -> Self {
        Self {
            seed: 1,
            size: (1280, 720),
            technique: Technique::WboitMrt,
            view_distance: scene::DEFAULT_RADIUS,
            frames: None,
            screenshot: None,
            cycle: None,
            heatmap: false,
            edit: false,
            resize: false,
        }
    }
}

/// Whether a window can be opened: an X11 or Wayland display is named in the environment.
pub fn have_display() -> bool {
    ["DISPLAY", "WAYLAND_DISPLAY"]
        .iter()
        .any(|v| std::env::var_os(v).is_some_and(|s| !s.is_empty()))
}

/// Opens the window and runs until it is closed (or the script ends).
pub fn run(opts: DemoOptions) -> Result<(), String> {
    let event_loop = EventLoop::new().map_err(|e| format!("cannot open a window: {e}"))?;
    let mut app = App {
        opts,
        gfx: None,
        error: None,
    };
    event_loop
        .run_app(&mut app)
        .map_err(|e| format!("event loop: {e}"))?;
    app.error.map_or(Ok(()), Err)
}

struct App {
    opts: DemoOptions,
    gfx: Option<Gfx>,
    error: Option<String>,
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.gfx.is_some() {
            return;
        }
        let attrs = Window::default_attributes()
            .with_title("voxel-oit")
            .with_inner_size(winit::dpi::PhysicalSize::new(
                self.opts.size.0,
                self.opts.size.1,
            ));
        let result = event_loop
            .create_window(attrs)
            .map_err(|e| format!("cannot create the window: {e}"))
            .and_then(|w| Gfx::new(Arc::new(w), self.opts.clone()));
        match result {
            Ok(g) => {
                g.window.request_redraw();
                self.gfx = Some(g);
            }
            Err(e) => {
                self.error = Some(e);
                event_loop.exit();
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(g) = &mut self.gfx else { return };
        let egui_wants = g.egui_state.on_window_event(&g.window, &event).consumed;
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => g.resize(size.width, size.height),
            WindowEvent::RedrawRequested => match g.frame() {
                Ok(Flow::Continue) => {}
                Ok(Flow::Quit) => event_loop.exit(),
                Err(e) => {
                    self.error = Some(e);
                    event_loop.exit();
                }
            },
            WindowEvent::KeyboardInput { event, .. } if !egui_wants => {
                if let PhysicalKey::Code(code) = event.physical_key {
                    g.key(code, event.state == ElementState::Pressed);
                }
            }
            WindowEvent::MouseInput { state, button, .. } => {
                g.mouse_button(button, state == ElementState::Pressed, egui_wants);
            }
            WindowEvent::ModifiersChanged(m) => g.ctrl = m.state().control_key(),
            _ => {}
        }
    }

    fn device_event(
        &mut self,
        _event_loop: &ActiveEventLoop,
        _id: winit::event::DeviceId,
        event: DeviceEvent,
    ) {
        if let (Some(g), DeviceEvent::MouseMotion { delta }) = (&mut self.gfx, event)
            && g.looking
        {
            g.dragged += delta.0.abs() + delta.1.abs();
            g.fly.yaw += delta.0 * 0.003;
            g.fly.pitch = (g.fly.pitch - delta.1 * 0.003).clamp(-1.5, 1.5);
        }
    }

    fn about_to_wait(&mut self, _event_loop: &ActiveEventLoop) {
        if let Some(g) = &self.gfx {
            g.window.request_redraw();
        }
    }
}

enum Flow {
    Continue,
    Quit,
}

/// Fly camera state.
#[derive(Clone, Copy, Debug)]
struct Fly {
    eye: DVec3,
    yaw: f64,
    pitch: f64,
    speed: f64,
}

/// Settings the panel edits.
#[derive(Clone, Debug, PartialEq)]
struct Settings {
    oit: OitConfig,
    msaa: bool,
    fade_in_frames: u32,
    seed: u32,
    view_distance: i32,
    heatmap: bool,
    place: BlockId,
}

/// An offscreen colour target of the window's size.
struct Target {
    texture: wgpu::Texture,
    view: wgpu::TextureView,
}

impl Target {
    fn new(device: &wgpu::Device, label: &str, w: u32, h: u32) -> Self {
        use wgpu::TextureUsages as U;
        let usage = U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC | U::COPY_DST;
        let (texture, view) = voxel_render::render_target(device, label, FRAME_FORMAT, usage, w, h);
        Self { texture, view }
    }
}

/// Fullscreen passes of the demo: the blit to the surface and the error map.
struct Post {
    layout: wgpu::BindGroupLayout,
    blit: wgpu::RenderPipeline,
    diff: wgpu::RenderPipeline,
    sampler: wgpu::Sampler,
}

const POST_WGSL: &str = r#"
struct Out { @builtin(position) clip: vec4<f32>, @location(0) uv: vec2<f32> };

@vertex
fn vs(@builtin(vertex_index) vi: u32) -> Out {
    let uv = vec2<f32>(f32((vi << 1u) & 2u), f32(vi & 2u));
    var out: Out;
    out.clip = vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
    out.uv = vec2<f32>(uv.x, 1.0 - uv.y);
    return out;
}

@group(0) @binding(0) var a: texture_2d<f32>;
@group(0) @binding(1) var b: texture_2d<f32>;
@group(0) @binding(2) var s: sampler;

override SRGB_ENCODE: bool = false;

fn encode(c: f32) -> f32 {
    if c <= 0.0031308 { return c * 12.92; }
    return 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}

@fragment
fn fs_blit(in: Out) -> @location(0) vec4<f32> {
    let c = textureSample(a, s, in.uv).rgb;
    if SRGB_ENCODE {
        return vec4<f32>(encode(c.r), encode(c.g), encode(c.b), 1.0);
    }
    return vec4<f32>(c, 1.0);
}

// Error map: the largest channel difference (in sRGB steps) between the technique's
// picture and the reference's, from black through red and yellow to white at 32/255,
// over a dim grey copy of the picture so that the scene stays readable. A difference of
// one step is rounding (the two exact methods differ by that much) and is not shown.
@fragment
fn fs_diff(in: Out) -> @location(0) vec4<f32> {
    let p = vec2<i32>(in.clip.xy);
    let x = textureLoad(a, p, 0).rgb;
    let y = textureLoad(b, p, 0).rgb;
    let d = abs(vec3<f32>(encode(x.r), encode(x.g), encode(x.b)) - vec3<f32>(encode(y.r), encode(y.g), encode(y.b)));
    let e = clamp(max(d.r, max(d.g, d.b)) * 255.0 / 32.0, 0.0, 1.0);
    let heat = clamp(vec3<f32>(e * 3.0, e * 3.0 - 1.0, e * 3.0 - 2.0), vec3<f32>(0.0), vec3<f32>(1.0));
    let grey = dot(x, vec3<f32>(0.3, 0.59, 0.11)) * 0.25;
    return vec4<f32>(select(vec3<f32>(grey), heat, e > 1.5 / 32.0), 1.0);
}
"#;

impl Post {
    fn new(device: &wgpu::Device, surface_format: wgpu::TextureFormat) -> Self {
        let tex = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: true },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("demo_post_layout"),
            entries: &[
                tex(0),
                tex(1),
                wgpu::BindGroupLayoutEntry {
                    binding: 2,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
            ],
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("demo_post"),
            source: wgpu::ShaderSource::Wgsl(POST_WGSL.into()),
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("demo_post"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let make = |label, entry, format: wgpu::TextureFormat| {
            let encode = if format.is_srgb() { 0.0 } else { 1.0 };
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(&pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: wgpu::PrimitiveState::default(),
                depth_stencil: None,
                multisample: wgpu::MultisampleState::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(entry),
                    compilation_options: wgpu::PipelineCompilationOptions {
                        constants: &[("SRGB_ENCODE", encode)],
                        ..Default::default()
                    },
                    targets: &[Some(wgpu::ColorTargetState {
                        format,
                        blend: None,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        Self {
            blit: make("demo_blit", "fs_blit", surface_format),
            diff: make("demo_error_map", "fs_diff", FRAME_FORMAT),
            sampler: device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("demo_blit"),
                ..Default::default()
            }),
            layout,
        }
    }

    fn group(
        &self,
        device: &wgpu::Device,
        a: &wgpu::TextureView,
        b: &wgpu::TextureView,
    ) -> wgpu::BindGroup {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("demo_post"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(a),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(b),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::Sampler(&self.sampler),
                },
            ],
        })
    }

    fn draw(
        encoder: &mut wgpu::CommandEncoder,
        pipeline: &wgpu::RenderPipeline,
        group: &wgpu::BindGroup,
        target: &wgpu::TextureView,
    ) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("demo_post"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, group, &[]);
        pass.draw(0..3, 0..1);
    }
}

/// Targets of the window's size.
/// Targets of one window size: the whole frame (panel included, what the surface and
/// screenshots get), and the 3D view right of the panel, with the technique's and the
/// reference's pictures for the error map.
struct Frames {
    frame: Target,
    view: Target,
    /// Left edge of the 3D view in the frame, pixels.
    view_x: u32,
    technique: Target,
    reference: Target,
    blit_group: wgpu::BindGroup,
    diff_group: wgpu::BindGroup,
}

impl Frames {
    fn new(device: &wgpu::Device, post: &Post, w: u32, h: u32, view_x: u32) -> Self {
        let view_w = w.saturating_sub(view_x).max(1);
        let frame = Target::new(device, "demo_frame", w, h);
        let view = Target::new(device, "demo_view", view_w, h);
        let technique = Target::new(device, "demo_technique", view_w, h);
        let reference = Target::new(device, "demo_reference", view_w, h);
        Self {
            blit_group: post.group(device, &frame.view, &frame.view),
            diff_group: post.group(device, &technique.view, &reference.view),
            frame,
            view,
            view_x,
            technique,
            reference,
        }
    }

    fn view_size(&self) -> (u32, u32) {
        (self.view.texture.width(), self.view.texture.height())
    }
}

struct Gfx {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    instance: wgpu::Instance,
    surface_config: wgpu::SurfaceConfiguration,
    ctx: GpuContext,
    renderer: Renderer,
    reference: Option<Renderer>,
    post: Post,
    frames: Frames,
    egui_ctx: egui::Context,
    egui_state: egui_winit::State,
    egui_renderer: egui_wgpu::Renderer,
    world: World,
    mesh_tx: Sender<(ChunkPos, u64, Result<ChunkMeshes, String>)>,
    mesh_rx: Receiver<(ChunkPos, u64, Result<ChunkMeshes, String>)>,
    generation: HashMap<ChunkPos, u64>,
    pending: usize,
    fly: Fly,
    far: f64,
    keys: HashSet<KeyCode>,
    looking: bool,
    dragged: f64,
    ctrl: bool,
    settings: Settings,
    applied: Settings,
    stats: voxel_render::FrameStats,
    gpu_times: Vec<(&'static str, f64)>,
    fps: f64,
    last: Instant,
    frame_index: u64,
    opts: DemoOptions,
    cycle: Vec<Technique>,
    screenshot_request: Option<PathBuf>,
    message: String,
}

impl Gfx {
    fn new(window: Arc<Window>, opts: DemoOptions) -> Result<Self, String> {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = wgpu::Backends::from_env().unwrap_or(wgpu::Backends::PRIMARY);
        let instance = wgpu::Instance::new(desc);
        let surface = instance
            .create_surface(window.clone())
            .map_err(|e| format!("cannot create a surface for the window: {e}"))?;
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            compatible_surface: Some(&surface),
            ..Default::default()
        }))
        .map_err(|e| {
            format!("no GPU adapter can draw to this window: {e} (install mesa-vulkan-drivers)")
        })?;
        let (device, queue) = pollster::block_on(voxel_render::request_device(&adapter))
            .map_err(|e| e.to_string())?;
        let ctx = GpuContext::from_device(&adapter, device, queue);
        let caps = surface.get_capabilities(&adapter);
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| f.is_srgb())
            .or_else(|| caps.formats.first().copied())
            .ok_or("the surface offers no format")?;
        let size = window.inner_size();
        let (w, h) = (size.width.max(1), size.height.max(1));
        let surface_config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            width: w,
            height: h,
            present_mode: wgpu::PresentMode::AutoVsync,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps
                .alpha_modes
                .first()
                .copied()
                .unwrap_or(wgpu::CompositeAlphaMode::Auto),
            view_formats: vec![],
            color_space: wgpu::SurfaceColorSpace::Auto,
        };
        surface.configure(&ctx.device, &surface_config);

        let scene = scene::default_scene_with_radius(opts.seed, opts.view_distance)?;
        let cam = scene.cameras[0];
        let (yaw, pitch) = cam.yaw_pitch();
        let mut oit = OitConfig {
            technique: opts.technique,
            ..OitConfig::default()
        };
        oit.width = w;
        oit.height = h;
        let settings = Settings {
            oit: oit.clone(),
            msaa: false,
            // New chunks dissolve in over 20 frames; a scripted run (a test, a screenshot)
            // shows the settled picture from its first frame instead.
            fade_in_frames: if opts.frames.is_some() { 0 } else { 20 },
            seed: opts.seed,
            view_distance: opts.view_distance,
            heatmap: opts.heatmap,
            place: voxel_core::blocks::GLASS,
        };
        let config = RendererConfig {
            width: w,
            height: h,
            output_format: FRAME_FORMAT,
            oit,
            fade_in_frames: settings.fade_in_frames,
            ..RendererConfig::default()
        };
        let renderer =
            Renderer::new(&ctx, scene.world.registry(), config).map_err(|e| e.to_string())?;
        let post = Post::new(&ctx.device, format);
        let frames = Frames::new(&ctx.device, &post, w, h, 0);
        let egui_ctx = egui::Context::default();
        let egui_state = egui_winit::State::new(
            egui_ctx.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(ctx.caps.limits.max_texture_dimension_2d as usize),
        );
        let egui_renderer = egui_wgpu::Renderer::new(
            &ctx.device,
            FRAME_FORMAT,
            egui_wgpu::RendererOptions::default(),
        );
        let (mesh_tx, mesh_rx) = channel();
        let cycle = if opts.cycle.is_some() {
            Technique::ALL.to_vec()
        } else {
            Vec::new()
        };
        let mut g = Self {
            window,
            surface,
            instance,
            surface_config,
            ctx,
            renderer,
            reference: None,
            post,
            frames,
            egui_ctx,
            egui_state,
            egui_renderer,
            world: scene.world,
            mesh_tx,
            mesh_rx,
            generation: HashMap::new(),
            pending: 0,
            fly: Fly {
                eye: cam.eye,
                yaw,
                pitch,
                speed: 12.0,
            },
            far: cam.far,
            keys: HashSet::new(),
            looking: false,
            dragged: 0.0,
            ctrl: false,
            applied: settings.clone(),
            settings,
            stats: Default::default(),
            gpu_times: Vec::new(),
            fps: 0.0,
            last: Instant::now(),
            frame_index: 0,
            opts,
            cycle,
            screenshot_request: None,
            message: String::new(),
        };
        if let Some(t) = g.cycle.first() {
            g.settings.oit.technique = *t;
        }
        // The first meshes: all at once, in parallel (a start-up cost, not a frame hitch).
        g.upload_all()?;
        Ok(g)
    }

    fn upload_all(&mut self) -> Result<(), String> {
        let positions: Vec<ChunkPos> = self.world.iter().map(|(p, _)| p).collect();
        self.world.take_dirty();
        let meshes = voxel_mesh::mesh_chunks(&self.world, &positions).map_err(|e| e.to_string())?;
        self.renderer.clear_chunks();
        for (pos, m) in &meshes {
            self.renderer.upload_chunk(*pos, m);
        }
        if let Some(r) = &mut self.reference {
            r.clear_chunks();
            for (pos, m) in &meshes {
                r.upload_chunk(*pos, m);
            }
        }
        Ok(())
    }

    fn camera(&self) -> Result<Camera, String> {
        Camera::from_yaw_pitch(
            self.fly.eye,
            self.fly.yaw,
            self.fly.pitch,
            70.0,
            0.1,
            self.far,
        )
        .map_err(|e| e.to_string())
    }

    fn resize(&mut self, w: u32, h: u32) {
        // Minimised: keep everything as it is until a real size comes back.
        if w == 0 || h == 0 {
            return;
        }
        self.surface_config.width = w;
        self.surface_config.height = h;
        self.surface
            .configure(&self.ctx.device, &self.surface_config);
        self.layout(self.frames.view_x);
    }

    /// Sizes the frame targets to the window and the 3D view to the room right of the
    /// panel (`view_x` pixels wide); renderers follow the view. Nothing happens when
    /// nothing changed.
    fn layout(&mut self, view_x: u32) {
        let (w, h) = (self.surface_config.width, self.surface_config.height);
        let view_x = view_x.min(w.saturating_sub(16));
        let frame = &self.frames.frame.texture;
        if (frame.width(), frame.height(), self.frames.view_x) == (w, h, view_x) {
            return;
        }
        self.frames = Frames::new(&self.ctx.device, &self.post, w, h, view_x);
        let (vw, vh) = self.frames.view_size();
        self.renderer.resize(vw, vh);
        if let Some(r) = &mut self.reference {
            r.resize(vw, vh);
        }
    }

    fn key(&mut self, code: KeyCode, pressed: bool) {
        if pressed {
            self.keys.insert(code);
        } else {
            self.keys.remove(&code);
        }
        if !pressed {
            return;
        }
        let digits = [
            KeyCode::Digit1,
            KeyCode::Digit2,
            KeyCode::Digit3,
            KeyCode::Digit4,
            KeyCode::Digit5,
            KeyCode::Digit6,
            KeyCode::Digit7,
            KeyCode::Digit8,
            KeyCode::Digit9,
        ];
        if let Some(i) = digits.iter().position(|d| *d == code) {
            self.settings.oit.technique = Technique::ALL[i];
        }
        match code {
            KeyCode::F2 | KeyCode::KeyP => self.request_screenshot(),
            KeyCode::KeyH => self.settings.heatmap = !self.settings.heatmap,
            KeyCode::KeyE => self.edit(true),
            KeyCode::KeyQ => self.edit(false),
            _ => {}
        }
    }

    fn mouse_button(&mut self, button: MouseButton, pressed: bool, egui_wants: bool) {
        match (button, pressed) {
            (MouseButton::Right, true) if !egui_wants => {
                self.looking = true;
                self.dragged = 0.0;
            }
            (MouseButton::Right, false) => {
                // A right click that did not turn the camera removes a block.
                if self.looking && self.dragged < 4.0 && !egui_wants {
                    self.edit(false);
                }
                self.looking = false;
            }
            (MouseButton::Left, true) if !egui_wants => self.edit(!self.ctrl),
            _ => {}
        }
    }

    fn request_screenshot(&mut self) {
        let n = self.frame_index;
        self.screenshot_request = Some(PathBuf::from(format!("screenshots/voxel-oit-{n}.png")));
    }

    /// Places the selected block in front of the aimed face, or removes the aimed block.
    fn edit(&mut self, place: bool) {
        let dir =
            Camera::from_yaw_pitch(DVec3::ZERO, self.fly.yaw, self.fly.pitch, 70.0, 0.1, 10.0)
                .map(|c| c.forward)
                .unwrap_or(DVec3::NEG_Z);
        let registry = self.world.registry().clone();
        let solid = |p: WorldPos| {
            registry
                .class(self.world.get_block(p))
                .is_ok_and(|c| c != RenderClass::Air)
        };
        let Some((hit, before)) = raycast(self.fly.eye, dir, 64.0, solid) else {
            self.message = "nothing to edit within 64 blocks".into();
            return;
        };
        let (pos, id) = if place {
            (before, self.settings.place)
        } else {
            (hit, BlockId::AIR)
        };
        match self.world.set_block(pos, id) {
            Ok(_) => self.schedule_remesh(),
            Err(e) => self.message = e.to_string(),
        }
    }

    /// Remeshes the dirty chunks on rayon's pool; results come back through a channel and
    /// are uploaded by the frame that receives them: editing never stalls a frame.
    fn schedule_remesh(&mut self) {
        for pos in self.world.take_dirty() {
            let generation = self.generation.entry(pos).or_insert(0);
            *generation += 1;
            let generation = *generation;
            let chunk = self.world.chunk(pos).cloned();
            let neighbours: [Option<voxel_core::Chunk>; 6] =
                self.world.neighbours(pos).map(|c| c.cloned());
            let registry = self.world.registry().clone();
            let tx = self.mesh_tx.clone();
            self.pending += 1;
            rayon::spawn(move || {
                let meshes = match &chunk {
                    Some(c) => {
                        let nb: [Option<&voxel_core::Chunk>; 6] =
                            std::array::from_fn(|i| neighbours[i].as_ref());
                        Mesher::new(&registry)
                            .mesh(c, nb)
                            .map_err(|e| e.to_string())
                    }
                    None => Ok(ChunkMeshes::default()),
                };
                let _ = tx.send((pos, generation, meshes));
            });
        }
    }

    fn receive_meshes(&mut self) {
        while let Ok((pos, generation, meshes)) = self.mesh_rx.try_recv() {
            self.pending = self.pending.saturating_sub(1);
            // A later edit of the same chunk has a newer job in flight: skip this one.
            if self.generation.get(&pos) != Some(&generation) {
                continue;
            }
            match meshes {
                Ok(m) => {
                    self.renderer.upload_chunk(pos, &m);
                    if let Some(r) = &mut self.reference {
                        r.upload_chunk(pos, &m);
                    }
                }
                Err(e) => self.message = e,
            }
        }
    }

    fn fly(&mut self, dt: f64) {
        let forward = DVec3::new(self.fly.yaw.sin(), 0.0, -self.fly.yaw.cos());
        let right = DVec3::new(-forward.z, 0.0, forward.x);
        let mut v = DVec3::ZERO;
        for (key, dir) in [
            (KeyCode::KeyW, forward),
            (KeyCode::KeyS, -forward),
            (KeyCode::KeyD, right),
            (KeyCode::KeyA, -right),
            (KeyCode::Space, DVec3::Y),
            (KeyCode::ShiftLeft, -DVec3::Y),
        ] {
            if self.keys.contains(&key) {
                v += dir;
            }
        }
        let turn = 1.5 * dt;
        for (key, dyaw, dpitch) in [
            (KeyCode::ArrowLeft, -turn, 0.0),
            (KeyCode::ArrowRight, turn, 0.0),
            (KeyCode::ArrowUp, 0.0, turn),
            (KeyCode::ArrowDown, 0.0, -turn),
        ] {
            if self.keys.contains(&key) {
                self.fly.yaw += dyaw;
                self.fly.pitch = (self.fly.pitch + dpitch).clamp(-1.5, 1.5);
            }
        }
        let fast = if self.keys.contains(&KeyCode::ControlLeft) {
            4.0
        } else {
            1.0
        };
        self.fly.eye += v.normalize_or_zero() * self.fly.speed * fast * dt;
    }

    /// Applies what the panel changed.
    fn apply_settings(&mut self) -> Result<(), String> {
        let s = self.settings.clone();
        let a = self.applied.clone();
        if s.seed != a.seed || s.view_distance != a.view_distance {
            let scene = scene::default_scene_with_radius(s.seed, s.view_distance)?;
            self.world = scene.world;
            self.far = (f64::from(s.view_distance) * 32.0 * 1.8).max(200.0);
            if s.seed != a.seed {
                let cam = scene.cameras[0];
                let (yaw, pitch) = cam.yaw_pitch();
                self.fly.eye = cam.eye;
                self.fly.yaw = yaw;
                self.fly.pitch = pitch;
            }
            self.generation.clear();
            self.upload_all()?;
        }
        if s.oit != a.oit {
            self.renderer.set_oit_config(s.oit.clone());
        }
        if s.msaa != a.msaa {
            self.renderer.set_msaa(s.msaa);
        }
        if s.fade_in_frames != a.fade_in_frames {
            self.renderer.set_fade_in_frames(s.fade_in_frames);
        }
        if s.heatmap && self.reference.is_none() {
            let (w, h) = self.renderer.size();
            let mut config = RendererConfig {
                width: w,
                height: h,
                output_format: FRAME_FORMAT,
                ..RendererConfig::default()
            };
            config.oit.technique = Technique::Reference;
            let mut r = Renderer::new(&self.ctx, self.world.registry(), config)
                .map_err(|e| e.to_string())?;
            let positions: Vec<ChunkPos> = self.world.iter().map(|(p, _)| p).collect();
            for (pos, m) in
                voxel_mesh::mesh_chunks(&self.world, &positions).map_err(|e| e.to_string())?
            {
                r.upload_chunk(pos, &m);
            }
            self.reference = Some(r);
        } else if !s.heatmap {
            self.reference = None;
        }
        self.applied = s;
        Ok(())
    }

    fn frame(&mut self) -> Result<Flow, String> {
        let now = Instant::now();
        let dt = now.duration_since(self.last).as_secs_f64().min(0.25);
        self.last = now;
        if dt > 0.0 {
            self.fps = if self.fps == 0.0 {
                1.0 / dt
            } else {
                self.fps * 0.9 + 0.1 / dt
            };
        }
        self.receive_meshes();
        self.fly(dt);
        if self.opts.edit && self.frame_index == 1 {
            self.edit(true);
        }
        if self.opts.resize {
            let (w, h) = self.opts.size;
            match self.frame_index {
                1 => {
                    let _ = self
                        .window
                        .request_inner_size(winit::dpi::PhysicalSize::new(w / 2, h / 2));
                }
                2 => self.resize(0, 0),
                3 => {
                    let _ = self
                        .window
                        .request_inner_size(winit::dpi::PhysicalSize::new(w, h));
                }
                _ => {}
            }
        }

        // The panel.
        let raw = self.egui_state.take_egui_input(&self.window);
        let egui_ctx = self.egui_ctx.clone();
        let mut panel_right = 0.0;
        let output = egui_ctx.run_ui(raw, |ui| panel_right = self.panel(ui));
        self.egui_state
            .handle_platform_output(&self.window, output.platform_output);
        let paint_jobs = egui_ctx.tessellate(output.shapes, output.pixels_per_point);
        self.apply_settings()?;
        self.layout((panel_right * output.pixels_per_point).ceil() as u32);

        let surface_texture = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t) => t,
            wgpu::CurrentSurfaceTexture::Suboptimal(t) => {
                drop(t);
                self.surface
                    .configure(&self.ctx.device, &self.surface_config);
                return Ok(Flow::Continue);
            }
            wgpu::CurrentSurfaceTexture::Outdated => {
                self.surface
                    .configure(&self.ctx.device, &self.surface_config);
                return Ok(Flow::Continue);
            }
            wgpu::CurrentSurfaceTexture::Lost => {
                self.surface = self
                    .instance
                    .create_surface(self.window.clone())
                    .map_err(|e| format!("surface lost and not recreated: {e}"))?;
                self.surface
                    .configure(&self.ctx.device, &self.surface_config);
                return Ok(Flow::Continue);
            }
            // Minimised, hidden or slow: try again next frame.
            wgpu::CurrentSurfaceTexture::Timeout
            | wgpu::CurrentSurfaceTexture::Occluded
            | wgpu::CurrentSurfaceTexture::Validation => return Ok(Flow::Continue),
        };
        let surface_view = surface_texture.texture.create_view(&Default::default());
        let camera = self.camera()?;
        let device = self.ctx.device.clone();
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("demo_frame"),
        });
        let frames = &self.frames;
        if let Some(reference) = &mut self.reference {
            self.stats = self
                .renderer
                .render(&mut encoder, &frames.technique.view, &camera)
                .map_err(|e| e.to_string())?;
            reference
                .render(&mut encoder, &frames.reference.view, &camera)
                .map_err(|e| e.to_string())?;
            Post::draw(
                &mut encoder,
                &self.post.diff,
                &frames.diff_group,
                &frames.view.view,
            );
        } else {
            self.stats = self
                .renderer
                .render(&mut encoder, &frames.view.view, &camera)
                .map_err(|e| e.to_string())?;
        }
        // The 3D view goes right of the panel; the panel is drawn over the rest.
        encoder.copy_texture_to_texture(
            frames.view.texture.as_image_copy(),
            wgpu::TexelCopyTextureInfo {
                texture: &frames.frame.texture,
                mip_level: 0,
                origin: wgpu::Origin3d {
                    x: frames.view_x,
                    y: 0,
                    z: 0,
                },
                aspect: wgpu::TextureAspect::All,
            },
            frames.view.texture.size(),
        );
        let (w, h) = (frames.frame.texture.width(), frames.frame.texture.height());
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [w, h],
            pixels_per_point: output.pixels_per_point,
        };
        for (id, deltas) in &output.textures_delta.set {
            for delta in deltas {
                self.egui_renderer
                    .update_texture(&device, &self.ctx.queue, *id, delta);
            }
        }
        let extra = self.egui_renderer.update_buffers(
            &device,
            &self.ctx.queue,
            &mut encoder,
            &paint_jobs,
            &screen,
        );
        {
            let pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("egui"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &self.frames.frame.view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Load,
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            self.egui_renderer
                .render(&mut pass.forget_lifetime(), &paint_jobs, &screen);
        }
        for id in &output.textures_delta.free {
            self.egui_renderer.free_texture(id);
        }
        Post::draw(
            &mut encoder,
            &self.post.blit,
            &self.frames.blit_group,
            &surface_view,
        );
        self.ctx
            .queue
            .submit(extra.into_iter().chain([encoder.finish()]));
        self.renderer.after_submit();
        if let Some(r) = &mut self.reference {
            r.after_submit();
        }
        self.window.pre_present_notify();
        self.ctx.queue.present(surface_texture);
        let _ = self.ctx.device.poll(wgpu::PollType::Poll);
        let times = self.renderer.gpu_times();
        if !times.is_empty() {
            self.gpu_times = times;
        }
        if let Some(path) = self.screenshot_request.take() {
            self.save_screenshot(&path)?;
        }
        self.frame_index += 1;
        self.script()
    }

    /// The scripted run: screenshots, technique cycling, quitting.
    fn script(&mut self) -> Result<Flow, String> {
        let Some(frames) = self.opts.frames else {
            return Ok(Flow::Continue);
        };
        // Edits are remeshed in the background: let them land before the last frame.
        if self.frame_index < frames || self.pending > 0 {
            return Ok(Flow::Continue);
        }
        if let Some(dir) = self.opts.cycle.clone() {
            let t = self.settings.oit.technique;
            self.save_screenshot(&dir.join(format!("{}.png", t.name())))?;
            let next = self.cycle.iter().position(|c| *c == t).map(|i| i + 1);
            match next.and_then(|i| self.cycle.get(i)) {
                Some(n) => {
                    self.settings.oit.technique = *n;
                    self.frame_index = 0;
                    return Ok(Flow::Continue);
                }
                None => return Ok(Flow::Quit),
            }
        }
        if let Some(path) = self.opts.screenshot.clone() {
            self.save_screenshot(&path)?;
        }
        Ok(Flow::Quit)
    }

    fn save_screenshot(&mut self, path: &std::path::Path) -> Result<(), String> {
        let rgba = readback::read_texture(&self.ctx, &self.frames.frame.texture, 4)
            .map_err(|e| e.to_string())?;
        let (w, h) = (
            self.frames.frame.texture.width(),
            self.frames.frame.texture.height(),
        );
        Image {
            width: w,
            height: h,
            rgba,
        }
        .save_png(path)
        .map_err(|e| e.to_string())?;
        self.message = format!("saved {}", path.display());
        Ok(())
    }

    /// Draws the side panel; returns its right edge in points.
    fn panel(&mut self, ui: &mut egui::Ui) -> f32 {
        let response = egui::Panel::left("settings")
            .default_size(250.0)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| self.panel_contents(ui));
            });
        response.response.rect.max.x
    }

    fn panel_contents(&mut self, ui: &mut egui::Ui) {
        {
            ui.heading("voxel-oit");
            let s = &mut self.settings;
            ui.label("Technique (keys 1-9)");
            egui::ComboBox::from_id_salt("technique")
                .selected_text(s.oit.technique.name())
                .show_ui(ui, |ui| {
                    for t in Technique::ALL {
                        ui.selectable_value(&mut s.oit.technique, t, t.name());
                    }
                });
            let wboit = matches!(
                s.oit.technique,
                Technique::WboitMrt | Technique::WboitTwoPass
            );
            ui.add_enabled_ui(wboit, |ui| {
                egui::ComboBox::from_label("WBOIT weight")
                    .selected_text(s.oit.weight.name())
                    .show_ui(ui, |ui| {
                        for w in WeightFunction::ALL {
                            ui.selectable_value(&mut s.oit.weight, w, w.name());
                        }
                    });
            });
            ui.add_enabled_ui(s.oit.technique == Technique::Stipple, |ui| {
                ui.horizontal(|ui| {
                    ui.label("Bayer");
                    for b in BayerSize::ALL {
                        ui.selectable_value(&mut s.oit.bayer, b, format!("{0}x{0}", b.side()));
                    }
                });
                ui.checkbox(&mut s.oit.stipple_depth_write, "stipple writes depth");
            });
            ui.add_enabled_ui(s.oit.technique == Technique::DepthPeeling, |ui| {
                ui.horizontal(|ui| {
                    ui.label("Peel layers");
                    for n in [4, 6, 8] {
                        ui.selectable_value(&mut s.oit.peel_layers, n, n.to_string());
                    }
                });
            });
            let sorted = matches!(s.oit.technique, Technique::Sorted | Technique::SortedQuads);
            ui.add_enabled_ui(sorted, |ui| {
                let mut quads = s.oit.technique == Technique::SortedQuads;
                if ui
                    .checkbox(&mut quads, "sort quads inside chunks")
                    .changed()
                {
                    s.oit.technique = if quads {
                        Technique::SortedQuads
                    } else {
                        Technique::Sorted
                    };
                }
            });
            ui.checkbox(&mut s.msaa, "4x MSAA (opaque and cutout)");
            ui.add(egui::Slider::new(&mut s.fade_in_frames, 0..=60).text("fade-in frames"));
            ui.checkbox(&mut s.heatmap, "error map against the reference (H)");
            ui.separator();
            ui.horizontal(|ui| {
                ui.label("Seed");
                ui.add(egui::DragValue::new(&mut s.seed));
            });
            ui.add(egui::Slider::new(&mut s.view_distance, 2..=10).text("view distance (chunks)"));
            let registry = self.world.registry().clone();
            egui::ComboBox::from_label("block to place")
                .selected_text(registry.get(s.place).map_or("?", |d| d.name.as_str()))
                .show_ui(ui, |ui| {
                    for (id, d) in registry.iter().skip(1) {
                        ui.selectable_value(&mut s.place, id, d.name.as_str());
                    }
                });
            if ui.button("Screenshot (F2)").clicked() {
                self.screenshot_request = Some(PathBuf::from(format!(
                    "screenshots/voxel-oit-{}.png",
                    self.frame_index
                )));
            }
            ui.separator();
            let st = &self.stats;
            ui.label(format!("{:.0} FPS, CPU {:.2} ms", self.fps, st.cpu_ms));
            ui.label(format!(
                "chunks drawn: {} opaque, {} cutout, {} translucent",
                st.meshes_drawn[0], st.meshes_drawn[1], st.meshes_drawn[2]
            ));
            ui.label(format!("translucent quads: {}", st.translucent_quads));
            if st.sort_ms > 0.0 || st.chunks_resorted > 0 {
                ui.label(format!(
                    "quad sort: {:.3} ms, {} chunks",
                    st.sort_ms, st.chunks_resorted
                ));
            }
            if let Some(l) = st.technique.layers {
                ui.label(format!("layers peeled: {l}"));
            }
            if let Some(o) = st.technique.overflow {
                ui.label(format!("reference overflow: {o}"));
            }
            ui.label("GPU ms per pass:");
            for (label, ms) in &self.gpu_times {
                ui.label(format!("  {label}: {ms:.3}"));
            }
            ui.separator();
            ui.small("WASD + Space/Shift fly, Ctrl faster; right-drag or arrows look; left click places, right click (or Ctrl+left, Q) removes, E places.");
            if !self.message.is_empty() {
                ui.small(&self.message);
            }
        }
    }
}

/// Walks the voxels along a ray (Amanatides & Woo) and returns the first solid block and the
/// cell just before it.
pub fn raycast(
    origin: DVec3,
    dir: DVec3,
    max: f64,
    solid: impl Fn(WorldPos) -> bool,
) -> Option<(WorldPos, WorldPos)> {
    let dir = dir.normalize_or_zero();
    if dir == DVec3::ZERO || !origin.is_finite() {
        return None;
    }
    let mut cell = origin.floor();
    let step = dir.signum();
    let next = |c: f64, s: f64| if s > 0.0 { c + 1.0 } else { c };
    let mut t_max = DVec3::new(
        if dir.x != 0.0 {
            (next(cell.x, step.x) - origin.x) / dir.x
        } else {
            f64::INFINITY
        },
        if dir.y != 0.0 {
            (next(cell.y, step.y) - origin.y) / dir.y
        } else {
            f64::INFINITY
        },
        if dir.z != 0.0 {
            (next(cell.z, step.z) - origin.z) / dir.z
        } else {
            f64::INFINITY
        },
    );
    let delta = DVec3::new(
        if dir.x != 0.0 {
            (1.0 / dir.x).abs()
        } else {
            f64::INFINITY
        },
        if dir.y != 0.0 {
            (1.0 / dir.y).abs()
        } else {
            f64::INFINITY
        },
        if dir.z != 0.0 {
            (1.0 / dir.z).abs()
        } else {
            f64::INFINITY
        },
    );
    let to_pos = |c: DVec3| -> Option<WorldPos> {
        let ok = |v: f64| v >= f64::from(i32::MIN) && v <= f64::from(i32::MAX);
        (ok(c.x) && ok(c.y) && ok(c.z)).then(|| WorldPos::new(c.x as i32, c.y as i32, c.z as i32))
    };
    let mut before = to_pos(cell)?;
    loop {
        let t = t_max.min_element();
        if t > max {
            return None;
        }
        if t_max.x == t {
            cell.x += step.x;
            t_max.x += delta.x;
        } else if t_max.y == t {
            cell.y += step.y;
            t_max.y += delta.y;
        } else {
            cell.z += step.z;
            t_max.z += delta.z;
        }
        let p = to_pos(cell)?;
        if solid(p) {
            return Some((p, before));
        }
        before = p;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn raycast_hits_the_first_solid_block_and_the_cell_before() {
        let wall = |p: WorldPos| p.z == -5 && p.x.abs() < 3 && p.y.abs() < 3;
        let (hit, before) = raycast(DVec3::new(0.5, 0.5, 0.5), DVec3::NEG_Z, 20.0, wall).unwrap();
        assert_eq!(hit, WorldPos::new(0, 0, -5));
        assert_eq!(before, WorldPos::new(0, 0, -4));
        // Diagonal rays step one axis at a time: the cell before shares a face with the hit.
        let (hit, before) = raycast(
            DVec3::new(0.2, 0.7, 0.5),
            DVec3::new(0.3, -0.2, -1.0),
            20.0,
            wall,
        )
        .unwrap();
        assert_eq!(hit.z, -5);
        let d = (hit.x - before.x).abs() + (hit.y - before.y).abs() + (hit.z - before.z).abs();
        assert_eq!(d, 1);
        assert!(
            raycast(DVec3::new(0.5, 0.5, 0.5), DVec3::Z, 20.0, wall).is_none(),
            "behind"
        );
        assert!(
            raycast(DVec3::new(0.5, 0.5, 0.5), DVec3::NEG_Z, 3.0, wall).is_none(),
            "too far"
        );
        assert!(raycast(DVec3::new(f64::NAN, 0.0, 0.0), DVec3::NEG_Z, 3.0, wall).is_none());
        assert!(raycast(DVec3::ZERO, DVec3::ZERO, 3.0, wall).is_none());
    }
}
