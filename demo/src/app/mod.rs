//! The interactive demo: a winit window with a wgpu surface, generated terrain (or a scene
//! file or MagicaVoxel model, `--scene`) streamed around the eye (a [`ChunkStreamer`]: chunks generated, meshed and uploaded in the
//! background, up to 32 chunks of view distance; past that, to 512, the terrain in levels of
//! detail, a [`FarField`]) and drawn by the voxel renderer, an egui
//! side panel to switch techniques and settings, a fly camera, block edits remeshed in the
//! background, live GPU timings and a live error map against the exact reference.
//!
//! A frame is drawn into an sRGB offscreen target (the scene, then the panel), which is
//! blitted to the surface: one picture for the window and for screenshots.

mod display;
mod game;
mod panel;
mod post;

use std::collections::HashSet;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::DVec3;
use voxel_core::{BlockId, BlockRegistry, ChunkPos, RenderClass, TerrainConfig, TerrainGenerator};
use voxel_lab::{chain, scene};

use crate::{Error, Result};
use voxel_mesh::ChunkMeshes;
use voxel_mesh::levels::LevelRings;
use voxel_render::far::{FarConfig, FarField, FarStatus};
use voxel_render::{
    Camera, ChunkSink, ChunkStreamer, FrameStats, GpuContext, GpuTimes, Image, Lighting, OitConfig,
    Renderer, RendererConfig, StreamConfig, StreamFrame, SunFeed, Technique, readback,
};
use winit::application::ApplicationHandler;
use winit::event::{DeviceEvent, ElementState, MouseButton, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

use display::Display;
use post::{FRAME_FORMAT, Frames, Post};

/// How the demo starts, and what a scripted run does.
#[derive(Clone, Debug)]
pub struct DemoOptions {
    /// The backends to find the window's adapter among (`None`: `WGPU_BACKEND`, else the
    /// primary ones).
    pub backends: Option<wgpu::Backends>,
    /// The limits and optional features of the device.
    pub limits: voxel_render::LimitsPreset,
    /// World seed.
    pub seed: u32,
    /// Initial window size.
    pub size: (u32, u32),
    /// Initial technique.
    pub technique: Technique,
    /// Chunks of terrain drawn around the eye, each way (1 to [`MAX_DEMO_VIEW_DISTANCE`];
    /// past [`STREAMED_VIEW_DISTANCE`] in levels of detail).
    pub view_distance: u32,
    /// Scripted: quit after this many frames (per technique with `cycle`).
    pub frames: Option<u64>,
    /// Scripted: save the last frame (with the panel) here.
    pub screenshot: Option<PathBuf>,
    /// Scripted: step through every technique, saving `DIR/<technique>.png` for each.
    pub cycle: Option<PathBuf>,
    /// Start with the error map on.
    pub heatmap: bool,
    /// Start with the levels of detail shown as bands (odd levels darker).
    pub level_bands: bool,
    /// Scripted: place a block in front of the camera on the second frame (remeshing test).
    pub edit: bool,
    /// Scripted: on frames 1 to 3, halve the window, get a zero size (what a minimised
    /// window reports), then restore the size (resize test).
    pub resize: bool,
    /// A scene to show instead of generated terrain (a scene file or a `.vox` model, read
    /// with [`scene::Scene::load`] before the window opens), from its first camera.
    pub scene: Option<scene::Scene>,
    /// Show the game content (bubbles, the glass cube, the boat) from the start; `None`:
    /// on in an interactive run, off in a scripted one (whose pictures tests compare).
    pub game: Option<bool>,
    /// Generated terrain lit as it streams (`ChunkStreamer::set_light`: sky light and
    /// light sources, on the streamer's workers), to [`STREAMED_VIEW_DISTANCE`]. A scene
    /// is lit by its own `light = true`.
    pub light: bool,
}

impl Default for DemoOptions {
    fn default() -> Self {
        Self {
            backends: None,
            limits: voxel_render::LimitsPreset::Adapter,
            seed: 1,
            size: (1280, 720),
            technique: voxel_render::OitConfig::default().technique,
            view_distance: 8,
            frames: None,
            screenshot: None,
            cycle: None,
            heatmap: false,
            level_bands: false,
            edit: false,
            resize: false,
            scene: None,
            game: None,
            light: false,
        }
    }
}

/// The demo's largest view distance, in chunks: past [`STREAMED_VIEW_DISTANCE`] the
/// generated terrain is drawn in levels of detail (a [`FarField`]; a scene stops at
/// [`STREAMED_VIEW_DISTANCE`]).
pub const MAX_DEMO_VIEW_DISTANCE: u32 = 512;

/// The largest view distance the streamer draws, all in full detail (its own limit is
/// higher); a far view keeps full detail to this distance.
pub const STREAMED_VIEW_DISTANCE: u32 = 32;

/// In a far view, the chunks the streamer keeps around the eye (not drawn: the far field
/// draws), which edits aim at and the eye's medium is read from.
const NEAR_WORLD: u32 = 4;

/// Whether a window can be opened: an X11 or Wayland display is named in the environment.
pub fn have_display() -> bool {
    ["DISPLAY", "WAYLAND_DISPLAY"]
        .iter()
        .any(|v| std::env::var_os(v).is_some_and(|s| !s.is_empty()))
}

/// Opens the window and runs until it is closed (or the script ends).
pub fn run(opts: DemoOptions) -> Result<()> {
    let event_loop = EventLoop::new().map_err(Error::NoEventLoop)?;
    let mut app = App {
        opts,
        gfx: None,
        error: None,
    };
    event_loop.run_app(&mut app).map_err(Error::EventLoop)?;
    app.error.map_or(Ok(()), Err)
}

struct App {
    opts: DemoOptions,
    gfx: Option<Gfx>,
    error: Option<Error>,
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
            .map_err(Error::CreateWindow)
            .and_then(|w| Gfx::new(Arc::new(w), self.opts.clone()));
        match result {
            Ok(g) => {
                g.display.window.request_redraw();
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
        let egui_wants =
            g.ui.state
                .on_window_event(&g.display.window, &event)
                .consumed;
        let result = match event {
            WindowEvent::CloseRequested => Ok(Flow::Quit),
            WindowEvent::Resized(size) => g.resize(size.width, size.height).map(|_| Flow::Continue),
            WindowEvent::RedrawRequested => g.frame(),
            WindowEvent::KeyboardInput { event, .. } if !egui_wants => {
                if let PhysicalKey::Code(code) = event.physical_key {
                    g.key(code, event.state == ElementState::Pressed);
                }
                Ok(Flow::Continue)
            }
            WindowEvent::MouseInput { state, button, .. } => {
                g.mouse_button(button, state == ElementState::Pressed, egui_wants);
                Ok(Flow::Continue)
            }
            WindowEvent::ModifiersChanged(m) => {
                g.input.ctrl = m.state().control_key();
                Ok(Flow::Continue)
            }
            _ => Ok(Flow::Continue),
        };
        match result {
            Ok(Flow::Continue) => {}
            Ok(Flow::Quit) => event_loop.exit(),
            Err(e) => {
                self.error = Some(e);
                event_loop.exit();
            }
        }
    }

    fn device_event(
        &mut self,
        _event_loop: &ActiveEventLoop,
        _id: winit::event::DeviceId,
        event: DeviceEvent,
    ) {
        if let (Some(g), DeviceEvent::MouseMotion { delta }) = (&mut self.gfx, event)
            && g.input.looking
        {
            let i = &mut g.input;
            i.dragged += delta.0.abs() + delta.1.abs();
            i.fly.yaw += delta.0 * 0.003;
            i.fly.pitch = (i.fly.pitch - delta.1 * 0.003).clamp(-1.5, 1.5);
        }
    }

    fn about_to_wait(&mut self, _event_loop: &ActiveEventLoop) {
        if let Some(g) = &self.gfx {
            g.display.window.request_redraw();
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

/// Keyboard and mouse state.
#[derive(Debug)]
struct Input {
    fly: Fly,
    keys: HashSet<KeyCode>,
    /// Right button held: mouse motion turns the camera.
    looking: bool,
    /// How far the mouse moved since the right button went down.
    dragged: f64,
    ctrl: bool,
}

/// Settings the panel edits.
#[derive(Clone, Debug, PartialEq)]
struct Settings {
    oit: OitConfig,
    msaa: bool,
    fade_in_frames: u32,
    seed: u32,
    view_distance: u32,
    heatmap: bool,
    /// The levels of detail drawn as bands (`Renderer::set_level_bands`).
    level_bands: bool,
    place: BlockId,
    /// Time of day in hours (`Lighting::daytime`), or `None` for the default lighting.
    hour: Option<f32>,
    /// The game content shown.
    game: game::Toggles,
}

/// egui's state.
struct Ui {
    ctx: egui::Context,
    state: egui_winit::State,
    renderer: egui_wgpu::Renderer,
}

/// One frame's panel: what to paint, and the right edge of the panel in pixels.
struct PanelFrame {
    paint_jobs: Vec<egui::ClippedPrimitive>,
    free: Vec<egui::TextureId>,
    pixels_per_point: f32,
    view_x: u32,
}

/// The streamed world: the chunks around the eye, generated and meshed on the streamer's
/// pool and uploaded by the frames (within a budget): no frame waits for a mesh.
struct Streaming {
    streamer: ChunkStreamer,
    /// What the last update did, for the panel.
    last: StreamFrame,
    /// Past [`STREAMED_VIEW_DISTANCE`]: the far view that draws the terrain, and what its
    /// last update did; the streamer then keeps only the world near the eye, undrawn.
    far: Option<(FarField, FarStatus)>,
    /// Sun shadows over lit terrain, for the renderer and the reference.
    sun: [SunFeed; 2],
}

impl Streaming {
    /// The world of `seed` (or the opened scene) drawn to `view_distance` chunks; the
    /// terrain lit as it streams with `light` (not a scene: it has its own light, nor a
    /// far view).
    fn new(seed: u32, view_distance: u32, scene: Option<&OpenScene>, light: bool) -> Result<Self> {
        if view_distance <= STREAMED_VIEW_DISTANCE || scene.is_some() {
            let view_distance = view_distance.min(STREAMED_VIEW_DISTANCE);
            return Ok(Self {
                streamer: streamer(seed, view_distance, scene, light)?,
                last: StreamFrame::default(),
                far: None,
                sun: Default::default(),
            });
        }
        let field = FarField::new(
            Arc::new(terrain(seed)),
            Arc::new(BlockRegistry::default()),
            FarConfig {
                rings: LevelRings::reaching(STREAMED_VIEW_DISTANCE, view_distance),
                ..FarConfig::default()
            },
        )?;
        Ok(Self {
            streamer: streamer(seed, NEAR_WORLD, None, false)?,
            last: StreamFrame::default(),
            far: Some((field, FarStatus::default())),
            sun: Default::default(),
        })
    }

    /// Whether everything within the view distance is drawn, edits included.
    fn is_idle(&self) -> bool {
        self.streamer.is_idle() && self.far.as_ref().is_none_or(|(f, _)| f.is_idle())
    }
}

/// A sink that keeps nothing: the streamer's chunks in a far view, which the far field
/// draws.
struct Undrawn;

impl ChunkSink for Undrawn {
    fn upload(&mut self, _: ChunkPos, _: &ChunkMeshes) -> voxel_render::Result<()> {
        Ok(())
    }

    fn remove(&mut self, _: ChunkPos) {}
}

/// The renderer, and the reference beside it when the error map is on: both get every
/// chunk.
struct Sinks<'a> {
    renderer: &'a mut Renderer,
    reference: Option<&'a mut Renderer>,
    /// A lit scene: every chunk the streamer uploads goes up meshed with its light.
    lit: Option<&'a SceneLight>,
}

impl ChunkSink for Sinks<'_> {
    fn upload(&mut self, pos: ChunkPos, meshes: &ChunkMeshes) -> voxel_render::Result<()> {
        let lit = match self.lit {
            Some(l) => Some(l.meshes(pos)?),
            None => None,
        };
        let meshes = lit.as_ref().unwrap_or(meshes);
        self.renderer.upload_chunk(pos, meshes)?;
        if let Some(r) = self.reference.as_deref_mut() {
            r.upload_chunk(pos, meshes)?;
        }
        Ok(())
    }

    fn remove(&mut self, pos: ChunkPos) {
        self.renderer.remove_chunk(pos);
        if let Some(r) = self.reference.as_deref_mut() {
            r.remove_chunk(pos);
        }
    }
}

/// A streamer of `seed`'s terrain (or of the opened scene's world) with `view_distance`
/// chunks each way (4 up and down); the terrain lit as it streams with `light` (a scene
/// has its own light).
fn streamer(
    seed: u32,
    view_distance: u32,
    scene: Option<&OpenScene>,
    light: bool,
) -> Result<ChunkStreamer> {
    let config = StreamConfig {
        view_distance,
        vertical_distance: 4,
        ..StreamConfig::default()
    };
    Ok(match scene {
        Some(s) => ChunkStreamer::new(s.world.registry().clone(), s.world.clone(), config)?,
        None => {
            let registry = Arc::new(terrain_registry(light));
            let mut streamer = ChunkStreamer::new(registry, terrain(seed), config)?;
            streamer.set_light(light);
            streamer
        }
    })
}

/// The blocks of the generated terrain: with the light sources where it is lit (the sun
/// shadows check that the renderer's registry is the streamer's).
fn terrain_registry(light: bool) -> BlockRegistry {
    if light {
        BlockRegistry::with_lights()
    } else {
        BlockRegistry::default()
    }
}

/// The default terrain of `seed`.
fn terrain(seed: u32) -> TerrainGenerator {
    TerrainGenerator::new(TerrainConfig {
        seed,
        ..TerrainConfig::default()
    })
}

/// A scene opened with `--scene`: its name and world (streamed like terrain).
struct OpenScene {
    name: String,
    world: voxel_core::World,
    /// The far plane of its camera: the window's never comes nearer.
    far: f64,
    /// Drawn with its light field (`light = true`), and with sun shadows.
    light: bool,
    sun_shadows: bool,
}

/// A lit scene's light (`docs/light.md`): a copy of its world that every edit reaches too,
/// and its light field. The streamer serves the scene's blocks as for any scene; each mesh
/// it uploads is replaced by the lit mesh of the same chunk ([`Sinks`]), and an edit
/// re-meshes the chunks whose light it changed.
struct SceneLight {
    world: voxel_core::World,
    field: voxel_core::LightField,
    sun_shadows: bool,
}

impl SceneLight {
    fn new(scene: &OpenScene) -> Option<Self> {
        scene.light.then(|| Self {
            field: voxel_core::LightField::new(&scene.world),
            world: scene.world.clone(),
            sun_shadows: scene.sun_shadows,
        })
    }

    /// Chunk `pos` meshed with its light.
    fn meshes(&self, pos: ChunkPos) -> voxel_render::Result<ChunkMeshes> {
        let meshed = voxel_mesh::mesh_chunks_lit(&self.world, &self.field, &[pos])
            .map_err(|e| voxel_render::Error::InvalidSetting(format!("lighting {pos:?}: {e}")))?;
        Ok(meshed
            .into_iter()
            .next()
            .map_or_else(ChunkMeshes::default, |(_, m)| m))
    }

    /// Sun shadows over the chunks nearest `eye` in `renderer`, when the scene has them,
    /// and the light volume there (the game's things lit by the field).
    fn shadow(&self, renderer: &mut Renderer, eye: DVec3) -> Result<()> {
        use voxel_render::{MAX_LIGHT_CHUNKS, SunRegion};
        let around = voxel_core::WorldPos::containing(eye.to_array());
        if let (true, Some(region)) = (self.sun_shadows, SunRegion::around(&self.world, around)) {
            renderer.set_sun_shadows(&self.world, region)?;
        }
        if let Some(region) = SunRegion::around_at_most(&self.world, around, MAX_LIGHT_CHUNKS) {
            renderer.set_light_volume(&self.world, &|p| self.field.shared(p), region)?;
        }
        Ok(())
    }
}

/// The far plane for a view distance: its chunks and a little more.
fn far_plane(view_distance: u32) -> f64 {
    (f64::from(view_distance) * 32.0 * 1.5).max(200.0)
}

/// What the panel shows about the last frames.
#[derive(Default)]
struct Status {
    stats: FrameStats,
    gpu_times: GpuTimes,
    fps: f64,
    frame_index: u64,
    message: String,
}

/// A scripted run: technique cycling, screenshots, quitting.
struct Script {
    opts: DemoOptions,
    cycle: Vec<Technique>,
    screenshot_request: Option<PathBuf>,
}

struct Gfx {
    display: Display,
    ctx: GpuContext,
    renderer: Renderer,
    /// The exact reference, drawn beside for the error map.
    reference: Option<Renderer>,
    /// A lit scene's light.
    lit: Option<SceneLight>,
    post: Post,
    frames: Frames,
    ui: Ui,
    streaming: Streaming,
    input: Input,
    far: f64,
    settings: Settings,
    applied: Settings,
    status: Status,
    last: Instant,
    script: Script,
    /// The scene shown instead of terrain, if any.
    scene: Option<OpenScene>,
    /// The terrain lit as it streams ([`DemoOptions::light`]).
    light: bool,
    /// The game's own content, drawn through the renderer's stages.
    game: game::Game,
    /// Seconds of animation: real time in an interactive run, 1/60 s a frame in a
    /// scripted one (the same pictures every run).
    game_time: f64,
}

impl Gfx {
    fn new(window: Arc<Window>, opts: DemoOptions) -> Result<Self> {
        let (display, ctx) = Display::new(window, opts.backends, opts.limits)?;
        // The scene's first camera, or the default view of the seed (its world is only the
        // few chunks around it).
        let (cam, open) = match &opts.scene {
            Some(s) => {
                let open = OpenScene {
                    name: s.name.clone(),
                    world: s.world.clone(),
                    far: s.cameras[0].far,
                    light: s.light,
                    sun_shadows: s.sun_shadows,
                };
                (s.cameras[0], Some(open))
            }
            None => (
                scene::default_scene_with_radius(opts.seed, 1)?.cameras[0],
                None,
            ),
        };
        let most = if open.is_some() {
            STREAMED_VIEW_DISTANCE
        } else {
            MAX_DEMO_VIEW_DISTANCE
        };
        let view_distance = opts.view_distance.clamp(1, most);
        let (yaw, pitch) = cam.yaw_pitch();
        let settings = Settings {
            oit: OitConfig::with(opts.technique),
            msaa: false,
            // New chunks dissolve in over 20 frames; a scripted run (a test, a screenshot)
            // shows the settled picture from its first frame instead.
            fade_in_frames: if opts.frames.is_some() { 0 } else { 20 },
            seed: opts.seed,
            view_distance,
            heatmap: opts.heatmap,
            level_bands: opts.level_bands,
            place: voxel_core::blocks::GLASS,
            hour: None,
            game: game::Toggles::all(opts.game.unwrap_or(opts.frames.is_none())),
        };
        let (w, h) = display.size();
        let config = RendererConfig {
            width: w,
            height: h,
            output_format: FRAME_FORMAT,
            oit: settings.oit.clone(),
            fade_in_frames: settings.fade_in_frames,
            ..RendererConfig::default()
        };
        let registry = open.as_ref().map_or_else(
            || terrain_registry(opts.light),
            |s| (**s.world.registry()).clone(),
        );
        let mut renderer = Renderer::new(&ctx, &registry, config)?;
        renderer.set_level_bands(settings.level_bands);
        let lit = open.as_ref().and_then(SceneLight::new);
        if let Some(l) = &lit {
            l.shadow(&mut renderer, cam.eye)?;
        }
        // Every real-time technique the device runs, built now: the number keys and the
        // panel switch without a hitch (the game's pipelines follow with its content).
        for t in Technique::supported(&ctx.caps) {
            if !t.stalls() {
                renderer.prebuild_technique(t)?;
            }
        }
        let post = Post::new(&ctx.device, display.config.format);
        let frames = Frames::new(&ctx.device, &post, w, h, 0);
        let ui = Ui::new(&display.window, &ctx);
        let cycle = if opts.cycle.is_some() {
            Technique::ALL.to_vec()
        } else {
            Vec::new()
        };
        let game = {
            // The default terrain's water: below the sea level.
            let terrain = TerrainGenerator::new(TerrainConfig {
                seed: opts.seed,
                ..TerrainConfig::default()
            });
            let sea = i64::from(terrain.config().sea_level);
            let water = |x, z| terrain.height_at(x, z) < sea - 1;
            let water: Option<&dyn Fn(i64, i64) -> bool> = open.is_none().then_some(&water);
            game::Game::new(&cam, water)
        };
        let mut g = Self {
            display,
            ctx,
            renderer,
            reference: None,
            lit,
            post,
            frames,
            ui,
            streaming: Streaming::new(opts.seed, view_distance, open.as_ref(), opts.light)?,
            input: Input {
                fly: Fly {
                    eye: cam.eye,
                    yaw,
                    pitch,
                    speed: 12.0,
                },
                keys: HashSet::new(),
                looking: false,
                dragged: 0.0,
                ctrl: false,
            },
            far: far_plane(view_distance).max(open.as_ref().map_or(0.0, |s| s.far)),
            applied: settings.clone(),
            settings,
            status: Status::default(),
            last: Instant::now(),
            light: opts.light,
            script: Script {
                opts,
                cycle,
                screenshot_request: None,
            },
            scene: open,
            game,
            game_time: 0.0,
        };
        if let Some(t) = g.script.cycle.first() {
            g.settings.oit.technique = *t;
        }
        // A scripted run (a test, a screenshot) starts from the loaded view distance; an
        // interactive one watches the chunks stream in.
        if g.script.opts.frames.is_some() {
            g.load_all(Duration::from_secs(120))?;
        }
        Ok(g)
    }

    /// Streams one frame's worth around the eye into the renderer (and the reference), or
    /// in a far view, follows the eye with the far field.
    fn stream(&mut self) -> Result<()> {
        let eye = self.input.fly.eye;
        let frame = match &mut self.streaming.far {
            Some((field, last)) => {
                *last = field.update(&mut self.renderer, eye)?;
                self.streaming.streamer.update(eye, &mut Undrawn)?
            }
            None => {
                let mut sinks = Sinks {
                    renderer: &mut self.renderer,
                    reference: self.reference.as_mut(),
                    lit: self.lit.as_ref(),
                };
                self.streaming.streamer.update(eye, &mut sinks)?
            }
        };
        if let Some((pos, why)) = frame.failed.first() {
            self.status.message = format!("chunk {pos:?}: {why}");
        }
        // Lit terrain: sun shadows over its chunks as they stream.
        let s = &mut self.streaming;
        if self.lit.is_none() && s.far.is_none() && s.streamer.has_light() {
            s.sun[0].update(&mut self.renderer, &s.streamer, eye, &frame)?;
            if let Some(r) = &mut self.reference {
                s.sun[1].update(r, &s.streamer, eye, &frame)?;
            }
        }
        // A lit scene's sun shadows follow the eye (a scene wider than the volume).
        if let Some(l) = &self.lit {
            let at = voxel_core::WorldPos::containing(eye.to_array());
            self.renderer.follow_sun_shadows(&l.world, at);
            if let Some(r) = &mut self.reference {
                r.follow_sun_shadows(&l.world, at);
            }
        }
        self.streaming.last = frame;
        Ok(())
    }

    /// Streams until everything within the view distance is drawn (or `limit` passes).
    fn load_all(&mut self, limit: Duration) -> Result<()> {
        let start = Instant::now();
        loop {
            self.stream()?;
            if self.streaming.is_idle() {
                return Ok(());
            }
            if start.elapsed() > limit {
                return Err(Error::LoadTimeout {
                    seconds: limit.as_secs(),
                });
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }

    /// The fly camera, immersed in whatever translucent block holds the eye.
    fn camera(&self) -> Result<Camera> {
        let f = &self.input.fly;
        let medium = self.streaming.streamer.world().medium_at(f.eye.to_array());
        Camera::from_yaw_pitch(f.eye, f.yaw, f.pitch, 70.0, 0.1, self.far)
            .map(|c| c.in_medium(medium))
            .map_err(Error::from)
    }

    fn resize(&mut self, w: u32, h: u32) -> Result<()> {
        // Minimised: keep everything as it is until a real size comes back.
        if w == 0 || h == 0 {
            return Ok(());
        }
        self.display.resize(&self.ctx, w, h);
        self.layout(self.frames.view_x)
    }

    /// Sizes the frame targets to the window and the 3D view to the room right of the
    /// panel (`view_x` pixels wide); renderers follow the view. Nothing happens when
    /// nothing changed.
    fn layout(&mut self, view_x: u32) -> Result<()> {
        let (w, h) = self.display.size();
        let view_x = view_x.min(w.saturating_sub(16));
        let frame = &self.frames.frame.texture;
        if (frame.width(), frame.height(), self.frames.view_x) == (w, h, view_x) {
            return Ok(());
        }
        self.frames = Frames::new(&self.ctx.device, &self.post, w, h, view_x);
        let (vw, vh) = self.frames.view_size();
        for r in std::iter::once(&mut self.renderer).chain(self.reference.as_mut()) {
            r.resize(vw, vh)?;
        }
        Ok(())
    }

    fn key(&mut self, code: KeyCode, pressed: bool) {
        if pressed {
            self.input.keys.insert(code);
        } else {
            self.input.keys.remove(&code);
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
            KeyCode::Digit0,
        ];
        if let Some(t) = digits
            .iter()
            .position(|d| *d == code)
            .and_then(|i| Technique::ALL.get(i))
        {
            self.settings.oit.technique = *t;
        }
        // [ and ] step through every technique, however many there are (the digits reach
        // the first ten).
        let step = match code {
            KeyCode::BracketRight => Some(1),
            KeyCode::BracketLeft => Some(Technique::ALL.len() - 1),
            _ => None,
        };
        if let Some(step) = step {
            self.settings.oit.technique = step_technique(self.settings.oit.technique, step);
        }
        match code {
            KeyCode::F2 | KeyCode::KeyP => self.request_screenshot(),
            KeyCode::KeyH => self.settings.heatmap = !self.settings.heatmap,
            KeyCode::KeyL => self.settings.level_bands = !self.settings.level_bands,
            KeyCode::KeyE => self.edit(true),
            KeyCode::KeyQ => self.edit(false),
            _ => {}
        }
    }

    fn mouse_button(&mut self, button: MouseButton, pressed: bool, egui_wants: bool) {
        match (button, pressed) {
            (MouseButton::Right, true) if !egui_wants => {
                self.input.looking = true;
                self.input.dragged = 0.0;
            }
            (MouseButton::Right, false) => {
                // A right click that did not turn the camera removes a block.
                if self.input.looking && self.input.dragged < 4.0 && !egui_wants {
                    self.edit(false);
                }
                self.input.looking = false;
            }
            (MouseButton::Left, true) if !egui_wants => self.edit(!self.input.ctrl),
            _ => {}
        }
    }

    fn request_screenshot(&mut self) {
        let n = self.status.frame_index;
        self.script.screenshot_request =
            Some(PathBuf::from(format!("screenshots/voxel-oit-{n}.png")));
    }

    /// Places the selected block in front of the aimed face, or removes the aimed block.
    fn edit(&mut self, place: bool) {
        let f = self.input.fly;
        let dir = Camera::from_yaw_pitch(DVec3::ZERO, f.yaw, f.pitch, 70.0, 0.1, 10.0)
            .map(|c| c.forward)
            .unwrap_or(DVec3::NEG_Z);
        let world = self.streaming.streamer.world();
        let visible = RenderClass::VISIBLE;
        let hit = match world.raycast(f.eye.to_array(), dir.to_array(), 64.0, &visible) {
            Ok(Some(hit)) => hit,
            Ok(None) => {
                self.status.message = "nothing to edit within 64 blocks".into();
                return;
            }
            Err(e) => {
                self.status.message = e.to_string();
                return;
            }
        };
        let (pos, id) = match (place, hit.adjacent()) {
            (true, Some(before)) => (before, self.settings.place),
            (true, None) => return,
            (false, _) => (hit.pos, BlockId::AIR),
        };
        if let Err(e) = self.streaming.streamer.set_block(pos, id) {
            self.status.message = chain(&e);
            return;
        }
        if let Err(e) = self.relight(pos, id) {
            self.status.message = chain(&e);
        }
        if let Some((field, _)) = &mut self.streaming.far
            && let Err(e) = field.set_block(pos, id)
        {
            self.status.message = chain(&e);
        }
    }

    /// A lit scene: the edit in the light field, and the chunks whose light it changed
    /// meshed again and uploaded (those the streamer draws), the sun shadows read again.
    fn relight(&mut self, pos: voxel_core::WorldPos, id: BlockId) -> Result<()> {
        let Some(lit) = &mut self.lit else {
            return Ok(());
        };
        lit.field.set_block(&mut lit.world, pos, id)?;
        let drawn: HashSet<ChunkPos> = self.streaming.streamer.uploaded().collect();
        let meshed = voxel_mesh::mesh_dirty_lit(&mut lit.world, &mut lit.field)?;
        let mut changed = Vec::with_capacity(meshed.len());
        for (p, m) in meshed {
            changed.push(p);
            if drawn.contains(&p) {
                self.renderer.upload_chunk(p, &m)?;
                if let Some(r) = &mut self.reference {
                    r.upload_chunk(p, &m)?;
                }
            }
        }
        let light = |p| lit.field.shared(p);
        self.renderer.update_sun_shadows(&lit.world, &changed);
        self.renderer
            .update_light_volume(&lit.world, &light, &changed);
        if let Some(r) = &mut self.reference {
            r.update_sun_shadows(&lit.world, &changed);
            r.update_light_volume(&lit.world, &light, &changed);
        }
        Ok(())
    }

    fn fly(&mut self, dt: f64) {
        let i = &mut self.input;
        let forward = DVec3::new(i.fly.yaw.sin(), 0.0, -i.fly.yaw.cos());
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
            if i.keys.contains(&key) {
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
            if i.keys.contains(&key) {
                i.fly.yaw += dyaw;
                i.fly.pitch = (i.fly.pitch + dpitch).clamp(-1.5, 1.5);
            }
        }
        let fast = if i.keys.contains(&KeyCode::ControlLeft) {
            4.0
        } else {
            1.0
        };
        i.fly.eye += v.normalize_or_zero() * i.fly.speed * fast * dt;
    }

    /// Drops every chunk drawn (by the renderer and the reference) and streams the world
    /// of `seed` (or the opened scene) to `view_distance` from nothing.
    fn restart_world(&mut self, seed: u32, view_distance: u32) -> Result<()> {
        self.renderer.clear_chunks();
        if let Some(r) = &mut self.reference {
            r.clear_chunks();
        }
        if self.lit.is_none() {
            // Lit terrain's shadows: the new world's are read as it streams.
            self.renderer.clear_sun_shadows();
            if let Some(r) = &mut self.reference {
                r.clear_sun_shadows();
            }
        }
        self.streaming = Streaming::new(seed, view_distance, self.scene.as_ref(), self.light)?;
        Ok(())
    }

    /// Applies what the panel changed.
    fn apply_settings(&mut self) -> Result<()> {
        let mut s = self.settings.clone();
        let a = self.applied.clone();
        if s.seed != a.seed && self.scene.is_none() {
            // Another world: start it over at its default view.
            let cam = scene::default_scene_with_radius(s.seed, 1)?.cameras[0];
            let (yaw, pitch) = cam.yaw_pitch();
            self.input.fly.eye = cam.eye;
            self.input.fly.yaw = yaw;
            self.input.fly.pitch = pitch;
            self.restart_world(s.seed, s.view_distance)?;
        } else if s.view_distance != a.view_distance {
            let far = |d: u32| d > STREAMED_VIEW_DISTANCE && self.scene.is_none();
            if far(s.view_distance) || far(a.view_distance) {
                // Into, out of or within a far view: drawn again from nothing (the far
                // view coarse first).
                self.restart_world(s.seed, s.view_distance)?;
            } else {
                self.streaming.streamer.set_view_distance(s.view_distance)?;
            }
        }
        if s.heatmap && self.streaming.far.is_some() {
            // The reference renderer is fed the streamer's chunks only.
            s.heatmap = false;
            self.settings.heatmap = false;
            self.status.message =
                "the error map draws the streamed world: view distance 32 at most".into();
        }
        self.far = far_plane(s.view_distance).max(self.scene.as_ref().map_or(0.0, |s| s.far));
        if s.oit != a.oit {
            match self.renderer.set_oit_config(s.oit.clone()) {
                // A technique this device cannot run: said, and the one in force kept.
                Err(e @ voxel_render::Error::Unsupported(_)) => {
                    log::warn!("{e}");
                    s.oit = a.oit.clone();
                    self.settings.oit = a.oit.clone();
                }
                other => other?,
            }
        }
        if s.msaa != a.msaa {
            self.renderer.set_msaa(s.msaa)?;
        }
        if s.fade_in_frames != a.fade_in_frames {
            self.renderer.set_fade_in_frames(s.fade_in_frames);
        }
        if s.hour != a.hour {
            // Uniforms only: applied at the next frame, no chunk uploaded again.
            let lighting = s.hour.map_or_else(Lighting::default_day, Lighting::daytime);
            for r in std::iter::once(&mut self.renderer).chain(self.reference.as_mut()) {
                r.set_lighting(lighting)?;
            }
        }
        if s.level_bands != a.level_bands {
            self.renderer.set_level_bands(s.level_bands);
        }
        if s.heatmap && self.reference.is_none() {
            self.reference = Some(self.reference_renderer()?);
        } else if !s.heatmap {
            self.reference = None;
        }
        self.applied = s;
        Ok(())
    }

    /// A renderer drawing the exact reference of the same world and view.
    fn reference_renderer(&self) -> Result<Renderer> {
        let (w, h) = self.renderer.size();
        let config = RendererConfig {
            width: w,
            height: h,
            output_format: FRAME_FORMAT,
            oit: OitConfig::with(Technique::Reference),
            ..RendererConfig::default()
        };
        let streamer = &self.streaming.streamer;
        let world = streamer.world();
        let mut r = Renderer::new(&self.ctx, world.registry(), config)?;
        // What the renderer draws, meshed at once (the same meshes the streamer made, or a
        // lit scene's).
        let positions: Vec<ChunkPos> = streamer.uploaded().collect();
        let meshed = match &self.lit {
            Some(l) => voxel_mesh::mesh_chunks_lit(&l.world, &l.field, &positions)?,
            None => voxel_mesh::mesh_chunks(world, &positions)?,
        };
        for (pos, m) in meshed {
            r.upload_chunk(pos, &m)?;
        }
        if let (Some(l), Some(region)) = (&self.lit, self.renderer.sun_region()) {
            r.set_sun_shadows(&l.world, region)?;
        }
        if let (Some(l), Some(region)) = (&self.lit, self.renderer.light_region()) {
            r.set_light_volume(&l.world, &|p| l.field.shared(p), region)?;
        }
        Ok(r)
    }

    /// Frame time and FPS.
    fn tick(&mut self) -> f64 {
        let now = Instant::now();
        let dt = now.duration_since(self.last).as_secs_f64().min(0.25);
        self.last = now;
        if dt > 0.0 {
            let fps = &mut self.status.fps;
            *fps = if *fps == 0.0 {
                1.0 / dt
            } else {
                *fps * 0.9 + 0.1 / dt
            };
        }
        dt
    }

    /// The scripted edit and resizes of the window test.
    fn scripted_events(&mut self) -> Result<()> {
        let n = self.status.frame_index;
        if self.script.opts.edit && n == 1 {
            self.edit(true);
        }
        if self.script.opts.resize {
            let (w, h) = self.script.opts.size;
            let window = &self.display.window;
            match n {
                1 => {
                    let _ = window.request_inner_size(winit::dpi::PhysicalSize::new(w / 2, h / 2));
                }
                2 => self.resize(0, 0)?,
                3 => {
                    let _ = window.request_inner_size(winit::dpi::PhysicalSize::new(w, h));
                }
                _ => {}
            }
        }
        Ok(())
    }

    fn frame(&mut self) -> Result<Flow> {
        let dt = self.tick();
        self.game_time += if self.script.opts.frames.is_some() {
            1.0 / 60.0
        } else {
            dt
        };
        self.fly(dt);
        self.stream()?;
        self.scripted_events()?;
        let panel = self.run_panel();
        self.apply_settings()?;
        self.layout(panel.view_x)?;

        let Some(surface_texture) = self.display.acquire(&self.ctx)? else {
            // No frame this time (outdated surface, minimised): the panel's texture
            // updates are already applied, only what it freed is let go.
            self.ui.free(&panel.free);
            return Ok(Flow::Continue);
        };
        let surface_view = surface_texture.texture.create_view(&Default::default());
        let mut encoder = self
            .ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("demo_frame"),
            });
        self.draw_scene(&mut encoder)?;
        let extra = self.draw_panel(&mut encoder, &panel);
        Post::draw(
            &mut encoder,
            &self.post.blit,
            &self.frames.blit_group,
            &surface_view,
        );
        self.ctx
            .queue
            .submit(extra.into_iter().chain([encoder.finish()]));
        self.ui.free(&panel.free);
        // Nothing to call after the submit: the renderers read their timings and counters
        // back once the frame's commands are submitted.
        self.display.window.pre_present_notify();
        self.ctx.queue.present(surface_texture);
        let _ = self.ctx.device.poll(wgpu::PollType::Poll);
        let times = self.renderer.gpu_times();
        if !times.is_empty() {
            self.status.gpu_times = times;
        }
        if let Some(path) = self.script.screenshot_request.take() {
            self.save_screenshot(&path)?;
        }
        self.status.frame_index += 1;
        self.script()
    }

    /// The 3D view (and the error map against the reference when on), copied right of
    /// the panel.
    fn draw_scene(&mut self, encoder: &mut wgpu::CommandEncoder) -> Result<()> {
        let camera = self.camera()?;
        let toggles = self.settings.game;
        self.game.update(
            &self.ctx,
            &mut self.renderer,
            self.reference.as_mut(),
            toggles,
            self.game_time,
        )?;
        let (stages, reference_stages) = self.game.stages(toggles);
        let mut no_game = voxel_render::NoGame;
        let stages: &mut dyn voxel_render::GameStages = match stages {
            Some(s) => s,
            None => &mut no_game,
        };
        let frames = &self.frames;
        match &mut self.reference {
            Some(reference) => {
                self.status.stats =
                    self.renderer
                        .render(encoder, &frames.technique.view, &camera, stages)?;
                let mut no_game = voxel_render::NoGame;
                let reference_stages: &mut dyn voxel_render::GameStages = match reference_stages {
                    Some(s) => s,
                    None => &mut no_game,
                };
                reference.render(encoder, &frames.reference.view, &camera, reference_stages)?;
                Post::draw(
                    encoder,
                    &self.post.diff,
                    &frames.diff_group,
                    &frames.view.view,
                );
            }
            None => {
                self.status.stats =
                    self.renderer
                        .render(encoder, &frames.view.view, &camera, stages)?;
            }
        }
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
        Ok(())
    }

    /// The scripted run: screenshots, technique cycling, quitting.
    fn script(&mut self) -> Result<Flow> {
        let Some(frames) = self.script.opts.frames else {
            return Ok(Flow::Continue);
        };
        // Edits are remeshed in the background: let them land before the last frame.
        if self.status.frame_index < frames || !self.streaming.is_idle() {
            return Ok(Flow::Continue);
        }
        if let Some(dir) = self.script.opts.cycle.clone() {
            let t = self.settings.oit.technique;
            self.save_screenshot(&dir.join(format!("{}.png", t.name())))?;
            let next = self
                .script
                .cycle
                .iter()
                .position(|c| *c == t)
                .map(|i| i + 1);
            match next.and_then(|i| self.script.cycle.get(i)) {
                Some(n) => {
                    self.settings.oit.technique = *n;
                    self.status.frame_index = 0;
                    return Ok(Flow::Continue);
                }
                None => return Ok(Flow::Quit),
            }
        }
        if let Some(path) = self.script.opts.screenshot.clone() {
            self.save_screenshot(&path)?;
        }
        Ok(Flow::Quit)
    }

    fn save_screenshot(&mut self, path: &std::path::Path) -> Result<()> {
        let texture = &self.frames.frame.texture;
        let rgba = readback::read_texture(&self.ctx, texture, 4)?;
        Image {
            width: texture.width(),
            height: texture.height(),
            rgba,
        }
        .save_png(path)?;
        self.status.message = format!("saved {}", path.display());
        Ok(())
    }
}

/// The technique `step` places after `current` in `Technique::ALL`, wrapping around.
fn step_technique(current: Technique, step: usize) -> Technique {
    let all = Technique::ALL;
    let at = all.iter().position(|t| *t == current).unwrap_or(0);
    all[(at + step) % all.len()]
}

#[cfg(test)]
mod key_tests {
    use super::*;

    #[test]
    fn the_bracket_keys_reach_every_technique_and_wrap() {
        let all = Technique::ALL;
        let mut t = all[0];
        let mut seen = vec![t];
        for _ in 1..all.len() {
            t = step_technique(t, 1);
            seen.push(t);
        }
        assert_eq!(seen, all.to_vec());
        assert_eq!(step_technique(*all.last().unwrap(), 1), all[0]);
        assert_eq!(step_technique(all[0], all.len() - 1), *all.last().unwrap());
    }
}
