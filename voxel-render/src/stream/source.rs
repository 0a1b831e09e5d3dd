//! Where chunks come from ([`ChunkSource`]) and where their meshes go ([`ChunkSink`]), and
//! a source's blocks checked on the way in.

use std::collections::BTreeMap;
use std::panic::AssertUnwindSafe;

use voxel_core::{BlockId, BlockRegistry, Chunk, ChunkPos, TerrainGenerator, World};
use voxel_mesh::ChunkMeshes;

use super::local::local_of;
use crate::{Renderer, Result};

/// Where chunks come from. Called on rayon's workers, any number at once.
pub trait ChunkSource: Send + Sync + 'static {
    /// The blocks of the chunk at `pos` (a valid position). Every id must be in the
    /// registry the streamer was made with. A chunk whose generation panics or holds an
    /// unknown id is reported by the update ([`StreamFrame::failed`]) or by
    /// [`ChunkStreamer::set_block`] ([`Error::ChunkSource`]), and counts as air.
    ///
    /// [`StreamFrame::failed`]: super::StreamFrame::failed
    /// [`ChunkStreamer::set_block`]: super::ChunkStreamer::set_block
    /// [`Error::ChunkSource`]: crate::Error::ChunkSource
    fn generate(&self, pos: ChunkPos) -> Chunk;

    /// Whether its blocks are the registry's: checked by [`ChunkStreamer::new`] (default:
    /// nothing to check; a wrong id is then found per chunk).
    ///
    /// [`ChunkStreamer::new`]: super::ChunkStreamer::new
    fn check(&self, _registry: &BlockRegistry) -> Result<()> {
        Ok(())
    }
}

impl ChunkSource for TerrainGenerator {
    fn generate(&self, pos: ChunkPos) -> Chunk {
        self.generate_chunk(pos)
    }

    /// A generator made for another registry (its roles' ids name other blocks here) is
    /// refused, naming each role ([`TerrainGenerator::check`]).
    fn check(&self, registry: &BlockRegistry) -> Result<()> {
        Ok(TerrainGenerator::check(self, registry)?)
    }
}

/// A fixed world as a source: its chunks, air elsewhere (a loaded scene, tests).
impl ChunkSource for World {
    fn generate(&self, pos: ChunkPos) -> Chunk {
        self.chunk(pos).cloned().unwrap_or_default()
    }
}

/// Where meshes go: the renderer, or the renderer and a second one beside it.
pub trait ChunkSink {
    /// Uploads (or replaces) the meshes of the chunk at `pos`.
    fn upload(&mut self, pos: ChunkPos, meshes: &ChunkMeshes) -> Result<()>;
    /// Drops the chunk at `pos`.
    fn remove(&mut self, pos: ChunkPos);
}

impl ChunkSink for Renderer {
    fn upload(&mut self, pos: ChunkPos, meshes: &ChunkMeshes) -> Result<()> {
        self.upload_chunk(pos, meshes)
    }

    fn remove(&mut self, pos: ChunkPos) {
        self.remove_chunk(pos);
    }
}

/// Calls the source for `pos`, catching a panic, and checks its block ids: the chunk, or
/// why it failed. Then applies `edits` (ids the registry holds: checked when made).
pub(super) fn generate_checked(
    source: &dyn ChunkSource,
    registry: &BlockRegistry,
    pos: ChunkPos,
    edits: Option<&BTreeMap<u16, BlockId>>,
) -> std::result::Result<Chunk, String> {
    let mut chunk = std::panic::catch_unwind(AssertUnwindSafe(|| source.generate(pos)))
        .map_err(|_| "the chunk source panicked".to_owned())?;
    if let Some(id) = chunk
        .palette()
        .map(|(id, _)| id)
        .find(|id| !registry.contains(*id))
    {
        return Err(format!(
            "the chunk source made block id {}, unknown to the registry of {} blocks",
            id.0,
            registry.len()
        ));
    }
    for (&index, &id) in edits.into_iter().flatten() {
        let [x, y, z] = local_of(index);
        chunk.set(x, y, z, id).map_err(|e| e.to_string())?;
    }
    Ok(chunk)
}
