//! A 32³ chunk, in one of three forms behind one API:
//!
//! - **uniform**: a chunk made of a single block type stores just that id;
//! - **masks** (the *bitmask palette*, the mesher's input): for each block type present, the
//!   set of blocks of that type as bits, kept in two layouts (see [`Occupancy`]); the sets
//!   are disjoint and cover all 32³ blocks;
//! - **packed** (the compact resident form): a palette of the `n` types present and, per
//!   block, its palette index in `b = ceil(log2(n))` bits, stored as `b` *bit planes* in the
//!   column layout: bit `j` of the index of block `(x, y, z)` is bit `y` of word
//!   [`column_index`]`(x, z)` of plane `j`. That is exactly the size of a packed-index
//!   palette (`b` bits a block), but decoding needs no bit shuffling: the column mask of
//!   palette entry `k` is `b` ANDs per word ([`Chunk::build_masks`]).
//!
//! [`Chunk::pack`] and [`Chunk::unpack`] convert between masks and packed (a uniform chunk
//! stays uniform). Terrain generation writes the mask form (a column run at a time); a
//! streamer packs a chunk once it has been meshed ([`crate::World::pack_chunk`],
//! [`crate::World::pack_all`]).
//!
//! Why two forms. Figures from one run of `cargo bench -p voxel-mesh --bench mesher`
//! (results/mesher-bench.txt) on the shared 2-core development machine, whose load made
//! every time in it some 25-35% slower than in the previous recorded run; compare ratios
//! within the run:
//! - The binary mesher works on exactly the masks, so a remesh of a chunk in mask form needs
//!   no pass over 32 768 block ids (building masks from a `u16` per block costs 78.9 µs,
//!   more than twice our whole mesh). Two layouts make every face direction a pair of
//!   adjacent rows ANDed together: x faces from the vertical columns, y and z faces from the
//!   rows along x. From the mask form, ours takes 34.4 µs a chunk against 43.3 µs for
//!   binary-greedy-meshing's `fast_mesh`: 0.795× (target ≤ 0.8; 0.74 in the previous
//!   recorded run, on a quieter machine, with the same mask-form code path).
//! - But the masks cost 8 KiB per block type present: 76.5 MiB for the benchmark's
//!   2048-chunk world, 4.2× a packed-index palette (18.0 MiB), about a quarter of a
//!   gigabyte at a 32-chunk view distance. The packed form costs 18.2 MiB there, 1.01× the
//!   packed-index figure (target ≤ 2×; the rest is the palette with its counts and a small
//!   header); the masks take 4.21× that and a `u16` per block 5.90×. Packing a chunk takes
//!   2.4 µs, unpacking it 7.2 µs (allocation included); packing the whole world 4 ms on two
//!   threads.
//! - The mesher takes packed chunks as they are. For a packed centre it builds the masks of
//!   the non-air types into its own scratch memory ([`Chunk::build_masks`]): `b` bit-matrix
//!   transposes (two vectorised passes each, all 32 slabs at once) turn the planes into the
//!   row layout, then each type is `b` XOR-ANDs per word in each layout: 4.5 µs for the
//!   benchmark's chunks (7.5 types). Of a packed neighbour it reads only the touching layer
//!   ([`Chunk::side_layers`]: the layer of each plane, then the types from those), no
//!   slower than from mask-form neighbours (27.5 against 28.3 µs a mesh). A chunk and its
//!   neighbours all packed mesh in 37.7 µs in the rounds shared with binary-greedy-meshing:
//!   0.872× its time, above the 0.8 target that the mask form meets. In rounds of their own (no peer sweeping the caches) the gap is
//!   smaller, 30.4 against 28.3 µs, likely because the 12 KiB of a packed centre come in
//!   from memory where the stored masks are ten times that.
//! - So the design is: chunks are generated in mask form and meshed from it (the bulk of
//!   all meshing, at the mask form's speed), then packed by the streamer; what stays
//!   resident is packed. A later remesh of a packed chunk (an edit in it or on a
//!   neighbour's border) pays the mask build, about a tenth of a mesh; a caller that edits
//!   a chunk over and over can keep it in mask form ([`Chunk::unpack`]) while it is hot.
//! - Alternatives measured (the last two with a throwaway harness, minimum over 2 s of
//!   32-chunk passes): the caller unpacking the centre, meshing it and packing it again
//!   takes 35.1 µs against 30.4 µs for meshing it packed (unpacking allocates and decodes
//!   air too); decoding each type's column masks and transposing each type (`n` transposes
//!   instead of `b`) builds the masks in 4.0-4.3 µs against 3.7 µs; decoding all codes at
//!   once through a tree of ANDs shared between codes (about two per code and word instead
//!   of `b`) is slower, 3.7 µs against 2.2 µs for the decode alone, because on SSE2 it is
//!   bound by loads and stores of the tree, not by the ANDs. A packed index with
//!   power-of-two widths (1, 2, 4 or 8 bits, so that no index straddles a word) would cost
//!   up to a third more memory (5 to 8 types need 4 bits instead of 3) for a decode that the
//!   bit planes already make cheap; storing the planes in both layouts would spare the
//!   transposes but cost just over 2× the packed-index palette.
//!
//! Edits work in every form. An edit of a packed chunk edits the packed data and the chunk
//! stays packed: a write is `b` word updates per column touched (plus a count update per
//! palette entry), a new type may add a plane, and a type whose last block goes is dropped
//! (the last entry takes its index, the planes narrow when they can). Converting to masks
//! on edit would make that chunk's next remeshes a few µs cheaper but multiply its memory
//! by four until someone packs it again; that trade is left to the caller ([`Chunk::unpack`],
//! [`crate::World::unpack_chunk`]), so that memory never grows behind a streamer's back. An
//! edit of a uniform chunk gives the mask form, as in terrain generation (pack it
//! afterwards). [`Chunk::get`] on a packed chunk reads `b` bits (6.5 ns at random); in mask
//! form it scans the palette (7.4 ns).
//!
//! Files: `masks` holds the mask form and [`MaskBuffer`], `packed` the packed form, `bits`
//! the bit-matrix helpers both use (transposes, layers of a side).

mod bits;
mod masks;
mod packed;
#[cfg(test)]
mod tests;

use std::borrow::Cow;

use bits::{for_each_bit, plane_side_layer, side_layer, span_bits};
pub use masks::MaskBuffer;
use masks::{Entry, check_masks, fill_masks};
use packed::{Packed, Slot, check_packed, inverter};

use crate::{BlockId, Error, Face, Result};

/// Edge length of a chunk in blocks.
pub const CHUNK_SIZE: usize = 32;
/// Number of columns (and of blocks in a chunk layer): 32².
pub const CHUNK_AREA: usize = CHUNK_SIZE * CHUNK_SIZE;
/// Number of blocks in a chunk: 32³.
pub const CHUNK_VOLUME: usize = CHUNK_AREA * CHUNK_SIZE;

/// 1024 rows of 32 bits: one bit per block of a chunk, in one of two layouts.
pub type ColumnMask = [u32; CHUNK_AREA];

/// 32 rows of 32 bits: one bit per block of a chunk layer (see [`Chunk::side_layers`]).
pub type LayerMask = [u32; CHUNK_SIZE];

/// Index of the vertical column `(x, z)` in [`Occupancy::by_y`]: `x * 32 + z`.
#[inline]
pub const fn column_index(x: usize, z: usize) -> usize {
    x * CHUNK_SIZE + z
}

/// Index of the row along x at `(y, z)` in [`Occupancy::by_x`]: `y * 32 + z`.
#[inline]
pub const fn row_index(y: usize, z: usize) -> usize {
    y * CHUNK_SIZE + z
}

/// The blocks of one type in a chunk, as bits, in two layouts holding the same set.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Occupancy {
    /// Vertical columns: bit `y` of `by_y[column_index(x, z)]`.
    pub by_y: ColumnMask,
    /// Rows along x: bit `x` of `by_x[row_index(y, z)]`.
    pub by_x: ColumnMask,
}

/// The occupancy of a chunk made of one block type.
static FULL: Occupancy = Occupancy {
    by_y: [u32::MAX; CHUNK_AREA],
    by_x: [u32::MAX; CHUNK_AREA],
};

#[derive(Clone, Debug)]
enum Storage {
    Uniform(BlockId),
    Masks(Vec<Entry>),
    /// Boxed, so that a chunk stays three words (uniform chunks are common).
    Packed(Box<Packed>),
}

/// 32×32×32 blocks. See the module docs for the storage forms.
#[derive(Clone, Debug)]
pub struct Chunk {
    storage: Storage,
}

impl Default for Chunk {
    /// An all-air chunk.
    fn default() -> Self {
        Self::uniform(BlockId::AIR)
    }
}

fn check(x: usize, y: usize, z: usize) -> Result<()> {
    if x < CHUNK_SIZE && y < CHUNK_SIZE && z < CHUNK_SIZE {
        Ok(())
    } else {
        Err(Error::LocalOutOfRange { x, y, z })
    }
}

impl Chunk {
    /// A chunk made of one block type.
    pub fn uniform(id: BlockId) -> Self {
        Self {
            storage: Storage::Uniform(id),
        }
    }

    /// The block at local `(x, y, z)`; each coordinate must be below 32.
    pub fn get(&self, x: usize, y: usize, z: usize) -> Result<BlockId> {
        check(x, y, z)?;
        Ok(self.get_unchecked(x, y, z))
    }

    fn get_unchecked(&self, x: usize, y: usize, z: usize) -> BlockId {
        match &self.storage {
            Storage::Uniform(id) => *id,
            Storage::Masks(entries) => {
                let (i, bit) = (column_index(x, z), 1u32 << y);
                entries
                    .iter()
                    .find(|e| e.bits.by_y[i] & bit != 0)
                    .map_or(BlockId::AIR, |e| e.id)
            }
            Storage::Packed(p) => p.get(column_index(x, z), y),
        }
    }

    /// Sets the block at local `(x, y, z)` and returns the block that was there.
    pub fn set(&mut self, x: usize, y: usize, z: usize, id: BlockId) -> Result<BlockId> {
        check(x, y, z)?;
        let old = self.get_unchecked(x, y, z);
        if old != id {
            self.fill_column_bits(x, z, 1 << y, id);
            self.compact();
        }
        Ok(old)
    }

    /// Sets blocks `ys` of column `(x, z)` to `id`. An empty range changes nothing.
    pub fn fill_column(
        &mut self,
        x: usize,
        z: usize,
        ys: std::ops::Range<usize>,
        id: BlockId,
    ) -> Result<()> {
        check(x, ys.start.min(CHUNK_SIZE - 1), z)?;
        if ys.end > CHUNK_SIZE {
            return Err(Error::LocalOutOfRange {
                x,
                y: ys.end - 1,
                z,
            });
        }
        if ys.start < ys.end {
            self.fill_column_bits(x, z, span_bits(ys.start, ys.end), id);
            self.compact();
        }
        Ok(())
    }

    /// Sets every block of the box `min..=max` (local coordinates) to `id`.
    pub fn fill_box(&mut self, min: [usize; 3], max: [usize; 3], id: BlockId) -> Result<()> {
        check(min[0], min[1], min[2])?;
        check(max[0], max[1], max[2])?;
        if min.iter().zip(&max).any(|(a, b)| a > b) {
            return Ok(());
        }
        let bits = span_bits(min[1], max[1] + 1);
        for x in min[0]..=max[0] {
            for z in min[2]..=max[2] {
                self.fill_column_bits(x, z, bits, id);
            }
        }
        self.compact();
        Ok(())
    }

    /// Writes `id` at the set bits of column `(x, z)` in the chunk's form (a uniform chunk
    /// takes the mask form). Leaves empty entries behind: callers run [`Self::compact`]
    /// once they are done.
    fn fill_column_bits(&mut self, x: usize, z: usize, bits: u32, id: BlockId) {
        if let Storage::Uniform(u) = self.storage {
            if u == id {
                return;
            }
            self.storage = Storage::Masks(vec![Entry {
                id: u,
                count: CHUNK_VOLUME as u32,
                bits: Box::new(FULL.clone()),
            }]);
        }
        match &mut self.storage {
            Storage::Uniform(_) => {}
            Storage::Masks(entries) => fill_masks(entries, x, z, bits, id),
            Storage::Packed(p) => p.fill(column_index(x, z), bits, id),
        }
    }

    /// Drops palette entries that no block uses; a palette of one entry becomes uniform.
    fn compact(&mut self) {
        let only = match &mut self.storage {
            Storage::Uniform(_) => None,
            Storage::Masks(entries) => {
                entries.retain(|e| e.count > 0);
                entries.first().filter(|_| entries.len() == 1).map(|e| e.id)
            }
            Storage::Packed(p) => {
                p.compact();
                p.palette
                    .first()
                    .filter(|_| p.palette.len() == 1)
                    .map(|s| s.id)
            }
        };
        if let Some(id) = only {
            self.storage = Storage::Uniform(id);
        }
    }

    /// Converts the chunk to the packed form (see the module docs). A uniform or packed
    /// chunk stays as it is.
    pub fn pack(&mut self) {
        if let Storage::Masks(entries) = &self.storage {
            self.storage = Storage::Packed(Box::new(Packed::from_entries(entries)));
        }
    }

    /// Converts the chunk to the mask form, the mesher's input. A uniform or mask-form
    /// chunk stays as it is.
    pub fn unpack(&mut self) {
        if let Storage::Packed(p) = &self.storage {
            self.storage = Storage::Masks(p.to_entries());
        }
    }

    /// Whether the chunk is in the packed form.
    pub fn is_packed(&self) -> bool {
        matches!(self.storage, Storage::Packed(_))
    }

    /// `Some(id)` when every block of the chunk is `id`.
    pub fn as_uniform(&self) -> Option<BlockId> {
        match self.storage {
            Storage::Uniform(id) => Some(id),
            Storage::Masks(_) | Storage::Packed(_) => None,
        }
    }

    /// The block types present with their number of blocks, air included, in any form.
    /// The counts add up to 32³.
    pub fn palette(&self) -> impl Iterator<Item = (BlockId, usize)> {
        let (uniform, entries, slots) = match &self.storage {
            Storage::Uniform(id) => (Some((*id, CHUNK_VOLUME)), &[][..], &[][..]),
            Storage::Masks(entries) => (None, entries.as_slice(), &[][..]),
            Storage::Packed(p) => (None, &[][..], p.palette.as_slice()),
        };
        uniform
            .into_iter()
            .chain(entries.iter().map(|e| (e.id, e.count as usize)))
            .chain(slots.iter().map(|s| (s.id, s.count as usize)))
    }

    /// The stored masks of every block type present, air included, when the chunk holds
    /// them (mask form, or uniform: its one type, full); `None` for a packed chunk (see
    /// [`Chunk::build_masks`]). The sets are disjoint and together cover the chunk.
    pub fn stored_masks(&self) -> Option<impl Iterator<Item = (BlockId, &Occupancy)>> {
        let (uniform, entries) = match &self.storage {
            Storage::Uniform(id) => (Some((*id, &FULL)), &[][..]),
            Storage::Masks(entries) => (None, entries.as_slice()),
            Storage::Packed(_) => return None,
        };
        Some(
            uniform
                .into_iter()
                .chain(entries.iter().map(|e| (e.id, &*e.bits))),
        )
    }

    /// The masks of the block types that `want` selects, in palette order, into `out`
    /// (replacing what it held), in any form: copied from the mask form, decoded from the
    /// packed form. The mesher builds a packed centre's masks so, into its own buffer.
    pub fn build_masks(&self, out: &mut MaskBuffer, mut want: impl FnMut(BlockId) -> bool) {
        out.clear();
        match &self.storage {
            Storage::Uniform(id) => {
                if want(*id) {
                    out.push(*id).clone_from(&FULL);
                }
            }
            Storage::Masks(entries) => {
                for e in entries.iter().filter(|e| want(e.id)) {
                    out.push(e.id).clone_from(&e.bits);
                }
            }
            Storage::Packed(p) => p.build_masks(out, want),
        }
    }

    /// The bits of `id` (borrowed from the mask form, built from the packed form), or
    /// `None` when the chunk holds no such block.
    pub fn occupancy(&self, id: BlockId) -> Option<Cow<'_, Occupancy>> {
        if let Some(mut masks) = self.stored_masks() {
            return masks.find(|(i, _)| *i == id).map(|(_, m)| Cow::Borrowed(m));
        }
        let mut buf = MaskBuffer::new();
        self.build_masks(&mut buf, |i| i == id);
        buf.entries.into_iter().next().map(|(_, m)| Cow::Owned(*m))
    }

    /// For each block type present that `want` selects (in palette order), its blocks in
    /// the layer on `side` of the chunk (x = 31 for [`Face::PosX`], x = 0 for
    /// [`Face::NegX`], ...), into `out` (replacing what it held), in any form. Layout of a
    /// layer: for an x side row z bits y, for a y side row z bits x (a layer of
    /// [`Occupancy::by_x`]), for a z side row y bits x. A packed chunk extracts the layer of
    /// each bit plane once and decodes the types from those: no masks are built.
    pub fn side_layers(
        &self,
        side: Face,
        out: &mut Vec<(BlockId, LayerMask)>,
        mut want: impl FnMut(BlockId) -> bool,
    ) {
        out.clear();
        match &self.storage {
            Storage::Uniform(id) => {
                if want(*id) {
                    out.push((*id, [u32::MAX; CHUNK_SIZE]));
                }
            }
            Storage::Masks(entries) => out.extend(
                entries
                    .iter()
                    .filter(|e| want(e.id))
                    .map(|e| (e.id, side_layer(&e.bits, side))),
            ),
            Storage::Packed(p) => {
                if !p.palette.iter().any(|s| want(s.id)) {
                    return;
                }
                // At most 16 planes: ids are 16 bits.
                let mut layers = [[0; CHUNK_SIZE]; 16];
                for (l, q) in layers.iter_mut().zip(&p.planes) {
                    *l = plane_side_layer(q, side);
                }
                let layers = &layers[..p.planes.len()];
                for (k, s) in p.palette.iter().enumerate() {
                    if want(s.id) {
                        let mut m = [u32::MAX; CHUNK_SIZE];
                        for (j, l) in layers.iter().enumerate() {
                            let inv = inverter(k, j);
                            m.iter_mut().zip(l).for_each(|(m, l)| *m &= l ^ inv);
                        }
                        out.push((s.id, m));
                    }
                }
            }
        }
    }

    /// Number of blocks of type `id`.
    pub fn count(&self, id: BlockId) -> usize {
        self.palette().find(|(i, _)| *i == id).map_or(0, |(_, n)| n)
    }

    /// Number of distinct block types present.
    pub fn palette_len(&self) -> usize {
        match &self.storage {
            Storage::Uniform(_) => 1,
            Storage::Masks(entries) => entries.len(),
            Storage::Packed(p) => p.palette.len(),
        }
    }

    /// Heap and inline bytes this chunk occupies, in its current form (spare capacity
    /// included).
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of::<Self>()
            + match &self.storage {
                Storage::Uniform(_) => 0,
                Storage::Masks(entries) => {
                    entries.capacity() * std::mem::size_of::<Entry>()
                        + entries.len() * std::mem::size_of::<Occupancy>()
                }
                Storage::Packed(p) => {
                    std::mem::size_of::<Packed>()
                        + p.palette.capacity() * std::mem::size_of::<Slot>()
                        + p.planes.capacity() * std::mem::size_of::<ColumnMask>()
                }
            }
    }

    /// The bytes a packed-index palette would take for these blocks: the baseline resident
    /// storage is measured against. A uniform chunk is the chunk value alone; a mixed one
    /// has `ceil(log2 k)` bits per block for its `k` types and a `u16` per palette entry.
    pub fn packed_index_bytes(&self) -> usize {
        let k = self.palette_len();
        if self.as_uniform().is_some() || k < 2 {
            return std::mem::size_of::<Self>();
        }
        let bits = (usize::BITS - (k - 1).leading_zeros()) as usize;
        CHUNK_VOLUME * bits / 8 + k * 2
    }

    /// The chunk as one id per block, indexed by [`Chunk::dense_index`]. For tools, tests
    /// and peer meshers that want a dense array.
    pub fn to_dense(&self) -> Vec<BlockId> {
        let mut out = vec![BlockId::AIR; CHUNK_VOLUME];
        match &self.storage {
            Storage::Packed(p) => {
                for (i, column) in out.chunks_exact_mut(CHUNK_SIZE).enumerate() {
                    for (y, b) in column.iter_mut().enumerate() {
                        *b = p.get(i, y);
                    }
                }
            }
            _ => {
                for (id, bits) in self.stored_masks().into_iter().flatten() {
                    for (i, &col) in bits.by_y.iter().enumerate() {
                        for_each_bit(col, |y| out[i * CHUNK_SIZE + y] = id);
                    }
                }
            }
        }
        out
    }

    /// Index of `(x, y, z)` in [`Chunk::to_dense`]'s output: `(x * 32 + z) * 32 + y`.
    pub const fn dense_index(x: usize, y: usize, z: usize) -> usize {
        column_index(x, z) * CHUNK_SIZE + y
    }

    /// Checks the storage invariants. Mask form: both layouts hold the same set, sets
    /// disjoint and covering, counts right, no empty entry, no single-entry palette.
    /// Packed form: as many planes as the palette needs bits, no index past the palette,
    /// counts right, no empty entry, no repeated id, at least two entries. For tests.
    #[doc(hidden)]
    pub fn check_invariants(&self) -> std::result::Result<(), String> {
        match &self.storage {
            Storage::Uniform(_) => Ok(()),
            Storage::Masks(entries) => check_masks(entries),
            Storage::Packed(p) => check_packed(p),
        }
    }
}
