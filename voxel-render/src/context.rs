//! The GPU a renderer draws with: the game's own device and queue, or a headless one for
//! tests and tools, plus the capabilities the renderer adapts to.

use std::sync::{Arc, Mutex, PoisonError};

use crate::{Error, Result};

/// What the adapter can do that changes how we render. Read once from the adapter.
#[derive(Clone, Debug)]
pub struct Capabilities {
    /// The adapter's name and backend, for logs and reports.
    pub adapter_name: String,
    /// Backend in use.
    pub backend: wgpu::Backend,
    /// Device type (CPU for lavapipe).
    pub device_type: wgpu::DeviceType,
    /// Features enabled on the device.
    pub features: wgpu::Features,
    /// Downlevel flags of the adapter (independent blend, fragment storage writes, ...).
    pub downlevel: wgpu::DownlevelFlags,
    /// Whether `Rgba16Float` can be rendered to and blended (WBOIT accumulation).
    pub rgba16f_blendable: bool,
    /// Whether 4× MSAA works on the scene colour and depth formats.
    pub msaa4: bool,
    /// Device limits.
    pub limits: wgpu::Limits,
    /// Whether wgpu binds each resource where the shaders declare it: not on desktop GL
    /// below 4.2 that reports compute shaders (see [`Capabilities::new`]).
    shader_bindings: bool,
    /// The adapter, for the features of texture formats ([`Capabilities::renders_to`]).
    adapter: wgpu::Adapter,
}

impl Capabilities {
    /// Reads the capabilities of `adapter` for a device created with `features` and
    /// `limits`. On desktop GL older than 4.0 storage buffers and textures count as absent
    /// whatever the driver's extensions say, and on desktop GL older than 4.2 that reports
    /// compute shaders the world cannot be drawn (`low_level::Need::ShaderBindings` fails).
    pub fn new(adapter: &wgpu::Adapter, features: wgpu::Features, limits: wgpu::Limits) -> Self {
        let info = adapter.get_info();
        let mut limits = limits;
        let mut downlevel = adapter.get_downlevel_capabilities().flags;
        let desktop_gl = desktop_gl_version(info.backend, &info.driver_info);
        // wgpu writes the GLSL of the context's version (desktop GL 3.3 and later: the
        // version of `GL_VERSION`), and naga declares storage buffers from GLSL 4.00 and
        // compute shaders from 4.20; a driver may list the extensions that offer both on an
        // older context (NVIDIA's EGL gives a 3.3 context with them), and wgpu reports them.
        if desktop_gl.is_some_and(|v| v < (4, 0)) {
            limits.max_storage_buffers_per_shader_stage = 0;
            limits.max_storage_textures_per_shader_stage = 0;
            downlevel.remove(
                wgpu::DownlevelFlags::VERTEX_STORAGE
                    | wgpu::DownlevelFlags::FRAGMENT_WRITABLE_STORAGE,
            );
        }
        // wgpu (30) takes a GL adapter with compute shaders to have `layout(binding = n)`
        // in its shaders and binds nothing by name; naga writes those from GLSL 4.20 only,
        // so below it every uniform block and texture of a pipeline lands on slot 0.
        let shader_bindings = !(desktop_gl.is_some_and(|v| v < (4, 2))
            && downlevel.contains(wgpu::DownlevelFlags::COMPUTE_SHADERS));
        if desktop_gl.is_some_and(|v| v < (4, 2)) {
            downlevel.remove(wgpu::DownlevelFlags::COMPUTE_SHADERS);
        }
        let f16 = adapter.get_texture_format_features(wgpu::TextureFormat::Rgba16Float);
        let depth = adapter.get_texture_format_features(crate::DEPTH_FORMAT);
        let msaa4 = f16
            .flags
            .contains(wgpu::TextureFormatFeatureFlags::MULTISAMPLE_X4)
            && depth
                .flags
                .contains(wgpu::TextureFormatFeatureFlags::MULTISAMPLE_X4)
            && f16
                .flags
                .contains(wgpu::TextureFormatFeatureFlags::MULTISAMPLE_RESOLVE)
            // On wgpu's GL backend (Mesa's llvmpipe) the 4× opaque pass resolves to black and
            // its depth resolve reads zeros, with no error reported: the cause is not found,
            // so GL draws without MSAA (the fallback every device without 4× support takes).
            && info.backend != wgpu::Backend::Gl;
        Self {
            // A browser's WebGPU names no adapter.
            adapter_name: match info.name.as_str() {
                "" => format!("unnamed adapter ({:?})", info.backend),
                name => format!("{name} ({:?})", info.backend),
            },
            backend: info.backend,
            device_type: info.device_type,
            features,
            downlevel,
            rgba16f_blendable: f16
                .allowed_usages
                .contains(wgpu::TextureUsages::RENDER_ATTACHMENT)
                && f16
                    .flags
                    .contains(wgpu::TextureFormatFeatureFlags::BLENDABLE),
            msaa4,
            limits,
            shader_bindings,
            adapter: adapter.clone(),
        }
    }

    /// Whether `format` can be a render target (`blend`: with blending) on the device:
    /// what the adapter does, within what wgpu validates without
    /// `TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES` (the format's guaranteed features, with
    /// the device's features: `FLOAT32_BLENDABLE` for 32-bit floats).
    pub(crate) fn renders_to(&self, format: wgpu::TextureFormat, blend: bool) -> bool {
        let ok = |f: wgpu::TextureFormatFeatures| {
            f.allowed_usages
                .contains(wgpu::TextureUsages::RENDER_ATTACHMENT)
                && (!blend || f.flags.contains(wgpu::TextureFormatFeatureFlags::BLENDABLE))
        };
        ok(format.guaranteed_format_features(self.features))
            && ok(self.adapter.get_texture_format_features(format))
    }

    /// Whether wgpu binds each buffer and texture of a pipeline where its shaders declare
    /// it. Not on desktop GL below 4.2 whose driver reports compute shaders (an extension
    /// NVIDIA lists on its 3.3 context): wgpu 30 then expects the slots written in the
    /// shaders, which its translator writes from GLSL 4.20 only, and every resource lands
    /// on slot 0. Nothing can be drawn right there; the renderer refuses such a device.
    pub(crate) fn shader_bindings(&self) -> bool {
        self.shader_bindings
    }

    /// Whether render passes can count samples into occlusion queries. Not on a browser's
    /// WebGPU: wgpu 30 leaves the pass's occlusion query set out of what it gives the
    /// browser, which then refuses the pass's queries and the whole frame.
    pub(crate) fn occlusion_queries(&self) -> bool {
        self.backend != wgpu::Backend::BrowserWebGpu
    }

    /// Whether occlusion queries count the samples that pass (what a counted frame's
    /// samples and bytes are measured with, `low_level::count_next_frame`). Not on wgpu's
    /// GL backend (desktop GL, GLES, WebGL2), whose occlusion queries are GL's
    /// `ANY_SAMPLES_PASSED_CONSERVATIVE`: 1 where any sample passed, so a pass of a million
    /// samples reads 1; nor where there are no occlusion queries at all
    /// ([`Capabilities::occlusion_queries`]).
    pub(crate) fn counts_samples(&self) -> bool {
        self.occlusion_queries() && self.backend != wgpu::Backend::Gl
    }

    /// Whether timestamp queries at pass boundaries are available.
    pub fn timestamps(&self) -> bool {
        self.features.contains(wgpu::Features::TIMESTAMP_QUERY)
    }

    /// Whether chunks can be drawn with `multi_draw_indirect` (indirect execution, and
    /// indirect draws whose first instance is not zero).
    pub(crate) fn indirect_draws(&self) -> bool {
        self.downlevel
            .contains(wgpu::DownlevelFlags::INDIRECT_EXECUTION)
            && self
                .features
                .contains(wgpu::Features::INDIRECT_FIRST_INSTANCE)
    }

    /// Whether 32-bit float targets (R32Float, Rgba32Float) can be blended (MBOIT's
    /// moments; 16-bit ones otherwise).
    pub(crate) fn float32_blendable(&self) -> bool {
        self.features.contains(wgpu::Features::FLOAT32_BLENDABLE)
    }
}

/// The version of a desktop GL context (`None` for another backend, GLES or WebGL), read
/// from wgpu's `driver_info`, which on GL is the `GL_VERSION` string: `3.3.0 NVIDIA ...`
/// on desktop GL, `OpenGL ES 3.2 ...` or `WebGL 2.0 ...` otherwise.
pub(crate) fn desktop_gl_version(backend: wgpu::Backend, driver_info: &str) -> Option<(u32, u32)> {
    if backend != wgpu::Backend::Gl {
        return None;
    }
    let mut numbers = driver_info.split([' ', '.']).map(str::parse::<u32>);
    match (numbers.next(), numbers.next()) {
        (Some(Ok(major)), Some(Ok(minor))) => Some((major, minor)),
        _ => None,
    }
}

/// A device, its queue and its capabilities. Cheap to clone (wgpu handles are shared).
#[derive(Clone, Debug)]
pub struct GpuContext {
    /// The device everything is created on.
    pub device: wgpu::Device,
    /// The queue everything is submitted to.
    pub queue: wgpu::Queue,
    /// What the adapter can do.
    pub caps: Capabilities,
    /// Set by the device-lost callback (or by [`GpuContext::check_device`]): why the
    /// device was lost.
    lost: Arc<Mutex<Option<String>>>,
    /// Four bytes [`GpuContext::check_device`] writes to learn whether the device is
    /// still valid: wgpu calls the lost callback only once the device's queue has
    /// drained, but refuses a write at once on a destroyed or lost device.
    probe: wgpu::Buffer,
}

/// Optional features the renderer uses when the adapter has them (GPU timings, one
/// indirect draw per page, 32-bit float moments for MBOIT, the fragments a counted
/// frame's passes shade: `low_level::count_next_frame`). A game that requests its own
/// device asks for `adapter.features() & WANTED_FEATURES` besides its own, or builds the
/// whole request with [`device_descriptor`]; without them the renderer falls back (logged).
pub const WANTED_FEATURES: wgpu::Features = wgpu::Features::TIMESTAMP_QUERY
    .union(wgpu::Features::INDIRECT_FIRST_INSTANCE)
    .union(wgpu::Features::FLOAT32_BLENDABLE)
    .union(wgpu::Features::PIPELINE_STATISTICS_QUERY);

impl GpuContext {
    /// Wraps a device the embedding game already owns. `adapter` is the one it came from
    /// (for capability queries); `device.features()` says which optional features we may use.
    ///
    /// Installs the device's lost callback (wgpu keeps one per device, so this replaces a
    /// callback set before): the renderer learns of a loss through it and answers every
    /// call after it with [`Error::DeviceLost`]. A game that wants to know too asks
    /// [`GpuContext::check_device`] rather than setting a callback of its own (which would
    /// replace this one). So make one context per device and clone it (clones share the
    /// callback's state; [`GpuContext::same_device`] tells them apart from other devices').
    pub fn from_device(adapter: &wgpu::Adapter, device: wgpu::Device, queue: wgpu::Queue) -> Self {
        let caps = Capabilities::new(adapter, device.features(), device.limits());
        let lost = Arc::new(Mutex::new(None));
        let flag = Arc::clone(&lost);
        device.set_device_lost_callback(move |reason, message| {
            let why = if message.is_empty() {
                format!("{reason:?}")
            } else {
                format!("{reason:?}: {message}")
            };
            *flag.lock().unwrap_or_else(PoisonError::into_inner) = Some(why);
        });
        let probe_desc = wgpu::BufferDescriptor {
            label: Some("device_probe"),
            size: 4,
            usage: wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        };
        // wgpu-core names a buffer by an index and the count of buffers that held that
        // index (its epoch), per instance: made and dropped PROBE_EPOCH times first, the
        // probe's name is one that another instance's buffers hardly ever carry, so that
        // `check_encoder` finds an encoder of another instance rather than a buffer of its.
        for _ in 0..PROBE_EPOCH {
            drop(device.create_buffer(&probe_desc));
        }
        let probe = device.create_buffer(&probe_desc);
        Self {
            device,
            queue,
            caps,
            lost,
            probe,
        }
    }

    /// [`Error::DeviceLost`] once the device is lost, else `Ok`: what a game asks to learn
    /// of a loss (every renderer call returning a `Result` asks it too). Polls the device first
    /// (without waiting), because wgpu runs the lost callback only when it maintains the
    /// device; and since it runs it only once the device's queue has drained, a device
    /// destroyed or lost with work in flight is found by a four-byte queue write, which
    /// wgpu refuses at once on such a device (a few microseconds; the write lands in a
    /// buffer of the context's own at the next submit).
    pub fn check_device(&self) -> Result<()> {
        // A poll error on a lost device says no more than the callback does.
        let _ = self.device.poll(wgpu::PollType::Poll);
        let mut lost = self.lost.lock().unwrap_or_else(PoisonError::into_inner);
        if lost.is_none() {
            let size = wgpu::BufferSize::new(4).expect("4 is not zero");
            if self.queue.write_buffer_with(&self.probe, 0, size).is_none() {
                *lost =
                    Some("destroyed or lost (wgpu reports why once the GPU's queue drains)".into());
            }
        }
        match lost.as_ref() {
            Some(reason) => Err(Error::DeviceLost {
                reason: reason.clone(),
            }),
            None => Ok(()),
        }
    }

    /// An `Error::OtherDevice` when `encoder` comes from another wgpu instance than this
    /// context's device, found before anything of a frame is recorded: an empty clear of
    /// the context's own four-byte probe is recorded into it (nothing on the GPU), and
    /// wgpu-core, which looks up the probe's id in the encoder's instance, panics there
    /// ("Cannot get non-existent resource"); the panic is caught ([`guard_foreign`]).
    /// An encoder of another device of the same instance is not found here: wgpu refuses
    /// it when it is finished (`Renderer::render` says so).
    pub(crate) fn check_encoder(&self, encoder: &mut wgpu::CommandEncoder) -> Result<()> {
        guard_foreign("the command encoder", || {
            encoder.clear_buffer(&self.probe, 0, Some(0));
        })
    }

    /// Whether `other` is this context or a clone of it (the same device, made into a
    /// context once). wgpu tells devices of different instances apart by no public means,
    /// so the renderer and `content::ContentStages` compare contexts: a game wraps its
    /// device in one `GpuContext` and clones it.
    pub fn same_device(&self, other: &GpuContext) -> bool {
        Arc::ptr_eq(&self.lost, &other.lost)
    }

    /// Whether the device is known to be lost (no poll: what the last one found).
    pub fn is_lost(&self) -> bool {
        self.lost
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .is_some()
    }

    /// A headless context on the first adapter of `backends` (tests use
    /// `Backends::VULKAN`, which finds lavapipe on a machine without a GPU). Asks for
    /// [`WANTED_FEATURES`] where the adapter has them. Blocks until the device exists
    /// (not on wasm32, where a page cannot block).
    #[cfg(not(target_arch = "wasm32"))]
    pub fn headless(backends: wgpu::Backends) -> Result<Self> {
        Self::headless_with(backends, LimitsPreset::Adapter)
    }

    /// [`GpuContext::headless`] with the device's limits and features from `preset`
    /// ([`LimitsPreset::WebGl2`]: a device as small as WebGL2's on any adapter).
    #[cfg(not(target_arch = "wasm32"))]
    pub fn headless_with(backends: wgpu::Backends, preset: LimitsPreset) -> Result<Self> {
        pollster::block_on(Self::headless_async(backends, preset))
    }

    /// A context on an adapter that can draw to `surface` (a game's window), asking for
    /// [`WANTED_FEATURES`] where it has them; also returns the adapter, for the surface's
    /// capabilities and configuration. Blocks until the device exists (not on wasm32,
    /// where a page cannot block: there [`request_device`] is awaited and the context made
    /// with [`GpuContext::from_device`]).
    #[cfg(not(target_arch = "wasm32"))]
    pub fn for_surface(
        instance: &wgpu::Instance,
        surface: &wgpu::Surface<'_>,
    ) -> Result<(Self, wgpu::Adapter)> {
        pollster::block_on(async {
            let adapter = instance
                .request_adapter(&wgpu::RequestAdapterOptions {
                    power_preference: wgpu::PowerPreference::HighPerformance,
                    compatible_surface: Some(surface),
                    ..Default::default()
                })
                .await
                .map_err(|e| {
                    Error::Unsupported(format!("no adapter can draw to the surface: {e}"))
                })?;
            let (device, queue) = request_device(&adapter).await?;
            Ok((Self::from_device(&adapter, device, queue), adapter))
        })
    }

    #[cfg(not(target_arch = "wasm32"))]
    async fn headless_async(backends: wgpu::Backends, preset: LimitsPreset) -> Result<Self> {
        let instance = wgpu::Instance::new(instance_descriptor(backends));
        let adapter = instance
            .request_adapter(&wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::HighPerformance,
                ..Default::default()
            })
            .await
            .map_err(|error| Error::NoAdapter { backends, error })?;
        let (device, queue) = request_device_with(&adapter, preset).await?;
        Ok(Self::from_device(&adapter, device, queue))
    }
}

/// Buffers made and dropped before a context's probe ([`GpuContext::check_encoder`]).
const PROBE_EPOCH: u32 = 64;

/// Runs `f`, which hands wgpu an object the caller was given (`what`: an output view, an
/// encoder), turning wgpu-core's panic on an id its instance does not hold into
/// `Error::OtherDevice`: wgpu names objects by ids that each `wgpu::Instance` counts on
/// its own and offers no public way to ask an object's instance, so an object of another
/// instance is found only when wgpu-core looks its id up in the wrong one ("Cannot get
/// non-existent resource", or an id held by another object: "Cannot get …, found other
/// resource"). Any other panic goes on. Where a foreign id happens to name an object of
/// the same kind in this instance, wgpu-core takes that object instead and nothing is
/// caught here (docs/limits-and-errors.md). wgpu-core's message still reaches the panic
/// hook (stderr) before the error is returned.
pub(crate) fn guard_foreign<T>(what: &str, f: impl FnOnce() -> T) -> Result<T> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)).map_err(|payload| {
        let message = payload
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| payload.downcast_ref::<&str>().copied())
            .unwrap_or_default();
        if !message.contains("Cannot get") {
            std::panic::resume_unwind(payload);
        }
        let message = message.split_whitespace().collect::<Vec<_>>().join(" ");
        Error::OtherDevice(format!(
            "{what} (or an object it uses) comes from another wgpu::Instance than the \
             renderer's device: wgpu-core could not find it there ({message}); make every \
             device, texture, view and encoder a game gives the renderer through one \
             wgpu::Instance"
        ))
    })
}

/// The flags every wgpu instance of this crate (and of its lab, demo, examples and tests)
/// is created with: wgpu's defaults and the `WGPU_*` environment variables
/// (`wgpu::InstanceFlags::from_env_or_default`), less `VALIDATION_INDIRECT_CALL` when
/// `backends` include GL.
///
/// wgpu's indirect-call validation builds a compute pipeline on every device. A GL driver
/// can report compute shaders through an extension (`GL_ARB_compute_shader`) on a context
/// whose shading language cannot compile one (NVIDIA's EGL gives a desktop GL 3.3 context
/// with GLSL 3.30): the pipeline fails and wgpu loses the device before the first frame.
/// Which GL context a driver gives is known only once the instance exists, so GL goes
/// without that validation everywhere; the renderer writes every indirect draw itself
/// (first instance zero unless the device has `INDIRECT_FIRST_INSTANCE`).
pub fn instance_flags(backends: wgpu::Backends) -> wgpu::InstanceFlags {
    let mut flags = wgpu::InstanceFlags::from_env_or_default();
    if backends.contains(wgpu::Backends::GL) {
        flags.remove(wgpu::InstanceFlags::VALIDATION_INDIRECT_CALL);
    }
    flags
}

/// An instance descriptor for `backends` without a display handle, with
/// [`instance_flags`]. A window's instance (wgpu's GL backend wants the display) sets
/// `flags` to [`instance_flags`] on its own descriptor.
pub fn instance_descriptor(backends: wgpu::Backends) -> wgpu::InstanceDescriptor {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = backends;
    desc.flags = instance_flags(backends);
    desc
}

/// The limits and optional features a device is requested with.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum LimitsPreset {
    /// All of the adapter's limits (the A-buffer reference wants large storage buffers),
    /// and the [`WANTED_FEATURES`] it has.
    #[default]
    Adapter,
    /// WebGL2's limits (`wgpu::Limits::downlevel_webgl2_defaults`: no storage buffers or
    /// textures, no compute, 2048-texel textures) and no optional feature: what a
    /// browser's WebGL2 or a GLES 3.0 phone gives, on any adapter.
    WebGl2,
}

impl LimitsPreset {
    /// Both, in order.
    pub const ALL: [LimitsPreset; 2] = [LimitsPreset::Adapter, LimitsPreset::WebGl2];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            LimitsPreset::Adapter => "adapter",
            LimitsPreset::WebGl2 => "webgl2",
        }
    }

    /// The limits and features to request of `adapter`.
    pub(crate) fn request(self, adapter: &wgpu::Adapter) -> (wgpu::Limits, wgpu::Features) {
        match self {
            LimitsPreset::Adapter => (adapter.limits(), adapter.features() & WANTED_FEATURES),
            LimitsPreset::WebGl2 => (
                wgpu::Limits::downlevel_webgl2_defaults(),
                wgpu::Features::empty(),
            ),
        }
    }
}

/// Requests a device with the optional features the adapter has and all of its limits.
pub async fn request_device(adapter: &wgpu::Adapter) -> Result<(wgpu::Device, wgpu::Queue)> {
    request_device_with(adapter, LimitsPreset::Adapter).await
}

/// Requests a device with the limits and features of `preset` ([`device_descriptor`]).
pub async fn request_device_with(
    adapter: &wgpu::Adapter,
    preset: LimitsPreset,
) -> Result<(wgpu::Device, wgpu::Queue)> {
    adapter
        .request_device(&device_descriptor(adapter, preset))
        .await
        .map_err(Error::Device)
}

/// The device request [`request_device_with`] makes of `adapter`: `preset`'s limits and
/// the [`WANTED_FEATURES`] it has (none with [`LimitsPreset::WebGl2`]). A game that
/// requests its own device starts from it, adding its own features and limits, and wraps
/// the device with [`GpuContext::from_device`].
pub fn device_descriptor(
    adapter: &wgpu::Adapter,
    preset: LimitsPreset,
) -> wgpu::DeviceDescriptor<'static> {
    let (limits, features) = preset.request(adapter);
    wgpu::DeviceDescriptor {
        label: Some("voxel_render_device"),
        required_features: features,
        required_limits: limits,
        experimental_features: wgpu::ExperimentalFeatures::disabled(),
        memory_hints: wgpu::MemoryHints::Performance,
        trace: wgpu::Trace::Off,
    }
}

/// Parses a command-line name (what `name` gives); the error lists the known names.
impl std::str::FromStr for LimitsPreset {
    type Err = Error;

    fn from_str(name: &str) -> Result<Self> {
        crate::error::parse_name("limits preset", name, &Self::ALL, Self::name)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn desktop_gl_versions() {
        use wgpu::Backend::{Gl, Vulkan};
        // NVIDIA's EGL context, and Mesa's with MESA_GL_VERSION_OVERRIDE=3.3.
        assert_eq!(
            desktop_gl_version(Gl, "3.3.0 NVIDIA 550.54.15"),
            Some((3, 3))
        );
        assert_eq!(
            desktop_gl_version(Gl, "3.3 (Core Profile) Mesa 22.3.6"),
            Some((3, 3))
        );
        assert_eq!(
            desktop_gl_version(Gl, "4.5 (Core Profile) Mesa 22.3.6"),
            Some((4, 5))
        );
        // GLES and WebGL: wgpu offers storage and compute from GLES 3.1 only, where GLSL
        // ES 3.10 has them and naga writes the bindings.
        assert_eq!(desktop_gl_version(Gl, "OpenGL ES 3.2 Mesa 22.3.6"), None);
        assert_eq!(
            desktop_gl_version(Gl, "WebGL 2.0 (OpenGL ES 3.0 Chromium)"),
            None
        );
        assert_eq!(desktop_gl_version(Gl, ""), None);
        assert_eq!(desktop_gl_version(Vulkan, "3.3"), None);
    }

    #[test]
    fn gl_instances_go_without_indirect_validation() {
        let indirect = wgpu::InstanceFlags::VALIDATION_INDIRECT_CALL;
        assert!(!instance_flags(wgpu::Backends::GL).contains(indirect));
        assert!(!instance_flags(wgpu::Backends::all()).contains(indirect));
        assert_eq!(
            instance_descriptor(wgpu::Backends::VULKAN).flags,
            wgpu::InstanceFlags::from_env_or_default()
        );
        assert_eq!(
            instance_descriptor(wgpu::Backends::GL).backends,
            wgpu::Backends::GL
        );
    }
}
