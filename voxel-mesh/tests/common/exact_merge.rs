//! Which merges of occluded faces are exact for the renderer, and the fewest quads they
//! allow: the bound the mesher bench prints under "quads with AO / without", and the test
//! (`tests/exact_merge.rs`) that checks the pieces.
//!
//! The renderer splits a quad along the diagonal whose two corners have the larger sum of
//! values (`(1,0)-(0,1)` when `a10 + a01 > a00 + a11`, else `(0,0)-(1,1)`) and interpolates
//! the corner values linearly on each triangle; brightness is affine in the value, so the
//! value is what must match. A merged quad is exact when it shows at every point what its
//! unit faces show.
//!
//! If the corner values of a rectangle of faces are one affine function of the vertex
//! position, every face and the merged quad show that function, whatever diagonals they
//! use: exact. Conversely, the merged quad is linear on each of its two triangles; a face
//! that its diagonal does not cross must be linear there, and a face it crosses along a line
//! that is not the face's own diagonal can have no kink there, so both triangles carry the
//! same function: a rectangle that is not square is exact only when affine. A square can
//! have its kink along the diagonal of the faces it crosses, with a different linear
//! function on each side; with values 0 to 3 at integer vertices a side of 4 or more forces
//! both functions constant, so only 2×2 and 3×3 squares can be exact without being affine
//! ([`exact_non_affine_squares`] counts them on a mesh).

use std::collections::HashMap;

use voxel_mesh::{PackedQuad, UV_AXES};

/// The corner values of each unit face of one plane (face direction, layer, block and
/// flags), indexed `[v][u]` in the face's (U, V) axes; slots `u + 2v` as in `PackedQuad`.
pub type Plane = [[Option<[i8; 4]>; 32]; 32];

/// The value the renderer shows at `(s, t)` (each 0 to 1) of a quad with corner values
/// `a` (slots `u + 2v`).
pub fn render(a: [f64; 4], s: f64, t: f64) -> f64 {
    if a[1] + a[2] > a[0] + a[3] {
        if s + t <= 1.0 {
            a[0] + s * (a[1] - a[0]) + t * (a[2] - a[0])
        } else {
            a[3] + (1.0 - s) * (a[2] - a[3]) + (1.0 - t) * (a[1] - a[3])
        }
    } else if s >= t {
        a[0] + s * (a[1] - a[0]) + t * (a[3] - a[1])
    } else {
        a[0] + t * (a[2] - a[0]) + s * (a[3] - a[2])
    }
}

/// Whether a `w`×`h` rectangle of faces (w, h ≤ 3) whose vertex `(i, j)` has value
/// `vertex(i, j)` renders, merged into one quad, exactly as its faces. Both sides are
/// linear between the lines `x = i`, `y = j`, `x ± y = c` and the quad's diagonal, whose
/// crossings have denominators dividing 60 for sides up to 3: comparing on a 1/60 grid
/// is a proof.
pub fn renders_as_its_faces(w: usize, h: usize, vertex: &dyn Fn(usize, usize) -> i8) -> bool {
    let v = |i: usize, j: usize| f64::from(vertex(i, j));
    let big = [v(0, 0), v(w, 0), v(0, h), v(w, h)];
    const N: usize = 60;
    (0..w).all(|i| {
        (0..h).all(|j| {
            let face = [v(i, j), v(i + 1, j), v(i, j + 1), v(i + 1, j + 1)];
            (0..=N).all(|p| {
                (0..=N).all(|q| {
                    let (s, t) = (p as f64 / N as f64, q as f64 / N as f64);
                    let merged = render(big, (i as f64 + s) / w as f64, (j as f64 + t) / h as f64);
                    (render(face, s, t) - merged).abs() < 1e-9
                })
            })
        })
    })
}

/// Whether the corner values of one face are an affine function of the vertex position.
pub fn affine(a: [i8; 4]) -> bool {
    a[0] + a[3] == a[1] + a[2]
}

/// The unit faces of a mesh, per plane, with their corner values. Every quad the mesher
/// emits is affine over its faces (it merges only faces of equal values), so a face's
/// values are the quad's corner values interpolated at the face's corners (checked).
pub fn planes(quads: &[PackedQuad]) -> HashMap<(usize, u8, u32), Box<Plane>> {
    let mut planes: HashMap<(usize, u8, u32), Box<Plane>> = HashMap::new();
    for q in quads {
        let u = q.unpack().expect("a valid quad");
        let axis = u.face.axis();
        let [ua, va] = UV_AXES[axis];
        let key = (u.face as usize, u.pos[axis], q.block & 0x00ff_ffff);
        let plane = planes
            .entry(key)
            .or_insert_with(|| Box::new([[None; 32]; 32]));
        let ao = q.ao();
        let c = |slot: usize| i32::from(ao >> (2 * slot) & 3);
        let (w, h) = (i32::from(u.size[0]), i32::from(u.size[1]));
        let at = |i: i32, j: i32| -> i8 {
            let sum =
                c(0) * (w - i) * (h - j) + c(1) * i * (h - j) + c(2) * (w - i) * j + c(3) * i * j;
            assert_eq!(
                sum % (w * h),
                0,
                "a quad whose values are not affine: {u:?}"
            );
            (sum / (w * h)) as i8
        };
        for i in 0..w {
            for j in 0..h {
                let (pu, pv) = (
                    usize::from(u.pos[ua]) + i as usize,
                    usize::from(u.pos[va]) + j as usize,
                );
                let slot = &mut plane[pv][pu];
                assert!(slot.is_none(), "a face twice");
                *slot = Some([at(i, j), at(i + 1, j), at(i, j + 1), at(i + 1, j + 1)]);
            }
        }
    }
    planes
}

/// The fewest rectangles that partition the set bits of a 32×32 plane (bit `u` of row
/// `v`): reflex vertices − the most chords between them that do not meet + the Euler
/// number of the cells (4-connected), the theorem of Lipski, Lodi, Luccio, Mugnai and
/// Pagli (1979) / Ohtsuki (1982) summed over components, with the chords' independent set
/// from a bipartite matching (horizontal against vertical chords).
pub fn min_rects(rows: &[u32; 32]) -> usize {
    let cell = |u: i32, v: i32| {
        (0..32).contains(&u) && (0..32).contains(&v) && rows[v as usize] >> u & 1 != 0
    };
    let around = |u: i32, v: i32| {
        [
            cell(u - 1, v - 1),
            cell(u, v - 1),
            cell(u - 1, v),
            cell(u, v),
        ]
        .iter()
        .filter(|&&c| c)
        .count()
    };
    let (mut cells, mut adjacent, mut full, mut reflex) = (0i64, 0i64, 0i64, 0i64);
    for v in 0..=32 {
        for u in 0..=32 {
            if cell(u, v) {
                cells += 1;
                adjacent += i64::from(cell(u + 1, v)) + i64::from(cell(u, v + 1));
            }
            match around(u, v) {
                4 => full += 1,
                3 => reflex += 1,
                _ => {}
            }
        }
    }
    let euler = cells - adjacent + full;
    // Chords: maximal runs of edges with cells on both sides, ending at reflex vertices at
    // both ends (a reflex vertex ends exactly one such run per direction).
    let runs = |horizontal: bool| {
        let mut chords = Vec::new();
        for line in 1..32 {
            let inside = |k: i32| {
                if horizontal {
                    cell(k, line - 1) && cell(k, line)
                } else {
                    cell(line - 1, k) && cell(line, k)
                }
            };
            let vertex = |k: i32| {
                if horizontal {
                    around(k, line)
                } else {
                    around(line, k)
                }
            };
            let mut k = 0;
            while k < 32 {
                if !inside(k) {
                    k += 1;
                    continue;
                }
                let start = k;
                while k < 32 && inside(k) {
                    k += 1;
                }
                if vertex(start) == 3 && vertex(k) == 3 {
                    chords.push((line, start, k));
                }
            }
        }
        chords
    };
    let (hs, vs) = (runs(true), runs(false));
    // A horizontal chord (y, x0..x1) meets a vertical one (x, y0..y1), ends included.
    let meets: Vec<Vec<usize>> = hs
        .iter()
        .map(|&(y, x0, x1)| {
            (0..vs.len())
                .filter(|&k| {
                    let (x, y0, y1) = vs[k];
                    (x0..=x1).contains(&x) && (y0..=y1).contains(&y)
                })
                .collect()
        })
        .collect();
    fn augment(
        h: usize,
        meets: &[Vec<usize>],
        owner: &mut [Option<usize>],
        seen: &mut [bool],
    ) -> bool {
        for &v in &meets[h] {
            if !seen[v] {
                seen[v] = true;
                if owner[v].is_none_or(|o| augment(o, meets, owner, seen)) {
                    owner[v] = Some(h);
                    return true;
                }
            }
        }
        false
    }
    let mut owner = vec![None; vs.len()];
    let matched = (0..hs.len())
        .filter(|&h| augment(h, &meets, &mut owner, &mut vec![false; vs.len()]))
        .count();
    let independent = (hs.len() + vs.len() - matched) as i64;
    (reflex - independent + euler) as usize
}

/// How many of a plane's faces have corner values that are not affine (each a quad of its
/// own in any exact merging, but for the squares of [`exact_non_affine_squares`]).
pub fn non_affine_faces(plane: &Plane) -> usize {
    plane
        .iter()
        .flatten()
        .flatten()
        .filter(|&&a| !affine(a))
        .count()
}

/// The fewest exact quads for one plane's faces: a face whose values are not affine is a
/// quad of its own (squares that merge it exactly are counted apart, by
/// [`exact_non_affine_squares`]); the others group by the affine function of their values,
/// and each group takes its minimum partition.
pub fn fewest_exact_quads(plane: &Plane) -> usize {
    let mut groups: HashMap<(i8, i8, i32), [u32; 32]> = HashMap::new();
    let mut alone = 0;
    for (v, row) in plane.iter().enumerate() {
        for (u, face) in row.iter().enumerate() {
            let Some(a) = *face else { continue };
            if !affine(a) {
                alone += 1;
                continue;
            }
            let (du, dv) = (a[1] - a[0], a[2] - a[0]);
            let origin = i32::from(a[0]) - i32::from(du) * u as i32 - i32::from(dv) * v as i32;
            groups.entry((du, dv, origin)).or_insert([0; 32])[v] |= 1 << u;
        }
    }
    alone + groups.values().map(min_rects).sum::<usize>()
}

/// How many 2×2 and 3×3 squares of a plane's faces hold a face whose values are not affine
/// and still render exactly merged (the only exact merges that are not affine).
pub fn exact_non_affine_squares(plane: &Plane) -> usize {
    let not_affine = |u: usize, v: usize| plane[v][u].is_some_and(|a| !affine(a));
    let mut n = 0;
    for (v, u) in (0..32).flat_map(|v| (0..32).map(move |u| (v, u))) {
        if !not_affine(u, v) {
            continue;
        }
        // The squares holding this face, counted at their first face that is not affine.
        for k in 2..=3 {
            for (v0, u0) in (v.saturating_sub(k - 1)..=v.min(32 - k))
                .flat_map(|v0| (u.saturating_sub(k - 1)..=u.min(32 - k)).map(move |u0| (v0, u0)))
            {
                let cells = || (v0..v0 + k).flat_map(move |j| (u0..u0 + k).map(move |i| (j, i)));
                let first = cells().find(|&(j, i)| not_affine(i, j));
                if first != Some((v, u)) || cells().any(|(j, i)| plane[j][i].is_none()) {
                    continue;
                }
                let vertex = |i: usize, j: usize| {
                    let (fi, si) = if i == k { (i - 1, 1) } else { (i, 0) };
                    let (fj, sj) = if j == k { (j - 1, 1) } else { (j, 0) };
                    plane[v0 + fj][u0 + fi].expect("present")[si + 2 * sj]
                };
                // The merged quad must show each vertex's own value there (a cheap test
                // first), then everywhere.
                let big = [vertex(0, 0), vertex(k, 0), vertex(0, k), vertex(k, k)].map(f64::from);
                let at_vertices = (0..=k).all(|i| {
                    (0..=k).all(|j| {
                        let shown = render(big, i as f64 / k as f64, j as f64 / k as f64);
                        (shown - f64::from(vertex(i, j))).abs() < 1e-9
                    })
                });
                if at_vertices && renders_as_its_faces(k, k, &vertex) {
                    n += 1;
                }
            }
        }
    }
    n
}
