//! A headless Bevy app with the plugin, rendering one `VoxelCamera` into an image, and what
//! the tests compare it with.

#![allow(dead_code, clippy::unwrap_used, clippy::missing_panics_doc)] // test support

use bevy::app::{App, PluginGroup};
use bevy::asset::{Assets, Handle};
use bevy::camera::{Camera3d, Hdr, PerspectiveProjection, Projection, RenderTarget};
use bevy::ecs::entity::Entity;
use bevy::ecs::message::Messages;
use bevy::image::Image as BevyImage;
use bevy::math::Vec3;
use bevy::render::render_asset::RenderAssets;
use bevy::render::renderer::{RenderAdapter, RenderDevice, RenderQueue};
use bevy::render::settings::{RenderCreation, WgpuSettings};
use bevy::render::texture::GpuImage;
use bevy::render::view::{DebandDither, Msaa, Tonemapping};
use bevy::render::{RenderApp, RenderPlugin};
use bevy::transform::components::{GlobalTransform, Transform};
use bevy::window::{ExitCondition, WindowPlugin};
use bevy::winit::WinitPlugin;
use glam::DVec3;
use voxel_bevy::{VoxelCamera, VoxelMessage, VoxelPlugin, VoxelWorld, crate_camera};
use voxel_render::{GpuContext, Image, readback};

/// A headless app (no window, no winit) on Vulkan (lavapipe here) with the plugin.
pub struct Harness {
    pub app: App,
    pub image: Handle<BevyImage>,
    pub camera: Entity,
    pub size: (u32, u32),
    pub far: f64,
}

/// The view of a crate camera as a Bevy transform.
pub fn transform(eye: DVec3, forward: DVec3) -> Transform {
    let v = |d: DVec3| Vec3::new(d.x as f32, d.y as f32, d.z as f32);
    Transform::from_translation(v(eye)).looking_to(v(forward), Vec3::Y)
}

impl Harness {
    /// The app with `world`, a camera at `eye` looking along `forward` (vertical fov in
    /// degrees, near plane), the plugin's far plane `far`, drawing `size` pixels; `hdr`: an
    /// HDR camera.
    #[allow(clippy::too_many_arguments)] // a camera's numbers
    pub fn new(
        world: VoxelWorld,
        eye: DVec3,
        forward: DVec3,
        fov_deg: f64,
        near: f64,
        far: f64,
        size: (u32, u32),
        hdr: bool,
    ) -> Self {
        // Vulkan, or the backend WGPU_BACKEND names (`gl`: the GL path the WebGL2 page
        // takes, natively).
        let backends = wgpu::Backends::from_env().unwrap_or(wgpu::Backends::VULKAN);
        Self::with_plugin(
            world, eye, forward, fov_deg, near, far, size, hdr, true, backends,
        )
    }

    /// [`Harness::new`] on `backends`, or without the plugin (`plugin` false: the same
    /// camera settings, Bevy alone), for the cost bench.
    #[allow(clippy::too_many_arguments)] // a camera's numbers
    pub fn with_plugin(
        world: VoxelWorld,
        eye: DVec3,
        forward: DVec3,
        fov_deg: f64,
        near: f64,
        far: f64,
        size: (u32, u32),
        hdr: bool,
        plugin: bool,
        backends: wgpu::Backends,
    ) -> Self {
        let mut app = App::new();
        app.add_plugins(
            bevy::DefaultPlugins
                .build()
                .disable::<WinitPlugin>()
                .set(WindowPlugin {
                    primary_window: None,
                    exit_condition: ExitCondition::DontExit,
                    ..Default::default()
                })
                .set(RenderPlugin {
                    render_creation: RenderCreation::Automatic(Box::new(WgpuSettings {
                        backends: Some(backends),
                        ..Default::default()
                    })),
                    ..Default::default()
                }),
        );
        if plugin {
            app.add_plugins(VoxelPlugin {
                far,
                ..Default::default()
            });
        }
        app.insert_resource(world);
        app.finish();
        app.cleanup();
        let mut target = BevyImage::new_target_texture(
            size.0,
            size.1,
            wgpu::TextureFormat::Rgba8UnormSrgb,
            None,
        );
        // read back by the tests
        target.texture_descriptor.usage |= wgpu::TextureUsages::COPY_SRC;
        let image = app
            .world_mut()
            .resource_mut::<Assets<BevyImage>>()
            .add(target);
        let mut camera = app.world_mut().spawn((
            Camera3d::default(),
            (Msaa::Off, Tonemapping::None, DebandDither::Disabled),
            RenderTarget::Image(image.clone().into()),
            Projection::Perspective(PerspectiveProjection {
                fov: fov_deg.to_radians() as f32,
                near: near as f32,
                ..Default::default()
            }),
            transform(eye, forward),
        ));
        if hdr {
            camera.insert(Hdr);
        }
        if plugin {
            camera.insert(VoxelCamera);
        }
        let camera = camera.id();
        Self {
            app,
            image,
            camera,
            size,
            far,
        }
    }

    /// Bevy's device and queue as the crate's context (what the reference renders on).
    pub fn ctx(&self) -> GpuContext {
        let rw = self.app.sub_app(RenderApp).world();
        GpuContext::from_device(
            rw.resource::<RenderAdapter>(),
            rw.resource::<RenderDevice>().wgpu_device().clone(),
            (**rw.resource::<RenderQueue>()).clone(),
        )
    }

    /// The crate camera the plugin draws this frame with.
    pub fn camera(&self) -> voxel_render::Camera {
        let w = self.app.world();
        let t = w.get::<GlobalTransform>(self.camera).unwrap();
        let p = w.get::<Projection>(self.camera).unwrap();
        let world = w.resource::<VoxelWorld>();
        world
            .with_world(|w| crate_camera(t, p, self.far, Some(w)))
            .unwrap()
    }

    /// Runs `n` frames and reads the camera's image back.
    pub fn frames(&mut self, n: usize) -> Image {
        for _ in 0..n {
            self.app.update();
        }
        let ctx = self.ctx();
        let rw = self.app.sub_app(RenderApp).world();
        let gpu = rw
            .resource::<RenderAssets<GpuImage>>()
            .get(self.image.id())
            .expect("the target image on the GPU");
        let rgba = readback::read_texture(&ctx, &gpu.texture, 4).unwrap();
        Image {
            width: self.size.0,
            height: self.size.1,
            rgba,
        }
    }

    /// The plugin's messages since the last call.
    pub fn messages(&mut self) -> Vec<VoxelMessage> {
        self.app
            .world_mut()
            .resource_mut::<Messages<VoxelMessage>>()
            .drain()
            .collect()
    }
}

/// Fails (under CI) or skips loudly without a Vulkan adapter; the Bevy app then fails too.
pub fn have_gpu() -> bool {
    tests::gpu().is_some()
}

/// Pixels whose largest RGB difference is over 1/255, as a share of all.
pub fn share_over_one(a: &Image, b: &Image) -> f64 {
    let d = tests::diff(a, b);
    d.over_one as f64 / f64::from(a.width * a.height)
}

/// Saves both pictures and their difference under `target/test-output/bevy/`.
pub fn save(name: &str, bevy: &Image, reference: &Image) {
    let dir = tests::out_dir("bevy");
    bevy.save_png(&dir.join(format!("{name}-bevy.png")))
        .unwrap();
    reference
        .save_png(&dir.join(format!("{name}-crate.png")))
        .unwrap();
    tests::diff_image(bevy, reference)
        .save_png(&dir.join(format!("{name}-diff.png")))
        .unwrap();
}
