//! Bit tricks on a chunk's masks: runs of a column, set bits, the transpose between the
//! column and row layouts, and the layer of a mask on one side of the chunk.

use super::{CHUNK_SIZE, ColumnMask, LayerMask, Occupancy, column_index, row_index};
use crate::Face;

/// Bits `y0..y1` of a column.
pub(super) fn span_bits(y0: usize, y1: usize) -> u32 {
    debug_assert!(y0 <= y1 && y1 <= CHUNK_SIZE);
    let upto = |n: usize| if n >= 32 { u32::MAX } else { (1u32 << n) - 1 };
    upto(y1) & !upto(y0)
}

/// Calls `f(y)` for each set bit `y` of `bits`.
#[inline]
pub(super) fn for_each_bit(mut bits: u32, mut f: impl FnMut(usize)) {
    while bits != 0 {
        f(bits.trailing_zeros() as usize);
        bits &= bits - 1;
    }
}

pub(super) fn or_into(dst: &mut [u32], src: &[u32]) {
    dst.iter_mut().zip(src).for_each(|(d, s)| *d |= s);
}

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
pub(super) fn transpose_layout_into(src: &ColumnMask, dst: &mut ColumnMask) {
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
pub(super) fn transpose32(a: &mut LayerMask) {
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
/// [`Chunk::side_layers`](super::Chunk::side_layers)).
pub(super) fn side_layer(bits: &Occupancy, side: Face) -> LayerMask {
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
pub(super) fn plane_side_layer(plane: &ColumnMask, side: Face) -> LayerMask {
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
pub(super) fn side_index(side: Face) -> usize {
    if side.is_positive() {
        CHUNK_SIZE - 1
    } else {
        0
    }
}
