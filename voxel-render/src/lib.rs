//! wgpu renderer for voxel worlds with selectable order-independent transparency.
//!
//! - [`GpuContext`]: the game's device and queue, or a headless one.
//! - [`Renderer`]: chunks on the GPU and the passes of a frame; [`Camera`] to look with.
//! - [`oit`]: the transparency techniques behind [`OitManager`], one folder each.
//! - [`Image`] and [`readback`]: pictures back to the CPU, PNG files.
//! - [`ChunkStreamer`]: the chunks around a moving eye, generated, meshed and uploaded on
//!   rayon's workers.
//! - [`content`]: a game's particles and boxes, opaque or translucent, drawn through the
//!   frame's [`stages`] by every technique without WGSL of its own.
//!
//! Modules depend on each other one way, from the bottom: `error`, `context`, `ladder`
//! (what each pass needs of a device), `camera`, `readback`, `submission`, `timing`, `fetch`
//! (how quads reach the vertex shader) → `gpu` (pass and pipeline plumbing) → `bindings` (what every chunk
//! pipeline binds), `textures`, `arena` (the quad arena), `layers` (translucent planes) → `chunks` → `medium` (translucent volumes seen from
//! inside) → `stages` (what a game draws in a frame) → `oit` (techniques) → `renderer` → `content` (ready-made game content) → `stream` (chunks loaded around a moving eye). A test
//! (`tests/tests/architecture.rs`) checks that no `crate::` path points back up.

pub mod arena;
mod bindings;
mod camera;
mod chunks;
pub mod content;
mod context;
mod error;
mod fetch;
pub mod gpu;
pub mod ladder;
pub mod layers;
pub mod medium;
pub mod oit;
pub mod readback;
mod renderer;
pub mod stages;
pub mod stream;
mod submission;
pub mod textures;
mod timing;
#[cfg(test)]
mod wgsl_layout;

pub use bindings::{ChunkUniforms, FrameUniforms, SharedLayouts};
pub use camera::{Camera, MAX_FAR, MAX_FOV_DEG, MIN_FOV_DEG, MIN_NEAR, WORLD_EXTENT};
pub use chunks::{
    ChunkStore, Culled, DrawCommand, DrawList, DrawMode, FrameDraws, Frustum, GpuChunk, MeshKind,
    REGION_CHUNKS,
};
pub use context::{
    Capabilities, GpuContext, LimitsPreset, WANTED_FEATURES, request_device, request_device_with,
};
pub use error::{Error, Result};
pub use fetch::QuadFetch;
pub use ladder::{Limit, Need};
pub use oit::{
    BayerSize, MboitReport, MboitSettings, OitConfig, OitManager, PeelReport, PeelingSettings,
    ReferenceReport, ShadingState, SortReport, StippleSettings, Technique, TechniqueReport,
    TranslucentFrame, TranslucentTechnique, WboitReport, WboitSettings, WeightFit, WeightFunction,
};
pub use readback::Image;
pub use renderer::{ChunkMemory, FrameStats, Lighting, OUTPUT_FORMATS, Renderer, RendererConfig};
pub use stages::{
    DEPTH_COMPARE, GameFrame, GameStages, NoGame, OIT_GROUP, Stages, TranslucentContract,
    TranslucentObject, TranslucentVariant,
};
pub use stream::{
    ChunkSink, ChunkSource, ChunkStreamer, MAX_VIEW_DISTANCE, StreamConfig, StreamFrame,
};
pub use timing::{GpuPass, GpuTimes, Timer};

/// Depth format of every pass: 32-bit float, reverse-Z (1 near, 0 far).
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// The HDR scene colour format: opaque image, composites, before tonemapping.
pub const SCENE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
pub use bindings::{AO_DEPTH, OPAQUE_EXPANSION_PX, TONEMAP_SHOULDER};
