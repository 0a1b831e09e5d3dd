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
//! level. For a dense layer the field's odd cells ([`LightChunk::odd_cells`], kept until
//! the layer is written) give both, where at most half the open cells are odd against
//! them. A face with no odd cell in front of it takes its layer's reference at every
//! corner (a side face counts as having one too where an open cell in front of it lies in
//! the layer above or below, of another reference), and such faces are merged as the
//! unlit mesher merges them, grouped by reference. Only faces with an odd cell in front
//! read the cells and average them, each vertex's light computed and interned once per
//! plane.

use bytemuck::{Pod, Zeroable};
use voxel_core::{CHUNK_SIZE, ChunkPos, Light, LightChunk, LightField, LightLayer};

use crate::ao::Pad;
use crate::bits::greedy_rects_keyed;

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
    /// The last value interned and its index (neighbouring corners often agree).
    last: Option<(u64, u16)>,
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
        self.last = None;
    }

    #[inline]
    fn slot(v: u64, bits: u32) -> usize {
        (v.wrapping_mul(0x9e37_79b9_7f4a_7c15) >> (64 - bits)) as usize
    }

    #[inline]
    pub(crate) fn intern(&mut self, v: u64) -> u16 {
        match self.last {
            Some((l, i)) if l == v => i,
            _ => {
                let i = self.intern_hashed(v);
                self.last = Some((v, i));
                i
            }
        }
    }

    fn intern_hashed(&mut self, v: u64) -> u16 {
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

/// The light of a chunk and its 26 neighbours, a layer at a time: per padded layer `py`,
/// the layers of the nine chunks it crosses by `xr * 3 + zr` (regions of [`region`];
/// `None`: not lit).
#[derive(Clone, Copy)]
pub(crate) struct LitCells<'a> {
    layers: [[Option<LightLayer<'a>>; 9]; P],
    /// The 27 chunks, by `xr * 9 + yr * 3 + zr` (regions of [`region`]).
    chunks: [Option<&'a LightChunk>; 27],
}

impl<'a> LitCells<'a> {
    pub(crate) fn new(field: &'a LightField, pos: ChunkPos) -> Self {
        Self::from_fn(|d| pos.offset(d).and_then(|p| field.chunk(p)))
    }

    /// The light of the chunk at offset `d` (each coordinate −1 to 1) from `light`.
    pub(crate) fn from_fn(light: impl Fn([i32; 3]) -> Option<&'a LightChunk>) -> Self {
        let chunks: [Option<&'a LightChunk>; 27] =
            std::array::from_fn(|i| light([i / 9, i / 3 % 3, i % 3].map(|v| v as i32 - 1)));
        Self {
            layers: std::array::from_fn(|py| {
                let (yr, y) = region(py);
                std::array::from_fn(|k| chunks[k / 3 * 9 + yr * 3 + k % 3].map(|c| c.layer(y)))
            }),
            chunks,
        }
    }

    /// The field's odd cells of the layer of padded `py` in chunk `k` (`xr * 3 + zr`, as
    /// `layers`), where it is dense.
    fn odd_cells(&self, py: usize, k: usize) -> Option<&'a voxel_core::OddCells> {
        let (yr, y) = region(py);
        self.chunks[k / 3 * 9 + yr * 3 + k % 3].and_then(|c| c.odd_cells(y))
    }

    /// The levels at padded `(px, py, pz)`, `None` where unknown.
    #[inline(always)]
    fn get(&self, px: usize, py: usize, pz: usize) -> Option<u64> {
        let ((xr, x), (zr, z)) = (region(px), region(pz));
        Some(match self.layers[py][xr * 3 + zr]? {
            LightLayer::Uniform(v) => pack(&v),
            LightLayer::Dense(d) => pack(&d[x << 5 | z]),
        })
    }
}

/// Per plane of faces: the levels of the cells in front of its faces with an odd cell in
/// front, by `row * 34 + bit` (padded), and the light of its vertices, by `row * 34 + bit`
/// (rows and bits 0..33).
#[derive(Clone)]
struct Plane {
    raw: [u64; P * P],
    /// The same levels spread into 16-bit lanes: sky (`[0]`) and block (`[1]`).
    spread: [[u64; 2]; P * P],
    vertex: [u64; P * P],
    /// Bit `vb` of row `vr`: `vertex` holds that vertex.
    vertex_ok: [u64; P],
    /// The palette index of a vertex's light, where `index_ok` says it is interned.
    index: [u16; P * P],
    index_ok: [u64; P],
}

/// The light side of the mesher's working memory (see the module docs' "Cost").
#[derive(Clone)]
pub(crate) struct LightScratch {
    /// Odd cells, rows along x: bit `px` of `odd_x[py][pz]` (padded coordinates).
    odd_x: [[u64; P]; P],
    /// The same cells, columns along y: bit `py` of `odd_y[px][pz]`.
    odd_y: [[u64; P]; P],
    /// Bit `py`: rows of `odd_x[py]` written (to clear).
    written: u64,
    /// Reference levels per padded layer.
    refs: [u64; P],
    /// Their palette indices, interned on first use (`u16::MAX` before).
    ref_idx: [u16; P],
    pub(crate) palette: Palette,
    /// Per face of a plane (`row * 32 + bit`): its corner indices and AO byte.
    keys: Box<[u64; CHUNK_SIZE * CHUNK_SIZE]>,
    aos: Box<[u8; CHUNK_SIZE * CHUNK_SIZE]>,
    plane: Box<Plane>,
}

impl LightScratch {
    pub(crate) fn new() -> Box<Self> {
        Box::new(Self {
            odd_x: [[0; P]; P],
            odd_y: [[0; P]; P],
            written: 0,
            refs: [0; P],
            ref_idx: [u16::MAX; P],
            palette: Palette::default(),
            keys: Box::new([0; CHUNK_SIZE * CHUNK_SIZE]),
            aos: Box::new([0; CHUNK_SIZE * CHUNK_SIZE]),
            plane: Box::new(Plane {
                raw: [0; P * P],
                spread: [[0; 2]; P * P],
                vertex: [0; P * P],
                vertex_ok: [0; P],
                index: [0; P * P],
                index_ok: [0; P],
            }),
        })
    }

    /// Finds each layer's reference and the odd cells, from the light of the chunk and its
    /// neighbours (`cells`) and the opaque cells (`pad`, filled).
    pub(crate) fn build(&mut self, cells: &LitCells<'_>, pad: &Pad) {
        self.palette.clear();
        self.ref_idx = [u16::MAX; P];
        if self.written != 0 {
            let mut w = self.written;
            while w != 0 {
                self.odd_x[w.trailing_zeros() as usize] = [0; P];
                w &= w - 1;
            }
            self.odd_y = [[0; P]; P];
            self.written = 0;
        }
        let opaque = pad.rows_x();
        for py in (0..P).rev() {
            let layers = &cells.layers[py];
            let above = self.refs.get(py + 1).copied().filter(|_| py + 1 < P);
            let open_any = opaque[py].iter().any(|&r| r & FULL != FULL);
            // The reference: a uniform layer's levels, or the level most open cells of a
            // dense one hold (tried first: the reference of the layer above).
            let mut inner = [0u32; CHUNK_SIZE];
            let reference = match layers[4] {
                None => 0,
                Some(LightLayer::Uniform(v)) => pack(&v),
                Some(LightLayer::Dense(d)) if open_any => 'dense: {
                    let open: [u32; CHUNK_SIZE] =
                        std::array::from_fn(|z| !(opaque[py][z + 1] >> 1) as u32);
                    // The field's odd cells of the layer, where at most half the open
                    // cells are odd against its reference.
                    if let Some(odd) = cells.odd_cells(py, 4) {
                        let (mut n_open, mut n_odd) = (0, 0);
                        for z in 0..CHUNK_SIZE {
                            inner[z] = odd.rows[z] & open[z];
                            n_open += open[z].count_ones();
                            n_odd += inner[z].count_ones();
                        }
                        if 2 * n_odd <= n_open {
                            break 'dense pack(&odd.reference);
                        }
                    }
                    // The majority of 32 open cells spread over the layer (Boyer and Moore's
                    // vote), else the reference above.
                    let (mut vote, mut count) = (above.unwrap_or_else(|| pack(&d[0])), 0u32);
                    for z in 0..CHUNK_SIZE {
                        let x = z * 7 % CHUNK_SIZE;
                        if open[z] >> x & 1 != 0 {
                            let v = pack(&d[x << 5 | z]);
                            if count == 0 {
                                (vote, count) = (v, 1);
                            } else if v == vote {
                                count += 1;
                            } else {
                                count -= 1;
                            }
                        }
                    }
                    let first = vote;
                    let (n_open, n_odd) = odd_rows(d, &open, first, &mut inner);
                    let other = (0..CHUNK_SIZE)
                        .find(|&z| inner[z] != 0)
                        .map(|z| pack(&d[(inner[z].trailing_zeros() as usize) << 5 | z]));
                    match other {
                        Some(second) if 2 * n_odd > n_open => {
                            let mut again = [0u32; CHUNK_SIZE];
                            let (_, n2) = odd_rows(d, &open, second, &mut again);
                            if n2 < n_odd {
                                inner = again;
                                second
                            } else {
                                first
                            }
                        }
                        _ => first,
                    }
                }
                Some(LightLayer::Dense(d)) => pack(&d[0]),
            };
            // A layer without an open cell counts nowhere: it takes the reference above, so
            // that it does not make the layers next to it boundaries.
            let reference = match above {
                Some(a) if !open_any => a,
                _ => reference,
            };
            self.refs[py] = reference;
            let same = |l: &Option<LightLayer<'_>>| matches!(l, Some(LightLayer::Uniform(v)) if pack(v) == reference);
            if !open_any || layers.iter().all(same) {
                continue;
            }
            let odd_at = |l: Option<LightLayer<'_>>, x: usize, z: usize| match l {
                None => true,
                Some(LightLayer::Uniform(v)) => pack(&v) != reference,
                Some(LightLayer::Dense(d)) => pack(&d[x << 5 | z]) != reference,
            };
            self.written |= 1 << py;
            // Per layer of the nine: `Some(odd)` where every cell is alike (unknown or
            // uniform), `None` where it is dense.
            let whole: [Option<bool>; 9] = std::array::from_fn(|k| match layers[k] {
                None => Some(true),
                Some(LightLayer::Uniform(v)) => Some(pack(&v) != reference),
                Some(LightLayer::Dense(_)) => None,
            });
            let border = |k: usize, x: usize, z: usize| match whole[k] {
                Some(o) => o,
                None => odd_at(layers[k], x, z),
            };
            #[allow(clippy::needless_range_loop)] // pz indexes three tables and a region
            for pz in 0..P {
                let (zr, z) = region(pz);
                let mut bits = match (whole[3 + zr], layers[3 + zr]) {
                    (Some(true), _) => INNER,
                    (Some(false), _) => 0,
                    (None, _) if zr == 1 => u64::from(inner[z]) << 1,
                    (None, Some(LightLayer::Dense(d))) => match cells.odd_cells(py, 3 + zr) {
                        Some(odd) if pack(&odd.reference) == reference => {
                            u64::from(odd.rows[z]) << 1
                        }
                        _ => (0..CHUNK_SIZE).fold(0, |acc, x| {
                            acc | u64::from(pack(&d[x << 5 | z]) != reference) << (x + 1)
                        }),
                    },
                    (None, _) => INNER,
                };
                bits |= u64::from(border(zr, CHUNK_SIZE - 1, z));
                bits |= u64::from(border(6 + zr, 0, z)) << (P - 1);
                bits &= !opaque[py][pz] & FULL;
                self.odd_x[py][pz] = bits;
                while bits != 0 {
                    let px = bits.trailing_zeros() as usize;
                    bits &= bits - 1;
                    self.odd_y[px][pz] |= 1 << py;
                }
            }
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
    /// `next`), in the plane's layout (rows and bits as [`Pad::occluders`]).
    #[inline]
    fn odd_plane(&self, axis: usize, next: usize) -> [u64; P] {
        match axis {
            1 => self.odd_x[next],
            0 => self.odd_y[next],
            _ => std::array::from_fn(|py| self.odd_x[py][next]),
        }
    }
}

/// Marks in `out` (rows z, bits x) the open cells (`open`, the same layout) of a dense
/// layer whose levels are not `reference`; returns the number of open cells and of those
/// marked. Compares four cells (three words) at a time in memory order, then transposes.
fn odd_rows(
    d: &[[u8; 6]; CHUNK_SIZE * CHUNK_SIZE],
    open: &[u32; CHUNK_SIZE],
    reference: u64,
    out: &mut [u32; CHUNK_SIZE],
) -> (u32, u32) {
    const M: u64 = (1 << 48) - 1;
    let r = reference;
    // The reference repeated over 24 bytes (four cells), as three little-endian words.
    let (p0, p1, p2) = (r | r << 48, r >> 16 | r << 32, r >> 32 | r << 16);
    let mut by_x = [0u32; CHUNK_SIZE];
    for (column, cells) in by_x
        .iter_mut()
        .zip(d.as_flattened().chunks_exact(6 * CHUNK_SIZE))
    {
        let mut bits = 0u32;
        for (k, g) in cells.chunks_exact(24).enumerate() {
            let w = |i: usize| {
                let mut b = [0u8; 8];
                b.copy_from_slice(&g[8 * i..8 * i + 8]);
                u64::from_le_bytes(b)
            };
            let (a, b, c) = (w(0) ^ p0, w(1) ^ p1, w(2) ^ p2);
            let four = u32::from(a & M != 0)
                | u32::from((a >> 48 | b << 16) & M != 0) << 1
                | u32::from((b >> 32 | c << 32) & M != 0) << 2
                | u32::from(c >> 16 != 0) << 3;
            bits |= four << (4 * k);
        }
        *column = bits;
    }
    let rows = crate::bits::transpose32(&by_x);
    let (mut n_open, mut n_odd) = (0, 0);
    for z in 0..CHUNK_SIZE {
        out[z] = rows[z] & open[z];
        n_open += open[z].count_ones();
        n_odd += out[z].count_ones();
    }
    (n_open, n_odd)
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

/// Spreads four bytes into the four 16-bit lanes of a word.
#[inline(always)]
fn lanes(x: u64) -> u64 {
    (x & 0xff) | (x & 0xff00) << 8 | (x & 0xff_0000) << 16 | (x & 0xff00_0000) << 24
}

/// The inverse of [`lanes`] (lanes below 256).
#[inline(always)]
fn unlanes(l: u64) -> u64 {
    (l & 0xff) | (l >> 8 & 0xff00) | (l >> 16 & 0xff_0000) | (l >> 24 & 0xff00_0000)
}

/// The mean, rounded half up, of `n` (1 to 4) levels summed in the 16-bit lanes of `s`:
/// shifts for 1, 2 and 4; for 3, `(s + 1) · 21 846 >> 16` per lane (21 846 is 2^16 / 3
/// rounded up, exact for sums up to 3 · 255).
#[inline(always)]
fn mean_lanes(s: u64, n: u32) -> u64 {
    const ONES: u64 = 0x0001_0001_0001_0001;
    const LOW: u64 = 0x00ff_00ff_00ff_00ff;
    match n {
        1 => s,
        2 => (s + ONES) >> 1 & LOW,
        4 => (s + 2 * ONES) >> 2 & LOW,
        _ => (0..4).fold(0, |acc, i| {
            let l = s >> (16 * i) & 0xffff;
            acc | (((l + 1) * 21846) >> 16) << (16 * i)
        }),
    }
}

/// Covers the faces of `sel` (its live rows `live`) whose corner lights and AO are keyed
/// in `keys` and `aos` (`row * 32 + bit`) with rectangles of equal keys: the greedy cover
/// of [`greedy_rects_keyed`] with the pair as the key, as `ao::cover_occluded` keys by AO.
fn cover_keyed(
    sel: &mut [u32; CHUNK_SIZE],
    live: u32,
    keys: &[u64; CHUNK_SIZE * CHUNK_SIZE],
    aos: &[u8; CHUNK_SIZE * CHUNK_SIZE],
    mut emit: impl FnMut(usize, usize, usize, usize, u8, QuadLight),
) {
    let key = |r: usize, b: usize| (keys[r * CHUNK_SIZE + b], aos[r * CHUNK_SIZE + b]);
    greedy_rects_keyed(sel, live, key, |r, h, b, w, (light, ao)| {
        emit(r, h, b, w, ao, QuadLight::from_key(light));
    });
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
        // The plane's opaque cells in front, rows and bits as `odd`.
        let op: [u64; P] = match axis {
            1 => self.pad.rows_x()[next],
            0 => self.pad.columns_y()[next],
            _ => std::array::from_fn(|pr| self.pad.rows_x()[pr][next]),
        };
        let odd = self.s.odd_plane(axis, next);
        // Side faces: bit `p` of `low` (`high`), the reference of layer `p` differs from
        // that of layer `p + 1` (`p - 1`): a face at padded y whose open cells in front
        // reach a layer of another reference (y - 1 or y + 1) has an odd cell in front.
        let refs = &self.s.refs;
        let (mut low, mut high) = (0u64, 0u64);
        if axis != 1 && !self.flat {
            for p in 0..P - 1 {
                let d = u64::from(refs[p] != refs[p + 1]);
                low |= d << p;
                high |= d << (p + 1);
            }
        }
        if low == 0 && odd.iter().all(|&o| o == 0) {
            return live;
        }
        let mut sel = [0u32; CHUNK_SIZE];
        let (mut sel_live, mut left, mut l) = (0u32, live, live);
        while l != 0 {
            let r = l.trailing_zeros() as usize;
            l &= l - 1;
            let v = if self.flat {
                odd[r + 1] >> 1
            } else {
                let v = odd[r] | odd[r + 1] | odd[r + 2];
                let v = v | v >> 1 | v >> 2;
                if low == 0 {
                    v
                } else if axis == 0 {
                    // Bits are y.
                    let open = !(op[r] & op[r + 1] & op[r + 2]) & FULL;
                    v | (open & low) | (open & high) >> 2
                } else {
                    // Rows are y.
                    let open = |pr: usize| {
                        let o = !op[pr] & FULL;
                        o | o >> 1 | o >> 2
                    };
                    let mut e = 0;
                    if low >> r & 1 != 0 {
                        e |= open(r);
                    }
                    if high >> (r + 2) & 1 != 0 {
                        e |= open(r + 2);
                    }
                    v | e
                }
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
            plane,
            ..
        } = &mut *self.s;
        let Plane {
            raw,
            spread,
            vertex,
            vertex_ok,
            index,
            index_ok,
        } = &mut **plane;
        // The cells in front of the selected faces that count (open and known), read once.
        let mut need = [0u64; P];
        // Bit `pr`: row `pr` of `need` holds a cell.
        let mut need_live = 0u64;
        let mut l = sel_live;
        while l != 0 {
            let r = l.trailing_zeros() as usize;
            l &= l - 1;
            let d = u64::from(sel[r]);
            let w = if self.flat {
                d << 1
            } else {
                d | d << 1 | d << 2
            };
            let rows = if self.flat { r + 1..r + 2 } else { r..r + 3 };
            need_live |= if self.flat { 2 } else { 7 } << r;
            for n in &mut need[rows] {
                *n |= w;
            }
        }
        let mut counts = [0u64; P];
        let mut nl = need_live;
        while nl != 0 {
            let pr = nl.trailing_zeros() as usize;
            nl &= nl - 1;
            // Vertices of row `pr` are cached below.
            vertex_ok[pr] = 0;
            index_ok[pr] = 0;
            let mut bits = need[pr] & !op[pr];
            while bits != 0 {
                let pb = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                let (px, py, pz) = padded(axis, next, pr, pb);
                if let Some(v) = self.cells.get(px, py, pz) {
                    let i = pr * P + pb;
                    raw[i] = v;
                    spread[i] = [lanes(v & 0xff_ffff), lanes(v >> 24)];
                    counts[pr] |= 1 << pb;
                }
            }
        }
        // The light of vertex (vr, vb) of the plane, where the rule about the diagonal
        // does not apply: the mean of the counted cells of the 2 × 2 around it.
        let mut at_vertex = |vr: usize, vb: usize| -> u64 {
            let i = vr * P + vb;
            if vertex_ok[vr] >> vb & 1 != 0 {
                return vertex[i];
            }
            let (m0, m1) = (counts[vr] >> vb & 3, counts[vr + 1] >> vb & 3);
            // Set bits of m0 | m1 << 2 (no `count_ones`: x86-64's baseline has no popcnt).
            const ONES: [u8; 16] = [0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4];
            let n = u32::from(ONES[(m0 | m1 << 2) as usize]);
            let v = if n == 0 {
                0
            } else {
                let (mut sl, mut sh) = (0, 0);
                for (row, m) in [(vr, m0), (vr + 1, m1)] {
                    for k in 0..2 {
                        if m >> k & 1 != 0 {
                            let [l, h] = spread[row * P + vb + k];
                            sl += l;
                            sh += h;
                        }
                    }
                }
                unlanes(mean_lanes(sl, n)) | unlanes(mean_lanes(sh, n)) << 24
            };
            vertex[i] = v;
            vertex_ok[vr] |= 1 << vb;
            v
        };
        let mut l = sel_live;
        while l != 0 {
            let r = l.trailing_zeros() as usize;
            l &= l - 1;
            let mut bits = sel[r];
            while bits != 0 {
                let b = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                let front = if counts[r + 1] >> (b + 1) & 1 != 0 {
                    raw[(r + 1) * P + b + 1]
                } else {
                    0
                };
                let mut c = [front; 4];
                // The vertex of each corner (`NONE`: the front cell's light).
                const NONE: (usize, usize) = (usize::MAX, 0);
                let mut at = [NONE; 4];
                if !self.flat {
                    // Corners (dr, db), 0 or 2 for -1 or +1, in the slot order of
                    // `QuadLight::new`.
                    let corners = if axis == 1 {
                        [(0, 0), (2, 0), (0, 2), (2, 2)]
                    } else {
                        [(0, 0), (0, 2), (2, 0), (2, 2)]
                    };
                    for ((v, a), (dr, db)) in c.iter_mut().zip(&mut at).zip(corners) {
                        let walled =
                            op[r + dr] >> (b + 1) & 1 != 0 && op[r + 1] >> (b + db) & 1 != 0;
                        if !walled {
                            *a = (r + dr / 2, b + db / 2);
                            *v = at_vertex(a.0, a.1);
                        }
                    }
                }
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
                // Each vertex's light is interned once per plane.
                let mut intern = |(vr, vb): (usize, usize), v: u64| -> u16 {
                    if vr == usize::MAX {
                        return palette.intern(v);
                    }
                    if index_ok[vr] >> vb & 1 != 0 {
                        return index[vr * P + vb];
                    }
                    let i = palette.intern(v);
                    index[vr * P + vb] = i;
                    index_ok[vr] |= 1 << vb;
                    i
                };
                let k = if uniform {
                    let i = u64::from(intern(at[0], c[0]));
                    i * 0x0001_0001_0001_0001
                } else {
                    (0..4).fold(0, |acc, j| acc | u64::from(intern(at[j], c[j])) << (16 * j))
                };
                keys[r * CHUNK_SIZE + b] = k;
                aos[r * CHUNK_SIZE + b] =
                    occ.map_or(crate::AO_NONE, |o| crate::ao::face_ao(o, axis, r, b));
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
