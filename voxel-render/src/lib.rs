//! wgpu renderer for voxel worlds with selectable order-independent transparency.
//!
//! What a game needs is at the root:
//!
//! - [`GpuContext`]: the game's device and queue, or a headless one; [`Capabilities`] and
//!   [`LimitsPreset`] say what it can do; [`WANTED_FEATURES`] and [`device_descriptor`]
//!   for a game that requests its device itself.
//! - [`Renderer`] with its [`RendererConfig`] and [`Lighting`]: chunks on the GPU and the
//!   passes of a frame ([`Renderer::render`]); [`Camera`] to look with.
//! - [`Technique`] and its settings in [`OitConfig`]: how translucent water, glass and
//!   leaves are composed, switchable at run time.
//! - [`far::FarField`]: generated terrain to a far view distance in levels of detail
//!   around a moving eye, built coarse first off the frame.
//! - [`ChunkStreamer`]: the chunks around a moving eye, generated, meshed and uploaded on
//!   rayon's workers (on wasm32, where a browser page has one thread, on the page's
//!   thread within a time budget per update).
//! - [`stages`]: the game's own geometry in the frame ([`GameStages`]), composed by every
//!   technique, and the helpers its pipelines and overlays are built with; [`Both`] draws
//!   two games' stages (the ready-made content and the game's own) as one.
//! - [`content`]: a game's particles and boxes, opaque or translucent, drawn through the
//!   frame's stages by every technique without WGSL of its own, lit by the light field
//!   where the renderer has a light volume ([`Renderer::set_light_volume`]; a game's own
//!   shaders read it through [`light_wgsl`]).
//! - [`Image`] and [`readback`]: pictures back to the CPU, PNG files; [`textures`]: a
//!   game's block textures.
//!
//! [`low_level`] holds what the lab, the benchmarks and the tests reach into (the chunk
//! store, the transparency manager, each technique's internals and the limits inputs are
//! checked against); a game does not need it.
//!
//! Modules depend on each other one way, from the bottom: `error`, `context`, `ladder`
//! (what each pass needs of a device), `camera`, `readback`, `submission`, `timing`,
//! `cost` (what a frame asks of the GPU, counted), `fetch` (how quads reach the vertex shader),
//! `sun` (the sun shadows' volume) → `gpu` (pass and pipeline plumbing) → `light_volume`
//! (the light field around the eye for a game's shaders) → `bindings` (what every chunk pipeline binds), `textures`, `arena` (the quad arena),
//! `layers` (translucent planes) → `chunks` → `medium` (translucent volumes seen from
//! inside) → `stages` (what a game draws in a frame) → `oit` (techniques) → `renderer` →
//! `content` (ready-made game content) → `stream` (chunks loaded around a moving eye) →
//! `far` (levels of detail around a moving eye) → `low_level`. A test
//! (`tests/tests/architecture.rs`) checks that no `crate::` path points back up.

#![warn(missing_docs)]
#![warn(unreachable_pub)]

mod arena;
mod bindings;
mod camera;
mod chunks;
pub mod content;
mod context;
mod cost;
mod error;
pub mod far;
mod fetch;
mod gpu;
mod ladder;
mod layers;
mod light_volume;
pub mod low_level;
mod medium;
mod oit;
pub mod readback;
mod renderer;
pub mod stages;
mod stream;
mod submission;
mod sun;
pub mod textures;
mod timing;
#[cfg(test)]
mod wgsl_layout;

pub use camera::Camera;
pub use chunks::DrawMode;
pub use context::{
    Capabilities, GpuContext, LimitsPreset, WANTED_FEATURES, device_descriptor,
    instance_descriptor, instance_flags, request_device, request_device_with,
};
pub use error::{Error, Result};
pub use fetch::QuadFetch;
pub use light_volume::{ChunkLight, MAX_LIGHT_CHUNKS, light_wgsl};
pub use oit::{
    OitConfig, Technique, moments::MboitSettings, peeling::PeelingSettings,
    stipple::StippleSettings, stipple::bayer::BayerSize, wboit::WboitSettings,
    wboit::weights::WeightFunction,
};
pub use readback::Image;
pub use renderer::{
    FrameStats, Renderer, config::Lighting, config::OUTPUT_FORMATS, config::RendererConfig,
    level_key,
};
pub use stages::{
    Both, GameFrame, GameStages, NoGame, Stages, TranslucentContract, TranslucentObject,
};
pub use stream::{
    ChunkStreamer, config::StreamConfig, schedule::StreamFrame, source::ChunkSink,
    source::ChunkSource, sun_feed::SunFeed,
};
pub use sun::{MAX_SUN_CHUNKS, SunRegion};
pub use timing::{GpuPass, GpuTimes};

/// Depth format of every pass: 32-bit float, reverse-Z (1 near, 0 far).
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// The HDR scene colour format: opaque image, composites, before tonemapping.
pub const SCENE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
