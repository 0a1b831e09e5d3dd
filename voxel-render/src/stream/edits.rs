//! Edits of the blocks ([`ChunkStreamer::set_block`]): kept as a sparse list per chunk,
//! applied when a chunk is generated again, listed for a game to save, and the chunks they
//! touch meshed again before anything new.

use std::collections::BTreeMap;
use std::sync::Arc;

use voxel_core::{BlockId, Chunk, ChunkPos, WorldPos};

use super::ChunkStreamer;
use super::light::LightOp;
use super::local::{local_index, local_of};
use super::slot::State;
use super::source::generate_checked;
use crate::{Error, Result};

/// Bytes counted per edited block ([`ChunkStreamer::memory_bytes`]), an upper bound: a
/// 4-byte entry (index, block id) in a B-tree leaf of 11 entries that is at least half
/// full (56 bytes for 5 entries), plus its share of the inner nodes. Measured by a
/// counting allocator (`tests/tests/stream_memory.rs`): 10.6 bytes per edit when whole
/// chunks are edited.
pub const EDIT_BYTES: usize = 20;
/// Bytes counted per edited chunk, an upper bound: its hash table slot (25 bytes at a load
/// of 7/16 to 7/8), the shared map (40) and its first leaf (56). Measured: 138 bytes per
/// chunk with one edit, over 10 000 chunks.
pub const EDITED_CHUNK_BYTES: usize = 160;

/// The edits of one chunk: in-chunk index (`local_index`) → block.
pub(super) type ChunkEdits = Arc<BTreeMap<u16, BlockId>>;

impl ChunkStreamer {
    /// Bytes counted for the edits kept (see [`ChunkStreamer::memory_bytes`]).
    pub fn edit_bytes(&self) -> usize {
        self.edits
            .values()
            .map(|e| EDITED_CHUNK_BYTES + EDIT_BYTES * e.len())
            .sum()
    }

    /// Every edit kept, per chunk: `(position in the world, block)` for each block set
    /// through [`ChunkStreamer::set_block`] (the last value set), for a game to save.
    pub fn edits(&self) -> impl Iterator<Item = (WorldPos, BlockId)> + '_ {
        self.edits.iter().flat_map(|(pos, e)| {
            let o = pos.origin();
            e.iter().map(move |(&i, &id)| {
                let [x, y, z] = local_of(i);
                let at = |k: usize, v: usize| (o[k] + v as i64) as i32;
                (WorldPos::new(at(0, x), at(1, y), at(2, z)), id)
            })
        })
    }

    /// Restores saved edits ([`ChunkStreamer::edits`] of an earlier run, in any order):
    /// each chunk not loaded keeps them to apply when it loads (no chunk is generated
    /// here, unlike [`ChunkStreamer::set_block`]); a loaded one is edited now. Fails on
    /// the first block id the registry does not hold, having restored none of them.
    pub fn restore_edits(
        &mut self,
        edits: impl IntoIterator<Item = (WorldPos, BlockId)>,
    ) -> Result<()> {
        let edits: Vec<(WorldPos, BlockId)> = edits.into_iter().collect();
        if let Some(&(_, id)) = edits.iter().find(|(_, id)| !self.registry.contains(*id)) {
            return Err(voxel_core::Error::UnknownBlock(id, self.registry.len()).into());
        }
        for (pos, id) in edits {
            if self.slots.contains_key(&pos.split().0) {
                self.set_block(pos, id)?;
            } else {
                self.record_edit(pos, id);
            }
        }
        Ok(())
    }

    /// The blocks of the chunk at `pos` generated here, on the calling thread, with its
    /// edits: for an edit of a chunk whose generation is in flight.
    fn generate_here(&self, pos: ChunkPos) -> Result<Chunk> {
        generate_checked(
            &*self.source,
            &self.registry,
            pos,
            self.edits.get(&pos).map(|e| &**e),
        )
        .map_err(|why| Error::ChunkSource { pos, why })
    }

    /// The source's block at `local` of the chunk at `pos` (not loaded), its ids checked;
    /// the chunk is kept for the next edit of the same chunk.
    fn source_block(&mut self, pos: ChunkPos, [x, y, z]: [usize; 3]) -> Result<BlockId> {
        let chunk = match &self.last_source {
            Some((p, c)) if *p == pos => c.clone(),
            _ => {
                let c = generate_checked(&*self.source, &self.registry, pos, None)
                    .map_err(|why| Error::ChunkSource { pos, why })?;
                let c = Arc::new(c);
                self.last_source = Some((pos, c.clone()));
                c
            }
        };
        Ok(chunk.get(x, y, z)?)
    }

    /// Records an edit in the chunk's edit list.
    fn record_edit(&mut self, pos: WorldPos, id: BlockId) {
        let (c, local) = pos.split();
        Arc::make_mut(self.edits.entry(c).or_default()).insert(local_index(local), id);
    }

    /// Sets the block at `pos` and returns the old one. The chunks whose meshes it touches
    /// are meshed again before any new chunk. The edit is kept (see the module docs): a
    /// chunk not loaded is generated here to read the old block (one chunk's work on this
    /// thread), and comes back edited when it loads. Fails, changing nothing, on a block
    /// id the registry does not hold, and with [`Error::ChunkSource`] where the source
    /// fails for the chunk (it panicked or made unknown ids): the panic is caught here.
    pub fn set_block(&mut self, pos: WorldPos, id: BlockId) -> Result<BlockId> {
        if !self.registry.contains(id) {
            return Err(voxel_core::Error::UnknownBlock(id, self.registry.len()).into());
        }
        let (c, [x, y, z]) = pos.split();
        match self.slots.get(&c).map(|s| (s.state, s.failed)) {
            None => {
                // Not loaded: no drawn chunk's mesh depends on it (see `may_leave`).
                let old = match self
                    .edits
                    .get(&c)
                    .and_then(|e| e.get(&local_index([x, y, z])))
                {
                    Some(&old) => old,
                    None => self.source_block(c, [x, y, z])?,
                };
                self.record_edit(pos, id);
                return Ok(old);
            }
            Some((_, true)) => {
                return Err(Error::ChunkSource {
                    pos: c,
                    why: "the chunk source failed for it when it loaded (it stands as air)".into(),
                });
            }
            Some((State::Generating, false)) => {
                // Its job's result will not count: generate it here.
                let chunk = self.generate_here(c)?;
                let version = self.next_version();
                if let Some(slot) = self.slots.get_mut(&c) {
                    slot.version = version;
                    slot.state = State::Generated;
                }
                if chunk.as_uniform() != Some(BlockId::AIR) {
                    self.world.insert_chunk(c, chunk)?;
                }
                if let Some(light) = &mut self.light {
                    light.insert(c, self.world.shared(c));
                }
            }
            Some(_) => {}
        }
        self.world.take_dirty();
        let old = self.world.set_block(pos, id)?;
        self.record_edit(pos, id);
        if let Some(light) = &mut self.light {
            light.push(LightOp::Set(pos, id));
        }
        for d in self.world.take_dirty() {
            self.stale(d);
        }
        Ok(old)
    }
}
