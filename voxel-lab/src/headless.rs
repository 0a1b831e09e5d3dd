//! Rendering without a window: a headless GPU, an offscreen target, PNG output.

use crate::{Error, Result};

use voxel_render::{
    Camera, FrameStats, GpuContext, Image, LimitsPreset, NoGame, Renderer, RendererConfig, readback,
};

use voxel_render::content::ContentStages;

use crate::scene::Scene;

/// A headless context on Vulkan (lavapipe on a machine without a GPU), or the backends
/// named by `WGPU_BACKEND`, with the adapter's limits.
pub fn context() -> Result<GpuContext> {
    Device::from_env().context()
}

/// Which device the headless tools draw with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Device {
    /// The backends to find the adapter among.
    pub backends: wgpu::Backends,
    /// The limits and optional features it is requested with.
    pub limits: LimitsPreset,
}

impl Device {
    /// The backends of `WGPU_BACKEND` (Vulkan when unset), the adapter's limits.
    pub fn from_env() -> Self {
        Self {
            backends: wgpu::Backends::from_env().unwrap_or(wgpu::Backends::VULKAN),
            limits: LimitsPreset::Adapter,
        }
    }

    /// A headless context on it.
    pub fn context(&self) -> Result<GpuContext> {
        GpuContext::headless_with(self.backends, self.limits).map_err(Error::Render)
    }

    /// Its name in reports: the backends and, unless the adapter's, the limits.
    pub fn name(&self) -> String {
        let backend = BACKENDS
            .iter()
            .find(|(_, b)| *b == self.backends)
            .map_or_else(|| format!("{:?}", self.backends), |(n, _)| (*n).to_owned());
        match self.limits {
            LimitsPreset::Adapter => backend,
            other => format!("{backend}, {} limits", other.name()),
        }
    }
}

/// The backends a command line names, by name.
pub const BACKENDS: [(&str, wgpu::Backends); 4] = [
    ("vulkan", wgpu::Backends::VULKAN),
    ("gl", wgpu::Backends::GL),
    ("metal", wgpu::Backends::METAL),
    ("dx12", wgpu::Backends::DX12),
];

/// Parses a backend's name ([`BACKENDS`]); the error lists the names.
pub fn backend(name: &str) -> Result<wgpu::Backends> {
    BACKENDS
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, b)| *b)
        .ok_or_else(|| {
            let names: Vec<&str> = BACKENDS.iter().map(|(n, _)| *n).collect();
            Error::UnknownBackend {
                name: name.to_owned(),
                known: names.join(", "),
            }
        })
}

/// An RGBA8 sRGB texture to render into and read back.
#[derive(Debug)]
pub struct Offscreen {
    /// The texture.
    pub texture: wgpu::Texture,
    /// Its view.
    pub view: wgpu::TextureView,
}

impl Offscreen {
    /// A `width` × `height` target.
    pub fn new(ctx: &GpuContext, width: u32, height: u32) -> Self {
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
        let t = voxel_render::stages::target(
            &ctx.device,
            "offscreen_output",
            wgpu::TextureFormat::Rgba8UnormSrgb,
            usage,
            (width, height),
        );
        Self {
            texture: t.texture,
            view: t.view,
        }
    }

    /// Reads the target back.
    pub fn read(&self, ctx: &GpuContext) -> Result<Image> {
        let rgba = readback::read_texture(ctx, &self.texture, 4)?;
        Ok(Image {
            width: self.texture.width(),
            height: self.texture.height(),
            rgba,
        })
    }
}

/// A renderer with a scene's chunks uploaded, and the scene's game content (particles,
/// entities: [`voxel_render::content`]) drawn through its stages in every frame. Derefs to the
/// [`Renderer`].
#[derive(Debug)]
pub struct SceneRenderer {
    /// The renderer.
    pub renderer: Renderer,
    /// The scene's content, when it has any: it does not follow a technique switch by
    /// itself (`set_follow_contract(false)`), `render_and_submit` rebuilds its pipelines.
    pub content: Option<ContentStages>,
}

impl std::ops::Deref for SceneRenderer {
    type Target = Renderer;
    fn deref(&self) -> &Renderer {
        &self.renderer
    }
}

impl std::ops::DerefMut for SceneRenderer {
    fn deref_mut(&mut self) -> &mut Renderer {
        &mut self.renderer
    }
}

impl SceneRenderer {
    /// Renders one frame of `camera` into `output`, the content included, and submits it.
    pub fn render_and_submit(
        &mut self,
        output: &wgpu::TextureView,
        camera: &Camera,
    ) -> voxel_render::Result<FrameStats> {
        match &mut self.content {
            None => self.renderer.render_and_submit(output, camera, &mut NoGame),
            Some(content) => {
                content.update_pipelines(&mut self.renderer)?;
                self.renderer.render_and_submit(output, camera, content)
            }
        }
    }
}

/// A renderer with every chunk of `scene` meshed and uploaded, and its content ready (its
/// instances fetched as the renderer fetches the world's quads: from storage buffers, or
/// as vertex attributes under WebGL2's limits).
pub fn renderer_for(
    ctx: &GpuContext,
    scene: &Scene,
    config: RendererConfig,
) -> Result<SceneRenderer> {
    let mut renderer = Renderer::new(ctx, scene.world.registry(), config)?;
    let light = scene
        .light
        .then(|| voxel_core::LightField::new(&scene.world));
    for (pos, meshes) in voxel_mesh::mesh_world(&scene.world, light.as_ref())? {
        renderer.upload_chunk(pos, &meshes)?;
    }
    if let Some(region) = sun_region(scene) {
        renderer.set_sun_shadows(&scene.world, region)?;
    }
    // The lab builds its content's pipelines when it renders (`render_and_submit`), so that
    // its tests see the renderer refuse pipelines built for another contract.
    let content = if scene.content.is_empty() {
        None
    } else {
        let mut stages = ContentStages::new(&renderer, scene.content.clone())?;
        stages.set_follow_contract(false);
        Some(stages)
    };
    Ok(SceneRenderer { renderer, content })
}

/// The region `scene`'s sun shadows cover: its world, or the chunks of it nearest its first
/// camera; `None` for a scene drawn unlit or without sun shadows.
pub fn sun_region(scene: &Scene) -> Option<voxel_render::SunRegion> {
    let eye = scene.cameras.first().map_or([0.0; 3], |c| c.eye.to_array());
    (scene.light && scene.sun_shadows)
        .then(|| {
            voxel_render::SunRegion::around(&scene.world, voxel_core::WorldPos::containing(eye))
        })
        .flatten()
}

/// Renders `camera` into `target` and reads the picture back.
pub fn render_image(
    ctx: &GpuContext,
    renderer: &mut SceneRenderer,
    target: &Offscreen,
    camera: &Camera,
) -> Result<Image> {
    renderer.render_and_submit(&target.view, camera)?;
    target.read(ctx)
}
