//! A game's window: the game owns the winit window, device and surface; the renderer draws
//! into the surface texture (whatever format it has); then the game's own passes
//! (`window.wgsl`): a box around the block under the crosshair, tested against the frame's
//! depth (reverse-Z, camera-relative), and a HUD. Keys 1-8 pick a real-time technique
//! (built ahead: no frame stalls at a switch; the title names it); resizing works. Nothing
//! is called after the submit. The backend is wgpu's choice or `WGPU_BACKEND` (`gl`,
//! `vulkan`, ...); a screenshot draws the frame a second time into a texture of its own,
//! since a surface texture may not be copied from (GL's never are). Scripted: `cargo run
//! --release -p voxel-render --example window -- --frames N --screenshot FILE.png`.

use std::sync::Arc;

use glam::DVec3;
use voxel_core::{BlockRegistry, ChunkPos, RenderClass, TerrainConfig, TerrainGenerator, World};
use voxel_render::{Camera, GpuContext, NoGame, Renderer, RendererConfig, Technique, stages};
use wgpu::CurrentSurfaceTexture::Success;
use wgpu::PrimitiveTopology::{LineList, TriangleList};
use wgpu::util::DeviceExt;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, EventLoop, OwnedDisplayHandle};
use winit::window::{Window, WindowId};

/// Where the game's camera stands and what it looks at.
const EYE: DVec3 = DVec3::new(8.5, 33.5, -1.5);
const TARGET: DVec3 = DVec3::new(10.5, 29.0, -6.5);

struct Gfx {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    ctx: GpuContext,
    renderer: Renderer,
    world: World,
    uniforms: wgpu::Buffer,
    /// The selection box's pipeline and the HUD's, with their bind groups.
    passes: [(wgpu::RenderPipeline, wgpu::BindGroup); 2],
}

#[derive(Default)]
struct Game {
    gfx: Option<Gfx>,
    /// Frames left to draw in a scripted run.
    frames: Option<u32>,
    screenshot: Option<String>,
}

fn setup(
    window: Arc<Window>,
    display: OwnedDisplayHandle,
    world: World,
) -> Result<Gfx, Box<dyn std::error::Error>> {
    // `WGPU_BACKEND` (and wgpu's other variables) honoured; the display handle is what GL
    // needs to present (Vulkan ignores it).
    let mut desc = wgpu::InstanceDescriptor::new_with_display_handle_from_env(Box::new(display));
    // Without wgpu's indirect-call validation on GL (`voxel_render::instance_flags`).
    desc.flags = voxel_render::instance_flags(desc.backends);
    let instance = wgpu::Instance::new(desc);
    let surface = instance.create_surface(window.clone())?;
    let (ctx, adapter) = GpuContext::for_surface(&instance, &surface)?;
    println!("drawing on {}", ctx.caps.adapter_name);
    let (width, height) = window.inner_size().into();
    let config = surface.get_default_config(&adapter, width, height);
    let config = config.ok_or("the surface offers no format")?;
    surface.configure(&ctx.device, &config);
    let mut rc = RendererConfig::default();
    (rc.width, rc.height, rc.output_format) = (config.width, config.height, config.format);
    let mut renderer = Renderer::new(&ctx, world.registry(), rc)?;
    for (pos, meshes) in voxel_mesh::mesh_dirty(&mut world.clone())? {
        renderer.upload_chunk(pos, &meshes)?;
    }
    for technique in Technique::REAL_TIME {
        renderer.prebuild_technique(technique)?;
    }
    let d = &ctx.device;
    let module = stages::shader(d, "game_overlay", &[include_str!("window.wgsl")]);
    let uniforms = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("game_uniforms"),
        contents: &[0; 96],
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
    });
    let box_pass = (("vs_box", "fs_box"), LineList, true);
    let passes = [box_pass, (("vs_hud", "fs_hud"), TriangleList, false)];
    let passes = passes.map(|(entry, topology, depth)| {
        let p = stages::overlay_pipeline(d, &module, entry, config.format, topology, depth);
        let uniform = [uniforms.as_entire_binding()];
        let group = stages::bind_group(d, entry.1, &p.get_bind_group_layout(0), &uniform);
        (p, group)
    });
    Ok(Gfx {
        window,
        surface,
        config,
        ctx,
        renderer,
        world,
        uniforms,
        passes,
    })
}

impl Gfx {
    /// The frame into `view`: the renderer's, then the game's selection box and HUD.
    fn draw(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        view: &wgpu::TextureView,
        camera: &Camera,
    ) -> Result<(), Box<dyn std::error::Error>> {
        self.renderer.render(encoder, view, camera, &mut NoGame)?;
        // The game's passes see what the renderer drew, from the camera it drew with.
        let drawn = self.renderer.drawn_camera(camera);
        let (eye, forward) = (drawn.eye.to_array(), drawn.forward.to_array());
        let visible = RenderClass::VISIBLE;
        let hit = self.world.raycast(eye, forward, 300.0, &visible)?;
        let block = hit.map_or(DVec3::ZERO, |h| DVec3::from(h.pos.corner()) - drawn.eye);
        let (w, h) = (self.config.width as f32, self.config.height as f32);
        // The box's corners relative to the eye; their w: the window size, for the HUD.
        let lo = (block - 0.01).as_vec3().extend(w);
        let hi = (block + 1.01).as_vec3().extend(h);
        let vp = drawn.view_proj(f64::from(w / h));
        let u = [vp.x_axis, vp.y_axis, vp.z_axis, vp.w_axis, lo, hi];
        let queue = &self.ctx.queue;
        queue.write_buffer(&self.uniforms, 0, bytemuck::cast_slice(&u));
        let counts = [24 * u32::from(hit.is_some()), 12];
        for (i, (pipeline, group)) in self.passes.iter().enumerate() {
            // The box tests the frame's depth, read only: nearer blocks hide it.
            let depth = stages::Depth::ReadOnly(self.renderer.scene_depth_view());
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                color_attachments: &[stages::load(view)],
                depth_stencil_attachment: depth.attachment().filter(|_| i == 0),
                ..Default::default()
            });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, group, &[]);
            pass.draw(0..counts[i], 0..1);
        }
        Ok(())
    }
}

impl Game {
    fn redraw(&mut self, event_loop: &ActiveEventLoop) -> Result<(), Box<dyn std::error::Error>> {
        let g = self.gfx.as_mut().ok_or("no window yet")?;
        let Success(frame) = g.surface.get_current_texture() else {
            // Outdated, lost, timed out or hidden: try again next frame.
            g.surface.configure(&g.ctx.device, &g.config);
            return Ok(());
        };
        let camera = Camera::look_at(EYE, TARGET, 70.0, 0.1, 400.0)?;
        let view = frame.texture.create_view(&Default::default());
        let mut encoder = g.ctx.device.create_command_encoder(&Default::default());
        g.draw(&mut encoder, &view, &camera)?;
        self.frames = self.frames.map(|n| n.saturating_sub(1));
        let last = self.frames == Some(0);
        // The screenshot: the same frame drawn again into a texture that can be copied
        // from, in the same encoder (each frame recorded before a submit draws its own).
        let shot = self.screenshot.as_ref().filter(|_| last).map(|path| {
            let texture = g.ctx.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("screenshot"),
                size: frame.texture.size(),
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: g.config.format,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            });
            (path, texture)
        });
        if let Some((_, texture)) = &shot {
            g.draw(
                &mut encoder,
                &texture.create_view(&Default::default()),
                &camera,
            )?;
        }
        g.ctx.queue.submit([encoder.finish()]);
        if let Some((path, texture)) = shot {
            let image = voxel_render::readback::read_image(&g.ctx, &texture)?;
            image.save_png(path.as_ref())?;
            println!("wrote {path}: GPU ms {:?}", g.renderer.gpu_times_blocking());
        }
        if last {
            event_loop.exit();
        }
        g.ctx.queue.present(frame);
        Ok(())
    }
}

impl winit::application::ApplicationHandler for Game {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        let size = winit::dpi::PhysicalSize::new(800, 500);
        let window = event_loop.create_window(Window::default_attributes().with_inner_size(size));
        let generator = TerrainGenerator::new(TerrainConfig::default());
        let (min, max) = (ChunkPos::new(-4, 0, -5), ChunkPos::new(2, 1, 1));
        let world = generator.generate_world(Arc::new(BlockRegistry::default()), min, max);
        let world = world.expect("terrain of the default blocks");
        let display = event_loop.owned_display_handle();
        let gfx = setup(Arc::new(window.expect("a window")), display, world);
        self.gfx = Some(gfx.expect("a device and a renderer"));
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(g) = &mut self.gfx else { return };
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) if size.width > 0 && size.height > 0 => {
                (g.config.width, g.config.height) = (size.width, size.height);
                g.surface.configure(&g.ctx.device, &g.config);
                let resized = g.renderer.resize(size.width, size.height);
                resized.expect("a size the adapter allows");
            }
            WindowEvent::KeyboardInput { event, .. } if event.state.is_pressed() => {
                let digit = event.logical_key.to_text().and_then(|c| c.parse().ok());
                if let Some(&technique) =
                    digit.and_then(|n: usize| Technique::REAL_TIME.get(n.wrapping_sub(1)))
                {
                    match g.renderer.set_technique(technique) {
                        Ok(t) => g.window.set_title(&format!("window example: {t}")),
                        Err(e) => eprintln!("{technique}: {e}"),
                    }
                }
            }
            WindowEvent::RedrawRequested => self.redraw(event_loop).unwrap_or_else(|e| {
                eprintln!("error: {e}");
                event_loop.exit();
            }),
            _ => {}
        }
    }

    fn about_to_wait(&mut self, _: &ActiveEventLoop) {
        self.gfx.iter().for_each(|g| g.window.request_redraw());
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let arg = |name| Some(args.windows(2).find(|w| w[0] == name)?[1].clone());
    let frames = arg("--frames").map(|n| n.parse()).transpose()?;
    let screenshot = arg("--screenshot");
    let mut game = Game {
        frames,
        screenshot,
        ..Game::default()
    };
    Ok(EventLoop::new()?.run_app(&mut game)?)
}
