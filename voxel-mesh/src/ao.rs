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
//! The values go into the quad's word 1, bits 24..32 (see [`crate::quad`]), two bits per
//! corner in the order `(u0, v0)`, `(u1, v0)`, `(u0, v1)`, `(u1, v1)` of the face's (U, V)
//! axes. The renderer splits a quad along the diagonal whose two corners are brighter in
//! sum (Sodium's rule), so that a single dark corner shades one triangle's corner instead of
//! a band across the quad, and the result does not depend on how the quad is rotated.
//!
//! Occluders come from the chunk, its six face neighbours and (at the chunk's edges and
//! corners) its 12 edge and 8 corner neighbours: a 34³ shell of opaque bits, [`Pad`].

use voxel_core::{
    BlockId, CHUNK_SIZE, Face, LayerMask, Neighbourhood, Occupancy, column_index, row_index,
};

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
        for row in self.by_y.iter_mut().chain(self.by_x.iter_mut()) {
            row.fill(0);
        }
        for a in 0..CHUNK_SIZE {
            for z in 0..CHUNK_SIZE {
                self.by_y[a + 1][z + 1] = u64::from(opaque.by_y[column_index(a, z)]) << 1;
                self.by_x[a + 1][z + 1] = u64::from(opaque.by_x[row_index(a, z)]) << 1;
            }
        }
        // Face neighbours: one layout is a copy of the layer, the other a transpose.
        for face in Face::ALL {
            let plane = &faces[face as usize];
            let out = if face.is_positive() { P - 1 } else { 0 };
            match face.axis() {
                // Rows z, bits y.
                0 => {
                    copy_shifted(&mut self.by_y[out][1..], plane);
                    for y in 0..CHUNK_SIZE {
                        or_bit(&mut self.by_x[y + 1], plane, y, out);
                    }
                }
                // Rows z, bits x.
                1 => {
                    copy_shifted(&mut self.by_x[out][1..], plane);
                    for x in 0..CHUNK_SIZE {
                        or_bit(&mut self.by_y[x + 1], plane, x, out);
                    }
                }
                // Rows y, bits x: its transpose has rows x, bits y.
                _ => {
                    let columns = crate::bits::transpose32(plane);
                    for (a, (&row, &column)) in plane.iter().zip(&columns).enumerate() {
                        self.by_x[a + 1][out] = u64::from(row) << 1;
                        self.by_y[a + 1][out] = u64::from(column) << 1;
                    }
                }
            }
        }
        // Edge neighbours give a line of 32 blocks, corner neighbours one block.
        for d in &Neighbourhood::OFFSETS[6..] {
            let Some(chunk) = neighbours.get(*d) else {
                continue;
            };
            // The touching cells: coordinate 0 of the neighbour on a +1 axis, 31 on a -1
            // axis; `free` runs along the axis where d is 0 (none for a corner).
            let near = |v: i32| if v > 0 { 0 } else { CHUNK_SIZE - 1 };
            let padded = |v: i32| if v > 0 { P - 1 } else { 0 };
            let free = d.iter().position(|&v| v == 0);
            if let Some(id) = chunk.as_uniform() {
                if is_opaque(id) {
                    for k in 0..if free.is_some() { CHUNK_SIZE } else { 1 } {
                        let mut p = d.map(padded);
                        if let Some(f) = free {
                            p[f] = k + 1;
                        }
                        self.set(p);
                    }
                }
                continue;
            }
            // The neighbour's layer on the side facing us across the first non-zero axis.
            let axis = d.iter().position(|&v| v != 0).unwrap_or(0);
            let side = match (axis, d[axis] > 0) {
                (0, true) => Face::NegX,
                (0, false) => Face::PosX,
                (1, true) => Face::NegY,
                (1, false) => Face::PosY,
                (_, true) => Face::NegZ,
                (_, false) => Face::PosZ,
            };
            chunk.side_layers(side, layers, is_opaque);
            let mut plane = [0u32; CHUNK_SIZE];
            for (_, rows) in layers.iter() {
                plane.iter_mut().zip(rows).for_each(|(p, r)| *p |= r);
            }
            for k in 0..if free.is_some() { CHUNK_SIZE } else { 1 } {
                let mut local = d.map(near);
                let mut p = d.map(padded);
                if let Some(f) = free {
                    local[f] = k;
                    p[f] = k + 1;
                }
                if layer_bit(&plane, axis, local) {
                    self.set(p);
                }
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

    fn set(&mut self, p: [usize; 3]) {
        self.by_y[p[0]][p[2]] |= 1 << p[1];
        self.by_x[p[1]][p[2]] |= 1 << p[0];
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

/// Sets bit `to` of `dst[z + 1]` where bit `from` of `plane[z]` is set, for every z (one
/// column of a neighbour's layer into the shell's border bit; vectorises).
#[inline]
fn or_bit(dst: &mut [u64; P], plane: &LayerMask, from: usize, to: usize) {
    for (d, &p) in dst[1..=CHUNK_SIZE].iter_mut().zip(plane.iter()) {
        *d |= u64::from(p >> from & 1) << to;
    }
}

/// Whether the block at `local` (whose `axis` coordinate is ignored) is set in a layer in
/// the layout of [`voxel_core::Chunk::side_layers`] for a side along `axis`.
fn layer_bit(plane: &LayerMask, axis: usize, local: [usize; 3]) -> bool {
    let (row, bit) = match axis {
        0 => (local[2], local[1]),
        1 => (local[2], local[0]),
        _ => (local[1], local[0]),
    };
    plane[row] >> bit & 1 != 0
}

/// The corners of a face in the plane's (row, bit) directions.
#[cfg(test)]
const CORNERS: [(i32, i32); 4] = [(-1, -1), (-1, 1), (1, -1), (1, 1)];

/// Which of the quad's corner slots (`u + 2v`) the corner `(dr, db)` of a face is, for
/// faces whose U axis runs along the bits (x and z faces) or along the rows (y faces).
#[cfg(test)]
fn slot(axis: usize, (dr, db): (i32, i32)) -> usize {
    let (du, dv) = if axis == 1 { (dr, db) } else { (db, dr) };
    usize::from(du > 0) + 2 * usize::from(dv > 0)
}

/// Faces of one plane that share an AO byte, and which rows hold any.
#[derive(Clone)]
struct Bucket {
    ao: u8,
    live: u32,
    rows: [u32; CHUNK_SIZE],
}

/// Working memory of [`split_by_ao`]: the faces of one plane grouped by AO byte. Buckets
/// are reused; covering a bucket leaves its rows zero.
#[derive(Clone)]
pub(crate) struct Buckets {
    /// Index + 1 in `buckets` of each AO byte's group (0: none yet).
    index: [u8; 256],
    buckets: Vec<Bucket>,
    used: usize,
}

impl Buckets {
    pub(crate) fn new() -> Self {
        Self {
            index: [0; 256],
            buckets: Vec::new(),
            used: 0,
        }
    }

    #[inline]
    fn add(&mut self, ao: u8, row: usize, bits: u32) {
        let i = match self.index[usize::from(ao)] {
            0 => {
                if self.used == self.buckets.len() {
                    self.buckets.push(Bucket {
                        ao,
                        live: 0,
                        rows: [0; CHUNK_SIZE],
                    });
                }
                self.buckets[self.used].ao = ao;
                self.used += 1;
                self.index[usize::from(ao)] = self.used as u8;
                self.used - 1
            }
            i => usize::from(i) - 1,
        };
        let b = &mut self.buckets[i];
        b.rows[row] |= bits;
        b.live |= 1 << row;
    }
}

/// The value lanes of one corner over a row of 32 faces: `(low, high)` bits of
/// `3 − count` (count = sides + corner, taken as 3 when both sides are there).
#[inline(always)]
fn corner_lanes(s1: u32, s2: u32, c: u32) -> (u32, u32) {
    let both = s1 & s2;
    let low = (s1 ^ s2 ^ c) | both;
    let high = both | (s1 & c) | (s2 & c);
    (!low, !high)
}

/// Moves the faces of `rows` that an occluder touches out of `rows`, grouped by AO byte,
/// and calls `emit(ao, live rows, plane)` for each group, which must leave the plane zero
/// (as [`crate::greedy_rects`] does); the faces left in `rows` have [`AO_NONE`].
/// `axis` is the face's normal axis (it decides which corner is which slot).
pub(crate) fn split_by_ao(
    rows: &mut [u32; CHUNK_SIZE],
    occ: &Occluders,
    axis: usize,
    buckets: &mut Buckets,
    mut emit: impl FnMut(u8, u32, &mut [u32; CHUNK_SIZE]),
) {
    let mut live = crate::bits::live_rows(rows);
    while live != 0 {
        let r = live.trailing_zeros() as usize;
        live &= live - 1;
        let (up, mid, down) = (occ[r], occ[r + 1], occ[r + 2]);
        // Faces with any occluder among their eight neighbours in front.
        let v = up | mid | down;
        let shaded = rows[r] & ((v | v >> 1 | v >> 2) as u32);
        if shaded == 0 {
            continue;
        }
        rows[r] &= !shaded;
        // Sides: the row before or after (dr = ∓1) at the face's bit, and the face's row
        // at the bit before or after (db = ∓1); corners: both steps.
        let (side_before, side_after) = ((up >> 1) as u32, (down >> 1) as u32);
        let (bit_before, bit_after) = (mid as u32, (mid >> 2) as u32);
        let corner = |row: u64, db_after: bool| (row >> if db_after { 2 } else { 0 }) as u32;
        let a = corner_lanes(side_before, bit_before, corner(up, false)); // (-, -)
        let b = corner_lanes(side_before, bit_after, corner(up, true)); // (-, +)
        let c = corner_lanes(side_after, bit_before, corner(down, false)); // (+, -)
        let d = corner_lanes(side_after, bit_after, corner(down, true)); // (+, +)
        // Quad slots u + 2v: U along the bits for x and z faces, along the rows for y.
        let [s0, s1, s2, s3] = if axis == 1 {
            [a, c, b, d]
        } else {
            [a, b, c, d]
        };
        // Lane k is bit k of the AO byte.
        let lanes = [s0.0, s0.1, s1.0, s1.1, s2.0, s2.1, s3.0, s3.1];
        let mut left = shaded;
        while left != 0 {
            let bit = left.trailing_zeros();
            // The AO byte of this face (lane k is bit k), and the faces of the row with the
            // same byte: those where no lane differs from this face's bit.
            let mut ao = 0u32;
            let mut differs = 0u32;
            for (k, lane) in lanes.iter().enumerate() {
                let b = lane >> bit & 1;
                ao |= b << k;
                differs |= lane ^ 0u32.wrapping_sub(b);
            }
            let same = left & !differs;
            buckets.add(ao as u8, r, same);
            left &= !same;
        }
    }
    for b in &mut buckets.buckets[..buckets.used] {
        buckets.index[usize::from(b.ao)] = 0;
        emit(b.ao, b.live, &mut b.rows);
        b.live = 0;
    }
    buckets.used = 0;
}

/// The AO value (0 to 3) of corner `(u, v)` (each 0 or 1) of an AO byte.
pub fn corner_ao(ao: u8, u: usize, v: usize) -> u8 {
    ao >> (2 * (u + 2 * v)) & 3
}

/// The value, 0 (darkest) to 3 (open), of a vertex with these neighbours in front of its
/// face: the rule in the module docs, one vertex at a time (tests and tools use it).
pub fn vertex_ao(side1: bool, side2: bool, corner: bool) -> u8 {
    if side1 && side2 {
        0
    } else {
        3 - u8::from(side1) - u8::from(side2) - u8::from(corner)
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

    /// The bit-parallel split against `vertex_ao` per face, on random occluders.
    #[test]
    #[allow(clippy::needless_range_loop)] // (row, bit) indices read as the matrix they are
    fn split_matches_the_per_vertex_rule() {
        let mut s = 0x1234_5678_9abc_def0u64;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
        let mut buckets = Buckets::new();
        for axis in 0..3 {
            for _ in 0..20 {
                let occ: Occluders = std::array::from_fn(|_| next() & next() & ((1 << P) - 1));
                let faces: [u32; CHUNK_SIZE] = std::array::from_fn(|r| {
                    // Faces only where the cell in front is empty, as the mesher emits.
                    (next() as u32) & !((occ[r + 1] >> 1) as u32)
                });
                let cell = |r: i32, b: i32| occ[(r + 1) as usize] >> (b + 1) & 1 != 0;
                let mut want = [[AO_NONE; CHUNK_SIZE]; CHUNK_SIZE];
                let mut shaded_any = [[false; CHUNK_SIZE]; CHUNK_SIZE];
                for r in 0..CHUNK_SIZE as i32 {
                    for b in 0..CHUNK_SIZE as i32 {
                        let mut ao = 0u8;
                        for c @ (dr, db) in CORNERS {
                            let v =
                                vertex_ao(cell(r + dr, b), cell(r, b + db), cell(r + dr, b + db));
                            ao |= v << (2 * slot(axis, c));
                        }
                        want[r as usize][b as usize] = ao;
                        shaded_any[r as usize][b as usize] =
                            (-1..=1).any(|dr| (-1..=1).any(|db| cell(r + dr, b + db)));
                    }
                }
                let mut rows = faces;
                let mut got = [[None; CHUNK_SIZE]; CHUNK_SIZE];
                split_by_ao(&mut rows, &occ, axis, &mut buckets, |ao, _, plane| {
                    for (r, row) in std::mem::take(plane).iter().enumerate() {
                        for b in 0..CHUNK_SIZE {
                            if row >> b & 1 != 0 {
                                assert!(got[r][b].is_none(), "face twice");
                                got[r][b] = Some(ao);
                            }
                        }
                    }
                });
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
                    }
                }
            }
        }
    }
}
