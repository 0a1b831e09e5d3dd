//! Which chunks of the sequence an object is tested against: the chunk cells it touches
//! and their keys' range ([`cells_and_keys`]), found in the sequence by key
//! ([`KeyIndex`]) and by cell ([`CellIndex`]).

use glam::DVec3;

use voxel_core::ChunkPos;

use super::Ball;
use super::sound::touch;

/// The chunk cells a ball touches, inclusive per axis (a ball touching a cell's face
/// touches both cells), and their keys' range for an eye in cell `eye`: the least and
/// the greatest [`voxel_mesh::order::chunk_order_key`] among them.
pub(super) fn cells_and_keys(b: Ball, eye: [i64; 3]) -> ([[i64; 2]; 3], [u128; 2]) {
    let s = 1.0 / voxel_core::CHUNK_SIZE as f64;
    // Touching a cell's face within rounding counts as touching it (`side_of_plane`).
    let half = |a: usize| b.half[a] + touch(b.half[a]);
    // Most balls lie inside the cell of their centre, off its borders.
    let cell = [
        floor_i64(b.center.x * s),
        floor_i64(b.center.y * s),
        floor_i64(b.center.z * s),
    ];
    let inside = (0..3).all(|a| {
        let lo = cell[a] as f64 * voxel_core::CHUNK_SIZE as f64;
        b.center[a] - half(a) > lo && b.center[a] + half(a) < lo + voxel_core::CHUNK_SIZE as f64
    });
    if inside {
        let k = (0..3)
            .map(|a| {
                let d = (cell[a] - eye[a]).unsigned_abs();
                u128::from(d) * u128::from(d)
            })
            .sum();
        return (cell.map(|c| [c, c]), [k, k]);
    }
    let mut cells = [[0i64; 2]; 3];
    let (mut kmin, mut kmax) = (0u128, 0u128);
    for a in 0..3 {
        // `ceil(x) - 1` is `floor(x)` except on a border, where it is the cell below.
        let lo = ceil_i64((b.center[a] - half(a)) * s) - 1;
        let hi = floor_i64((b.center[a] + half(a)) * s);
        cells[a] = [lo, hi];
        let (dl, dh) = (lo - eye[a], hi - eye[a]);
        let sq = |d: i64| u128::from(d.unsigned_abs()) * u128::from(d.unsigned_abs());
        kmin += if dl <= 0 && dh >= 0 {
            0
        } else {
            sq(dl).min(sq(dh))
        };
        kmax += sq(dl).max(sq(dh));
    }
    (cells, [kmin, kmax])
}

/// The cell bound of a coordinate, clamped just past the `i32` world (as
/// [`voxel_mesh::order::chunk_order_key`] clamps): by truncation, since `floor` and `ceil`
/// are library calls on baseline x86-64.
pub(super) fn floor_i64(x: f64) -> i64 {
    let x = x.clamp(f64::from(i32::MIN) - 1.0, f64::from(i32::MAX) + 1.0);
    let t = x as i64;
    t - i64::from((t as f64) > x)
}

pub(super) fn ceil_i64(x: f64) -> i64 {
    let x = x.clamp(f64::from(i32::MIN) - 1.0, f64::from(i32::MAX) + 1.0);
    let t = x as i64;
    t + i64::from((t as f64) < x)
}

/// The eye's chunk cell, as [`voxel_mesh::order::chunk_order_key`] takes it.
pub(super) fn eye_cell(eye: DVec3) -> [i64; 3] {
    let s = 1.0 / voxel_core::CHUNK_SIZE as f64;
    [
        floor_i64(eye.x * s),
        floor_i64(eye.y * s),
        floor_i64(eye.z * s),
    ]
}

/// How many chunks of the sequence have a key above a given one: a table by key when the
/// keys are small (they are squared distances in chunks from the eye's chunk, below
/// 3 · 64² for everything within the largest view distance), else a binary search.
pub(super) struct KeyIndex<'a> {
    keys: &'a [u128],
    /// `above[k]`: chunks with a key above `k`, for `k` up to the largest key.
    above: Vec<u32>,
}

impl<'a> KeyIndex<'a> {
    /// Largest key a table is made for.
    const TABLE: u128 = 1 << 20;

    pub(super) fn new(keys: &'a [u128]) -> Self {
        let largest = keys.first().copied().unwrap_or(0);
        let mut above = Vec::new();
        if largest < Self::TABLE {
            // Keys are largest first: walk them from the end.
            above.resize(largest as usize + 1, 0);
            let mut i = keys.len();
            for k in 0..=largest {
                while i > 0 && keys[i - 1] <= k {
                    i -= 1;
                }
                above[k as usize] = i as u32;
            }
        }
        Self { keys, above }
    }

    /// How many chunks have a key above `k` (the index of the first with `k` or less).
    pub(super) fn above(&self, k: u128) -> usize {
        if self.above.is_empty() {
            return self.keys.partition_point(|&x| x > k);
        }
        if k >= self.above.len() as u128 {
            return 0;
        }
        self.above[k as usize] as usize
    }
}

/// Where each chunk cell stands in the sequence: a grid over the box the sequence's chunks
/// span (a few thousand cells within a view distance), else a map.
pub(super) struct CellIndex {
    lo: [i64; 3],
    size: [i64; 3],
    grid: Vec<u32>,
    map: std::collections::HashMap<[i64; 3], usize>,
}

impl CellIndex {
    /// Most cells a grid is made for.
    const GRID: i64 = 1 << 22;

    pub(super) fn new(positions: &[ChunkPos]) -> Self {
        let cell = |p: &ChunkPos| [i64::from(p.x), i64::from(p.y), i64::from(p.z)];
        let (mut lo, mut hi) = ([i64::MAX; 3], [i64::MIN; 3]);
        for p in positions {
            let c = cell(p);
            for a in 0..3 {
                lo[a] = lo[a].min(c[a]);
                hi[a] = hi[a].max(c[a]);
            }
        }
        let size = [0, 1, 2].map(|a| (hi[a] - lo[a] + 1).max(0));
        let mut index = Self {
            lo,
            size,
            grid: Vec::new(),
            map: std::collections::HashMap::new(),
        };
        let cells = size[0].saturating_mul(size[1]).saturating_mul(size[2]);
        if cells <= Self::GRID {
            index.grid = vec![u32::MAX; cells as usize];
            for (i, p) in positions.iter().enumerate() {
                let at = index.slot(cell(p)).unwrap_or(0);
                index.grid[at] = i as u32;
            }
        } else {
            index.map = positions
                .iter()
                .enumerate()
                .map(|(i, p)| (cell(p), i))
                .collect();
        }
        index
    }

    fn slot(&self, c: [i64; 3]) -> Option<usize> {
        let d = [0, 1, 2].map(|a| c[a] - self.lo[a]);
        if (0..3).any(|a| d[a] < 0 || d[a] >= self.size[a]) {
            return None;
        }
        Some((d[0] + self.size[0] * (d[1] + self.size[1] * d[2])) as usize)
    }

    /// The place in the sequence of the chunk in cell `c`, if it is there.
    pub(super) fn get(&self, c: [i64; 3]) -> Option<usize> {
        if self.grid.is_empty() {
            return self.map.get(&c).copied();
        }
        let i = self.grid[self.slot(c)?];
        (i != u32::MAX).then_some(i as usize)
    }
}
