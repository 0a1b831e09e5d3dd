//! What the lab, the benchmarks and the tests reach into, and a game does not need: the
//! chunk store and its draw lists, the transparency manager and its technique trait, the
//! frame uniforms' layout, the pass plumbing, each technique's internals and the limits
//! the renderer checks inputs against. Nothing here is needed to embed the renderer (the
//! crate root and [`crate::stages`] are); it changes more freely than the root.

pub use crate::arena::QUAD_BYTES;
pub use crate::bindings::{AO_DEPTH, OPAQUE_EXPANSION_PX, TONEMAP_SHOULDER};
pub use crate::camera::{MAX_FAR, MAX_FOV_DEG, MIN_FOV_DEG, MIN_NEAR, WORLD_EXTENT};
pub use crate::chunks::{MeshKind, gpu_chunk::GpuChunk, store::ChunkStore};
pub use crate::cost::{CostTotals, FrameCost, PassCost};
pub use crate::gpu::pipelines_built;
pub use crate::ladder::{Limit, Need, check};
pub use crate::oit::moments::single_precision;
pub use crate::oit::peeling::MAX_PEEL_LAYERS;
pub use crate::oit::stipple::bayer::bayer;
pub use crate::oit::wboit::{HEADROOM_SCALE, REVEALAGE_FORMAT, RGBA8_SCALE};
pub use crate::oit::{
    OitManager, TechniqueReport, moments::MboitReport, peeling::PeelReport,
    reference::ReferenceReport, sorted::SortReport, wboit::WboitReport, wboit::fit::WeightFit,
};
pub use crate::renderer::ChunkMemory;
pub use crate::stream::{config::MAX_VIEW_DISTANCE, edits::EDIT_BYTES, edits::EDITED_CHUNK_BYTES};
pub use crate::sun::SUN_NUDGE;

/// The chunks `renderer` holds on the GPU (the store's meshes, their places in the arena and
/// their generations).
pub fn chunks(renderer: &crate::Renderer) -> &ChunkStore {
    renderer.chunks()
}

/// Counts what the next frame of `renderer` asks of the GPU (`crate::cost`): per pass
/// its draw calls, pipeline and bind-group changes, full-screen draws and clears, and,
/// where the device has occlusion and pipeline-statistics queries and the technique does
/// not submit inside its frame, the fragments it shades and the samples it writes (from
/// which the bytes of targets written and read follow). Read it with [`frame_cost`] once
/// the frame is submitted. Frames not counted pay one thread-local look-up per command.
pub fn count_next_frame(renderer: &mut crate::Renderer) {
    renderer.count_next_frame();
}

/// What the last frame counted with [`count_next_frame`] asked of the GPU, once its
/// encoder is submitted (waits for its query results); `None` when no frame was counted
/// since the last call.
pub fn frame_cost(renderer: &mut crate::Renderer) -> crate::Result<Option<FrameCost>> {
    renderer.frame_cost()
}

/// The transparency manager of `renderer`: the technique's configuration, how many times
/// techniques were built, and WBOIT's accumulation target.
pub fn oit(renderer: &crate::Renderer) -> &OitManager {
    renderer.oit()
}
