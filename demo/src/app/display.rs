//! The window's surface: the device that can draw to it, configuration, resizes, and the
//! surface texture of each frame (outdated, lost and minimised surfaces handled).

use std::sync::Arc;

use crate::{Error, Result};
use voxel_render::GpuContext;
use winit::window::Window;

/// The window and its configured surface.
pub struct Display {
    pub window: Arc<Window>,
    instance: wgpu::Instance,
    surface: wgpu::Surface<'static>,
    pub config: wgpu::SurfaceConfiguration,
}

impl Display {
    /// A surface for `window` and a device (on the adapter of `backends` that can draw to
    /// it; `None`: `WGPU_BACKEND`, else the primary ones) with `limits`.
    pub fn new(
        window: Arc<Window>,
        backends: Option<wgpu::Backends>,
        limits: voxel_render::LimitsPreset,
    ) -> Result<(Self, GpuContext)> {
        // The window's display: wgpu's GL backend makes its EGL display from it.
        let mut desc = wgpu::InstanceDescriptor::new_with_display_handle(Box::new(window.clone()));
        desc.backends = backends
            .or_else(wgpu::Backends::from_env)
            .unwrap_or(wgpu::Backends::PRIMARY);
        desc.flags = voxel_render::instance_flags(desc.backends);
        let instance = wgpu::Instance::new(desc);
        let surface = instance
            .create_surface(window.clone())
            .map_err(Error::CreateSurface)?;
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            compatible_surface: Some(&surface),
            ..Default::default()
        }))
        .map_err(Error::NoWindowAdapter)?;
        let (device, queue) =
            pollster::block_on(voxel_render::request_device_with(&adapter, limits))?;
        let ctx = GpuContext::from_device(&adapter, device, queue);
        let caps = surface.get_capabilities(&adapter);
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| f.is_srgb())
            .or_else(|| caps.formats.first().copied())
            .ok_or(Error::NoSurfaceFormat)?;
        let size = window.inner_size();
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            width: size.width.max(1),
            height: size.height.max(1),
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
        surface.configure(&ctx.device, &config);
        Ok((
            Self {
                window,
                instance,
                surface,
                config,
            },
            ctx,
        ))
    }

    /// The surface size in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.config.width, self.config.height)
    }

    /// Reconfigures for a new (non-zero) size.
    pub fn resize(&mut self, ctx: &GpuContext, width: u32, height: u32) {
        self.config.width = width;
        self.config.height = height;
        self.surface.configure(&ctx.device, &self.config);
    }

    /// This frame's surface texture, or `None` when there is none to draw to this time
    /// (the surface was outdated or lost and is being reconfigured, or the window is
    /// minimised or hidden): try again next frame.
    pub fn acquire(&mut self, ctx: &GpuContext) -> Result<Option<wgpu::SurfaceTexture>> {
        match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t) => Ok(Some(t)),
            wgpu::CurrentSurfaceTexture::Suboptimal(t) => {
                drop(t);
                self.surface.configure(&ctx.device, &self.config);
                Ok(None)
            }
            wgpu::CurrentSurfaceTexture::Outdated => {
                self.surface.configure(&ctx.device, &self.config);
                Ok(None)
            }
            wgpu::CurrentSurfaceTexture::Lost => {
                self.surface = self
                    .instance
                    .create_surface(self.window.clone())
                    .map_err(Error::SurfaceLost)?;
                self.surface.configure(&ctx.device, &self.config);
                Ok(None)
            }
            wgpu::CurrentSurfaceTexture::Timeout
            | wgpu::CurrentSurfaceTexture::Occluded
            | wgpu::CurrentSurfaceTexture::Validation => Ok(None),
        }
    }
}
