//! What a game relies on of the API's types, checked when the tests compile.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

fn send_sync<T: Send + Sync>() {}

/// The renderer can live in an engine's shared state (a Bevy `Resource` must be both),
/// and so can what a game keeps beside it.
#[test]
fn the_renderer_and_its_companions_are_send_and_sync() {
    send_sync::<voxel_render::Renderer>();
    send_sync::<voxel_render::GpuContext>();
    send_sync::<voxel_render::RendererConfig>();
    send_sync::<voxel_core::World>();
}
