//! wgpu renderer for voxel worlds with selectable order-independent transparency.
//!
//! - [`GpuContext`]: the game's device and queue, or a headless one.
//! - [`Renderer`]: chunks on the GPU and the passes of a frame; [`Camera`] to look with.
//! - [`oit`]: the transparency techniques behind [`OitManager`].
//! - [`Image`] and [`readback`]: pictures back to the CPU, PNG files.

mod camera;
mod chunks;
mod context;
mod gpu_types;
pub mod layers;
pub mod oit;
mod pipelines;
pub mod readback;
mod renderer;
pub mod textures;
mod timing;

pub use camera::Camera;
pub use chunks::{ChunkStore, Frustum, GpuChunk, GpuMesh, MeshKind, Visible};
pub use context::{Capabilities, GpuContext, WANTED_FEATURES, request_device};
pub use gpu_types::{ChunkUniforms, FrameUniforms};
pub use oit::{
    BayerSize, OitConfig, OitManager, Technique, TechniqueReport, TranslucentFrame,
    TranslucentTechnique, WeightFit, WeightFunction,
};
pub use pipelines::{SharedLayouts, target as render_target};
pub use readback::Image;
pub use renderer::{FrameStats, Renderer, RendererConfig};
pub use timing::GpuTimer;

/// Depth format of every pass: 32-bit float, reverse-Z (1 near, 0 far).
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// The HDR scene colour format (seed 003): opaque image, composites, before tonemapping.
pub const SCENE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// Everything that can go wrong in the renderer. Each variant says what was at fault.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// No adapter of the asked backends was found.
    #[error("no GPU adapter found for {0}")]
    NoAdapter(String),
    /// The adapter refused to create a device.
    #[error("could not create a device: {0}")]
    Device(String),
    /// A camera with NaN, infinite or contradictory values.
    #[error("invalid camera: {0}")]
    InvalidCamera(String),
    /// A technique or weight name that does not exist.
    #[error("unknown {0}")]
    UnknownName(String),
    /// The adapter cannot do something that has no fallback.
    #[error("unsupported by this adapter: {0}")]
    Unsupported(String),
    /// A file could not be read or written.
    #[error("i/o: {0}")]
    Io(String),
    /// A GPU operation failed (readback, validation).
    #[error("gpu: {0}")]
    Gpu(String),
}

/// `Result` with this crate's [`Error`] as the default error.
pub type Result<T, E = Error> = std::result::Result<T, E>;
