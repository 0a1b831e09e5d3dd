//! Positions of blocks and chunks in the world, and the six face directions.

use crate::CHUNK_SIZE;

/// The six face directions, in the order used everywhere (mesher, quads, neighbours).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Face {
    /// +x
    PosX = 0,
    /// -x
    NegX = 1,
    /// +y (up)
    PosY = 2,
    /// -y (down)
    NegY = 3,
    /// +z
    PosZ = 4,
    /// -z
    NegZ = 5,
}

impl Face {
    /// All faces, indexed by their discriminant.
    pub const ALL: [Face; 6] = [
        Face::PosX,
        Face::NegX,
        Face::PosY,
        Face::NegY,
        Face::PosZ,
        Face::NegZ,
    ];

    /// The face with discriminant `i` (taken modulo nothing: `i` must be below 6).
    pub fn from_index(i: usize) -> Option<Face> {
        Self::ALL.get(i).copied()
    }

    /// The axis of the normal: 0 = x, 1 = y, 2 = z.
    pub fn axis(self) -> usize {
        self as usize / 2
    }

    /// Whether the normal points along +axis.
    pub fn is_positive(self) -> bool {
        (self as usize).is_multiple_of(2)
    }

    /// The outward unit normal.
    pub fn normal(self) -> [i32; 3] {
        let mut n = [0; 3];
        n[self.axis()] = if self.is_positive() { 1 } else { -1 };
        n
    }

    /// The face pointing the other way.
    pub fn opposite(self) -> Face {
        Self::ALL[self as usize ^ 1]
    }
}

/// A block position in the world.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct WorldPos {
    /// x
    pub x: i32,
    /// y (up)
    pub y: i32,
    /// z
    pub z: i32,
}

impl WorldPos {
    /// A world position.
    pub const fn new(x: i32, y: i32, z: i32) -> Self {
        Self { x, y, z }
    }

    /// The block holding `point` (world units; each coordinate saturates at the `i32`
    /// world's edge, NaN reads as 0).
    pub fn containing(point: [f64; 3]) -> Self {
        let [x, y, z] = point.map(|v| v.floor() as i32);
        Self { x, y, z }
    }

    /// The block's lowest corner, in world units (the block fills it to `corner + 1`).
    pub fn corner(self) -> [f64; 3] {
        [self.x, self.y, self.z].map(f64::from)
    }

    /// The chunk holding this block and the block's local coordinates in it.
    /// Defined for every `i32` position (floor division, so -1 is in chunk -1 at local 31).
    pub fn split(self) -> (ChunkPos, [usize; 3]) {
        let s = CHUNK_SIZE as i32;
        let c = ChunkPos::new(
            self.x.div_euclid(s),
            self.y.div_euclid(s),
            self.z.div_euclid(s),
        );
        let l = [self.x, self.y, self.z].map(|v| v.rem_euclid(s) as usize);
        (c, l)
    }
}

/// A chunk's position in chunk units: chunk `(1, 0, 0)` holds world x `32..64`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ChunkPos {
    /// x in chunks
    pub x: i32,
    /// y in chunks
    pub y: i32,
    /// z in chunks
    pub z: i32,
}

impl ChunkPos {
    /// Smallest chunk coordinate whose blocks fit the `i32` world: -2^26.
    pub const MIN: i32 = i32::MIN / CHUNK_SIZE as i32;
    /// Largest chunk coordinate whose blocks fit the `i32` world: 2^26 - 1.
    pub const MAX: i32 = i32::MAX / CHUNK_SIZE as i32;

    /// A chunk position (not checked: see [`ChunkPos::is_valid`]).
    pub const fn new(x: i32, y: i32, z: i32) -> Self {
        Self { x, y, z }
    }

    /// Whether all of the chunk's blocks have `i32` world coordinates.
    pub fn is_valid(self) -> bool {
        [self.x, self.y, self.z]
            .iter()
            .all(|v| (Self::MIN..=Self::MAX).contains(v))
    }

    /// World coordinates of the chunk's block `(0, 0, 0)`, as `i64` so that no chunk
    /// position overflows.
    pub fn origin(self) -> [i64; 3] {
        [self.x, self.y, self.z].map(|v| i64::from(v) * CHUNK_SIZE as i64)
    }

    /// The adjacent chunk across `face`, or `None` past the edge of the `i32` world.
    pub fn neighbour(self, face: Face) -> Option<ChunkPos> {
        self.offset(face.normal())
    }

    /// The chunk `d` chunks away, or `None` past the edge of the `i32` world.
    pub fn offset(self, d: [i32; 3]) -> Option<ChunkPos> {
        let p = ChunkPos::new(
            self.x.checked_add(d[0])?,
            self.y.checked_add(d[1])?,
            self.z.checked_add(d[2])?,
        );
        p.is_valid().then_some(p)
    }
}
