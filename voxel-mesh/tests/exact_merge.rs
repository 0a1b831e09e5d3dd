//! The pieces of the exact-merging bound that the mesher bench prints: the minimum
//! rectangle partition against an exhaustive search, and which merged rectangles render
//! exactly as their faces under the renderer's diagonal rule.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

#[path = "common/exact_merge.rs"]
#[allow(dead_code)] // the bench uses the rest
mod exact_merge;

use exact_merge::{affine, min_rects, renders_as_its_faces};

fn xorshift(mut s: u64) -> impl FnMut() -> u64 {
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        s
    }
}

fn plane(rows: &[u32]) -> [u32; 32] {
    let mut p = [0; 32];
    p[..rows.len()].copy_from_slice(rows);
    p
}

#[test]
fn min_rects_of_known_shapes() {
    for (rows, want) in [
        (vec![], 0),
        (vec![0b1], 1),
        (vec![0b111, 0b111], 1),
        (vec![0b11, 0b01], 2),          // L
        (vec![0b010, 0b111, 0b010], 3), // plus
        (vec![0b111, 0b010, 0b111], 3), // I-beam
        (vec![0b111, 0b101, 0b111], 4), // ring around a hole
        (vec![0b01, 0b10], 2),          // cells touching at a corner
        (vec![0b110, 0b101, 0b011], 4), // a ring pinched at two corners
        (vec![0b1111, 0b1001, 0b1001, 0b1111], 4),
    ] {
        assert_eq!(min_rects(&plane(&rows)), want, "{rows:?}");
    }
    assert_eq!(min_rects(&[u32::MAX; 32]), 1);
    let checker: [u32; 32] = std::array::from_fn(|v| 0x5555_5555 << (v % 2));
    assert_eq!(min_rects(&checker), 32 * 16);
}

/// The fewest rectangles covering `cells` (a set of bits of a small box) exactly once, by
/// trying every rectangle at the first cell left.
fn exhaustive(cells: &[u32], best: usize, used: usize) -> usize {
    let Some(v) = cells.iter().position(|&r| r != 0) else {
        return used;
    };
    if used + 1 >= best {
        return best;
    }
    let u = cells[v].trailing_zeros() as usize;
    let mut best = best;
    let mut w = 1;
    while u + w <= 32 && cells[v] >> (u + w - 1) & 1 != 0 {
        let run = ((1u64 << w) - 1) as u32;
        let run = run << u;
        let mut h = 1;
        while v + h <= cells.len() && cells[v + h - 1] & run == run {
            let mut rest = cells.to_vec();
            for r in &mut rest[v..v + h] {
                *r &= !run;
            }
            best = best.min(exhaustive(&rest, best, used + 1));
            h += 1;
        }
        w += 1;
    }
    best
}

#[test]
fn min_rects_matches_an_exhaustive_search() {
    let mut next = xorshift(0x5eed_1234_abcd_0001);
    for case in 0..3000 {
        let (w, h) = (2 + case % 4, 2 + case / 4 % 4);
        let dense = case % 3;
        let rows: Vec<u32> = (0..h)
            .map(|_| {
                let mut r = next() as u32;
                for _ in 0..dense {
                    r |= next() as u32;
                }
                r & ((1 << w) - 1)
            })
            .collect();
        assert_eq!(
            min_rects(&plane(&rows)),
            exhaustive(&rows, usize::MAX, 0),
            "{rows:?}"
        );
    }
}

/// Every affine rectangle renders as its faces; a rectangle that renders as its faces
/// without being affine is a 2×2 or 3×3 square.
#[test]
fn exact_merges_are_affine_or_small_squares() {
    let mut next = xorshift(0x0123_4567_89ab_cdef);
    let mut exact_non_affine = 0;
    for case in 0..4000 {
        let (w, h) = (1 + case % 3, 1 + case / 3 % 3);
        if w * h == 1 {
            continue;
        }
        // Random values, or an affine function (kept when all values are in 0..=3), or
        // one linear function on each side of the rectangle's diagonal.
        let mut field = [[0i8; 4]; 4];
        let (a, du, dv, db) = (
            (next() % 4) as i8,
            (next() % 3) as i8 - 1,
            (next() % 3) as i8 - 1,
            (next() % 3) as i8 - 1,
        );
        for (i, column) in field.iter_mut().enumerate().take(w + 1) {
            for (j, value) in column.iter_mut().enumerate().take(h + 1) {
                let (i, j) = (i as i8, j as i8);
                *value = match case % 3 {
                    0 => (next() % 4) as i8,
                    1 => a + du * i + dv * j,
                    _ => {
                        a + du * i
                            + dv * j
                            + if i + j > h as i8 {
                                db * (i + j - h as i8)
                            } else {
                                0
                            }
                    }
                };
            }
        }
        if field.iter().flatten().any(|v| !(0..=3).contains(v)) {
            continue;
        }
        let vertex = |i: usize, j: usize| field[i][j];
        let faces_affine = (0..w).all(|i| {
            (0..h).all(|j| {
                affine([
                    vertex(i, j),
                    vertex(i + 1, j),
                    vertex(i, j + 1),
                    vertex(i + 1, j + 1),
                ])
            })
        });
        let one_function = faces_affine
            && (0..=w).all(|i| {
                (0..=h).all(|j| {
                    let (du, dv) = (vertex(1, 0) - vertex(0, 0), vertex(0, 1) - vertex(0, 0));
                    vertex(i, j) == vertex(0, 0) + du * i as i8 + dv * j as i8
                })
            });
        let exact = renders_as_its_faces(w, h, &vertex);
        assert!(
            !one_function || exact,
            "affine but not exact: {w}x{h} {field:?}"
        );
        if exact && !one_function {
            assert_eq!(w, h, "exact, not affine, not square: {field:?}");
            exact_non_affine += 1;
        }
    }
    // The exception exists: the square case is not empty.
    assert!(exact_non_affine > 0);
    // One of them: 1 at a corner rising to 3 at the three others, 2 between; its faces at
    // (1, 0) and (0, 1) are not affine, the merged quad's diagonal runs along theirs.
    let square = [[1, 2, 3], [2, 3, 3], [3, 3, 3]];
    assert!(renders_as_its_faces(2, 2, &|i, j| square[i][j]));
    assert!(!affine([2, 3, 3, 3]));
}

#[test]
fn the_square_exception_is_counted_on_a_plane() {
    use exact_merge::{Plane, exact_non_affine_squares, fewest_exact_quads, non_affine_faces};
    let square = [[1i8, 2, 3], [2, 3, 3], [3, 3, 3]];
    let mut plane: Plane = [[None; 32]; 32];
    for (i, j) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
        let v = |di: usize, dj: usize| square[i + di][j + dj];
        plane[j + 5][i + 7] = Some([v(0, 0), v(1, 0), v(0, 1), v(1, 1)]);
    }
    assert_eq!(exact_non_affine_squares(&plane), 1);
    assert_eq!(non_affine_faces(&plane), 2);
    // Without it: two faces that are not affine, alone, and two affine ones of different
    // functions.
    assert_eq!(fewest_exact_quads(&plane), 4);
    // A face missing: no square.
    plane[6][8] = None;
    assert_eq!(exact_non_affine_squares(&plane), 0);
}
