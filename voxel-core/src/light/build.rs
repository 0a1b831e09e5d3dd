//! Lighting every loaded chunk of a world from scratch.

use std::sync::Arc;

use super::LightField;
use super::engine::{Cell, Engine, Entry, NONE, level, step, step_beam};
use super::store::{Beam, Levels, LightChunk, local};
use crate::{
    BlockId, CHUNK_AREA, CHUNK_SIZE, CHUNK_VOLUME, Chunk, ChunkPos, Face, LIGHT_FALLOFF, World,
};

impl LightField {
    /// Adds an entry for `pos` (dark, beam 0) and links it to its lit neighbours.
    pub(super) fn insert_entry(&mut self, pos: ChunkPos) -> u32 {
        if let Some(&i) = self.index.get(&pos) {
            return i;
        }
        let i = self.entries.len() as u32;
        let mut neigh = [NONE; 6];
        for (d, face) in Face::ALL.iter().enumerate() {
            if let Some(&n) = pos.neighbour(*face).and_then(|p| self.index.get(&p)) {
                neigh[d] = n;
                self.entries[n as usize].neigh[d ^ 1] = i;
            }
        }
        self.entries.push(Entry {
            pos,
            light: Arc::new(LightChunk::uniform([0; 6])),
            beam_in: Beam::Uniform([0.0; 3]),
            neigh,
        });
        self.index.insert(pos, i);
        self.columns
            .entry([pos.x, pos.z])
            .or_default()
            .insert(pos.y);
        i
    }

    /// Lights every loaded chunk of `world`, replacing what was lit.
    pub(super) fn light_all(&mut self, world: &World) {
        self.entries.clear();
        self.changed.clear();
        self.index.clear();
        self.columns.clear();
        let mut positions: Vec<ChunkPos> = world.iter().map(|(p, _)| p).collect();
        positions.sort_unstable();
        for &p in &positions {
            self.insert_entry(p);
        }
        // The beam, a chunk column at a time from the top, and the emitters.
        let mut stacks: Vec<([i32; 2], Vec<i32>)> = self
            .columns
            .iter()
            .map(|(k, v)| (*k, v.iter().rev().copied().collect()))
            .collect();
        stacks.sort_unstable();
        let mut cells: Vec<Levels> = vec![[0; 6]; CHUNK_VOLUME];
        for ([cx, cz], ys) in stacks {
            let mut beam = [[1.0f32; 3]; CHUNK_AREA];
            let mut kinds = [0u16; CHUNK_AREA];
            let mut last: Option<i32> = None;
            for cy in ys {
                if last != Some(cy + 1) {
                    // Above the column or a gap of unlit chunks: air.
                    kinds = [0; CHUNK_AREA];
                }
                last = Some(cy);
                let pos = ChunkPos::new(cx, cy, cz);
                let i = self.index[&pos] as usize;
                let chunk = world.chunk(pos);
                self.entries[i].beam_in = Beam::from_columns(&beam);
                self.fill_chunk(chunk, &mut beam, &mut kinds, &mut cells);
                self.entries[i].light = Arc::new(LightChunk::from_cells(&cells));
            }
        }
        // Flood from every cell that can raise a neighbour.
        let mut seeds: [Vec<Cell>; 6] = Default::default();
        for c in 0..self.entries.len() as u32 {
            self.seeds_of(c, &mut seeds);
        }
        let mut engine = Engine::new(&mut self.entries, &self.props, world);
        for (ch, mut queue) in seeds.into_iter().enumerate() {
            engine.increase(ch, &mut queue);
        }
        // Cells stay in the form the flood wrote them in; compact once.
        self.compact();
        self.changed.extend(positions);
    }

    /// Writes the sources of a chunk's cells (beam levels, emission) into `cells` and
    /// carries `beam` and the kinds above each column through it.
    pub(super) fn fill_chunk(
        &self,
        chunk: Option<&Chunk>,
        beam: &mut [[f32; 3]; CHUNK_AREA],
        kinds: &mut [u16; CHUNK_AREA],
        cells: &mut [Levels],
    ) {
        let uniform = match chunk {
            None => Some(BlockId::AIR),
            Some(c) => c.as_uniform(),
        };
        if let Some(id) = uniform
            && beam.iter().all(|b| *b == beam[0])
            && kinds.iter().all(|k| *k == kinds[0])
        {
            // One block type under the same beam everywhere (sky, rock): every column
            // is the first.
            let p = self.props.get(id.index()).unwrap_or(&self.props[0]);
            let (mut b, mut kind) = (beam[0], kinds[0]);
            for y in (0..CHUNK_SIZE).rev() {
                b = step_beam(b, p, kind);
                kind = p.kind;
                let s = b.map(level);
                let levels = [s[0], s[1], s[2], p.emit[0], p.emit[1], p.emit[2]];
                let at = usize::from(local(0, y, 0));
                cells[at..at + CHUNK_AREA].fill(levels);
            }
            beam.fill(b);
            kinds.fill(kind);
            return;
        }
        let ids = match uniform {
            Some(id) => vec![id; CHUNK_VOLUME],
            None => chunk.map_or_else(|| vec![BlockId::AIR; CHUNK_VOLUME], Chunk::to_dense),
        };
        for col in 0..CHUNK_AREA {
            let (x, z) = (col >> 5, col & 31);
            let (mut b, mut kind) = (beam[col], kinds[col]);
            for y in (0..CHUNK_SIZE).rev() {
                let id = ids[Chunk::dense_index(x, y, z)];
                let p = self.props.get(id.index()).unwrap_or(&self.props[0]);
                b = step_beam(b, p, kind);
                kind = p.kind;
                let s = b.map(level);
                cells[usize::from(local(x, y, z))] =
                    [s[0], s[1], s[2], p.emit[0], p.emit[1], p.emit[2]];
            }
            beam[col] = b;
            kinds[col] = kind;
        }
    }

    /// Adds to `seeds` (per channel) the cells of chunk `c` whose level can raise a
    /// neighbour's: more than the falloff above it.
    pub(super) fn seeds_of(&self, c: u32, seeds: &mut [Vec<Cell>; 6]) {
        let e = &self.entries[c as usize];
        let layer = |c: u32, y: usize| self.entries[c as usize].light.uniform_layer(y);
        let cell = |(c, l): Cell| self.entries[c as usize].light.levels(l);
        // A layer equal to the layers above and below needs checking only at its edges.
        let flat = |y: usize| -> bool {
            let Some(v) = layer(c, y) else { return false };
            let side = |d: usize, y2: Option<usize>| match y2 {
                Some(y2) => layer(c, y2) == Some(v),
                None => {
                    e.neigh[d] == NONE || layer(e.neigh[d], if d == 2 { 0 } else { 31 }) == Some(v)
                }
            };
            side(2, (y < 31).then_some(y + 1)) && side(3, y.checked_sub(1))
        };
        let engine_step = |l: u16, dir: usize| step(&self.entries, c, l, dir);
        let mut check = |l: u16| {
            let v = e.light.levels(l);
            if v.iter().all(|&v| v <= LIGHT_FALLOFF) {
                return;
            }
            let mut want = [false; 6];
            for dir in 0..6 {
                if let Some(n) = engine_step(l, dir) {
                    let w = cell(n);
                    for ch in 0..6 {
                        want[ch] |= u16::from(w[ch]) + u16::from(LIGHT_FALLOFF) < u16::from(v[ch]);
                    }
                }
            }
            for ch in 0..6 {
                if want[ch] {
                    seeds[ch].push((c, l));
                }
            }
        };
        for y in 0..CHUNK_SIZE {
            if flat(y) {
                for x in 0..CHUNK_SIZE {
                    for z in 0..CHUNK_SIZE {
                        if x == 0 || x == 31 || z == 0 || z == 31 {
                            check(local(x, y, z));
                        }
                    }
                }
            } else {
                for i in 0..CHUNK_AREA {
                    check(((y << 10) | i) as u16);
                }
            }
        }
    }
}
