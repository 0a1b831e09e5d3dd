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

use std::borrow::Cow;

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

const EMPTY: Occupancy = Occupancy {
    by_y: [0; CHUNK_AREA],
    by_x: [0; CHUNK_AREA],
};

/// A block type of the mask form.
#[derive(Clone, Debug)]
struct Entry {
    id: BlockId,
    count: u32,
    bits: Box<Occupancy>,
}

/// A block type of the packed form.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Slot {
    id: BlockId,
    count: u32,
}

/// The packed form: a palette and the bit planes of each block's index in it.
#[derive(Clone, Debug)]
struct Packed {
    /// Block types present, none empty, at least two.
    palette: Vec<Slot>,
    /// [`planes_for`]`(palette.len())` planes: bit `j` of the palette index of block
    /// `(x, y, z)` is bit `y` of `planes[j][column_index(x, z)]`. No index reaches
    /// `palette.len()`.
    planes: Vec<ColumnMask>,
}

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

fn or_into(dst: &mut [u32], src: &[u32]) {
    dst.iter_mut().zip(src).for_each(|(d, s)| *d |= s);
}

/// Number of bit planes for a palette of `len` entries: `ceil(log2(len))`, at least 1.
fn planes_for(len: usize) -> usize {
    (usize::BITS - len.saturating_sub(1).leading_zeros()).max(1) as usize
}

/// What to XOR plane `j` with so that it reads 1 where bit `j` of an index equals that of
/// `k`: all ones where bit `j` of `k` is clear.
#[inline]
fn inverter(k: usize, j: usize) -> u32 {
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

/// A block type's masks in a [`MaskBuffer`].
type Built = (BlockId, Box<Occupancy>);

/// One step of a bit-matrix transpose, on rows `a` and `b` that are `J` rows apart: bit
/// `c + J` of `a` and bit `c` of `b` change places for every column `c` selected by `m`
/// (those whose bit `J` is clear).
#[inline(always)]
fn swap_bits<const J: u32>(a: &mut u32, b: &mut u32, m: u32) {
    let t = ((*a >> J) ^ *b) & m;
    *a ^= t << J;
    *b ^= t;
}

/// Transposes, for all 32 values of z at once, the 32×32 bit matrix whose row `x` is word
/// `x * 32 + z` (bits y) of `src` into rows `y` at words `y * 32 + z` (bits x) of `dst`:
/// turns a mask in the `by_y` layout into the same set in the `by_x` layout.
///
/// The classic recursive block swap (halves, quarters, ... of the matrix: five steps, one
/// per bit of the row index), where each row operation runs over the 32 values of z,
/// contiguous in memory, so that it vectorises. Two passes over memory: the first does the
/// steps of row bits 4, 3 and 2 on groups of 8 rows held in registers, the second those of
/// bits 1 and 0 on groups of 4 rows.
fn transpose_layout_into(src: &ColumnMask, dst: &mut ColumnMask) {
    let (s, _) = src.as_chunks::<CHUNK_SIZE>();
    let (d, _) = dst.as_chunks_mut::<CHUNK_SIZE>();
    for base in 0..4 {
        for z in 0..CHUNK_SIZE {
            let mut v: [u32; 8] = std::array::from_fn(|i| s[base + 4 * i][z]);
            let [v0, v1, v2, v3, v4, v5, v6, v7] = &mut v;
            swap_bits::<16>(v0, v4, 0x0000_ffff);
            swap_bits::<16>(v1, v5, 0x0000_ffff);
            swap_bits::<16>(v2, v6, 0x0000_ffff);
            swap_bits::<16>(v3, v7, 0x0000_ffff);
            swap_bits::<8>(v0, v2, 0x00ff_00ff);
            swap_bits::<8>(v1, v3, 0x00ff_00ff);
            swap_bits::<8>(v4, v6, 0x00ff_00ff);
            swap_bits::<8>(v5, v7, 0x00ff_00ff);
            swap_bits::<4>(v0, v1, 0x0f0f_0f0f);
            swap_bits::<4>(v2, v3, 0x0f0f_0f0f);
            swap_bits::<4>(v4, v5, 0x0f0f_0f0f);
            swap_bits::<4>(v6, v7, 0x0f0f_0f0f);
            for (i, v) in v.into_iter().enumerate() {
                d[base + 4 * i][z] = v;
            }
        }
    }
    for group in d.chunks_exact_mut(4) {
        let [r0, r1, r2, r3] = group else {
            continue;
        };
        for (((a, b), c), e) in r0.iter_mut().zip(r1.iter_mut()).zip(r2.iter_mut()).zip(r3) {
            swap_bits::<2>(a, c, 0x3333_3333);
            swap_bits::<2>(b, e, 0x3333_3333);
            swap_bits::<1>(a, b, 0x5555_5555);
            swap_bits::<1>(c, e, 0x5555_5555);
        }
    }
}

/// Transposes one 32×32 bit matrix: bit `j` of row `i` becomes bit `i` of row `j`.
fn transpose32(a: &mut LayerMask) {
    let mut j = 16;
    let mut m: u32 = 0x0000_ffff;
    while j != 0 {
        for k in (0..CHUNK_SIZE).filter(|k| k & j == 0) {
            let t = ((a[k] >> j) ^ a[k + j]) & m;
            a[k] ^= t << j;
            a[k + j] ^= t;
        }
        j >>= 1;
        m ^= m << j;
    }
}

/// The layer of `bits` on `side` of the chunk, in that axis's plane layout (see
/// [`Chunk::side_layers`]).
fn side_layer(bits: &Occupancy, side: Face) -> LayerMask {
    let i = side_index(side);
    let rows =
        |mask: &ColumnMask| -> LayerMask { std::array::from_fn(|r| mask[i * CHUNK_SIZE + r]) };
    match side.axis() {
        0 => rows(&bits.by_y),
        1 => rows(&bits.by_x),
        _ => std::array::from_fn(|y| bits.by_x[row_index(y, i)]),
    }
}

/// The layer of one column plane on `side`, in that axis's plane layout.
fn plane_side_layer(plane: &ColumnMask, side: Face) -> LayerMask {
    let i = side_index(side);
    match side.axis() {
        0 => std::array::from_fn(|z| plane[column_index(i, z)]),
        1 => {
            let mut out = [0; CHUNK_SIZE];
            let (cols, _) = plane.as_chunks::<CHUNK_SIZE>();
            for (x, col) in cols.iter().enumerate() {
                out.iter_mut()
                    .zip(col)
                    .for_each(|(o, c)| *o |= (c >> i & 1) << x);
            }
            out
        }
        _ => {
            let mut m: LayerMask = std::array::from_fn(|x| plane[column_index(x, i)]);
            transpose32(&mut m);
            m
        }
    }
}

/// The coordinate of the layer on `side`: 31 on a positive side, 0 on a negative one.
fn side_index(side: Face) -> usize {
    if side.is_positive() {
        CHUNK_SIZE - 1
    } else {
        0
    }
}

/// Per-type masks built from a chunk by [`Chunk::build_masks`], with the scratch memory
/// that building them takes; kept between calls so that a remesh allocates nothing.
#[derive(Clone, Debug, Default)]
pub struct MaskBuffer {
    /// The first `len` entries are valid; the others keep their allocation.
    entries: Vec<Built>,
    len: usize,
    /// A packed chunk's planes, transposed to the row layout.
    rows: Vec<ColumnMask>,
    /// The palette index of each entry, for a packed chunk.
    codes: Vec<usize>,
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
    fn push(&mut self, id: BlockId) -> &mut Occupancy {
        if self.len == self.entries.len() {
            self.entries.push((id, Box::new(EMPTY)));
        }
        let slot = &mut self.entries[self.len];
        slot.0 = id;
        self.len += 1;
        &mut slot.1
    }
}

impl Packed {
    fn from_entries(entries: &[Entry]) -> Self {
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
    fn build_masks(&self, out: &mut MaskBuffer, mut want: impl FnMut(BlockId) -> bool) {
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

    fn to_entries(&self) -> Vec<Entry> {
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

    fn get(&self, i: usize, y: usize) -> BlockId {
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
    fn fill(&mut self, i: usize, bits: u32, id: BlockId) {
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
    fn compact(&mut self) {
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

/// Writes `id` at the set bits of column `(x, z)` of a mask form, keeping both layouts in
/// step, the sets disjoint and the counts right. Leaves empty entries behind.
fn fill_masks(entries: &mut Vec<Entry>, x: usize, z: usize, bits: u32, id: BlockId) {
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

fn check_masks(entries: &[Entry]) -> std::result::Result<(), String> {
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

fn check_packed(p: &Packed) -> std::result::Result<(), String> {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::blocks::*;

    /// A tiny xorshift, so the tests need no dependency and run the same every time.
    fn xorshift(seed: u64) -> impl FnMut() -> u64 {
        let mut s = seed;
        move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        }
    }

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
        let mut next = xorshift(0x2545_f491_4f6c_dd1d);
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

    /// A chunk of several types from a seed: boxes, columns and single blocks of up to
    /// `types` ids (1..=types), on air.
    fn varied_chunk(seed: u64, types: u16) -> Chunk {
        let mut next = xorshift(seed | 1);
        let mut c = Chunk::default();
        for step in 0..400 {
            let r = next();
            let p = [r % 32, (r >> 8) % 32, (r >> 16) % 32].map(|v| v as usize);
            let id = BlockId((r >> 24) as u16 % (types + 1));
            if step % 4 == 0 {
                let q = [(r >> 32) % 12, (r >> 40) % 12, (r >> 48) % 12]
                    .map(|v| v as usize)
                    .iter()
                    .zip(&p)
                    .map(|(e, p)| (p + e).min(31))
                    .collect::<Vec<_>>();
                c.fill_box(p, [q[0], q[1], q[2]], id).unwrap();
            } else {
                c.set(p[0], p[1], p[2], id).unwrap();
            }
        }
        c
    }

    fn masks_by_id(c: &Chunk) -> Vec<(BlockId, Occupancy)> {
        let mut v: Vec<_> = c
            .stored_masks()
            .unwrap()
            .map(|(id, m)| (id, m.clone()))
            .collect();
        v.sort_by_key(|(id, _)| *id);
        v
    }

    #[test]
    fn plane_counts_follow_the_palette() {
        let want = [
            (2, 1),
            (3, 2),
            (4, 2),
            (5, 3),
            (8, 3),
            (9, 4),
            (16, 4),
            (17, 5),
        ];
        for (len, planes) in want {
            assert_eq!(planes_for(len), planes, "{len} entries");
        }
    }

    #[test]
    fn the_layout_transpose_turns_columns_into_rows() {
        let c = varied_chunk(7, 6);
        for (_, m) in c.stored_masks().unwrap() {
            let mut t = [0; CHUNK_AREA];
            transpose_layout_into(&m.by_y, &mut t);
            assert_eq!(t, m.by_x);
        }
        let mut a: LayerMask = std::array::from_fn(|i| (i as u32).wrapping_mul(0x9e37_79b9));
        let b = a;
        transpose32(&mut a);
        for (i, row) in b.iter().enumerate() {
            for (j, col) in a.iter().enumerate() {
                assert_eq!(col >> i & 1, row >> j & 1);
            }
        }
    }

    #[test]
    fn pack_and_unpack_keep_every_block() {
        // Up to 21 types: five planes, past the vectorised decoding of up to four.
        for (seed, types) in [
            (1, 1),
            (2, 2),
            (3, 3),
            (4, 4),
            (5, 7),
            (6, 8),
            (7, 12),
            (8, 20),
        ] {
            let c = varied_chunk(seed, types);
            assert!(types < 20 || c.palette_len() > 16, "five planes");
            let mut p = c.clone();
            p.pack();
            assert!(p.is_packed() || c.as_uniform().is_some());
            p.check_invariants().unwrap();
            assert_eq!(p.to_dense(), c.to_dense(), "seed {seed}");
            assert_eq!(
                p.palette().collect::<Vec<_>>(),
                c.palette().collect::<Vec<_>>()
            );
            assert_eq!(p.palette_len(), c.palette_len());
            for id in 0..=types {
                assert_eq!(p.count(BlockId(id)), c.count(BlockId(id)));
                assert_eq!(p.occupancy(BlockId(id)), c.occupancy(BlockId(id)));
            }
            for (x, y, z) in [(0, 0, 0), (31, 31, 31), (5, 17, 30), (30, 2, 9)] {
                assert_eq!(p.get(x, y, z), c.get(x, y, z));
            }
            if c.as_uniform().is_none() {
                let bits = planes_for(c.palette_len());
                let data = bits * CHUNK_VOLUME / 8;
                assert!(p.memory_bytes() >= data && p.memory_bytes() < data + 256);
                assert!(p.memory_bytes() * 2 < c.memory_bytes());
            }
            p.pack();
            p.unpack();
            assert!(!p.is_packed());
            p.check_invariants().unwrap();
            if c.as_uniform().is_none() {
                assert_eq!(masks_by_id(&p), masks_by_id(&c));
            }
            p.unpack();
            assert_eq!(p.to_dense(), c.to_dense());
        }
    }

    #[test]
    fn built_masks_and_side_layers_agree_across_forms() {
        for types in [9, 20] {
            let c = varied_chunk(11, types);
            assert!(
                c.palette_len() > 8 + 8 * usize::from(types > 9),
                "more planes than 3, 4"
            );
            built_masks_and_side_layers_agree(&c);
        }
    }

    fn built_masks_and_side_layers_agree(c: &Chunk) {
        let c = c.clone();
        let mut p = c.clone();
        p.pack();
        assert!(p.stored_masks().is_none());
        let mut buf = MaskBuffer::new();
        for chunk in [&c, &p] {
            chunk.build_masks(&mut buf, |id| id != BlockId::AIR);
            let want: Vec<_> = c
                .stored_masks()
                .unwrap()
                .filter(|(id, _)| *id != BlockId::AIR)
                .collect();
            assert_eq!(buf.len(), want.len());
            for ((a, ma), (b, mb)) in buf.iter().zip(want) {
                assert_eq!((a, ma), (b, mb));
            }
        }
        // Reused for a chunk of fewer types: only those are held.
        Chunk::uniform(STONE).build_masks(&mut buf, |_| true);
        assert_eq!(buf.iter().map(|(id, _)| id).collect::<Vec<_>>(), [STONE]);
        assert_eq!(buf.iter().next().unwrap().1, &FULL);
        let dense = c.to_dense();
        let (mut a, mut b) = (Vec::new(), Vec::new());
        for side in Face::ALL {
            c.side_layers(side, &mut a, |_| true);
            p.side_layers(side, &mut b, |_| true);
            let mut no_air = Vec::new();
            p.side_layers(side, &mut no_air, |id| id != AIR);
            assert_eq!(no_air.len() + 1, a.len());
            assert_eq!(a, b, "{side:?}");
            let l = side_index(side);
            for (id, rows) in &a {
                for (r, row) in rows.iter().enumerate() {
                    for bit in 0..32 {
                        let [x, y, z] = match side.axis() {
                            0 => [l, bit, r],
                            1 => [bit, l, r],
                            _ => [bit, r, l],
                        };
                        let here = dense[Chunk::dense_index(x, y, z)] == *id;
                        assert_eq!(row >> bit & 1 == 1, here, "{side:?} {x} {y} {z}");
                    }
                }
            }
        }
        Chunk::uniform(WATER).side_layers(Face::NegY, &mut a, |_| true);
        assert_eq!(a, vec![(WATER, [u32::MAX; 32])]);
    }

    #[test]
    fn packed_planes_grow_and_narrow_with_the_palette() {
        let mut c = Chunk::default();
        c.set(0, 0, 0, STONE).unwrap();
        c.pack();
        c.check_invariants().unwrap();
        let one_plane = c.memory_bytes();
        // Types 2..=8 (ids up to 8): 9 types need 4 planes.
        for i in 2..=8u16 {
            c.set(usize::from(i), 3, 4, BlockId(i)).unwrap();
            c.check_invariants().unwrap();
        }
        assert!(c.is_packed());
        assert_eq!(c.palette_len(), 9);
        assert!(c.memory_bytes() >= one_plane + 3 * 4096);
        // Remove all but air and one type: back to one plane.
        for i in 2..=8 {
            c.set(i, 3, 4, AIR).unwrap();
            c.check_invariants().unwrap();
        }
        assert_eq!(c.palette_len(), 2);
        assert!(c.memory_bytes() <= one_plane + 256, "{}", c.memory_bytes());
        // Removing a type from the middle of the palette relabels the last one.
        c.fill_box([0, 10, 0], [3, 12, 3], WATER).unwrap();
        c.fill_box([5, 10, 5], [6, 12, 6], GLASS).unwrap();
        c.set(0, 0, 0, AIR).unwrap();
        c.check_invariants().unwrap();
        assert_eq!(c.count(STONE), 0);
        assert_eq!(c.get(0, 11, 0).unwrap(), WATER);
        assert_eq!(c.get(6, 12, 6).unwrap(), GLASS);
        assert_eq!(c.count(GLASS), 2 * 3 * 2);
        // A packed chunk filled with one type becomes uniform.
        c.fill_box([0; 3], [31; 3], SAND).unwrap();
        assert_eq!(c.as_uniform(), Some(SAND));
    }

    #[test]
    fn random_edits_of_packed_chunks_match_a_dense_model() {
        let mut next = xorshift(0x1234_5678_9abc_def1);
        let mut c = varied_chunk(99, 6);
        let mut model = c.to_dense();
        c.pack();
        for step in 0..20_000 {
            let r = next();
            let (x, y, z) = (
                r as usize % 32,
                (r >> 8) as usize % 32,
                (r >> 16) as usize % 32,
            );
            // Up to 11 types at once, so that the planes grow and narrow.
            let id = BlockId((r >> 24) as u16 % if step % 5000 < 2500 { 3 } else { 11 });
            if step % 50 == 0 {
                let y1 = (y + (r >> 32) as usize % 8).min(32);
                c.fill_column(x, z, y..y1, id).unwrap();
                for yy in y..y1 {
                    model[Chunk::dense_index(x, yy, z)] = id;
                }
            } else if step % 997 == 0 {
                let m = [x, y, z].map(|v| (v + 6).min(31));
                c.fill_box([x, y, z], m, id).unwrap();
                for xx in x..=m[0] {
                    for yy in y..=m[1] {
                        for zz in z..=m[2] {
                            model[Chunk::dense_index(xx, yy, zz)] = id;
                        }
                    }
                }
            } else {
                assert_eq!(
                    c.set(x, y, z, id).unwrap(),
                    model[Chunk::dense_index(x, y, z)]
                );
                model[Chunk::dense_index(x, y, z)] = id;
            }
            if step % 1000 == 0 {
                c.check_invariants().unwrap();
                if c.as_uniform().is_none() {
                    assert!(c.is_packed(), "edits keep the packed form");
                }
            }
        }
        c.check_invariants().unwrap();
        assert_eq!(c.to_dense(), model);
    }
}
