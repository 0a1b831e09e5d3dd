//! The propagation: the sky's beam down each column, the flood of light with falloff and
//! filters (increase), and its removal and refill after a change, one channel at a time.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};
use std::sync::Arc;

use super::props::{ONE, Props};
use super::store::{Beam, LightChunk, Local, local};
use crate::{BlockId, CHUNK_SIZE, Chunk, ChunkPos, LIGHT_FALLOFF, World, WorldPos};

/// No chunk there (not lit).
pub(super) const NONE: u32 = u32::MAX;

/// A lit chunk: its light (shared with the snapshots [`super::LightField::shared`] hands
/// out, copied on the first write after one), the beam entering it from above, its six
/// lit neighbours (in [`crate::Face`] order, [`NONE`] where none).
#[derive(Clone, Debug)]
pub(super) struct Entry {
    pub pos: ChunkPos,
    pub light: Arc<LightChunk>,
    pub beam_in: Beam,
    pub neigh: [u32; 6],
}

impl Entry {
    /// Turns its layers whose cells all agree back into uniform ones; a snapshot handed
    /// out is copied only where there is something to compact.
    pub fn compact(&mut self) {
        if self.light.compactable() {
            Arc::make_mut(&mut self.light).compact();
        }
    }
}

/// The block of `world` just above the top of column `col` (`x << 5 | z`) of the chunk at
/// `pos`.
pub(super) fn block_above(world: &World, pos: ChunkPos, col: usize) -> BlockId {
    let o = pos.origin();
    let (x, z) = ((col >> 5) as i64, (col & 31) as i64);
    world.get_block(WorldPos::new(
        (o[0] + x) as i32,
        (o[1] + CHUNK_SIZE as i64) as i32,
        (o[2] + z) as i32,
    ))
}

/// A cell of the lit world: entry index and local index.
pub(super) type Cell = (u32, Local);

/// The level of a beam's transmittance.
pub(super) fn level(b: f32) -> u8 {
    (b * 255.0).round().clamp(0.0, 255.0) as u8
}

/// One update's view of the light field and the world.
pub(super) struct Engine<'a> {
    pub entries: &'a mut [Entry],
    props: &'a [Props],
    world: &'a World,
    blocks: Vec<Option<Option<&'a Chunk>>>,
    beams: HashMap<Cell, [[u8; 3]; CHUNK_SIZE], BuildHasherDefault<CellHasher>>,
    /// A chunk being unlit: its cells are cleared but never refilled.
    pub dead: u32,
    /// The chunks whose light changed.
    pub touched: Vec<u32>,
}

impl<'a> Engine<'a> {
    pub fn new(entries: &'a mut [Entry], props: &'a [Props], world: &'a World) -> Self {
        let n = entries.len();
        Self {
            entries,
            props,
            world,
            blocks: vec![None; n],
            beams: HashMap::default(),
            dead: NONE,
            touched: Vec::new(),
        }
    }

    fn chunk(&mut self, c: u32) -> Option<&'a Chunk> {
        let slot = &mut self.blocks[c as usize];
        if let Some(ch) = *slot {
            return ch;
        }
        let ch = self.world.chunk(self.entries[c as usize].pos);
        *slot = Some(ch);
        ch
    }

    /// The block at a cell (air where the world holds no chunk).
    #[inline]
    pub fn id(&mut self, c: u32, l: Local) -> BlockId {
        let (x, y, z) = (
            usize::from((l >> 5) & 31),
            usize::from(l >> 10),
            usize::from(l & 31),
        );
        self.chunk(c)
            .and_then(|ch| ch.get(x, y, z).ok())
            .unwrap_or(BlockId::AIR)
    }

    #[inline]
    pub fn props_of(&self, id: BlockId) -> &'a Props {
        self.props.get(id.index()).unwrap_or(&self.props[0])
    }

    #[inline]
    fn props_at(&mut self, c: u32, l: Local) -> &'a Props {
        let id = self.id(c, l);
        self.props_of(id)
    }

    /// The cell next to `(c, l)` across face `dir`, if lit.
    #[inline]
    pub fn step(&self, c: u32, l: Local, dir: usize) -> Option<Cell> {
        step(self.entries, c, l, dir)
    }

    #[inline]
    pub fn get(&self, (c, l): Cell, ch: usize) -> u8 {
        self.entries[c as usize].light.channel(l, ch)
    }

    #[inline]
    fn set(&mut self, (c, l): Cell, ch: usize, v: u8) {
        if self.get((c, l), ch) == v {
            return;
        }
        Arc::make_mut(&mut self.entries[c as usize].light).set_channel(l, ch, v);
        if self.touched.last() != Some(&c) && !self.touched.contains(&c) {
            self.touched.push(c);
        }
    }

    /// The block above the top of chunk `c` at column `col` as light sees it: air where
    /// no lit chunk lies directly above.
    pub fn above(&self, c: u32, col: usize) -> BlockId {
        let e = &self.entries[c as usize];
        if e.neigh[2] == NONE {
            return BlockId::AIR;
        }
        block_above(self.world, e.pos, col)
    }

    /// The beam (exact) in each cell of column `col` of chunk `c`, by y, from the beam
    /// entering its top and the block above.
    pub fn walk(&mut self, c: u32, col: usize) -> [[f32; 3]; CHUNK_SIZE] {
        let above = self.above(c, col);
        let mut kind = self.props_of(above).kind;
        let mut b = self.entries[c as usize].beam_in.get(col);
        let mut out = [[0.0; 3]; CHUNK_SIZE];
        let (x, z) = (col >> 5, col & 31);
        for y in (0..CHUNK_SIZE).rev() {
            let p = self.props_at(c, local(x, y, z));
            b = step_beam(b, p, kind);
            kind = p.kind;
            out[y] = b;
        }
        out
    }

    /// The source level of a cell in channel `ch`: the beam's level (sky) or the block's
    /// emission (block light).
    fn source(&mut self, (c, l): Cell, ch: usize) -> u8 {
        if ch >= 3 {
            return self.props_at(c, l).emit[ch - 3];
        }
        let col = usize::from(l & 1023);
        let key = (c, col as Local);
        let levels = match self.beams.get(&key) {
            Some(v) => *v,
            None => {
                let v = self.walk(c, col).map(|b| b.map(level));
                self.beams.insert(key, v);
                v
            }
        };
        levels[usize::from(l >> 10)][ch]
    }

    /// Floods channel `ch` from the cells of `queue` (emptied).
    pub fn increase(&mut self, ch: usize, queue: &mut Vec<Cell>) {
        let mut head = 0;
        while head < queue.len() {
            let cell = queue[head];
            head += 1;
            let v = self.get(cell, ch);
            if v <= LIGHT_FALLOFF {
                continue;
            }
            // Filters only lower a level: a neighbour at `v − falloff` or above cannot
            // rise, and needs no block looked up.
            let upper = v - LIGHT_FALLOFF;
            let mut kind = None;
            for dir in 0..6 {
                let Some(n) = self.step(cell.0, cell.1, dir) else {
                    continue;
                };
                let now = self.get(n, ch);
                if now >= upper {
                    continue;
                }
                let p = self.props_at(n.0, n.1);
                if !p.open {
                    continue;
                }
                let kind = *kind.get_or_insert_with(|| self.props_at(cell.0, cell.1).kind);
                let f = if p.kind == kind {
                    p.within_fx[ch % 3]
                } else {
                    p.enter_fx[ch % 3]
                };
                let cand = filtered(v, f).saturating_sub(LIGHT_FALLOFF);
                if cand > now {
                    self.set(n, ch, cand);
                    queue.push(n);
                }
            }
        }
        queue.clear();
    }

    /// Clears channel `ch` at `seeds` and at every cell whose level may have come through
    /// them (a level at most the falloff below a cleared neighbour's: filters only lower
    /// it), then refills what was cleared from the cells around it and from sources.
    /// Then floods from `flood` too (cells set to their sources by the caller).
    pub fn update(&mut self, ch: usize, seeds: &[Cell], flood: &[Cell], scratch: &mut Scratch) {
        let Scratch {
            stack,
            cleared,
            queue,
        } = scratch;
        for &s in seeds {
            let v = self.get(s, ch);
            self.set(s, ch, 0);
            stack.push((s, v));
            cleared.push(s);
        }
        while let Some((cell, old)) = stack.pop() {
            for dir in 0..6 {
                let Some(n) = self.step(cell.0, cell.1, dir) else {
                    continue;
                };
                let v = self.get(n, ch);
                if v == 0 || n.0 == self.dead {
                    continue;
                }
                if u16::from(v) + u16::from(LIGHT_FALLOFF) <= u16::from(old) {
                    self.set(n, ch, 0);
                    stack.push((n, v));
                    cleared.push(n);
                } else if n.0 != self.dead {
                    queue.push(n);
                }
            }
        }
        // Sources first, then only those that can raise a neighbour flood (a chunk lit
        // whole would otherwise push every cell of it).
        cleared.retain(|&c| {
            if c.0 == self.dead {
                return false;
            }
            let s = self.source(c, ch);
            let raised = s > self.get(c, ch);
            if raised {
                self.set(c, ch, s);
            }
            raised && s > LIGHT_FALLOFF
        });
        for &c in cleared.iter() {
            let v = self.get(c, ch);
            let lower = |n: Option<Cell>| {
                n.is_some_and(|n| {
                    u16::from(self.get(n, ch)) + u16::from(LIGHT_FALLOFF) < u16::from(v)
                })
            };
            if (0..6).any(|dir| lower(self.step(c.0, c.1, dir))) {
                queue.push(c);
            }
        }
        cleared.clear();
        queue.extend_from_slice(flood);
        self.increase(ch, queue);
    }
}

/// Queues an update reuses.
#[derive(Clone, Debug, Default)]
pub(super) struct Scratch {
    stack: Vec<(Cell, u8)>,
    cleared: Vec<Cell>,
    queue: Vec<Cell>,
}

/// `v` through a fixed-point filter, rounded.
#[inline]
pub(super) fn filtered(v: u8, f: u32) -> u8 {
    ((u32::from(v) * f + ONE / 2) >> 16) as u8
}

/// The beam `b` entering a block of properties `p` from a block of kind `from`.
#[inline]
pub(super) fn step_beam(b: [f32; 3], p: &Props, from: u16) -> [f32; 3] {
    if !p.beam {
        return [0.0; 3];
    }
    let f = if p.kind == from { p.within } else { p.enter };
    [b[0] * f[0], b[1] * f[1], b[2] * f[2]]
}

/// The cell next to `(c, l)` across face `dir` ([`crate::Face`] order), if lit.
#[inline]
pub(super) fn step(entries: &[Entry], c: u32, l: Local, dir: usize) -> Option<Cell> {
    let (x, y, z) = ((l >> 5) & 31, l >> 10, l & 31);
    let (inside, near, far): (bool, i32, i32) = match dir {
        0 => (x < 31, 32, -(31 * 32)),
        1 => (x > 0, -32, 31 * 32),
        2 => (y < 31, 1024, -(31 * 1024)),
        3 => (y > 0, -1024, 31 * 1024),
        4 => (z < 31, 1, -31),
        _ => (z > 0, -1, 31),
    };
    let moved = |d: i32| (i32::from(l) + d) as Local;
    if inside {
        Some((c, moved(near)))
    } else {
        let n = entries[c as usize].neigh[dir];
        (n != NONE).then(|| (n, moved(far)))
    }
}

/// A multiplicative hash of a cell's two numbers: the beam cache is looked up once per
/// cleared cell and sky channel, where SipHash would cost more than the walk it saves.
#[derive(Default)]
pub(super) struct CellHasher(u64);

impl Hasher for CellHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }
    fn write_u16(&mut self, v: u16) {
        self.write_u64(u64::from(v));
    }
    fn write_u32(&mut self, v: u32) {
        self.write_u64(u64::from(v));
    }
    fn write_u64(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(5) ^ v).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}
