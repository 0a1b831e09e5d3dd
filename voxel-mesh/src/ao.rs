//! Per-vertex ambient occlusion of faces, in the manner of Minecraft's smooth lighting and
//! 0fps's "Ambient occlusion for Minecraft-like worlds" (Mikola Lysenko, 2013).
//!
//! A vertex of a face is darkened by the opaque blocks in the layer in front of the face
//! that touch it: two *sides* (sharing an edge with the face's own front cell) and one
//! *corner* (sharing only the vertex). Its value is 3 with none of them, `3 − count`
//! otherwise, and 0 when both sides are there (the corner block cannot be seen then, and
//! would otherwise make an inner corner brighter than it is). Only opaque blocks occlude:
//! cutout leaves and glass let the sky through.
//!
//! The mesher merges faces only when their four corner values are the same. Two coplanar
//! faces side by side share two vertices, and a shared vertex has one value (its side
//! blocks are the same two cells seen from either face, the face's own front cells being
//! empty), so in a merged row the values can change across the row only, never along it:
//! the linear interpolation over the merged quad is exactly the per-face one, whatever
//! diagonal its triangles use.
//!
//! The mesher reads the four values of a face once, with one lookup of the 3×3 opaque
//! cells in front of it in a 512-entry table, and covers the occluded faces of a plane with
//! the AO byte as a per-face merge key (`cover_occluded`).
//!
//! The values go into the quad's word 1, bits 24..32 (see [`PackedQuad`](crate::PackedQuad)),
//! two bits per corner in the order `(u0, v0)`, `(u1, v0)`, `(u0, v1)`, `(u1, v1)` of the
//! face's (U, V) axes. The renderer splits a quad along the diagonal whose two corners are
//! brighter in sum (Sodium's rule), so that a single dark corner shades one triangle's
//! corner instead of a band across the quad, and the result does not depend on how the quad
//! is rotated.
//!
//! Occluders come from the chunk, its six face neighbours and (at the chunk's edges and
//! corners) its 12 edge and 8 corner neighbours: a 34³ shell of opaque bits, `Pad`.

use voxel_core::{
    BlockId, CHUNK_SIZE, Face, LayerMask, Neighbourhood, Occupancy, column_index, row_index,
};

use crate::bits::greedy_rects_keyed;

/// AO byte of a face no opaque block touches: every corner 3.
pub const AO_NONE: u8 = 0xff;

/// Side of the padded shell: a chunk and one block of each neighbour around it.
const P: usize = CHUNK_SIZE + 2;

/// The opaque blocks of a chunk and of the one-block shell around it, as bits: padded
/// coordinate `c + 1` for chunk coordinate `c` in `-1..=32`. Each layout holds the planes
/// of one face axis, so that the occluders of a plane are one slice.
#[derive(Clone)]
pub(crate) struct Pad {
    /// Columns along y: bit `y + 1` of `by_y[x + 1][z + 1]` (x planes: rows z, bits y).
    by_y: [[u64; P]; P],
    /// Rows along x: bit `x + 1` of `by_x[y + 1][z + 1]` (y planes: rows z, bits x).
    by_x: [[u64; P]; P],
    /// Rows along x by z: bit `x + 1` of `by_z[z + 1][y + 1]` (z planes: rows y, bits x).
    by_z: [[u64; P]; P],
    /// Per axis and padded layer: whether the plane holds any opaque block.
    any: [[bool; P]; 3],
}

/// The occluders in front of one plane of faces: 34 rows of 34 bits in the plane's layout
/// (row `r + 1`, bit `b + 1` for face row `r` and bit `b`).
pub(crate) type Occluders = [u64; P];

impl Pad {
    pub(crate) fn new() -> Box<Self> {
        Box::new(Self {
            by_y: [[0; P]; P],
            by_x: [[0; P]; P],
            by_z: [[0; P]; P],
            any: [[false; P]; 3],
        })
    }

    /// An empty shell: no occluder anywhere (the planes are left as they were; only the
    /// flags that say whether a plane holds any are read first).
    pub(crate) fn clear(&mut self) {
        self.any = [[false; P]; 3];
    }

    /// Fills the shell: `opaque` are the chunk's opaque blocks, `faces` each face
    /// neighbour's touching layer of opaque blocks (in the layouts of
    /// [`voxel_core::Chunk::side_layers`]), and the edge and corner neighbours are read from
    /// `neighbours` with `is_opaque`.
    pub(crate) fn fill(
        &mut self,
        opaque: &Occupancy,
        faces: &[LayerMask; 6],
        neighbours: &Neighbourhood<'_>,
        is_opaque: &dyn Fn(BlockId) -> bool,
        layers: &mut Vec<(BlockId, LayerMask)>,
    ) {
        let [px, nx, py, ny, pz, nz] = faces;
        // Every entry is written below but the four corner columns of each layout (x or y
        // outside and z outside), which only edge and corner neighbours fill.
        for plane in [&mut self.by_y, &mut self.by_x] {
            for out in [0, P - 1] {
                plane[out][0] = 0;
                plane[out][P - 1] = 0;
            }
        }
        // The chunk's columns, with the ±y neighbours' cells at y = -1 and 32 (their layers:
        // rows z, bits x), and its rows along x, with the ±x neighbours' cells at x = -1 and
        // 32 (rows z, bits y).
        for a in 0..CHUNK_SIZE {
            let columns = &opaque.by_y[column_index(a, 0)..][..CHUNK_SIZE];
            let out = &mut self.by_y[a + 1][1..=CHUNK_SIZE];
            for (z, (o, &c)) in out.iter_mut().zip(columns).enumerate() {
                *o = u64::from(c) << 1
                    | u64::from(ny[z] >> a & 1)
                    | u64::from(py[z] >> a & 1) << (CHUNK_SIZE + 1);
            }
            let rows = &opaque.by_x[row_index(a, 0)..][..CHUNK_SIZE];
            let out = &mut self.by_x[a + 1][1..=CHUNK_SIZE];
            for (z, (o, &r)) in out.iter_mut().zip(rows).enumerate() {
                *o = u64::from(r) << 1
                    | u64::from(nx[z] >> a & 1)
                    | u64::from(px[z] >> a & 1) << (CHUNK_SIZE + 1);
            }
        }
        // The ±x neighbours' layers are the columns at x = -1 and 32, the ±y ones the rows
        // at y = -1 and 32.
        copy_shifted(&mut self.by_y[0][1..], nx);
        copy_shifted(&mut self.by_y[P - 1][1..], px);
        copy_shifted(&mut self.by_x[0][1..], ny);
        copy_shifted(&mut self.by_x[P - 1][1..], py);
        // The ±z neighbours' layers (rows y, bits x) are the rows at z = -1 and 32, and
        // their transposes (rows x, bits y) the columns there.
        for (plane, out) in [(nz, 0), (pz, P - 1)] {
            let columns = crate::bits::transpose32(plane);
            for (a, (&row, &column)) in plane.iter().zip(&columns).enumerate() {
                self.by_x[a + 1][out] = u64::from(row) << 1;
                self.by_y[a + 1][out] = u64::from(column) << 1;
            }
        }
        // Edge neighbours give a line of 32 blocks, corner neighbours one block.
        for d in &Neighbourhood::OFFSETS[6..] {
            let Some(chunk) = neighbours.get(*d) else {
                continue;
            };
            let line = touching_line(chunk, *d, is_opaque, layers);
            if line != 0 {
                self.or_line(*d, line);
            }
        }
        for z in 0..P {
            for y in 0..P {
                self.by_z[z][y] = self.by_x[y][z];
            }
        }
        for (any, planes) in self
            .any
            .iter_mut()
            .zip([&self.by_y, &self.by_x, &self.by_z])
        {
            for (a, plane) in any.iter_mut().zip(planes) {
                *a = plane.iter().fold(0, |acc, r| acc | r) != 0;
            }
        }
    }

    /// Sets the opaque cells `line` of the edge or corner neighbour at offset `d` (see
    /// [`touching_line`]) in both layouts.
    fn or_line(&mut self, d: [i32; 3], line: u32) {
        let [x, y, z] = d.map(|v| if v > 0 { P - 1 } else { 0 });
        let bits = |k: usize| u64::from(line >> k & 1);
        match d {
            // Along x: a row of `by_x`, one bit of each column of `by_y` at (y, z).
            [0, _, _] => {
                self.by_x[y][z] |= u64::from(line) << 1;
                for k in 0..CHUNK_SIZE {
                    self.by_y[k + 1][z] |= bits(k) << y;
                }
            }
            // Along y: a column of `by_y`, one bit of each row of `by_x` at (y, z).
            [_, 0, _] => {
                self.by_y[x][z] |= u64::from(line) << 1;
                for k in 0..CHUNK_SIZE {
                    self.by_x[k + 1][z] |= bits(k) << x;
                }
            }
            // Along z: one bit of each column and of each row.
            [_, _, 0] => {
                for k in 0..CHUNK_SIZE {
                    self.by_y[x][k + 1] |= bits(k) << y;
                    self.by_x[y][k + 1] |= bits(k) << x;
                }
            }
            // A corner: one block.
            _ => {
                self.by_y[x][z] |= bits(0) << y;
                self.by_x[y][z] |= bits(0) << x;
            }
        }
    }

    /// Rows along x: bit `x + 1` of `[y + 1][z + 1]`.
    #[inline]
    pub(crate) fn rows_x(&self) -> &[[u64; P]; P] {
        &self.by_x
    }

    /// Columns along y: bit `y + 1` of `[x + 1][z + 1]`.
    #[inline]
    pub(crate) fn columns_y(&self) -> &[[u64; P]; P] {
        &self.by_y
    }

    /// The occluders in front of the faces of layer `layer` of `face` (the layer one step
    /// along the normal, possibly in a neighbour), or `None` when there are none.
    #[inline]
    pub(crate) fn occluders(&self, face: Face, layer: usize) -> Option<&Occluders> {
        // Padded index of the next layer: layer + 1 ± 1.
        let next = if face.is_positive() { layer + 2 } else { layer };
        let axis = face.axis();
        if !self.any[axis][next] {
            return None;
        }
        Some(match axis {
            0 => &self.by_y[next],
            1 => &self.by_x[next],
            _ => &self.by_z[next],
        })
    }
}

/// `dst[i] = src[i] << 1` (a layer's rows into padded coordinates).
#[inline]
fn copy_shifted(dst: &mut [u64], src: &LayerMask) {
    for (d, &s) in dst.iter_mut().zip(src) {
        *d = u64::from(s) << 1;
    }
}

/// The opaque blocks of the edge or corner neighbour at offset `d` that touch the chunk:
/// for an edge, the line of 32 blocks along the axis where `d` is 0 (bit k: coordinate k
/// there); for a corner, its one block (bit 0). A touching cell is at coordinate 0 of the
/// neighbour along a +1 axis, 31 along a -1 axis.
fn touching_line(
    chunk: &voxel_core::Chunk,
    d: [i32; 3],
    is_opaque: &dyn Fn(BlockId) -> bool,
    layers: &mut Vec<(BlockId, LayerMask)>,
) -> u32 {
    let corner = !d.contains(&0);
    if let Some(id) = chunk.as_uniform() {
        return match (is_opaque(id), corner) {
            (false, _) => 0,
            (true, true) => 1,
            (true, false) => u32::MAX,
        };
    }
    // The neighbour's layer facing us across x (rows z, bits y), or across y for an edge
    // along x (rows z, bits x); both layers are contiguous in the mask layouts.
    let side = match d {
        [0, dy, _] if dy > 0 => Face::NegY,
        [0, _, _] => Face::PosY,
        [dx, _, _] if dx > 0 => Face::NegX,
        _ => Face::PosX,
    };
    chunk.side_layers(side, layers, is_opaque);
    let mut plane = [0u32; CHUNK_SIZE];
    for (_, rows) in layers.iter() {
        plane.iter_mut().zip(rows).for_each(|(p, r)| *p |= r);
    }
    let [_, y, z] = d.map(|v| if v > 0 { 0 } else { CHUNK_SIZE - 1 });
    match d {
        // Along x (rows z, bits x) or along y (rows z, bits y): the row at z.
        [0, _, _] | [_, 0, _] => plane[z],
        // Along z: bit y of every row.
        [_, _, 0] => (0..CHUNK_SIZE).fold(0, |acc, k| acc | (plane[k] >> y & 1) << k),
        _ => plane[z] >> y & 1,
    }
}

/// The corners of a face in the plane's (row, bit) directions.
const CORNERS: [(i32, i32); 4] = [(-1, -1), (-1, 1), (1, -1), (1, 1)];

/// Which of the quad's corner slots (`u + 2v`) the corner `(dr, db)` of a face is, for
/// faces whose U axis runs along the bits (x and z faces) or along the rows (y faces).
const fn slot(u_along_rows: bool, (dr, db): (i32, i32)) -> usize {
    let (du, dv) = if u_along_rows { (dr, db) } else { (db, dr) };
    (du > 0) as usize + 2 * (dv > 0) as usize
}

/// The AO byte of a face for each of the 512 patterns of opaque cells in the 3×3 block in
/// front of it: bit `3 (dr + 1) + (db + 1)` is the cell `dr` rows and `db` bits away (the
/// face's own front cell, bit 4, is never opaque where a face is).
const fn ao_table(u_along_rows: bool) -> [u8; 512] {
    let mut table = [0u8; 512];
    let mut n = 0;
    while n < 512 {
        let mut ao = 0u8;
        let mut c = 0;
        while c < 4 {
            let (dr, db) = CORNERS[c];
            let v = vertex_ao(cell(n, dr, 0), cell(n, 0, db), cell(n, dr, db));
            ao |= v << (2 * slot(u_along_rows, (dr, db)));
            c += 1;
        }
        table[n as usize] = ao;
        n += 1;
    }
    table
}

/// Whether the cell `dr` rows and `db` bits away is set in a 3×3 pattern of [`ao_table`].
const fn cell(pattern: i32, dr: i32, db: i32) -> bool {
    pattern >> (3 * (dr + 1) + db + 1) & 1 != 0
}

/// [`ao_table`] for x and z faces (U along the bits) and for y faces (U along the rows).
static AO_TABLES: [[u8; 512]; 2] = [ao_table(false), ao_table(true)];

/// Covers the faces of `rows` (`live`: its rows holding any) that an occluder touches with
/// rectangles of faces of equal corner values, and takes them out of `rows`; the faces
/// left there have [`AO_NONE`]. Calls `emit(row, rows, bit, bits, ao)` per rectangle and
/// returns the rows still holding faces. `axis` is the face's normal axis
/// (it decides which corner is which slot).
///
/// The corner values of a face are read once from the 3×3 occluders in front of it (one
/// table lookup, [`face_ao`]), and the faces are covered by
/// [`crate::bits::greedy_rects_keyed`] with the AO byte as the key, which gives exactly the
/// rectangles of grouping the faces by byte and covering each group alone.
#[inline]
pub(crate) fn cover_occluded(
    rows: &mut [u32; CHUNK_SIZE],
    rows_live: u32,
    occ: &Occluders,
    axis: usize,
    emit: impl FnMut(usize, usize, usize, usize, u8),
) -> u32 {
    // The faces an occluder touches (any of the nine cells in front).
    let mut shaded = [0u32; CHUNK_SIZE];
    let mut live = 0u32;
    let mut remaining = rows_live;
    let mut left = rows_live;
    while left != 0 {
        let r = left.trailing_zeros() as usize;
        left &= left - 1;
        let v = occ[r] | occ[r + 1] | occ[r + 2];
        let s = rows[r] & (v | v >> 1 | v >> 2) as u32;
        shaded[r] = s;
        rows[r] &= !s;
        live |= u32::from(s != 0) << r;
        remaining &= !(u32::from(rows[r] == 0) << r);
    }
    let ao_at = |r: usize, b: usize| face_ao(occ, axis, r, b);
    greedy_rects_keyed(&mut shaded, live, ao_at, emit);
    remaining
}

/// The AO byte of the face at row `r`, bit `b` of a plane with occluders `occ` (normal
/// `axis`): what [`cover_occluded`] gives it.
#[inline]
pub(crate) fn face_ao(occ: &Occluders, axis: usize, r: usize, b: usize) -> u8 {
    let (up, mid, down) = (occ[r] >> b & 7, occ[r + 1] >> b & 7, occ[r + 2] >> b & 7);
    AO_TABLES[usize::from(axis == 1)][(up | mid << 3 | down << 6) as usize]
}

/// The AO value (0 to 3) of corner `(u, v)` (each 0 or 1) of an AO byte.
pub fn corner_ao(ao: u8, u: usize, v: usize) -> u8 {
    ao >> (2 * (u + 2 * v)) & 3
}

/// The value, 0 (darkest) to 3 (open), of a vertex with these neighbours in front of its
/// face: the rule in the module docs, one vertex at a time (tests and tools use it).
pub const fn vertex_ao(side1: bool, side2: bool, corner: bool) -> u8 {
    if side1 && side2 {
        0
    } else {
        3 - side1 as u8 - side2 as u8 - corner as u8
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vertex_values_follow_the_rule() {
        assert_eq!(vertex_ao(false, false, false), 3);
        assert_eq!(vertex_ao(false, false, true), 2);
        assert_eq!(vertex_ao(true, false, false), 2);
        assert_eq!(vertex_ao(true, false, true), 1);
        assert_eq!(vertex_ao(true, true, false), 0);
        assert_eq!(vertex_ao(true, true, true), 0);
    }

    fn xorshift(mut s: u64) -> impl FnMut() -> u64 {
        move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        }
    }

    /// Random occluders and faces where the cell in front is empty (as the mesher emits),
    /// from sparse to dense occluders and faces.
    fn random_plane(next: &mut impl FnMut() -> u64, k: usize) -> (Occluders, [u32; CHUNK_SIZE]) {
        let occ: Occluders = std::array::from_fn(|_| {
            let mut o = next();
            for _ in 0..k % 3 {
                o &= next();
            }
            o & ((1 << P) - 1)
        });
        let faces = std::array::from_fn(|r| {
            let f = if k.is_multiple_of(2) {
                next() as u32
            } else {
                !0
            };
            f & !((occ[r + 1] >> 1) as u32)
        });
        (occ, faces)
    }

    /// The covering against `vertex_ao` per face, on random occluders.
    #[test]
    #[allow(clippy::needless_range_loop)] // (row, bit) indices read as the matrix they are
    fn cover_matches_the_per_vertex_rule() {
        let mut next = xorshift(0x1234_5678_9abc_def0);
        for axis in 0..3 {
            for k in 0..30 {
                let (occ, faces) = random_plane(&mut next, k);
                let cell = |r: i32, b: i32| occ[(r + 1) as usize] >> (b + 1) & 1 != 0;
                let mut want = [[AO_NONE; CHUNK_SIZE]; CHUNK_SIZE];
                let mut shaded_any = [[false; CHUNK_SIZE]; CHUNK_SIZE];
                for r in 0..CHUNK_SIZE as i32 {
                    for b in 0..CHUNK_SIZE as i32 {
                        let mut ao = 0u8;
                        for c @ (dr, db) in CORNERS {
                            let v =
                                vertex_ao(cell(r + dr, b), cell(r, b + db), cell(r + dr, b + db));
                            ao |= v << (2 * slot(axis == 1, c));
                        }
                        want[r as usize][b as usize] = ao;
                        shaded_any[r as usize][b as usize] =
                            (-1..=1).any(|dr| (-1..=1).any(|db| cell(r + dr, b + db)));
                    }
                }
                let mut rows = faces;
                let mut got = [[None; CHUNK_SIZE]; CHUNK_SIZE];
                let live = crate::bits::live_rows(&rows);
                let left = cover_occluded(&mut rows, live, &occ, axis, |r, h, b, w, ao| {
                    for row in &mut got[r..r + h] {
                        for g in &mut row[b..b + w] {
                            assert!(g.is_none(), "face twice");
                            *g = Some(ao);
                        }
                    }
                });
                assert_eq!(left, crate::bits::live_rows(&rows), "rows left");
                for r in 0..CHUNK_SIZE {
                    for b in 0..CHUNK_SIZE {
                        if faces[r] >> b & 1 == 0 {
                            assert!(got[r][b].is_none() && rows[r] >> b & 1 == 0);
                            continue;
                        }
                        let ao = got[r][b].unwrap_or_else(|| {
                            assert!(rows[r] >> b & 1 != 0, "face lost");
                            AO_NONE
                        });
                        assert_eq!(ao, want[r][b], "axis {axis} face ({r}, {b})");
                        assert_eq!(got[r][b].is_some(), shaded_any[r][b]);
                        assert!(got[r][b].is_none() || rows[r] >> b & 1 == 0, "left in rows");
                    }
                }
            }
        }
    }

    /// The covering gives exactly the rectangles of grouping the occluded faces by AO byte
    /// and covering each group with `greedy_rects` (the mesher's cover before the per-face
    /// key), so the quads do not change.
    #[test]
    fn cover_equals_greedy_rects_per_ao_group() {
        let mut next = xorshift(0x0bad_cafe_f00d_1234);
        for axis in 0..3 {
            for k in 0..30 {
                let (occ, faces) = random_plane(&mut next, k);
                let mut got = Vec::new();
                let mut rows = faces;
                let live = crate::bits::live_rows(&rows);
                cover_occluded(&mut rows, live, &occ, axis, |r, h, b, w, ao| {
                    got.push((ao, r, h, b, w));
                });
                // The reference: each face's byte from the table, one plane per byte.
                let mut groups = std::collections::BTreeMap::<u8, [u32; CHUNK_SIZE]>::new();
                for r in 0..CHUNK_SIZE {
                    for b in 0..CHUNK_SIZE {
                        let front = occ[r] | occ[r + 1] | occ[r + 2];
                        if faces[r] >> b & 1 == 0 || front >> b & 7 == 0 {
                            continue;
                        }
                        let n = |o: u64| (o >> b & 7) as usize;
                        let ao = AO_TABLES[usize::from(axis == 1)]
                            [n(occ[r]) | n(occ[r + 1]) << 3 | n(occ[r + 2]) << 6];
                        groups.entry(ao).or_insert([0; CHUNK_SIZE])[r] |= 1 << b;
                    }
                }
                let mut want = Vec::new();
                for (ao, mut plane) in groups {
                    crate::greedy_rects(&mut plane, |r, h, b, w| want.push((ao, r, h, b, w)));
                }
                got.sort_unstable();
                want.sort_unstable();
                assert_eq!(got, want, "axis {axis} case {k}");
            }
        }
    }

    #[test]
    fn table_matches_vertex_ao_on_single_occluders() {
        // One side occluder in the face's row, one bit before it (dr = 0, db = -1: pattern
        // bit 3): the two corners at db = -1 drop to 2.
        let side = 1 << 3;
        for (u_along_rows, table) in [(false, &AO_TABLES[0]), (true, &AO_TABLES[1])] {
            let ao = table[side];
            for c @ (_, db) in CORNERS {
                let v = ao >> (2 * slot(u_along_rows, c)) & 3;
                assert_eq!(v, if db < 0 { 2 } else { 3 });
            }
            assert_eq!(table[0], AO_NONE);
        }
    }
}
