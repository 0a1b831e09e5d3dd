//! The mask form: per block type present, its set of blocks as bits in both layouts; and
//! [`MaskBuffer`], the masks a chunk in any form builds for the mesher.

use super::bits::for_each_bit;
use super::{CHUNK_AREA, CHUNK_SIZE, ColumnMask, Occupancy, column_index, row_index};
use crate::BlockId;

/// A block type of the mask form.
#[derive(Clone, Debug)]
pub(super) struct Entry {
    pub(super) id: BlockId,
    pub(super) count: u32,
    pub(super) bits: Box<Occupancy>,
}

/// No block.
pub(super) const EMPTY: Occupancy = Occupancy {
    by_y: [0; CHUNK_AREA],
    by_x: [0; CHUNK_AREA],
};

/// A block type's masks in a [`MaskBuffer`].
type Built = (BlockId, Box<Occupancy>);

/// Per-type masks built from a chunk by [`Chunk::build_masks`](super::Chunk::build_masks),
/// with the scratch memory that building them takes; kept between calls so that a remesh
/// allocates nothing.
#[derive(Clone, Debug, Default)]
pub struct MaskBuffer {
    /// The first `len` entries are valid; the others keep their allocation.
    pub(super) entries: Vec<Built>,
    pub(super) len: usize,
    /// A packed chunk's planes, transposed to the row layout.
    pub(super) rows: Vec<ColumnMask>,
    /// The palette index of each entry, for a packed chunk.
    pub(super) codes: Vec<usize>,
}

impl MaskBuffer {
    /// An empty buffer.
    pub fn new() -> Self {
        Self::default()
    }

    /// Forgets the masks (keeping the memory).
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// Number of block types held.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether no block type is held.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The block types held with their masks, in palette order.
    pub fn iter(&self) -> impl Iterator<Item = (BlockId, &Occupancy)> {
        self.entries[..self.len].iter().map(|(id, m)| (*id, &**m))
    }

    /// Heap and inline bytes of the buffer, spare capacity included.
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of::<Self>()
            + self.entries.capacity() * std::mem::size_of::<(BlockId, Box<Occupancy>)>()
            + self.entries.len() * std::mem::size_of::<Occupancy>()
            + self.rows.capacity() * std::mem::size_of::<ColumnMask>()
    }

    /// A slot for the masks of `id` (its contents stale), reusing an allocation if any.
    pub(super) fn push(&mut self, id: BlockId) -> &mut Occupancy {
        if self.len == self.entries.len() {
            self.entries.push((id, Box::new(EMPTY)));
        }
        let slot = &mut self.entries[self.len];
        slot.0 = id;
        self.len += 1;
        &mut slot.1
    }
}

/// Writes `id` at the set bits of column `(x, z)` of a mask form, keeping both layouts in
/// step, the sets disjoint and the counts right. Leaves empty entries behind.
pub(super) fn fill_masks(entries: &mut Vec<Entry>, x: usize, z: usize, bits: u32, id: BlockId) {
    let i = column_index(x, z);
    let xbit = 1u32 << x;
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

pub(super) fn check_masks(entries: &[Entry]) -> std::result::Result<(), String> {
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
