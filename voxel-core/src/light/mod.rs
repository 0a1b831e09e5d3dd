//! Light fields: RGB sky light and RGB block light for every block of the lit chunks,
//! flooded through air and translucent blocks, filtered by the translucent blocks they
//! cross with the same colour, opacity and absorption that tint the view through them.
//!
//! **Levels.** Each block holds six levels from 0 to 255, linear: sky red, green, blue
//! and block red, green, blue ([`Light`]). 255 is the open sky's full light (day and night
//! scale it where it is drawn) or the brightest emitter.
//!
//! **Sources.** The sky: a beam straight down each column from above the highest lit chunk,
//! at full strength, without falloff, multiplied by the filter of each block it enters and
//! stopped by opaque and cutout blocks (leaves cast shade). The beam is carried exactly
//! (`f32`) and rounded per block, so deep water darkens its floor by exactly the product of
//! its blocks' filters. Blocks with an [`crate::BlockDef::emission`]: their own cell holds
//! it (an opaque emitter too; light never enters an opaque block otherwise).
//!
//! **Flood.** From a cell of level `v` into a face neighbour that is not opaque:
//! `round(v · f) − LIGHT_FALLOFF` (not below 0), per channel, where `f` is the
//! neighbour's filter: 1 for air and cutout blocks in air; for a translucent block of linear
//! colour `c`, opacity `a`, absorption `s`, one block of its volume `e^−s + (1 − e^−s)·c`,
//! times its surface `(1 − a) + a·c` when the light comes from a cell of another type (a
//! cutout block standing in a medium counts as that medium). A block's level is the
//! largest over its sources and neighbours: the least fixed point, the same whatever
//! order it is computed in. The surface factor is what the view through a surface shows
//! of a white thing behind it with both lit alike (the over blend of the block's colour
//! at its opacity); the volume factor the same for a path of one block (the renderer's
//! `exp(−s d)` and the block's colour for the rest), so stacked blocks multiply. Red
//! glass lets through (0.82, 0.51, 0.51), a water surface (0.31, 0.40, 0.56) and each
//! block of water under it (0.93, 0.94, 0.95). Like the view through a translucent
//! block, light crossing several blocks of one type crosses one surface.
//!
//! **Falloff and width.** A byte a channel, falling [`LIGHT_FALLOFF`] = 16 a block: 255
//! reaches 15 blocks, Minecraft's and Luanti's reach, where Cubyz falls 8 a block and
//! reaches 31. 8-bit channels keep the tint of a filter (4 bits would round red glass's
//! 0.51 to a level of the sixteen); the short reach keeps the cells an edit touches (the
//! volume within reach grows with its cube) inside the millisecond budget.
//!
//! **Chunks.** Light lives in the chunks the field lights (all of a world's at
//! [`LightField::new`], then [`LightField::add_chunk`] and [`LightField::remove_chunk`] as
//! chunks stream); it crosses borders between lit chunks. A chunk that is not lit holds
//! no light and passes none sideways (dark, unknown); the sky's beam passes down through
//! a gap of unlit chunks as through air (a missing chunk reads as air), and enters at full
//! strength above the highest lit chunk of a column.
//!
//! **Storage** ([`LightChunk`]): 6 bytes a block, a layer (32 × 32 blocks of one y) at a
//! time: a layer whose blocks all hold the same levels (open sky above the ground, dark
//! rock below) takes 6 bytes. Plus the beam entering each column of a chunk (12 bytes a
//! column where the columns differ).
//!
//! **Edits** ([`LightField::set_block`], [`crate::World::set_block_lit`]): the cell
//! edited and every cell whose beam changed are cleared, with every cell whose level may
//! have come through them; the cleared cells are refilled from their sources and from
//! the levels around them. Only cells within reach of the change are visited.

mod build;
mod edit;
mod engine;
mod props;
mod store;
mod sun;
#[cfg(test)]
mod tests;

use std::collections::{BTreeSet, HashMap, HashSet};
use std::sync::Arc;

pub use store::{Light, LightChunk, LightLayer, OddCells};
pub use sun::{SunCell, SunFilters, SunMarch};

use crate::{BlockDef, BlockId, BlockRegistry, ChunkPos, Error, Result, World, WorldPos};
use engine::Entry;
use props::Props;

/// What light loses per block it travels (of 255).
pub const LIGHT_FALLOFF: u8 = 16;

/// Ids of the light sources [`BlockRegistry::with_lights`] adds after the blocks of
/// [`BlockRegistry::default`].
pub mod light_blocks {
    use crate::BlockId;
    /// A torch: opaque, warm light (255, 170, 90).
    pub const TORCH: BlockId = BlockId(13);
    /// Lava: opaque, orange light (255, 110, 30).
    pub const LAVA: BlockId = BlockId(14);
    /// Glowing glass: translucent (opacity 0.4), pale yellow light (200, 190, 120).
    pub const GLOW_GLASS: BlockId = BlockId(15);
}

impl BlockRegistry {
    /// The blocks of [`BlockRegistry::default`], then three light sources with the ids of
    /// [`light_blocks`]: a torch, lava and glowing glass.
    pub fn with_lights() -> Self {
        let mut r = Self::default();
        for def in [
            BlockDef::new("torch", [250, 200, 120], 1.0).emitting([255, 170, 90]),
            BlockDef::new("lava", [230, 90, 20], 1.0).emitting([255, 110, 30]),
            BlockDef::new("glow_glass", [250, 235, 160], 0.4)
                .with_pattern(crate::Pattern::Framed)
                .emitting([200, 190, 120]),
        ] {
            // Valid by construction; the light tests check the ids.
            let _ = r.register(def);
        }
        r
    }
}

/// The light of a world's lit chunks (see the module docs). Built for one world's
/// registry; every edit of a lit chunk must go through it ([`LightField::set_block`]) or
/// be followed by [`LightField::add_chunk`] for that chunk, else its light is stale.
#[derive(Clone, Debug)]
pub struct LightField {
    registry: Arc<BlockRegistry>,
    props: Vec<Props>,
    entries: Vec<Entry>,
    index: HashMap<ChunkPos, u32>,
    /// Lit chunk heights by chunk column `(x, z)`.
    columns: HashMap<[i32; 2], BTreeSet<i32>>,
    /// Queues the updates reuse.
    scratch: engine::Scratch,
    /// Chunks whose light changed since [`LightField::take_changed`].
    changed: HashSet<ChunkPos>,
}

impl LightField {
    /// An empty field for worlds over `registry`: nothing is lit.
    pub fn empty(registry: Arc<BlockRegistry>) -> Self {
        Self {
            props: props::table(&registry),
            registry,
            entries: Vec::new(),
            index: HashMap::new(),
            columns: HashMap::new(),
            scratch: engine::Scratch::default(),
            changed: HashSet::new(),
        }
    }

    /// Lights every loaded chunk of `world` from scratch.
    pub fn new(world: &World) -> Self {
        let mut field = Self::empty(world.registry().clone());
        field.light_all(world);
        field
    }

    /// The light at `pos`; `None` where its chunk is not lit.
    pub fn get(&self, pos: WorldPos) -> Option<Light> {
        let (c, [x, y, z]) = pos.split();
        self.chunk(c).and_then(|l| l.get(x, y, z))
    }

    /// The light of the chunk at `pos`, if lit.
    pub fn chunk(&self, pos: ChunkPos) -> Option<&LightChunk> {
        self.index
            .get(&pos)
            .map(|&i| &*self.entries[i as usize].light)
    }

    /// The light of the chunk at `pos`, if lit, as a snapshot: it stays as it is now while
    /// the field goes on (the field copies the chunk on its next write to it). What a
    /// mesher on another thread reads ([`crate::LightChunk`] is `Send + Sync`).
    pub fn shared(&self, pos: ChunkPos) -> Option<Arc<LightChunk>> {
        self.index
            .get(&pos)
            .map(|&i| self.entries[i as usize].light.clone())
    }

    /// Whether the chunk at `pos` is lit.
    pub fn is_lit(&self, pos: ChunkPos) -> bool {
        self.index.contains_key(&pos)
    }

    /// Number of lit chunks.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether no chunk is lit.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Bytes of the lit chunks' light and beams.
    pub fn memory_bytes(&self) -> usize {
        self.entries
            .iter()
            .map(|e| {
                e.light.memory_bytes() + e.beam_in.memory_bytes() + std::mem::size_of::<Entry>()
            })
            .sum()
    }

    /// The lit chunks whose light changed since the last call (every chunk lit by
    /// [`LightField::new`] or [`LightField::add_chunk`], every chunk where an edit or a
    /// chunk unlit wrote a level, if only to clear and refill it), sorted: what a lit mesh must be rebuilt for (with the
    /// neighbours whose border vertices read them).
    pub fn take_changed(&mut self) -> Vec<ChunkPos> {
        let mut v: Vec<_> = self.changed.drain().collect();
        v.sort_unstable();
        v
    }

    /// Turns layers whose blocks all hold the same light back into 6 bytes (edits leave
    /// the layers they touch in the 6 KiB form, as cheap to edit again).
    pub fn compact(&mut self) {
        for e in &mut self.entries {
            e.compact();
        }
    }

    /// [`LightField::compact`] for the chunk at `pos` only.
    pub fn compact_chunk(&mut self, pos: ChunkPos) {
        if let Some(&i) = self.index.get(&pos) {
            self.entries[i as usize].compact();
        }
    }

    /// Fails when `world` is not over the registry this field was built for.
    fn check(&self, world: &World) -> Result<()> {
        let r = world.registry();
        if Arc::ptr_eq(r, &self.registry) || **r == *self.registry {
            Ok(())
        } else {
            Err(Error::LightRegistry)
        }
    }
}

impl World {
    /// Sets the block at `pos` as [`World::set_block`] does and updates `light` for the
    /// change ([`LightField::set_block`]).
    pub fn set_block_lit(
        &mut self,
        light: &mut LightField,
        pos: WorldPos,
        id: BlockId,
    ) -> Result<BlockId> {
        light.set_block(self, pos, id)
    }
}
