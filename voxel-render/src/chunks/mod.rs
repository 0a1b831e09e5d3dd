//! Chunk meshes on the GPU: the quads of every mesh in one arena of large buffers
//! ([`crate::arena`]), one record per chunk (origin, fade-in alpha) in a storage array
//! indexed by the chunk's *slot*, frustum culling, and the draw lists of a frame: one
//! indirect draw command per visible mesh (`first_vertex` = its place in the page,
//! `first_instance` = its slot), issued with `multi_draw_indirect` per page, or one direct
//! draw per mesh where the adapter lacks indirect first-instance draws (logged).
//!
//! A frame finds its visible meshes in one pass ([`ChunkStore::cull`]): chunks are grouped
//! into regions of [`REGION_CHUNKS`] (Sodium's 8 × 4 × 8), whose box is tested first, so that
//! a region outside the frustum costs one test and one wholly inside costs none per chunk;
//! only the chunks of regions the frustum's planes cut are tested one by one. The result is
//! exactly what testing every chunk with [`Frustum::level_chunk_distance`] finds (a randomized
//! test).
//!
//! Each upload of a chunk gets a new *generation* number, so that what a technique derives
//! from a chunk's quads (a sort structure) can be cached by position and generation and
//! recomputed only when the chunk is remeshed. The planes of its translucent mesh
//! ([`crate::layers`]) are summed up at the upload and kept with the region's records, so
//! that the culling hands them over in its walk when asked to.

mod command;
mod cull;
mod draws;
pub(crate) mod gpu_chunk;
mod light;
pub(crate) mod store;
#[cfg(test)]
mod tests;

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

pub(crate) use cull::Culled;
pub(crate) use cull::Frustum;
pub(crate) use draws::{DrawBuilder, DrawList, FrameDraws};
pub(crate) use gpu_chunk::GpuChunk;
pub(crate) use gpu_chunk::Surfaces;
pub(crate) use store::ChunkStore;

/// A fast hasher for small keys of integers (chunk positions): a multiply-rotate per word
/// and a final mix, instead of SipHash (the store and the techniques look chunks up by
/// position every frame; nothing here needs resistance to chosen keys).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct PosHasher(u64);

impl PosHasher {
    const K: u64 = 0x9e37_79b9_7f4a_7c15;

    fn add(&mut self, word: u64) {
        self.0 = (self.0.rotate_left(26) ^ word).wrapping_mul(Self::K);
    }
}

impl Hasher for PosHasher {
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.add(u64::from(b));
        }
    }

    fn write_u32(&mut self, v: u32) {
        self.add(u64::from(v));
    }

    fn write_i32(&mut self, v: i32) {
        self.add(u64::from(v as u32));
    }

    fn write_u64(&mut self, v: u64) {
        self.add(v);
    }

    fn write_usize(&mut self, v: usize) {
        self.add(v as u64);
    }

    fn finish(&self) -> u64 {
        // The table takes its bucket from the low bits and its tag from the high ones: mix
        // both.
        let h = self.0 ^ (self.0 >> 32);
        let h = h.wrapping_mul(0xd6e8_feb8_6659_fd93);
        h ^ (h >> 29)
    }
}

/// A hash map keyed by chunk position (or another small integer key), with [`PosHasher`].
pub(crate) type PosMap<K, V> = HashMap<K, V, BuildHasherDefault<PosHasher>>;

/// Which of a chunk's three meshes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MeshKind {
    /// Drawn in the opaque pass.
    Opaque = 0,
    /// Drawn in the cutout (alpha-tested) pass.
    Cutout = 1,
    /// Drawn by the transparency technique.
    Translucent = 2,
}

/// How meshes are drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum DrawMode {
    /// One `multi_draw_indirect` per page and pass (the default where the adapter can).
    #[default]
    Indirect,
    /// One direct draw per mesh (the fallback, and the baseline of the measurements).
    PerChunk,
}

impl DrawMode {
    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            DrawMode::Indirect => "indirect",
            DrawMode::PerChunk => "per-chunk",
        }
    }
}
