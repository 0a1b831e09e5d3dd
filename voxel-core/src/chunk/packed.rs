//! The packed form: a palette of the types present and, per block, its palette index in
//! `ceil(log2(n))` bit planes in the column layout.

use super::bits::{or_into, transpose_layout_into};
use super::masks::{Entry, MaskBuffer};
use super::{CHUNK_AREA, CHUNK_VOLUME, ColumnMask};
use crate::BlockId;

/// A block type of the packed form.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Slot {
    pub(super) id: BlockId,
    pub(super) count: u32,
}

/// The packed form: a palette and the bit planes of each block's index in it.
#[derive(Clone, Debug)]
pub(super) struct Packed {
    /// Block types present, none empty, at least two.
    pub(super) palette: Vec<Slot>,
    /// [`planes_for`]`(palette.len())` planes: bit `j` of the palette index of block
    /// `(x, y, z)` is bit `y` of `planes[j][column_index(x, z)]`. No index reaches
    /// `palette.len()`.
    pub(super) planes: Vec<ColumnMask>,
}

/// Number of bit planes for a palette of `len` entries: `ceil(log2(len))`, at least 1.
pub(super) fn planes_for(len: usize) -> usize {
    (usize::BITS - len.saturating_sub(1).leading_zeros()).max(1) as usize
}

/// What to XOR plane `j` with so that it reads 1 where bit `j` of an index equals that of
/// `k`: all ones where bit `j` of `k` is clear.
#[inline]
pub(super) fn inverter(k: usize, j: usize) -> u32 {
    if k >> j & 1 == 1 { 0 } else { u32::MAX }
}

/// The bits of word `w` whose palette index is `k`.
#[inline]
fn index_word(planes: &[ColumnMask], k: usize, w: usize) -> u32 {
    planes
        .iter()
        .enumerate()
        .fold(u32::MAX, |m, (j, p)| m & (p[w] ^ inverter(k, j)))
}

/// Writes into `out` the set of blocks whose palette index is `k`, in the layout of
/// `planes` (the stored column planes, or their transposes for the row layout): one AND of
/// plane `j` or its complement per bit `j` of `k`, in one vectorised pass when there are
/// at most four planes (16 types).
fn decode_index(planes: &[ColumnMask], k: usize, out: &mut ColumnMask) {
    fn fixed<const B: usize>(planes: &[ColumnMask; B], k: usize, out: &mut ColumnMask) {
        let inv: [u32; B] = std::array::from_fn(|j| inverter(k, j));
        for (w, o) in out.iter_mut().enumerate() {
            let mut m = u32::MAX;
            for j in 0..B {
                m &= planes[j][w] ^ inv[j];
            }
            *o = m;
        }
    }
    if let Ok(p) = <&[ColumnMask; 1]>::try_from(planes) {
        fixed(p, k, out);
    } else if let Ok(p) = <&[ColumnMask; 2]>::try_from(planes) {
        fixed(p, k, out);
    } else if let Ok(p) = <&[ColumnMask; 3]>::try_from(planes) {
        fixed(p, k, out);
    } else if let Ok(p) = <&[ColumnMask; 4]>::try_from(planes) {
        fixed(p, k, out);
    } else {
        out.fill(u32::MAX);
        for (j, p) in planes.iter().enumerate() {
            let inv = inverter(k, j);
            out.iter_mut().zip(p).for_each(|(o, p)| *o &= p ^ inv);
        }
    }
}

impl Packed {
    pub(super) fn from_entries(entries: &[Entry]) -> Self {
        let mut planes = vec![[0; CHUNK_AREA]; planes_for(entries.len())];
        for (k, e) in entries.iter().enumerate() {
            for (j, plane) in planes.iter_mut().enumerate() {
                if k >> j & 1 == 1 {
                    or_into(plane, &e.bits.by_y);
                }
            }
        }
        Self {
            palette: entries
                .iter()
                .map(|e| Slot {
                    id: e.id,
                    count: e.count,
                })
                .collect(),
            planes,
        }
    }

    /// The planes transposed to the row layout, into `rows` (resized to fit).
    fn transposed_into(&self, rows: &mut Vec<ColumnMask>) {
        rows.resize(self.planes.len(), [0; CHUNK_AREA]);
        for (src, dst) in self.planes.iter().zip(rows.iter_mut()) {
            transpose_layout_into(src, dst);
        }
    }

    /// The masks of the palette entries that `want` selects, into `out`.
    pub(super) fn build_masks(&self, out: &mut MaskBuffer, mut want: impl FnMut(BlockId) -> bool) {
        out.clear();
        out.codes.clear();
        for (k, s) in self.palette.iter().enumerate() {
            if want(s.id) {
                out.push(s.id);
                out.codes.push(k);
            }
        }
        if out.is_empty() {
            return;
        }
        self.transposed_into(&mut out.rows);
        let MaskBuffer {
            entries,
            len,
            rows,
            codes,
        } = out;
        for (&k, (_, m)) in codes.iter().zip(&mut entries[..*len]) {
            decode_index(&self.planes, k, &mut m.by_y);
            decode_index(rows, k, &mut m.by_x);
        }
    }

    pub(super) fn to_entries(&self) -> Vec<Entry> {
        let mut buf = MaskBuffer::new();
        self.build_masks(&mut buf, |_| true);
        buf.entries
            .into_iter()
            .zip(&self.palette)
            .map(|((id, bits), s)| Entry {
                id,
                count: s.count,
                bits,
            })
            .collect()
    }

    pub(super) fn get(&self, i: usize, y: usize) -> BlockId {
        let k = self
            .planes
            .iter()
            .enumerate()
            .fold(0, |k, (j, p)| k | ((p[i] >> y & 1) as usize) << j);
        self.palette[k].id
    }

    /// Writes `id` at the set bits of column word `i`, keeping the counts right. Adds `id`
    /// to the palette (and a plane when the indices need one more bit) if it is new; leaves
    /// emptied entries behind for [`Self::compact`].
    pub(super) fn fill(&mut self, i: usize, bits: u32, id: BlockId) {
        let k = match self.palette.iter().position(|s| s.id == id) {
            Some(k) => k,
            None => {
                self.palette.push(Slot { id, count: 0 });
                if self.palette.len() > 1 << self.planes.len() {
                    // All indices so far have a 0 in the new top bit.
                    self.planes.reserve_exact(1);
                    self.planes.push([0; CHUNK_AREA]);
                }
                self.palette.len() - 1
            }
        };
        for (k2, s) in self.palette.iter_mut().enumerate() {
            let have = index_word(&self.planes, k2, i) & bits;
            if k2 == k {
                s.count += (bits & !have).count_ones();
            } else {
                s.count -= have.count_ones();
            }
        }
        for (j, p) in self.planes.iter_mut().enumerate() {
            if k >> j & 1 == 1 {
                p[i] |= bits;
            } else {
                p[i] &= !bits;
            }
        }
    }

    /// Drops the entries no block uses: the last entry takes the place of each (its blocks
    /// are relabelled), and the planes narrow when fewer bits suffice.
    pub(super) fn compact(&mut self) {
        while let Some(r) = self.palette.iter().position(|s| s.count == 0) {
            let last = self.palette.len() - 1;
            if r != last {
                for w in 0..CHUNK_AREA {
                    let m = index_word(&self.planes, last, w);
                    if m != 0 {
                        for (j, p) in self.planes.iter_mut().enumerate() {
                            if r >> j & 1 == 1 {
                                p[w] |= m;
                            } else {
                                p[w] &= !m;
                            }
                        }
                    }
                }
                self.palette.swap(r, last);
            }
            self.palette.pop();
            let need = planes_for(self.palette.len());
            if self.planes.len() > need {
                // Every index is below 2^need now: the planes above are all zero.
                self.planes.truncate(need);
                self.planes.shrink_to_fit();
            }
        }
    }
}

pub(super) fn check_packed(p: &Packed) -> std::result::Result<(), String> {
    let n = p.palette.len();
    if n < 2 {
        return Err(format!("packed palette of {n} entries"));
    }
    if p.planes.len() != planes_for(n) {
        return Err(format!("{} planes for {n} entries", p.planes.len()));
    }
    for (k, s) in p.palette.iter().enumerate() {
        let held: u32 = (0..CHUNK_AREA)
            .map(|w| index_word(&p.planes, k, w).count_ones())
            .sum();
        if held != s.count || held == 0 {
            return Err(format!(
                "slot {k} ({}) counts {} holds {held}",
                s.id, s.count
            ));
        }
        if p.palette[k + 1..].iter().any(|t| t.id == s.id) {
            return Err(format!("id {} twice", s.id));
        }
    }
    // The counts of valid indices add up to the volume exactly when no index is past the
    // palette.
    let total: u32 = p.palette.iter().map(|s| s.count).sum();
    if total as usize != CHUNK_VOLUME {
        return Err(format!("indices past the palette: {total} blocks counted"));
    }
    Ok(())
}
