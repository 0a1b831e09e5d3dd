//! The greedy rectangle cover of a 32×32 bit plane, the last step of the binary mesher.

/// Covers the set bits of a 32×32 plane with rectangles, greedily: the lowest run of the
/// lowest row first, as wide as the run, then as tall as the rows below repeat it.
/// Calls `emit(row, rows, bit, bits)` per rectangle and leaves `rows` all zero.
#[inline]
pub fn greedy_rects(rows: &mut [u32; 32], emit: impl FnMut(usize, usize, usize, usize)) {
    // Most planes are empty: a vectorised OR finds out before any per-row work.
    if rows.iter().fold(0, |acc, &r| acc | r) == 0 {
        return;
    }
    greedy_rects_live(rows, live_rows(rows), emit);
}

/// One bit per row of `rows` that holds any bit.
#[inline]
pub(crate) fn live_rows(rows: &[u32; 32]) -> u32 {
    rows.iter()
        .enumerate()
        .fold(0u32, |acc, (r, &bits)| acc | u32::from(bits != 0) << r)
}

/// [`greedy_rects_live`] with a key per face (`key(row, bit)`): a rectangle covers faces of
/// one key only. The run grows right while the next face has the key of its first, and down
/// while the row below has the same faces with the same keys. Rectangles of different keys
/// never meet, so this gives exactly the rectangles of grouping the faces by key and
/// covering each group alone. `rows` is emptied.
#[inline]
pub(crate) fn greedy_rects_keyed<K: Copy + PartialEq>(
    rows: &mut [u32; 32],
    mut live: u32,
    key: impl Fn(usize, usize) -> K,
    mut emit: impl FnMut(usize, usize, usize, usize, K),
) {
    while live != 0 {
        let r = live.trailing_zeros() as usize;
        live &= live - 1;
        let mut bits = rows[r];
        rows[r] = 0;
        while bits != 0 {
            let b0 = bits.trailing_zeros() as usize;
            let k = key(r, b0);
            let mut end = b0 + 1;
            while end < 32 && bits >> end & 1 != 0 && key(r, end) == k {
                end += 1;
            }
            let run = (u32::MAX >> (32 - (end - b0))) << b0;
            bits &= !run;
            let mut h = 1;
            while r + h < 32 && rows[r + h] & run == run && (b0..end).all(|b| key(r + h, b) == k) {
                rows[r + h] &= !run;
                if rows[r + h] == 0 {
                    live &= !(1 << (r + h));
                }
                h += 1;
            }
            emit(r, h, b0, end - b0, k);
        }
    }
}

/// [`greedy_rects`] when the caller knows which rows hold bits (`live`, one bit per row):
/// empty rows cost nothing.
#[inline]
pub(crate) fn greedy_rects_live(
    rows: &mut [u32; 32],
    mut live: u32,
    mut emit: impl FnMut(usize, usize, usize, usize),
) {
    while live != 0 {
        let r = live.trailing_zeros() as usize;
        live &= live - 1;
        let mut bits = rows[r];
        rows[r] = 0;
        while bits != 0 {
            let b0 = bits.trailing_zeros();
            let w = (bits >> b0).trailing_ones();
            let run = if w == 32 {
                u32::MAX
            } else {
                ((1u32 << w) - 1) << b0
            };
            bits &= !run;
            let mut h = 1;
            while r + h < 32 && rows[r + h] & run == run {
                rows[r + h] &= !run;
                if rows[r + h] == 0 {
                    live &= !(1 << (r + h));
                }
                h += 1;
            }
            emit(r, h, b0 as usize, w as usize);
        }
    }
}

/// Transposes a 32×32 bit matrix: bit `c` of row `r` becomes bit `r` of row `c`.
pub(crate) fn transpose32(rows: &[u32; 32]) -> [u32; 32] {
    let mut a = *rows;
    // Swap ever smaller blocks across the diagonal (Hacker's Delight 7-3, with bit 0 as the
    // first column): the upper-right block of each 2j × 2j square with the lower-left one.
    let mut j = 16;
    let mut m: u32 = 0x0000_ffff;
    while j != 0 {
        let mut k = 0;
        while k < 32 {
            // Row k's high j bits of each 2j group against row k + j's low j bits.
            let t = ((a[k] >> j) ^ a[k + j]) & m;
            a[k] ^= t << j;
            a[k + j] ^= t;
            k = (k + j + 1) & !j;
        }
        j >>= 1;
        m ^= m << j;
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lcg(seed: &mut u64) -> u32 {
        *seed = seed
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (*seed >> 32) as u32
    }

    #[test]
    fn greedy_covers_each_bit_exactly_once() {
        let mut s = 11;
        for density in [1u32, 3, 7] {
            for _ in 0..50 {
                // Blocky random planes: runs and rectangles, as terrain has.
                let a: [u32; 32] = std::array::from_fn(|_| {
                    (0..density).fold(u32::MAX, |acc, _| acc & lcg(&mut s))
                });
                let mut rows = a;
                let mut cover = [0u32; 32];
                greedy_rects(&mut rows, |r, h, b, w| {
                    let run = if w == 32 {
                        u32::MAX
                    } else {
                        ((1u32 << w) - 1) << b
                    };
                    for row in &mut cover[r..r + h] {
                        assert_eq!(*row & run, 0, "overlap");
                        *row |= run;
                    }
                });
                assert_eq!(cover, a);
                assert_eq!(rows, [0; 32]);
            }
        }
    }

    #[test]
    #[allow(clippy::needless_range_loop)] // (row, bit) indices read as the matrix they are
    fn transpose_moves_every_bit_across_the_diagonal() {
        let mut s = 5;
        for _ in 0..20 {
            let a: [u32; 32] = std::array::from_fn(|_| lcg(&mut s));
            let t = transpose32(&a);
            for r in 0..32 {
                for c in 0..32 {
                    assert_eq!(a[r] >> c & 1, t[c] >> r & 1, "({r}, {c})");
                }
            }
            assert_eq!(transpose32(&t), a);
        }
    }

    #[test]
    fn full_plane_is_one_rectangle() {
        let mut rows = [u32::MAX; 32];
        let mut n = Vec::new();
        greedy_rects(&mut rows, |r, h, b, w| n.push((r, h, b, w)));
        assert_eq!(n, vec![(0, 32, 0, 32)]);
    }
}
