//! Chunks keyed by chunk coordinates, block access by world coordinate, and the dirty set
//! that tells the mesher what to rebuild.
//!
//! Coordinates and faces are in `coords`, the 26 neighbours of a chunk in `neighbours`, ray
//! casts ([`World::raycast_by`], [`World::raycast`]) in `raycast`.

mod coords;
mod neighbours;
mod raycast;
#[cfg(test)]
mod tests;

use std::collections::{HashMap, HashSet};
use std::sync::Arc;

#[cfg(not(target_arch = "wasm32"))]
use rayon::prelude::*;

pub use coords::{ChunkPos, Face, WorldPos};
pub use neighbours::{Neighbourhood, touched_neighbours};
pub use raycast::{MAX_RAY_DISTANCE, RayHit, unit_direction};

use crate::{BlockId, BlockRegistry, CHUNK_SIZE, Chunk, Error, Result};

/// A sparse world of chunks over one block registry. Chunks are shared (`Arc`): cloning a
/// world, or handing a chunk to a meshing job ([`World::shared`]), copies no blocks; an
/// edit copies a chunk only while someone else still holds it.
#[derive(Debug, Clone)]
pub struct World {
    registry: Arc<BlockRegistry>,
    chunks: HashMap<ChunkPos, Arc<Chunk>>,
    dirty: HashSet<ChunkPos>,
}

impl World {
    /// An empty world. Missing chunks read as air.
    pub fn new(registry: Arc<BlockRegistry>) -> Self {
        Self {
            registry,
            chunks: HashMap::new(),
            dirty: HashSet::new(),
        }
    }

    /// The block registry every chunk's ids refer to.
    pub fn registry(&self) -> &Arc<BlockRegistry> {
        &self.registry
    }

    /// The translucent block type at `point` (world block units; the block containing
    /// it), or the medium a block there stands in ([`crate::BlockDef::medium`]), or `None`
    /// when neither, or the point is not finite or lies outside the `i32` world: what an
    /// eye at `point` is immersed in.
    pub fn medium_at(&self, point: [f64; 3]) -> Option<BlockId> {
        let inside =
            |v: f64| v.is_finite() && v >= f64::from(i32::MIN) && v < f64::from(i32::MAX) + 1.0;
        if !point.iter().all(|&v| inside(v)) {
            return None;
        }
        let id = self.get_block(WorldPos::containing(point));
        let def = self.registry.get(id).ok()?;
        // A block standing in a medium (waterlogged kelp) is in that medium.
        def.medium
            .or((def.class == crate::RenderClass::Translucent).then_some(id))
    }

    /// The block at `pos`; air where no chunk is loaded.
    pub fn get_block(&self, pos: WorldPos) -> BlockId {
        let (c, [x, y, z]) = pos.split();
        self.chunks
            .get(&c)
            .and_then(|chunk| chunk.get(x, y, z).ok())
            .unwrap_or(BlockId::AIR)
    }

    /// Sets the block at `pos` (creating an air chunk if needed) and returns the old one.
    /// Marks the chunk dirty, and each loaded neighbour whose border the block touches.
    pub fn set_block(&mut self, pos: WorldPos, id: BlockId) -> Result<BlockId> {
        if !self.registry.contains(id) {
            return Err(Error::UnknownBlock(id, self.registry.len()));
        }
        let (c, [x, y, z]) = pos.split();
        if id == BlockId::AIR && !self.chunks.contains_key(&c) {
            return Ok(BlockId::AIR);
        }
        let old = Arc::make_mut(self.chunks.entry(c).or_default()).set(x, y, z, id)?;
        if old != id {
            self.dirty.insert(c);
            for d in touched_neighbours([x, y, z]) {
                if let Some(n) = c.offset(d).filter(|n| self.chunks.contains_key(n)) {
                    self.dirty.insert(n);
                }
            }
        }
        Ok(old)
    }

    /// Sets every block of the box `min..=max` to `id`, a chunk at a time. Marks the
    /// touched chunks and their loaded neighbours dirty. Chunks are created only to hold a
    /// block that is not air.
    pub fn fill_box(&mut self, min: WorldPos, max: WorldPos, id: BlockId) -> Result<()> {
        if !self.registry.contains(id) {
            return Err(Error::UnknownBlock(id, self.registry.len()));
        }
        if min.x > max.x || min.y > max.y || min.z > max.z {
            return Ok(());
        }
        let (c0, _) = min.split();
        let (c1, _) = max.split();
        let last = CHUNK_SIZE as i64 - 1;
        for cx in c0.x..=c1.x {
            for cy in c0.y..=c1.y {
                for cz in c0.z..=c1.z {
                    let pos = ChunkPos::new(cx, cy, cz);
                    let o = pos.origin();
                    let lo = [min.x, min.y, min.z]
                        .iter()
                        .zip(o)
                        .map(|(&m, o)| (i64::from(m) - o).clamp(0, last) as usize)
                        .collect::<Vec<_>>();
                    let hi = [max.x, max.y, max.z]
                        .iter()
                        .zip(o)
                        .map(|(&m, o)| (i64::from(m) - o).clamp(0, last) as usize)
                        .collect::<Vec<_>>();
                    if id == BlockId::AIR && !self.chunks.contains_key(&pos) {
                        continue;
                    }
                    Arc::make_mut(self.chunks.entry(pos).or_default()).fill_box(
                        [lo[0], lo[1], lo[2]],
                        [hi[0], hi[1], hi[2]],
                        id,
                    )?;
                    self.mark_with_neighbours(pos);
                }
            }
        }
        Ok(())
    }

    /// Puts a whole chunk in place (returning the one it replaces) and marks it and its
    /// loaded neighbours dirty. Fails on a position outside the `i32` world or a block id the
    /// registry does not hold.
    pub fn insert_chunk(&mut self, pos: ChunkPos, chunk: Chunk) -> Result<Option<Chunk>> {
        if !pos.is_valid() {
            return Err(Error::ChunkOutOfRange(pos));
        }
        if let Some((id, _)) = chunk.palette().find(|(id, _)| !self.registry.contains(*id)) {
            return Err(Error::UnknownBlock(id, self.registry.len()));
        }
        self.mark_with_neighbours(pos);
        Ok(self
            .chunks
            .insert(pos, Arc::new(chunk))
            .map(Arc::unwrap_or_clone))
    }

    /// Unloads a chunk; it and its loaded neighbours become dirty (the mesher then returns
    /// empty meshes for it).
    pub fn remove_chunk(&mut self, pos: ChunkPos) -> Option<Chunk> {
        self.remove_shared(pos).map(Arc::unwrap_or_clone)
    }

    /// Marks `pos` and its loaded neighbours (all 26: ambient occlusion reads diagonal
    /// blocks) dirty.
    fn mark_with_neighbours(&mut self, pos: ChunkPos) {
        self.dirty.insert(pos);
        for d in Neighbourhood::OFFSETS {
            if let Some(n) = pos.offset(d).filter(|n| self.chunks.contains_key(n)) {
                self.dirty.insert(n);
            }
        }
    }

    /// The chunk at `pos`, if loaded.
    pub fn chunk(&self, pos: ChunkPos) -> Option<&Chunk> {
        self.chunks.get(&pos).map(|c| &**c)
    }

    /// The chunk at `pos` as a shared handle (for a job on another thread), if loaded.
    pub fn shared(&self, pos: ChunkPos) -> Option<Arc<Chunk>> {
        self.chunks.get(&pos).cloned()
    }

    /// Puts the shared `chunk` at `pos` (one another world holds too: no copy), as
    /// [`World::insert_chunk`] does, and returns the chunk it replaced, shared. Fails the
    /// same way.
    pub fn insert_shared(
        &mut self,
        pos: ChunkPos,
        chunk: Arc<Chunk>,
    ) -> Result<Option<Arc<Chunk>>> {
        if !pos.is_valid() {
            return Err(Error::ChunkOutOfRange(pos));
        }
        if let Some((id, _)) = chunk.palette().find(|(id, _)| !self.registry.contains(*id)) {
            return Err(Error::UnknownBlock(id, self.registry.len()));
        }
        self.mark_with_neighbours(pos);
        Ok(self.chunks.insert(pos, chunk))
    }

    /// Unloads a chunk as [`World::remove_chunk`] does, returning it shared (no copy where
    /// another world or a job holds it too).
    pub fn remove_shared(&mut self, pos: ChunkPos) -> Option<Arc<Chunk>> {
        let old = self.chunks.remove(&pos);
        if old.is_some() {
            self.mark_with_neighbours(pos);
        }
        old
    }

    /// Puts `chunk` at `pos` in place of `expected` (the same blocks in another form, say
    /// packed by a meshing job), if the chunk there is still exactly `expected`: an edit or
    /// a replacement since wins. Nothing becomes dirty. Returns whether it was replaced.
    pub fn replace_shared(&mut self, pos: ChunkPos, expected: &Arc<Chunk>, chunk: Chunk) -> bool {
        match self.chunks.get_mut(&pos) {
            Some(c) if Arc::ptr_eq(c, expected) => {
                *c = Arc::new(chunk);
                true
            }
            _ => false,
        }
    }

    /// Converts the chunk at `pos` to the compact packed form (see [`Chunk::pack`]), e.g.
    /// once a streamer has meshed it. Blocks do not change, so nothing becomes dirty.
    /// Returns whether a chunk is loaded there.
    pub fn pack_chunk(&mut self, pos: ChunkPos) -> bool {
        self.chunks
            .get_mut(&pos)
            .map(|c| Arc::make_mut(c).pack())
            .is_some()
    }

    /// Converts the chunk at `pos` to the mask form (see [`Chunk::unpack`]), e.g. for a chunk
    /// about to be edited and remeshed often. Returns whether a chunk is loaded there.
    pub fn unpack_chunk(&mut self, pos: ChunkPos) -> bool {
        self.chunks
            .get_mut(&pos)
            .map(|c| Arc::make_mut(c).unpack())
            .is_some()
    }

    /// Packs every loaded chunk, in parallel (one after another on wasm32).
    pub fn pack_all(&mut self) {
        #[cfg(not(target_arch = "wasm32"))]
        let chunks = self.chunks.par_iter_mut();
        #[cfg(target_arch = "wasm32")]
        let chunks = self.chunks.iter_mut();
        chunks.for_each(|(_, c)| Arc::make_mut(c).pack());
    }

    /// Heap and inline bytes of the loaded chunks ([`Chunk::memory_bytes`] summed; the map
    /// itself not counted).
    pub fn chunk_memory_bytes(&self) -> usize {
        self.chunks.values().map(|c| c.memory_bytes()).sum()
    }

    /// What the loaded chunks would take as packed-index palettes
    /// ([`Chunk::packed_index_bytes`] summed): the baseline of [`World::chunk_memory_bytes`].
    pub fn packed_index_bytes(&self) -> usize {
        self.chunks.values().map(|c| c.packed_index_bytes()).sum()
    }

    /// The 26 chunks around `pos` (what the mesher needs); `None` where not loaded.
    pub fn neighbourhood(&self, pos: ChunkPos) -> Neighbourhood<'_> {
        Neighbourhood::from_fn(|d| pos.offset(d).and_then(|n| self.chunk(n)))
    }

    /// All loaded chunks, in no particular order.
    pub fn iter(&self) -> impl Iterator<Item = (ChunkPos, &Chunk)> {
        self.chunks.iter().map(|(p, c)| (*p, &**c))
    }

    /// Number of loaded chunks.
    pub fn len(&self) -> usize {
        self.chunks.len()
    }

    /// The smallest and largest coordinates, per axis, of the loaded chunks; `None` for a
    /// world with no chunk.
    pub fn chunk_bounds(&self) -> Option<(ChunkPos, ChunkPos)> {
        let mut it = self.chunks.keys();
        let first = *it.next()?;
        Some(it.fold((first, first), |(lo, hi), p| {
            (
                ChunkPos::new(lo.x.min(p.x), lo.y.min(p.y), lo.z.min(p.z)),
                ChunkPos::new(hi.x.max(p.x), hi.y.max(p.y), hi.z.max(p.z)),
            )
        }))
    }

    /// Whether no chunk is loaded.
    pub fn is_empty(&self) -> bool {
        self.chunks.is_empty()
    }

    /// Chunks waiting to be remeshed.
    pub fn dirty(&self) -> &HashSet<ChunkPos> {
        &self.dirty
    }

    /// Marks a chunk for remeshing.
    pub fn mark_dirty(&mut self, pos: ChunkPos) {
        self.dirty.insert(pos);
    }

    /// Empties the dirty set and returns it, sorted so that work is reproducible.
    pub fn take_dirty(&mut self) -> Vec<ChunkPos> {
        let mut v: Vec<_> = self.dirty.drain().collect();
        v.sort_unstable();
        v
    }
}
