//! A 32³ chunk stored as a *bitmask palette*: for each block type present, the set of
//! blocks of that type as bits, kept in two layouts (see [`Occupancy`]). The sets of a chunk
//! are disjoint and cover all 32³ blocks. A chunk made of a single block type stores just
//! that id.
//!
//! Why this layout (measured by `cargo bench -p voxel-mesh`, section "storage"):
//! - The binary mesher works on exactly these bits, so a remesh needs no pass over 32 768
//!   block ids to build masks (that pass alone costs more than twice our whole mesh). The
//!   bits are the storage, so an edit keeps them correct by construction.
//! - Two layouts make every face direction a pair of adjacent rows ANDed together: x faces
//!   from the vertical columns, y and z faces from the rows along x. With one layout, the
//!   faces of one axis need 32×32 bit-matrix transposes at every remesh.
//! - Terrain is written a column run at a time ([`Chunk::fill_column`]).
//! - Memory is 8 KiB per block type present; uniform chunks (deep rock, open sky, open
//!   sea) cost nothing. On generated terrain this is about 70% of a `u16` per block; a
//!   packed-index palette would be smaller (3-4 bits a block) but would have to be unpacked
//!   into masks on every remesh.
//! - [`Chunk::get`] scans the palette, which is short in practice (4-9 types on terrain);
//!   random access is not on any hot path of the renderer.

use crate::{BlockId, Error, Result};

/// Edge length of a chunk in blocks.
pub const CHUNK_SIZE: usize = 32;
/// Number of columns (and of blocks in a chunk layer): 32².
pub const CHUNK_AREA: usize = CHUNK_SIZE * CHUNK_SIZE;
/// Number of blocks in a chunk: 32³.
pub const CHUNK_VOLUME: usize = CHUNK_AREA * CHUNK_SIZE;

/// 1024 rows of 32 bits: one bit per block of a chunk, in one of two layouts.
pub type ColumnMask = [u32; CHUNK_AREA];

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

const EMPTY: Occupancy = Occupancy {
    by_y: [0; CHUNK_AREA],
    by_x: [0; CHUNK_AREA],
};

#[derive(Clone, Debug)]
struct Entry {
    id: BlockId,
    count: u32,
    bits: Box<Occupancy>,
}

#[derive(Clone, Debug)]
enum Storage {
    Uniform(BlockId),
    Palette(Vec<Entry>),
}

/// 32×32×32 blocks. See the module docs for the storage.
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

/// Bits `y0..y1` of a column.
fn span_bits(y0: usize, y1: usize) -> u32 {
    debug_assert!(y0 <= y1 && y1 <= CHUNK_SIZE);
    let upto = |n: usize| if n >= 32 { u32::MAX } else { (1u32 << n) - 1 };
    upto(y1) & !upto(y0)
}

/// Calls `f(y)` for each set bit `y` of `bits`.
#[inline]
fn for_each_bit(mut bits: u32, mut f: impl FnMut(usize)) {
    while bits != 0 {
        f(bits.trailing_zeros() as usize);
        bits &= bits - 1;
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
            Storage::Palette(entries) => {
                let (i, bit) = (column_index(x, z), 1u32 << y);
                entries
                    .iter()
                    .find(|e| e.bits.by_y[i] & bit != 0)
                    .map_or(BlockId::AIR, |e| e.id)
            }
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

    /// Writes `id` at the set bits of column `(x, z)`, keeping both layouts in step, the
    /// sets disjoint and the counts right. Leaves empty entries behind: callers run
    /// [`Self::compact`] once they are done.
    fn fill_column_bits(&mut self, x: usize, z: usize, bits: u32, id: BlockId) {
        let i = column_index(x, z);
        let xbit = 1u32 << x;
        if let Storage::Uniform(u) = self.storage {
            if u == id {
                return;
            }
            self.storage = Storage::Palette(vec![Entry {
                id: u,
                count: CHUNK_VOLUME as u32,
                bits: Box::new(FULL.clone()),
            }]);
        }
        let Storage::Palette(entries) = &mut self.storage else {
            return;
        };
        let mut target = None;
        for (k, e) in entries.iter_mut().enumerate() {
            if e.id == id {
                target = Some(k);
                continue;
            }
            let taken = e.bits.by_y[i] & bits;
            if taken != 0 {
                e.bits.by_y[i] &= !bits;
                e.count -= taken.count_ones();
                for_each_bit(taken, |y| e.bits.by_x[row_index(y, z)] &= !xbit);
            }
        }
        let k = target.unwrap_or_else(|| {
            entries.push(Entry {
                id,
                count: 0,
                bits: Box::new(EMPTY),
            });
            entries.len() - 1
        });
        let e = &mut entries[k];
        let added = bits & !e.bits.by_y[i];
        e.count += added.count_ones();
        e.bits.by_y[i] |= bits;
        for_each_bit(added, |y| e.bits.by_x[row_index(y, z)] |= xbit);
    }

    /// Drops palette entries that no block uses; a palette of one entry becomes uniform.
    fn compact(&mut self) {
        if let Storage::Palette(entries) = &mut self.storage {
            entries.retain(|e| e.count > 0);
            if let [only] = entries.as_slice() {
                self.storage = Storage::Uniform(only.id);
            }
        }
    }

    /// `Some(id)` when every block of the chunk is `id`.
    pub fn as_uniform(&self) -> Option<BlockId> {
        match self.storage {
            Storage::Uniform(id) => Some(id),
            Storage::Palette(_) => None,
        }
    }

    /// The block types present with their bits, air included. The sets are disjoint and
    /// together cover the chunk.
    pub fn palette(&self) -> impl Iterator<Item = (BlockId, &Occupancy)> {
        let (uniform, entries) = match &self.storage {
            Storage::Uniform(id) => (Some((*id, &FULL)), &[][..]),
            Storage::Palette(entries) => (None, entries.as_slice()),
        };
        uniform
            .into_iter()
            .chain(entries.iter().map(|e| (e.id, &*e.bits)))
    }

    /// The bits of `id`, or `None` when the chunk holds no such block.
    pub fn occupancy(&self, id: BlockId) -> Option<&Occupancy> {
        self.palette().find(|(i, _)| *i == id).map(|(_, m)| m)
    }

    /// Number of blocks of type `id`.
    pub fn count(&self, id: BlockId) -> usize {
        match &self.storage {
            Storage::Uniform(u) => usize::from(*u == id) * CHUNK_VOLUME,
            Storage::Palette(entries) => entries
                .iter()
                .find(|e| e.id == id)
                .map_or(0, |e| e.count as usize),
        }
    }

    /// Number of distinct block types present.
    pub fn palette_len(&self) -> usize {
        match &self.storage {
            Storage::Uniform(_) => 1,
            Storage::Palette(entries) => entries.len(),
        }
    }

    /// Heap and inline bytes this chunk occupies.
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of::<Self>()
            + match &self.storage {
                Storage::Uniform(_) => 0,
                Storage::Palette(entries) => {
                    entries.capacity() * std::mem::size_of::<Entry>()
                        + entries.len() * std::mem::size_of::<Occupancy>()
                }
            }
    }

    /// The chunk as one id per block, indexed by [`Chunk::dense_index`]. For tools, tests
    /// and peer meshers that want a dense array.
    pub fn to_dense(&self) -> Vec<BlockId> {
        let mut out = vec![BlockId::AIR; CHUNK_VOLUME];
        for (id, bits) in self.palette() {
            for (i, &col) in bits.by_y.iter().enumerate() {
                for_each_bit(col, |y| out[i * CHUNK_SIZE + y] = id);
            }
        }
        out
    }

    /// Index of `(x, y, z)` in [`Chunk::to_dense`]'s output: `(x * 32 + z) * 32 + y`.
    pub const fn dense_index(x: usize, y: usize, z: usize) -> usize {
        column_index(x, z) * CHUNK_SIZE + y
    }

    /// Checks the storage invariants: both layouts hold the same set, sets disjoint and
    /// covering, counts right, no empty entry, no single-entry palette. For tests.
    #[doc(hidden)]
    pub fn check_invariants(&self) -> std::result::Result<(), String> {
        let Storage::Palette(entries) = &self.storage else {
            return Ok(());
        };
        if entries.len() < 2 {
            return Err(format!("palette of {} entries", entries.len()));
        }
        for (k, e) in entries.iter().enumerate() {
            let n: u32 = e.bits.by_y.iter().map(|c| c.count_ones()).sum();
            if n != e.count || n == 0 {
                return Err(format!("entry {k} ({}) counts {} holds {n}", e.id, e.count));
            }
            if entries[k + 1..].iter().any(|f| f.id == e.id) {
                return Err(format!("id {} twice", e.id));
            }
            for x in 0..CHUNK_SIZE {
                for y in 0..CHUNK_SIZE {
                    for z in 0..CHUNK_SIZE {
                        let a = e.bits.by_y[column_index(x, z)] >> y & 1;
                        let b = e.bits.by_x[row_index(y, z)] >> x & 1;
                        if a != b {
                            return Err(format!("layouts differ at ({x}, {y}, {z})"));
                        }
                    }
                }
            }
        }
        for i in 0..CHUNK_AREA {
            let mut union = 0u32;
            for e in entries {
                if union & e.bits.by_y[i] != 0 {
                    return Err(format!("sets overlap in column {i}"));
                }
                union |= e.bits.by_y[i];
            }
            if union != u32::MAX {
                return Err(format!("column {i} not covered: {union:#x}"));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::blocks::*;

    #[test]
    fn set_and_get_round_trip() {
        let mut c = Chunk::default();
        assert_eq!(c.set(1, 2, 3, STONE).unwrap(), AIR);
        assert_eq!(c.get(1, 2, 3).unwrap(), STONE);
        assert_eq!(c.get(3, 2, 1).unwrap(), AIR);
        assert_eq!(c.set(1, 2, 3, WATER).unwrap(), STONE);
        assert_eq!(c.count(WATER), 1);
        assert_eq!(c.count(STONE), 0);
        assert_eq!(c.palette_len(), 2);
        c.check_invariants().unwrap();
    }

    #[test]
    fn out_of_range_is_an_error() {
        let mut c = Chunk::default();
        assert_eq!(
            c.get(32, 0, 0),
            Err(Error::LocalOutOfRange { x: 32, y: 0, z: 0 })
        );
        assert!(c.set(0, usize::MAX, 0, STONE).is_err());
        assert!(c.fill_column(0, 0, 0..33, STONE).is_err());
        assert!(c.fill_column(0, 32, 0..3, STONE).is_err());
        assert!(c.fill_box([0; 3], [0, 0, 32], STONE).is_err());
        assert_eq!(c.as_uniform(), Some(AIR));
    }

    #[test]
    fn uniform_chunks_store_one_value_and_collapse_back() {
        let mut c = Chunk::uniform(STONE);
        assert_eq!(c.memory_bytes(), std::mem::size_of::<Chunk>());
        c.set(5, 5, 5, AIR).unwrap();
        assert_eq!(c.as_uniform(), None);
        c.check_invariants().unwrap();
        c.set(5, 5, 5, STONE).unwrap();
        assert_eq!(c.as_uniform(), Some(STONE));
        c.fill_box([0; 3], [31; 3], WATER).unwrap();
        assert_eq!(c.as_uniform(), Some(WATER));
    }

    #[test]
    fn column_fills_keep_masks_exact() {
        let mut c = Chunk::default();
        c.fill_column(4, 7, 0..20, STONE).unwrap();
        c.fill_column(4, 7, 18..25, WATER).unwrap();
        c.fill_column(4, 7, 3..3, SAND).unwrap();
        assert_eq!(
            c.occupancy(STONE).unwrap().by_y[column_index(4, 7)],
            (1 << 18) - 1
        );
        assert_eq!(
            c.occupancy(WATER).unwrap().by_y[column_index(4, 7)],
            ((1 << 25) - 1) & !((1 << 18) - 1)
        );
        assert!(c.occupancy(SAND).is_none());
        assert_eq!(c.count(STONE), 18);
        c.check_invariants().unwrap();
        c.fill_column(4, 7, 0..32, AIR).unwrap();
        assert_eq!(c.as_uniform(), Some(AIR));
    }

    #[test]
    fn random_edits_match_a_dense_model() {
        // A tiny xorshift so the test needs no dependency and is the same on every run.
        let mut s = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
        let mut c = Chunk::default();
        let mut model = vec![AIR; CHUNK_VOLUME];
        for step in 0..20_000 {
            let r = next();
            let (x, y, z) = (
                r as usize % 32,
                (r >> 8) as usize % 32,
                (r >> 16) as usize % 32,
            );
            let id = BlockId((r >> 24) as u16 % 5);
            if step % 50 == 0 {
                let y1 = (y + (r >> 32) as usize % 8).min(32);
                c.fill_column(x, z, y..y1, id).unwrap();
                for yy in y..y1 {
                    model[Chunk::dense_index(x, yy, z)] = id;
                }
            } else {
                c.set(x, y, z, id).unwrap();
                model[Chunk::dense_index(x, y, z)] = id;
            }
        }
        c.check_invariants().unwrap();
        assert_eq!(c.to_dense(), model);
    }
}
