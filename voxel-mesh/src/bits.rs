//! The greedy rectangle cover of a 32×32 bit plane, the last step of the binary mesher.

/// Covers the set bits of a 32×32 plane with rectangles, greedily: the lowest run of the
/// lowest row first, as wide as the run, then as tall as the rows below repeat it.
/// Calls `emit(row, rows, bit, bits)` per rectangle and leaves `rows` all zero.
#[inline]
pub fn greedy_rects(rows: &mut [u32; 32], mut emit: impl FnMut(usize, usize, usize, usize)) {
    // Most planes are empty: a vectorised OR finds out before any per-row work.
    if rows.iter().fold(0, |acc, &r| acc | r) == 0 {
        return;
    }
    // Rows still holding bits, one bit each, so that empty rows cost nothing below.
    let mut live = rows
        .iter()
        .enumerate()
        .fold(0u32, |acc, (r, &bits)| acc | u32::from(bits != 0) << r);
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
    fn full_plane_is_one_rectangle() {
        let mut rows = [u32::MAX; 32];
        let mut n = Vec::new();
        greedy_rects(&mut rows, |r, h, b, w| n.push((r, h, b, w)));
        assert_eq!(n, vec![(0, 32, 0, 32)]);
    }
}
