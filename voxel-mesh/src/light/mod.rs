//! Smooth light per vertex for the lit mesher ([`crate::Mesher::mesh_lit`]), Minecraft's
//! smooth lighting on `voxel_core`'s RGB sky and block light ([`voxel_core::LightField`]).
//!
//! **Model.** A corner of an opaque or cutout face takes the mean, per channel and rounded,
//! of the light of the cells in front of the face around that corner: the face's own front
//! cell, the two *sides* (sharing an edge with it in the face's plane) and the *diagonal*.
//! Opaque cells and cells of chunks the field has not lit (unknown) do not count; the
//! diagonal does not count either when both sides are opaque (light around the corner of
//! a wall would leak through it), as in ambient occlusion ([`crate::ao`]). A corner where
//! nothing counts (an edge of the lit area) is dark. A translucent face (water, glass) takes
//! the light of its front cell at all four corners. Between two translucent types (water
//! against glass) each of the two faces points into the other type and takes that cell's
//! light: a face is lit from the side it faces, the side the eye is on when it sees the
//! face from the front, and the light on its own side has crossed the surface already
//! (filtered by the colour the face is drawn with: lighting the face with it would tint
//! the surface twice).
//!
//! Two coplanar faces side by side share two vertices, and a shared vertex has one light:
//! its four cells are the same for both faces, and the rule about the diagonal never applies
//! to it (both faces' front cells are open). So, as for ambient occlusion, quads merge only
//! where the four corner lights (and AO values) of their faces are the same, and the light
//! then changes across a merged row only, never along it: the interpolation over a merged
//! quad is exactly the per-face one.
//!
//! **Layout** (what the renderer uploads beside the quads, one entry per quad in the same
//! order, for each of the three meshes; [`LightStreams`]):
//!
//! ```text
//! QuadLight, 8 bytes (vec2<u32>): the palette indices of the quad's corners
//!   word 0: bits  0..16  corner (u0, v0)    bits 16..32  corner (u1, v0)
//!   word 1: bits  0..16  corner (u0, v1)    bits 16..32  corner (u1, v1)
//!   (the corner order of the AO bits of PackedQuad)
//! PackedLight, 8 bytes (vec2<u32>): one entry of the chunk's palette
//!   word 0: bits  0..8 sky R, 8..16 sky G, 16..24 sky B, 24..32 0
//!   word 1: bits  0..8 block R, 8..16 block G, 16..24 block B, 24..32 0
//! ```
//!
//! One palette per chunk, shared by its three meshes, holding each distinct corner light
//! once. 8 bytes a quad, the size of a [`crate::PackedQuad`], plus 8 bytes a distinct light:
//! the corners of open-sky terrain hold a handful of values, and 16-bit indices give any
//! chunk room (a corner light written per corner would be 24 bytes a quad; 8-bit indices
//! would overflow near several torches). Indices stay below 65 536 (else meshing fails with
//! [`crate::Error::LightPalette`]).
//!
//! **Cost.** Each layer's light is compared once, a cell at a time only where the light
//! field stores the layer dense, with a reference level of that layer (the level most of its
//! open cells hold), giving the *odd* cells: open cells that are unknown or hold another
//! level. A face with no odd cell in front of it takes its layer's reference at every
//! corner (for the side faces of two layers of different references every cell of both
//! counts as odd), and such faces are merged as the unlit mesher merges them, grouped by
//! reference. Only faces with an odd cell in front read the cells and average them.

use bytemuck::{Pod, Zeroable};
use voxel_core::{CHUNK_SIZE, ChunkPos, Light, LightChunk, LightField, LightLayer};

use crate::ao::Pad;

/// Side of the padded shell (a chunk and one block of each neighbour around it).
pub(crate) const P: usize = CHUNK_SIZE + 2;
const FULL: u64 = (1 << P) - 1;
/// Bits 1..=32 of a padded row: the chunk's own cells.
const INNER: u64 = FULL & !1 & !(1 << (P - 1));

/// One light value of a chunk's palette; see the module docs for the layout.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Pod, Zeroable)]
pub struct PackedLight {
    /// Sky light: R in bits 0..8, G in 8..16, B in 16..24.
    pub sky: u32,
    /// Block light: R in bits 0..8, G in 8..16, B in 16..24.
    pub block: u32,
}

impl PackedLight {
    /// Packs a light.
    pub fn new(l: Light) -> Self {
        let rgb = |c: [u8; 3]| u32::from_le_bytes([c[0], c[1], c[2], 0]);
        Self {
            sky: rgb(l.sky),
            block: rgb(l.block),
        }
    }

    /// Unpacks.
    pub fn unpack(self) -> Light {
        let rgb = |w: u32| {
            let [r, g, b, _] = w.to_le_bytes();
            [r, g, b]
        };
        Light {
            sky: rgb(self.sky),
            block: rgb(self.block),
        }
    }

    fn from_levels(v: u64) -> Self {
        Self {
            sky: (v & 0xff_ffff) as u32,
            block: (v >> 24 & 0xff_ffff) as u32,
        }
    }
}

/// The palette indices of a quad's four corners; see the module docs for the layout.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Pod, Zeroable)]
pub struct QuadLight {
    /// Corners (u0, v0) in bits 0..16 and (u1, v0) in bits 16..32.
    pub v0: u32,
    /// Corners (u0, v1) in bits 0..16 and (u1, v1) in bits 16..32.
    pub v1: u32,
}

impl QuadLight {
    /// The entry of corner indices `c`, in the order (u0, v0), (u1, v0), (u0, v1), (u1, v1).
    pub fn new(c: [u16; 4]) -> Self {
        Self {
            v0: u32::from(c[0]) | u32::from(c[1]) << 16,
            v1: u32::from(c[2]) | u32::from(c[3]) << 16,
        }
    }

    /// The palette index of corner `(u, v)` (each 0 or 1).
    #[inline]
    pub fn corner(self, u: usize, v: usize) -> u16 {
        let w = if v == 0 { self.v0 } else { self.v1 };
        (w >> (16 * (u & 1))) as u16
    }

    /// The four indices, in the order of [`QuadLight::new`].
    pub fn corners(self) -> [u16; 4] {
        [(0, 0), (1, 0), (0, 1), (1, 1)].map(|(u, v)| self.corner(u, v))
    }

    fn from_key(k: u64) -> Self {
        Self {
            v0: k as u32,
            v1: (k >> 32) as u32,
        }
    }
}

/// The light of a chunk's meshes: one [`QuadLight`] per quad of each mesh, in the order of
/// its quads, and the palette they index. Empty when the chunk was meshed without light.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LightStreams {
    /// One entry per quad of [`crate::ChunkMeshes::opaque`].
    pub opaque: Vec<QuadLight>,
    /// One entry per quad of [`crate::ChunkMeshes::cutout`].
    pub cutout: Vec<QuadLight>,
    /// One entry per quad of [`crate::ChunkMeshes::translucent`].
    pub translucent: Vec<QuadLight>,
    /// The distinct corner lights of the chunk.
    pub palette: Vec<PackedLight>,
}

impl LightStreams {
    /// Whether there is no light (an unlit mesh, or no quad).
    pub fn is_empty(&self) -> bool {
        self.opaque.is_empty() && self.cutout.is_empty() && self.translucent.is_empty()
    }

    /// Empties the streams, keeping their allocations.
    pub fn clear(&mut self) {
        self.opaque.clear();
        self.cutout.clear();
        self.translucent.clear();
        self.palette.clear();
    }

    /// Bytes the renderer uploads: the three streams and the palette.
    pub fn bytes(&self) -> usize {
        (self.opaque.len() + self.cutout.len() + self.translucent.len())
            * std::mem::size_of::<QuadLight>()
            + self.palette.len() * std::mem::size_of::<PackedLight>()
    }

    /// The light of corner `(u, v)` of a quad whose entry is `q` (what the shaders compute):
    /// `None` for an index outside the palette.
    pub fn corner_light(&self, q: QuadLight, u: usize, v: usize) -> Option<Light> {
        self.palette
            .get(usize::from(q.corner(u, v)))
            .map(|p| p.unpack())
    }

    /// The four corner lights of a quad's entry, in the order of [`QuadLight::new`].
    pub fn corners(&self, q: QuadLight) -> Option<[Light; 4]> {
        let c = q.corners();
        let get = |i: u16| self.palette.get(usize::from(i)).map(|p| p.unpack());
        Some([get(c[0])?, get(c[1])?, get(c[2])?, get(c[3])?])
    }
}

/// The six levels of a cell in the low 48 bits (sky R, G, B, block R, G, B from bit 0).
#[inline(always)]
fn pack(l: &[u8; 6]) -> u64 {
    u64::from(u32::from_le_bytes([l[0], l[1], l[2], l[3]]))
        | u64::from(u16::from_le_bytes([l[4], l[5]])) << 32
}

/// The distinct light values of a chunk, interned (open addressing, keys below 2^48).
#[derive(Clone, Debug, Default)]
pub(crate) struct Palette {
    pub(crate) values: Vec<u64>,
    /// Index + 1 per slot, 0 free.
    table: Vec<u32>,
    /// Set when a chunk needed more than 65 536 values.
    pub(crate) overflow: bool,
}

impl Palette {
    pub(crate) fn clear(&mut self) {
        let bits = self.table.len().trailing_zeros();
        for &v in &self.values {
            let mut i = Self::slot(v, bits);
            while self.table[i] != 0 {
                self.table[i] = 0;
                i = (i + 1) & (self.table.len() - 1);
            }
        }
        self.values.clear();
        self.overflow = false;
    }

    #[inline]
    fn slot(v: u64, bits: u32) -> usize {
        (v.wrapping_mul(0x9e37_79b9_7f4a_7c15) >> (64 - bits)) as usize
    }

    #[inline]
    pub(crate) fn intern(&mut self, v: u64) -> u16 {
        if self.table.len() < 2 * (self.values.len() + 1) {
            self.grow();
        }
        let bits = self.table.len().trailing_zeros();
        let mask = self.table.len() - 1;
        let mut i = Self::slot(v, bits);
        loop {
            match self.table[i] {
                0 => break,
                k if self.values[k as usize - 1] == v => return (k - 1) as u16,
                _ => i = (i + 1) & mask,
            }
        }
        if self.values.len() > usize::from(u16::MAX) {
            self.overflow = true;
            return 0;
        }
        self.values.push(v);
        self.table[i] = self.values.len() as u32;
        (self.values.len() - 1) as u16
    }

    fn grow(&mut self) {
        let len = (self.table.len() * 2).max(256);
        self.table.clear();
        self.table.resize(len, 0);
        let bits = len.trailing_zeros();
        for (k, &v) in self.values.iter().enumerate() {
            let mut i = Self::slot(v, bits);
            while self.table[i] != 0 {
                i = (i + 1) & (len - 1);
            }
            self.table[i] = k as u32 + 1;
        }
    }

    pub(crate) fn write(&self, out: &mut Vec<PackedLight>) {
        out.clear();
        out.extend(self.values.iter().map(|&v| PackedLight::from_levels(v)));
    }
}

/// Region (0: the neighbour below, 1: the chunk, 2: the neighbour above) and local
/// coordinate of padded coordinate `p` (0..34).
#[inline(always)]
fn region(p: usize) -> (usize, usize) {
    if p == 0 {
        (0, CHUNK_SIZE - 1)
    } else if p <= CHUNK_SIZE {
        (1, p - 1)
    } else {
        (2, 0)
    }
}

/// The light chunks of a chunk and its 26 neighbours (`None`: not lit).
#[derive(Clone, Copy)]
pub(crate) struct LitCells<'a> {
    /// By `xr * 9 + yr * 3 + zr` (regions of [`region`]).
    chunks: [Option<&'a LightChunk>; 27],
}

impl<'a> LitCells<'a> {
    pub(crate) fn new(field: &'a LightField, pos: ChunkPos) -> Self {
        Self {
            chunks: std::array::from_fn(|i| {
                let d = [i / 9, i / 3 % 3, i % 3].map(|v| v as i32 - 1);
                pos.offset(d).and_then(|p| field.chunk(p))
            }),
        }
    }

    #[inline(always)]
    fn chunk(&self, xr: usize, yr: usize, zr: usize) -> Option<&'a LightChunk> {
        self.chunks[xr * 9 + yr * 3 + zr]
    }

    /// The levels at padded `(px, py, pz)`, `None` where unknown.
    #[inline]
    fn get(&self, px: usize, py: usize, pz: usize) -> Option<u64> {
        let ((xr, x), (yr, y), (zr, z)) = (region(px), region(py), region(pz));
        let c = self.chunk(xr, yr, zr)?;
        Some(match c.layer(y) {
            LightLayer::Uniform(v) => pack(&v),
            LightLayer::Dense(d) => pack(&d[x << 5 | z]),
        })
    }
}

/// The light side of the mesher's working memory (see the module docs' "Cost").
#[derive(Clone)]
pub(crate) struct LightScratch {
    /// Odd cells, rows along x: bit `px` of `odd_x[py][pz]` (padded coordinates).
    odd_x: [[u64; P]; P],
    /// The same cells, columns along y: bit `py` of `odd_y[px][pz]`.
    odd_y: [[u64; P]; P],
    /// Bit `py`: the reference of layer `py` differs from that of a layer next to it.
    boundary: u64,
    /// Reference levels per padded layer.
    refs: [u64; P],
    /// Their palette indices, interned on first use (`u16::MAX` before).
    ref_idx: [u16; P],
    pub(crate) palette: Palette,
    /// Per face of a plane (`row * 32 + bit`): its corner indices and AO byte.
    keys: Box<[u64; CHUNK_SIZE * CHUNK_SIZE]>,
    aos: Box<[u8; CHUNK_SIZE * CHUNK_SIZE]>,
}

impl LightScratch {
    pub(crate) fn new() -> Box<Self> {
        Box::new(Self {
            odd_x: [[0; P]; P],
            odd_y: [[0; P]; P],
            boundary: 0,
            refs: [0; P],
            ref_idx: [u16::MAX; P],
            palette: Palette::default(),
            keys: Box::new([0; CHUNK_SIZE * CHUNK_SIZE]),
            aos: Box::new([0; CHUNK_SIZE * CHUNK_SIZE]),
        })
    }

    /// Finds each layer's reference and the odd cells, from the light of the chunk and its
    /// neighbours (`cells`) and the opaque cells (`pad`, filled).
    pub(crate) fn build(&mut self, cells: &LitCells<'_>, pad: &Pad) {
        self.palette.clear();
        self.ref_idx = [u16::MAX; P];
        self.odd_x = [[0; P]; P];
        self.odd_y = [[0; P]; P];
        let opaque = pad.rows_x();
        for py in (0..P).rev() {
            let (yr, y) = region(py);
            // The reference: a uniform layer's levels, or the level most open cells of a
            // dense one hold (tried first: the reference of the layer above).
            let mut inner = [0u32; CHUNK_SIZE];
            let reference = match cells.chunk(1, yr, 1).map(|c| c.layer(y)) {
                None => 0,
                Some(LightLayer::Uniform(v)) => pack(&v),
                Some(LightLayer::Dense(d)) => {
                    let open: [u32; CHUNK_SIZE] =
                        std::array::from_fn(|z| !(opaque[py][z + 1] >> 1) as u32);
                    let above = self.refs.get(py + 1).copied();
                    let first = above.unwrap_or_else(|| pack(&d[0]));
                    let (n_open, n_odd, other) = odd_rows(d, &open, first, &mut inner);
                    match other {
                        Some(second) if 2 * n_odd > n_open => {
                            let (_, n2, _) = odd_rows(d, &open, second, &mut inner);
                            if n2 < n_odd {
                                second
                            } else {
                                odd_rows(d, &open, first, &mut inner);
                                first
                            }
                        }
                        _ => first,
                    }
                }
            };
            // A layer without an open cell counts nowhere: it takes the reference above, so
            // that it does not make the layers next to it boundaries.
            let open = opaque[py].iter().any(|&r| r & FULL != FULL);
            let reference = match self.refs.get(py + 1) {
                Some(&above) if !open => above,
                _ => reference,
            };
            self.refs[py] = reference;
            let uniform = |c: Option<&LightChunk>| {
                matches!(c.map(|c| c.layer(y)), Some(LightLayer::Uniform(v)) if pack(&v) == reference)
            };
            let quiet = (0..9).all(|k| uniform(cells.chunk(k / 3, yr, k % 3)));
            if quiet {
                continue;
            }
            for pz in 0..P {
                let (zr, z) = region(pz);
                let mut bits = match cells.chunk(1, yr, zr).map(|c| c.layer(y)) {
                    None => INNER,
                    Some(LightLayer::Uniform(v)) if pack(&v) == reference => 0,
                    Some(LightLayer::Uniform(_)) => INNER,
                    Some(LightLayer::Dense(_)) if zr == 1 => u64::from(inner[z]) << 1,
                    Some(LightLayer::Dense(d)) => (0..CHUNK_SIZE).fold(0, |acc, x| {
                        acc | u64::from(pack(&d[x << 5 | z]) != reference) << (x + 1)
                    }),
                };
                for (px, xr, x) in [(0, 0, CHUNK_SIZE - 1), (P - 1, 2, 0)] {
                    let odd = match cells.chunk(xr, yr, zr).map(|c| c.layer(y)) {
                        None => true,
                        Some(LightLayer::Uniform(v)) => pack(&v) != reference,
                        Some(LightLayer::Dense(d)) => pack(&d[x << 5 | z]) != reference,
                    };
                    bits |= u64::from(odd) << px;
                }
                bits &= !opaque[py][pz] & FULL;
                self.odd_x[py][pz] = bits;
                while bits != 0 {
                    let px = bits.trailing_zeros() as usize;
                    bits &= bits - 1;
                    self.odd_y[px][pz] |= 1 << py;
                }
            }
        }
        self.boundary = 0;
        for py in 0..P {
            let differs = (py > 0 && self.refs[py - 1] != self.refs[py])
                || (py + 1 < P && self.refs[py + 1] != self.refs[py]);
            self.boundary |= u64::from(differs) << py;
        }
    }

    /// The palette index of the reference of padded layer `py`.
    #[inline]
    pub(crate) fn reference(&mut self, py: usize) -> u16 {
        if self.ref_idx[py] == u16::MAX {
            self.ref_idx[py] = self.palette.intern(self.refs[py]);
        }
        self.ref_idx[py]
    }

    /// Whether padded layers `a` and `b` have the same reference.
    #[inline]
    pub(crate) fn same_reference(&self, a: usize, b: usize) -> bool {
        self.refs[a] == self.refs[b]
    }

    /// The odd cells of the layer in front of a plane of faces (`axis`, padded layer
    /// `next`), in the plane's layout (rows and bits as [`Pad::occluders`]). For x and z
    /// planes the cells of a layer whose reference differs from a layer next to it count
    /// as odd.
    #[inline]
    fn odd_plane(&self, axis: usize, next: usize, pad: &Pad) -> [u64; P] {
        match axis {
            1 => self.odd_x[next],
            0 => {
                let opaque = pad.columns_y();
                std::array::from_fn(|pz| {
                    self.odd_y[next][pz] | (self.boundary & !opaque[next][pz] & FULL)
                })
            }
            _ => {
                let opaque = pad.rows_x();
                std::array::from_fn(|py| {
                    let b = if self.boundary >> py & 1 != 0 {
                        !opaque[py][next] & FULL
                    } else {
                        0
                    };
                    self.odd_x[py][next] | b
                })
            }
        }
    }
}

/// Marks in `out` the open cells (`open`, rows z, bits x) of a dense layer whose levels are
/// not `reference`; returns the open cells, the odd ones, and the first odd level.
fn odd_rows(
    d: &[[u8; 6]; CHUNK_SIZE * CHUNK_SIZE],
    open: &[u32; CHUNK_SIZE],
    reference: u64,
    out: &mut [u32; CHUNK_SIZE],
) -> (u32, u32, Option<u64>) {
    let (mut n_open, mut n_odd, mut other) = (0, 0, None);
    for z in 0..CHUNK_SIZE {
        let mut row = 0u32;
        for x in 0..CHUNK_SIZE {
            row |= u32::from(pack(&d[x << 5 | z]) != reference) << x;
        }
        row &= open[z];
        if row != 0 && other.is_none() {
            let x = row.trailing_zeros() as usize;
            other = Some(pack(&d[x << 5 | z]));
        }
        n_open += open[z].count_ones();
        n_odd += row.count_ones();
        out[z] = row;
    }
    (n_open, n_odd, other)
}

/// What the emitting code of a plane needs for light.
pub(crate) struct LitPlane<'s, 'c> {
    pub(crate) s: &'s mut LightScratch,
    pub(crate) cells: &'s LitCells<'c>,
    pub(crate) pad: &'s Pad,
    /// Translucent faces: the light of the front cell only.
    pub(crate) flat: bool,
}

/// Where a face's (row, bit) neighbour `(dr, db)` goes in a plane of `axis` at padded
/// layer `next`: padded (x, y, z).
#[inline(always)]
fn padded(axis: usize, next: usize, pr: usize, pb: usize) -> (usize, usize, usize) {
    match axis {
        0 => (next, pb, pr),
        1 => (pb, next, pr),
        _ => (pb, pr, next),
    }
}

/// The levels of a cell that counts (open and known).
#[inline]
fn counted(cells: &LitCells<'_>, pad: &Pad, p: (usize, usize, usize)) -> Option<u64> {
    if pad.opaque_at(p.0, p.1, p.2) {
        None
    } else {
        cells.get(p.0, p.1, p.2)
    }
}

/// The mean, rounded, per channel, of `n` (1 to 4) levels summed in 16-bit lanes.
#[inline]
fn mean(sum: [u16; 6], n: u16) -> u64 {
    let mut v = 0u64;
    for (i, s) in sum.into_iter().enumerate() {
        v |= u64::from((s + n / 2) / n) << (8 * i);
    }
    v
}

/// The corner lights of the face at row `r`, bit `b` of a plane (`axis`, padded layer
/// `next` in front), in the slot order of [`QuadLight::new`]; `flat`: the front cell's.
pub(crate) fn face_corners(
    cells: &LitCells<'_>,
    pad: &Pad,
    axis: usize,
    next: usize,
    r: usize,
    b: usize,
    flat: bool,
) -> [u64; 4] {
    let at = |dr: isize, db: isize| {
        let pr = (r as isize + 1 + dr) as usize;
        let pb = (b as isize + 1 + db) as usize;
        padded(axis, next, pr, pb)
    };
    let front = counted(cells, pad, at(0, 0));
    if flat {
        return [front.unwrap_or(0); 4];
    }
    let mut out = [0; 4];
    for (dr, db) in [(-1, -1), (-1, 1), (1, -1), (1, 1)] {
        let s1 = at(dr, 0);
        let s2 = at(0, db);
        let walled = pad.opaque_at(s1.0, s1.1, s1.2) && pad.opaque_at(s2.0, s2.1, s2.2);
        let diag = if walled { None } else { Some(at(dr, db)) };
        let (mut sum, mut n) = ([0u16; 6], 0u16);
        for v in [Some(s1), Some(s2), diag]
            .into_iter()
            .flatten()
            .filter_map(|p| counted(cells, pad, p))
            .chain(front)
        {
            for (i, s) in sum.iter_mut().enumerate() {
                *s += (v >> (8 * i) & 0xff) as u16;
            }
            n += 1;
        }
        let value = if n == 0 { 0 } else { mean(sum, n) };
        let (du, dv) = if axis == 1 { (dr, db) } else { (db, dr) };
        out[usize::from(du > 0) + 2 * usize::from(dv > 0)] = value;
    }
    out
}

/// Covers the faces of `sel` (its live rows `live`) whose corner lights and AO are keyed
/// in `keys` and `aos` (`row * 32 + bit`) with rectangles of equal keys: the greedy cover
/// of [`crate::greedy_rects`] with a per-face key, as `ao::cover_occluded` does.
fn cover_keyed(
    sel: &mut [u32; CHUNK_SIZE],
    mut live: u32,
    keys: &[u64; CHUNK_SIZE * CHUNK_SIZE],
    aos: &[u8; CHUNK_SIZE * CHUNK_SIZE],
    mut emit: impl FnMut(usize, usize, usize, usize, u8, QuadLight),
) {
    let key = |r: usize, b: usize| (keys[r * CHUNK_SIZE + b], aos[r * CHUNK_SIZE + b]);
    while live != 0 {
        let r = live.trailing_zeros() as usize;
        live &= live - 1;
        let mut bits = sel[r];
        sel[r] = 0;
        while bits != 0 {
            let b0 = bits.trailing_zeros() as usize;
            let k = key(r, b0);
            let mut end = b0 + 1;
            while end < CHUNK_SIZE && bits >> end & 1 != 0 && key(r, end) == k {
                end += 1;
            }
            let run = (u32::MAX >> (CHUNK_SIZE - (end - b0))) << b0;
            bits &= !run;
            let mut h = 1;
            while r + h < CHUNK_SIZE
                && sel[r + h] & run == run
                && (b0..end).all(|b| key(r + h, b) == k)
            {
                sel[r + h] &= !run;
                if sel[r + h] == 0 {
                    live &= !(1 << (r + h));
                }
                h += 1;
            }
            emit(r, h, b0, end - b0, k.1, QuadLight::from_key(k.0));
        }
    }
}

impl LitPlane<'_, '_> {
    /// Takes out of `rows` (live rows `live`) the faces with an odd cell in front of them,
    /// covers them by their own corner lights and AO (`occ`: the AO occluders of the
    /// plane) and emits them; returns the rows still holding faces.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn emit_odd(
        &mut self,
        rows: &mut [u32; CHUNK_SIZE],
        live: u32,
        axis: usize,
        next: usize,
        occ: Option<&crate::ao::Occluders>,
        mut emit: impl FnMut(usize, usize, usize, usize, u8, QuadLight),
    ) -> u32 {
        let odd = self.s.odd_plane(axis, next, self.pad);
        let mut sel = [0u32; CHUNK_SIZE];
        let (mut sel_live, mut left, mut l) = (0u32, live, live);
        while l != 0 {
            let r = l.trailing_zeros() as usize;
            l &= l - 1;
            let v = if self.flat {
                odd[r + 1] >> 1
            } else {
                let v = odd[r] | odd[r + 1] | odd[r + 2];
                v | v >> 1 | v >> 2
            };
            let s = rows[r] & v as u32;
            if s != 0 {
                sel[r] = s;
                rows[r] &= !s;
                sel_live |= 1 << r;
                if rows[r] == 0 {
                    left &= !(1 << r);
                }
            }
        }
        if sel_live == 0 {
            return left;
        }
        let LightScratch {
            keys,
            aos,
            palette,
            refs,
            ..
        } = &mut *self.s;
        let mut l = sel_live;
        while l != 0 {
            let r = l.trailing_zeros() as usize;
            l &= l - 1;
            let mut bits = sel[r];
            while bits != 0 {
                let b = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                let c = face_corners(self.cells, self.pad, axis, next, r, b, self.flat);
                let uniform = c[1..].iter().all(|&v| v == c[0]);
                // A face whose corners all take the reference of its front cell's layer
                // goes back to the faces covered by reference, so that it merges with them
                // as without light.
                let own = match axis {
                    1 => next,
                    0 => b + 1,
                    _ => r + 1,
                };
                if uniform && c[0] == refs[own] {
                    sel[r] &= !(1 << b);
                    rows[r] |= 1 << b;
                    left |= 1 << r;
                    continue;
                }
                let k = if uniform {
                    let i = u64::from(palette.intern(c[0]));
                    i * 0x0001_0001_0001_0001
                } else {
                    c.iter()
                        .enumerate()
                        .fold(0, |acc, (j, &v)| acc | u64::from(palette.intern(v)) << (16 * j))
                };
                keys[r * CHUNK_SIZE + b] = k;
                aos[r * CHUNK_SIZE + b] = occ.map_or(crate::AO_NONE, |o| crate::ao::face_ao(o, axis, r, b));
            }
        }
        let sel_live = crate::bits::live_rows(&sel);
        cover_keyed(&mut sel, sel_live, keys, aos, &mut emit);
        left
    }
}

/// The entry of a quad whose corners all take palette index `i`.
#[inline]
pub(crate) fn uniform(i: u16) -> QuadLight {
    QuadLight::new([i; 4])
}

#[cfg(test)]
mod tests;
