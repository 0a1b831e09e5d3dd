//! Incremental updates: an edited block, a chunk lit as it streams in, a chunk unlit as it
//! goes.

use std::collections::HashSet;
use std::sync::Arc;

use super::LightField;
use super::engine::{Cell, Engine, NONE, Scratch, block_above, level};
use super::store::{Beam, LightChunk, Local, local};
use crate::{
    BlockId, CHUNK_AREA, CHUNK_SIZE, CHUNK_VOLUME, ChunkPos, Error, Result, World, WorldPos,
};

/// The beam's levels in each cell of one column, by y.
type ColumnLevels = [[u8; 3]; CHUNK_SIZE];

impl LightField {
    /// Sets the block at `pos` in `world` ([`World::set_block`]) and updates the light for
    /// it: only the cells within reach of the change are visited. An edit in a chunk that
    /// is not lit lights that chunk ([`LightField::add_chunk`]). Fails, changing nothing,
    /// on an unknown block or a world over another registry.
    pub fn set_block(&mut self, world: &mut World, pos: WorldPos, id: BlockId) -> Result<BlockId> {
        self.check(world)?;
        if !world.registry().contains(id) {
            return Err(Error::UnknownBlock(id, world.registry().len()));
        }
        let (c, [x, y, z]) = pos.split();
        let Some(&ci) = self.index.get(&c) else {
            let old = world.set_block(pos, id)?;
            self.add_chunk(world, c)?;
            return Ok(old);
        };
        let old = world.get_block(pos);
        if old == id {
            return Ok(old);
        }
        let col = x * CHUNK_SIZE + z;
        let mut stack = vec![ci];
        stack.extend(self.below(c));
        let before: Vec<ColumnLevels> = {
            let mut engine = Engine::new(&mut self.entries, &self.props, world);
            stack
                .iter()
                .map(|&e| quantize(engine.walk(e, col)))
                .collect()
        };
        world.set_block(pos, id)?;
        let mut engine = Engine::new(&mut self.entries, &self.props, world);
        let mut sky = Vec::new();
        let mut bottom = None;
        for (&e, was) in stack.iter().zip(&before) {
            if let Some(b) = bottom {
                engine.entries[e as usize].beam_in.set(col, b);
            }
            let now = engine.walk(e, col);
            bottom = Some(now[0]);
            for (y2, (n, w)) in now.iter().zip(was).enumerate() {
                if n.map(level) != *w {
                    sky.push((e, local(x, y2, z)));
                }
            }
        }
        run(
            &mut engine,
            &[(ci, local(x, y, z))],
            &sky,
            &NO_FLOOD,
            &mut self.scratch,
            &mut self.changed,
        );
        Ok(old)
    }

    /// Lights the chunk at `pos` of `world` (one streamed in), or relights it when it is
    /// lit already (replaced). Light flows in from the lit chunks around it and out to
    /// them, and the sky's beam below it changes. Returns whether the world holds a chunk
    /// there (else nothing changes). Fails on a world over another registry.
    pub fn add_chunk(&mut self, world: &World, pos: ChunkPos) -> Result<bool> {
        self.check(world)?;
        if world.chunk(pos).is_none() {
            return Ok(false);
        }
        if !self.index.contains_key(&pos) {
            self.add_chunks(world, &[pos])?;
            return Ok(true);
        }
        // Replaced.
        let below = self.below(pos);
        let before = self.column_levels(world, &below);
        let ci = self.insert_entry(pos);
        let beam = self.beam_from_above(world, pos);
        self.entries[ci as usize].beam_in = beam;
        let mut sky = self.changed_below(world, ci, &below, &before);
        if below
            .first()
            .is_some_and(|&b| self.entries[b as usize].pos.y == pos.y - 1)
        {
            // Its old bottom blocks are gone: what the beam below was is unknown.
            sky.extend((0..CHUNK_VOLUME).map(|l| (below[0], l as Local)));
        }
        // Its old light may have gone anywhere from any of its cells.
        let all: Vec<Cell> = (0..CHUNK_VOLUME).map(|l| (ci, l as Local)).collect();
        let mut engine = Engine::new(&mut self.entries, &self.props, world);
        run(
            &mut engine,
            &all,
            &sky,
            &NO_FLOOD,
            &mut self.scratch,
            &mut self.changed,
        );
        Ok(true)
    }

    /// [`LightField::add_chunk`] for each of `positions` (chunks streamed in), with one
    /// flood for all the new ones: the same light as adding them one at a time, for less
    /// work where many come in together (their common borders are flooded once). A
    /// position the world holds no chunk at is skipped; one lit already is relit. Fails
    /// on a world over another registry, lighting none.
    pub fn add_chunks(&mut self, world: &World, positions: &[ChunkPos]) -> Result<()> {
        self.check(world)?;
        let (relit, mut new): (Vec<ChunkPos>, Vec<ChunkPos>) = positions
            .iter()
            .copied()
            .filter(|p| world.chunk(*p).is_some())
            .partition(|p| self.index.contains_key(p));
        // A column from the top down: each chunk's beam comes from the one placed above.
        new.sort_unstable_by_key(|p| (p.x, p.z, std::cmp::Reverse(p.y)));
        new.dedup();
        let mut sky = Vec::new();
        let placed: Vec<u32> = new
            .iter()
            .map(|&pos| self.insert_new(world, pos, &mut sky))
            .collect();
        let mut flood: [Vec<Cell>; 6] = Default::default();
        for &ci in &placed {
            self.seeds_of(ci, &mut flood);
            let around = self.around(ci);
            for f in &mut flood {
                f.extend_from_slice(&around);
            }
        }
        let mut engine = Engine::new(&mut self.entries, &self.props, world);
        run(
            &mut engine,
            &[],
            &sky,
            &flood,
            &mut self.scratch,
            &mut self.changed,
        );
        for p in relit {
            self.add_chunk(world, p)?;
        }
        Ok(())
    }

    /// Lights the chunk at `pos` (not lit yet) with its sources as a full light writes
    /// them (dark, nothing come through it yet: the flood is the caller's), sets the beam
    /// below it, adds to `sky` the cells below whose beam changed, and marks it changed.
    /// Returns its entry.
    fn insert_new(&mut self, world: &World, pos: ChunkPos, sky: &mut Vec<Cell>) -> u32 {
        let beam_in = self.beam_from_above(world, pos);
        // The kinds of the blocks just above its columns: air unless a lit chunk lies
        // directly above.
        let air = self.props[0].kind;
        let lit_above = self
            .index
            .contains_key(&ChunkPos::new(pos.x, pos.y + 1, pos.z));
        let mut kinds = [air; CHUNK_AREA];
        let mut beam = [[0.0; 3]; CHUNK_AREA];
        for (col, (k, b)) in kinds.iter_mut().zip(&mut beam).enumerate() {
            *b = beam_in.get(col);
            if lit_above {
                let id = block_above(world, pos, col);
                *k = self.props.get(id.index()).unwrap_or(&self.props[0]).kind;
            }
        }
        let mut cells = vec![[0; 6]; CHUNK_VOLUME];
        self.fill_chunk(world.chunk(pos), &mut beam, &mut kinds, &mut cells);
        // The chunks below see the beam leaving its bottom (and, the one right below,
        // its bottom blocks): where that is what they saw before, nothing below changes
        // (a chunk of sky coming in above the top of a column), and walking them is
        // skipped.
        let below = self.below(pos);
        let same_below = below.first().is_none_or(|&b| {
            let e = &self.entries[b as usize];
            let adjacent = e.pos.y == pos.y - 1;
            (0..CHUNK_AREA)
                .all(|col| e.beam_in.get(col) == beam[col] && (!adjacent || kinds[col] == air))
        });
        let before = if same_below {
            Vec::new()
        } else {
            self.column_levels(world, &below)
        };
        let ci = self.insert_entry(pos);
        self.entries[ci as usize].beam_in = beam_in;
        if !same_below {
            sky.extend(self.changed_below(world, ci, &below, &before));
        }
        self.entries[ci as usize].light = Arc::new(LightChunk::from_cells(&cells));
        self.changed.insert(pos);
        ci
    }

    /// Unlights the chunk at `pos`: light that came through it leaves its neighbours, and
    /// the sky's beam passes down through it as through air. Call it before the world
    /// unloads the chunk (after, the cells below it are relit in full). Returns whether it
    /// was lit. Fails on a world over another registry.
    pub fn remove_chunk(&mut self, world: &World, pos: ChunkPos) -> Result<bool> {
        self.check(world)?;
        let Some(&ci) = self.index.get(&pos) else {
            return Ok(false);
        };
        let below = self.below(pos);
        // A chunk of air passes the beam down as a gap does: nothing below changes.
        let air = world
            .chunk(pos)
            .is_some_and(|c| c.as_uniform() == Some(BlockId::AIR));
        let before = if air {
            Vec::new()
        } else {
            self.column_levels(world, &below)
        };
        // Nothing leads into it any more; it still leads out, for the removal.
        for d in 0..6 {
            let n = self.entries[ci as usize].neigh[d];
            if n != NONE {
                self.entries[n as usize].neigh[d ^ 1] = NONE;
            }
        }
        if let Some(set) = self.columns.get_mut(&[pos.x, pos.z]) {
            set.remove(&pos.y);
        }
        let mut sky = Vec::new();
        if let Some(&top) = below.first().filter(|_| !air) {
            let beam = self.beam_from_above(world, pos);
            self.entries[top as usize].beam_in = beam;
            sky = self.changed_below(world, NONE, &below, &before);
            if world.chunk(pos).is_none() && self.entries[top as usize].pos.y == pos.y - 1 {
                sky.extend((0..CHUNK_VOLUME).map(|l| (top, l as Local)));
            }
        }
        let mut engine = Engine::new(&mut self.entries, &self.props, world);
        engine.dead = ci;
        // Light that came through it left it by its border.
        run(
            &mut engine,
            &border(ci),
            &sky,
            &NO_FLOOD,
            &mut self.scratch,
            &mut self.changed,
        );
        // Take it out; the last entry takes its index.
        self.index.remove(&pos);
        if self
            .columns
            .get(&[pos.x, pos.z])
            .is_some_and(|s| s.is_empty())
        {
            self.columns.remove(&[pos.x, pos.z]);
        }
        self.entries.swap_remove(ci as usize);
        if let Some(moved) = self.entries.get(ci as usize) {
            let (p, neigh) = (moved.pos, moved.neigh);
            self.index.insert(p, ci);
            for (d, n) in neigh.into_iter().enumerate() {
                if n != NONE {
                    self.entries[n as usize].neigh[d ^ 1] = ci;
                }
            }
        }
        Ok(true)
    }

    /// The lit chunks below `pos` in its chunk column, nearest first.
    fn below(&self, pos: ChunkPos) -> Vec<u32> {
        self.columns
            .get(&[pos.x, pos.z])
            .map(|s| {
                s.range(..pos.y)
                    .rev()
                    .map(|&y| self.index[&ChunkPos::new(pos.x, y, pos.z)])
                    .collect()
            })
            .unwrap_or_default()
    }

    /// The beam entering the top of `pos` from the nearest lit chunk above it in its
    /// column (full where none).
    fn beam_from_above(&mut self, world: &World, pos: ChunkPos) -> Beam {
        let above = self
            .columns
            .get(&[pos.x, pos.z])
            .and_then(|s| s.range(pos.y + 1..).next())
            .map(|&y| self.index[&ChunkPos::new(pos.x, y, pos.z)]);
        let Some(a) = above else {
            return Beam::Uniform([1.0; 3]);
        };
        let mut engine = Engine::new(&mut self.entries, &self.props, world);
        let mut cols = [[0.0; 3]; CHUNK_AREA];
        for (col, b) in cols.iter_mut().enumerate() {
            *b = engine.walk(a, col)[0];
        }
        Beam::from_columns(&cols)
    }

    /// The beam's levels in every column of each chunk of `stack`.
    fn column_levels(&mut self, world: &World, stack: &[u32]) -> Vec<Vec<ColumnLevels>> {
        let mut engine = Engine::new(&mut self.entries, &self.props, world);
        stack
            .iter()
            .map(|&e| {
                (0..CHUNK_AREA)
                    .map(|col| quantize(engine.walk(e, col)))
                    .collect()
            })
            .collect()
    }

    /// Carries the beam from `top` (or the beam already set on `stack[0]` when `top` is
    /// [`NONE`]) down `stack`, setting each chunk's entering beam, and returns the cells
    /// whose beam level differs from `before`.
    fn changed_below(
        &mut self,
        world: &World,
        top: u32,
        stack: &[u32],
        before: &[Vec<ColumnLevels>],
    ) -> Vec<Cell> {
        let mut engine = Engine::new(&mut self.entries, &self.props, world);
        let mut out = Vec::new();
        let mut bottoms: Option<Box<[[f32; 3]; CHUNK_AREA]>> = (top != NONE).then(|| {
            let mut b = Box::new([[0.0; 3]; CHUNK_AREA]);
            for (col, b) in b.iter_mut().enumerate() {
                *b = engine.walk(top, col)[0];
            }
            b
        });
        for (&e, was) in stack.iter().zip(before) {
            if let Some(b) = &bottoms {
                engine.entries[e as usize].beam_in = Beam::from_columns(b);
            }
            let mut next = Box::new([[0.0; 3]; CHUNK_AREA]);
            for (col, w) in was.iter().enumerate() {
                let now = engine.walk(e, col);
                next[col] = now[0];
                for (y, (n, w)) in now.iter().zip(w).enumerate() {
                    if n.map(level) != *w {
                        out.push((e, local(col >> 5, y, col & 31)));
                    }
                }
            }
            bottoms = Some(next);
        }
        out
    }
}

fn quantize(w: [[f32; 3]; CHUNK_SIZE]) -> ColumnLevels {
    w.map(|b| b.map(level))
}

impl LightField {
    /// The cells of the lit chunks around chunk `c` that touch it.
    fn around(&self, c: u32) -> Vec<Cell> {
        let mut out = Vec::with_capacity(6 * CHUNK_AREA);
        for (d, &n) in self.entries[c as usize].neigh.iter().enumerate() {
            if n == NONE {
                continue;
            }
            // The layer of `n` facing `c`: its low side when `n` lies on the positive side.
            let axis = d / 2;
            let fixed = if d % 2 == 0 { 0 } else { CHUNK_SIZE - 1 };
            for a in 0..CHUNK_SIZE {
                for b in 0..CHUNK_SIZE {
                    let p = match axis {
                        0 => [fixed, a, b],
                        1 => [a, fixed, b],
                        _ => [a, b, fixed],
                    };
                    out.push((n, local(p[0], p[1], p[2])));
                }
            }
        }
        out
    }
}

/// The cells on the six sides of chunk `c`.
fn border(c: u32) -> Vec<Cell> {
    let mut out = Vec::with_capacity(6 * CHUNK_AREA);
    for x in 0..CHUNK_SIZE {
        for y in 0..CHUNK_SIZE {
            for z in 0..CHUNK_SIZE {
                let edge = [x, y, z].iter().any(|&v| v == 0 || v == CHUNK_SIZE - 1);
                if edge {
                    out.push((c, local(x, y, z)));
                }
            }
        }
    }
    out
}

/// No cells to flood from besides the update's own.
const NO_FLOOD: [&[Cell]; 6] = [&[]; 6];

/// Updates the six channels for a change at `seeds` (every channel) and `sky` (cells whose
/// beam changed), then floods each channel from `flood` too.
fn run<F: AsRef<[Cell]>>(
    engine: &mut Engine<'_>,
    seeds: &[Cell],
    sky: &[Cell],
    flood: &[F; 6],
    scratch: &mut Scratch,
    changed: &mut HashSet<ChunkPos>,
) {
    let mut both = Vec::with_capacity(seeds.len() + sky.len());
    both.extend_from_slice(seeds);
    both.extend_from_slice(sky);
    for (ch, flood) in flood.iter().enumerate() {
        let s = if ch < 3 { &both[..] } else { seeds };
        engine.update(ch, s, flood.as_ref(), scratch);
    }
    for &c in &engine.touched {
        if c != engine.dead {
            changed.insert(engine.entries[c as usize].pos);
        }
    }
}
