//! Light levels of a chunk, stored a layer (a y slice of 32 × 32 cells) at a time: a layer
//! whose cells all hold the same levels (open sky, dark rock) is 6 bytes, any other 6 KiB.
//! Also the sky's beam entering each column of a chunk from above.

use std::sync::OnceLock;

use crate::{CHUNK_AREA, CHUNK_SIZE};

/// The six levels of a cell: sky red, green, blue, then block red, green, blue.
pub(super) type Levels = [u8; 6];

/// A cell of a chunk: `y << 10 | x << 5 | z`.
pub(super) type Local = u16;

/// The local index of `(x, y, z)`.
#[inline]
pub(super) const fn local(x: usize, y: usize, z: usize) -> Local {
    ((y << 10) | (x << 5) | z) as Local
}

/// The light of one block: the sky's light reaching it and the light of blocks that
/// emit, each linear RGB from 0 to 255 (see [`crate::LightField`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Light {
    /// Sky light, RGB; 255 is the open sky's full light.
    pub sky: [u8; 3],
    /// Block light, RGB.
    pub block: [u8; 3],
}

impl Light {
    pub(super) fn from_levels(l: Levels) -> Self {
        Self {
            sky: [l[0], l[1], l[2]],
            block: [l[3], l[4], l[5]],
        }
    }
}

/// One layer (the 32 × 32 cells of one y) of a [`LightChunk`], as stored: what a reader
/// that visits many cells (the lit mesher) uses to skip per-cell work where a layer is
/// uniform.
#[derive(Clone, Copy, Debug)]
pub enum LightLayer<'a> {
    /// Every cell of the layer holds these levels (sky R, G, B, block R, G, B).
    Uniform([u8; 6]),
    /// The levels of each cell, indexed by `x << 5 | z`.
    Dense(&'a [[u8; 6]; CHUNK_AREA]),
}

#[derive(Clone, Debug)]
enum Layer {
    Uniform(Levels),
    Dense(Box<Dense>),
}

#[derive(Clone, Debug)]
struct Dense {
    cells: [Levels; CHUNK_AREA],
    /// The layer's [`OddCells`], made on first use after the layer was last written.
    odd: OnceLock<OddCells>,
}

impl Dense {
    fn new(cells: [Levels; CHUNK_AREA]) -> Box<Self> {
        Box::new(Self {
            cells,
            odd: OnceLock::new(),
        })
    }
}

/// Which cells of a dense layer hold other levels than most of its lit cells: what a
/// reader that compares every cell with one level (the lit mesher) reads instead, kept
/// with the layer until the layer is written ([`LightChunk::odd_cells`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct OddCells {
    /// The levels most cells of the layer hold, of those not all 0 (dark rock does not
    /// count: it is mostly opaque), else 0.
    pub reference: [u8; 6],
    /// Bit `x` of `rows[z]`: cell `(x, z)` holds other levels than `reference`.
    pub rows: [u32; CHUNK_SIZE],
}

impl OddCells {
    fn of(cells: &[Levels; CHUNK_AREA]) -> Self {
        // Boyer and Moore's vote over a sample of the cells that are not dark (every
        // seventh: 147 cells spread over the rows and columns).
        let (mut vote, mut count) = ([0u8; 6], 0u32);
        for c in cells.iter().step_by(7).filter(|c| **c != [0; 6]) {
            if count == 0 {
                (vote, count) = (*c, 1);
            } else if *c == vote {
                count += 1;
            } else {
                count -= 1;
            }
        }
        // Columns (bit z of `by_x[x]`, memory order), then rows.
        let mut by_x = [0u32; CHUNK_SIZE];
        for (col, cs) in by_x.iter_mut().zip(cells.chunks_exact(CHUNK_SIZE)) {
            *col = cs
                .iter()
                .enumerate()
                .fold(0, |acc, (z, c)| acc | u32::from(*c != vote) << z);
        }
        let mut rows = [0u32; CHUNK_SIZE];
        for (x, &col) in by_x.iter().enumerate() {
            let mut b = col;
            while b != 0 {
                rows[b.trailing_zeros() as usize] |= 1 << x;
                b &= b - 1;
            }
        }
        Self {
            reference: vote,
            rows,
        }
    }
}

/// The light of the 32³ blocks of a chunk: 6 bytes a block (RGB sky and RGB block light, a
/// byte a channel) where a layer varies, 6 bytes a layer where it does not.
#[derive(Clone, Debug)]
pub struct LightChunk {
    layers: Vec<Layer>,
}

impl LightChunk {
    pub(super) fn uniform(levels: Levels) -> Self {
        Self {
            layers: vec![Layer::Uniform(levels); CHUNK_SIZE],
        }
    }

    /// A chunk from one `Levels` per cell, indexed by [`local`].
    pub(super) fn from_cells(cells: &[Levels]) -> Self {
        let layers = cells
            .chunks_exact(CHUNK_AREA)
            .map(|layer| {
                if layer.iter().all(|l| *l == layer[0]) {
                    Layer::Uniform(layer[0])
                } else {
                    let mut b = Dense::new([[0; 6]; CHUNK_AREA]);
                    b.cells.copy_from_slice(layer);
                    Layer::Dense(b)
                }
            })
            .collect();
        Self { layers }
    }

    /// The light of local `(x, y, z)`, each below 32 (else `None`).
    pub fn get(&self, x: usize, y: usize, z: usize) -> Option<Light> {
        (x < CHUNK_SIZE && y < CHUNK_SIZE && z < CHUNK_SIZE)
            .then(|| Light::from_levels(self.levels(local(x, y, z))))
    }

    /// Layer `y` (below 32) as stored: uniform levels, or one entry per cell.
    #[inline]
    pub fn layer(&self, y: usize) -> LightLayer<'_> {
        match &self.layers[y] {
            Layer::Uniform(v) => LightLayer::Uniform(*v),
            Layer::Dense(d) => LightLayer::Dense(&d.cells),
        }
    }

    /// The odd cells of layer `y` (below 32) where it is stored dense (`None` where it is
    /// uniform), made on the first call after the layer was last written.
    pub fn odd_cells(&self, y: usize) -> Option<&OddCells> {
        match &self.layers[y] {
            Layer::Uniform(_) => None,
            Layer::Dense(d) => Some(d.odd.get_or_init(|| OddCells::of(&d.cells))),
        }
    }

    #[inline]
    pub(super) fn levels(&self, l: Local) -> Levels {
        match &self.layers[usize::from(l >> 10)] {
            Layer::Uniform(v) => *v,
            Layer::Dense(d) => d.cells[usize::from(l & 1023)],
        }
    }

    #[inline]
    pub(super) fn channel(&self, l: Local, ch: usize) -> u8 {
        match &self.layers[usize::from(l >> 10)] {
            Layer::Uniform(v) => v[ch],
            Layer::Dense(d) => d.cells[usize::from(l & 1023)][ch],
        }
    }

    #[inline]
    pub(super) fn set_channel(&mut self, l: Local, ch: usize, v: u8) {
        let layer = &mut self.layers[usize::from(l >> 10)];
        if let Layer::Uniform(u) = layer {
            if u[ch] == v {
                return;
            }
            *layer = Layer::Dense(Dense::new([*u; CHUNK_AREA]));
        }
        if let Layer::Dense(d) = layer {
            d.cells[usize::from(l & 1023)][ch] = v;
            if d.odd.get().is_some() {
                d.odd = OnceLock::new();
            }
        }
    }

    /// Whether layer `y` holds the same levels everywhere, and which.
    pub(super) fn uniform_layer(&self, y: usize) -> Option<Levels> {
        match &self.layers[y] {
            Layer::Uniform(v) => Some(*v),
            Layer::Dense(_) => None,
        }
    }

    /// Whether a dense layer's cells all agree ([`LightChunk::compact`] has work).
    pub(super) fn compactable(&self) -> bool {
        self.layers
            .iter()
            .any(|l| matches!(l, Layer::Dense(d) if d.cells.iter().all(|c| *c == d.cells[0])))
    }

    /// Turns dense layers whose cells all agree back into uniform ones.
    pub(super) fn compact(&mut self) {
        for layer in &mut self.layers {
            if let Layer::Dense(d) = layer
                && d.cells.iter().all(|l| *l == d.cells[0])
            {
                *layer = Layer::Uniform(d.cells[0]);
            }
        }
    }

    /// Layers stored dense (6 KiB each).
    pub fn dense_layers(&self) -> usize {
        self.layers
            .iter()
            .filter(|l| matches!(l, Layer::Dense(_)))
            .count()
    }

    /// Heap and inline bytes.
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of::<Self>()
            + CHUNK_SIZE * std::mem::size_of::<Layer>()
            + self.dense_layers() * std::mem::size_of::<Dense>()
    }
}

/// The sky's beam entering a chunk's 1024 columns from above, exact (a transmittance per
/// channel, 1 the open sky): the product of every filter above it.
#[derive(Clone, Debug)]
pub(super) enum Beam {
    Uniform([f32; 3]),
    Columns(Box<[[f32; 3]; CHUNK_AREA]>),
}

impl Beam {
    pub(super) fn get(&self, col: usize) -> [f32; 3] {
        match self {
            Beam::Uniform(b) => *b,
            Beam::Columns(c) => c[col],
        }
    }

    pub(super) fn set(&mut self, col: usize, b: [f32; 3]) {
        if let Beam::Uniform(u) = self {
            if *u == b {
                return;
            }
            *self = Beam::Columns(Box::new([*u; CHUNK_AREA]));
        }
        if let Beam::Columns(c) = self {
            c[col] = b;
        }
    }

    pub(super) fn from_columns(cols: &[[f32; 3]; CHUNK_AREA]) -> Self {
        if cols.iter().all(|c| *c == cols[0]) {
            Beam::Uniform(cols[0])
        } else {
            Beam::Columns(Box::new(*cols))
        }
    }

    pub(super) fn memory_bytes(&self) -> usize {
        match self {
            Beam::Uniform(_) => 0,
            Beam::Columns(_) => CHUNK_AREA * 12,
        }
    }
}
