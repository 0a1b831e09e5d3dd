//! The 8-byte packed quad that the renderer expands in its vertex shader.
//!
//! Bit layout (two little-endian `u32` words, `vec2<u32>` in WGSL):
//!
//! ```text
//! word 0: bits  0..5   x        block x of the quad's minimum corner, 0..31
//!         bits  5..10  y        block y
//!         bits 10..15  z        block z
//!         bits 15..20  w - 1    extent along the face's U axis, 1..32
//!         bits 20..25  h - 1    extent along the face's V axis, 1..32
//!         bits 25..28  face     0 +x, 1 -x, 2 +y, 3 -y, 4 +z, 5 -z (voxel_core::Face)
//!         bits 28..32  0        reserved
//! word 1: bits  0..16  block    BlockId
//!         bits 16..24  flags    bit 16: interface, a translucent face toward another
//!                               translucent type; bits 17..24 reserved (0)
//!         bits 24..32  occlusion  ambient occlusion of the corners (u0,v0), (u1,v0),
//!                               (u0,v1), (u1,v1), 2 bits each: 3 − the corner's AO value
//!                               (see `ao`), so that 0 is an unoccluded corner
//! ```
//!
//! The face's (U, V) axes are cyclic after the normal axis: +-x → (y, z), +-y → (z, x),
//! +-z → (x, y), so U × V points along +normal. A quad covers the blocks
//! `pos + i·U + j·V` for `i < w`, `j < h`; its plane lies on the block's far side for a
//! positive face (`pos[axis] + 1`) and on its near side for a negative one.

use bytemuck::{Pod, Zeroable};
use voxel_core::{BlockId, Face};

/// One quad in 8 bytes; see the module docs for the layout.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Pod, Zeroable)]
pub struct PackedQuad {
    /// Position, extents and face.
    pub geometry: u32,
    /// Block id (low 16 bits).
    pub block: u32,
}

/// The unpacked fields of a [`PackedQuad`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Quad {
    /// Block coordinates of the minimum corner inside the chunk, each 0..32.
    pub pos: [u8; 3],
    /// Extents `(w, h)` along the face's (U, V) axes, each 1..=32.
    pub size: [u8; 2],
    /// Which way the quad faces.
    pub face: Face,
    /// The block the face belongs to.
    pub block: BlockId,
}

/// Mask of the flag bits in word 1 (after shifting down by 16).
const FLAG_MASK: u32 = 0xff;

impl Quad {
    /// The face's rectangle in block coordinates of its chunk: lowest and highest corner
    /// (equal along the face's axis, which is one past the block on positive faces).
    pub fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        let axis = self.face.axis();
        let [ua, va] = UV_AXES[axis];
        let mut min = self.pos.map(f64::from);
        if self.face.is_positive() {
            min[axis] += 1.0;
        }
        let mut max = min;
        max[ua] += f64::from(self.size[0]);
        max[va] += f64::from(self.size[1]);
        (min, max)
    }
}

/// Quad flag (word 1, bit 16): a translucent face toward a block of another translucent
/// type (the renderer counts such a face from behind differently; see
/// `voxel_render::medium`).
pub const FLAG_INTERFACE: u32 = 1;

/// The (U, V) axes of faces along each normal axis.
pub const UV_AXES: [[usize; 2]; 3] = [[1, 2], [2, 0], [0, 1]];

impl PackedQuad {
    /// Packs a quad. Coordinates must be below 32 and extents in 1..=32 (checked in debug
    /// builds; the mesher only produces such quads).
    #[inline]
    pub fn new(pos: [usize; 3], w: usize, h: usize, face: Face, block: BlockId) -> Self {
        debug_assert!(
            pos.iter().all(|&p| p < 32) && (1..=32).contains(&w) && (1..=32).contains(&h)
        );
        let geometry = pos[0] as u32
            | (pos[1] as u32) << 5
            | (pos[2] as u32) << 10
            | (w as u32 - 1) << 15
            | (h as u32 - 1) << 20
            | (face as u32) << 25;
        Self {
            geometry,
            block: u32::from(block.0),
        }
    }

    /// The same quad with `flags` (8 bits: [`FLAG_INTERFACE`]) in word 1's bits 16..24.
    #[inline]
    pub fn with_flags(self, flags: u32) -> Self {
        Self {
            block: (self.block & !(FLAG_MASK << 16)) | (flags & FLAG_MASK) << 16,
            ..self
        }
    }

    /// The flags in word 1's bits 16..24 ([`FLAG_INTERFACE`]).
    #[inline]
    pub fn flags(self) -> u32 {
        self.block >> 16 & FLAG_MASK
    }

    /// The same quad with corner AO values `ao` (2 bits per corner, 3 = unoccluded, in the
    /// order of [`crate::ao`]: [`crate::AO_NONE`] is no occlusion).
    #[inline]
    pub fn with_ao(self, ao: u8) -> Self {
        Self {
            block: (self.block & 0x00ff_ffff) | u32::from(!ao) << 24,
            ..self
        }
    }

    /// The corner AO values (see [`PackedQuad::with_ao`]).
    #[inline]
    pub fn ao(self) -> u8 {
        !((self.block >> 24) as u8)
    }

    /// Packs an unpacked quad.
    pub fn pack(q: &Quad) -> Self {
        Self::new(
            q.pos.map(usize::from),
            usize::from(q.size[0]),
            usize::from(q.size[1]),
            q.face,
            q.block,
        )
    }

    /// Unpacks; `None` when the face bits hold 6 or 7 (not made by [`PackedQuad::new`]).
    pub fn unpack(self) -> Option<Quad> {
        let g = self.geometry;
        Some(Quad {
            pos: [g & 31, (g >> 5) & 31, (g >> 10) & 31].map(|v| v as u8),
            size: [((g >> 15) & 31) as u8 + 1, ((g >> 20) & 31) as u8 + 1],
            face: Face::from_index(((g >> 25) & 7) as usize)?,
            block: BlockId(self.block as u16),
        })
    }

    /// The face bits, 0..8.
    #[inline]
    pub fn face_index(self) -> usize {
        ((self.geometry >> 25) & 7) as usize
    }

    /// Area in block faces.
    #[inline]
    pub fn area(self) -> u32 {
        (((self.geometry >> 15) & 31) + 1) * (((self.geometry >> 20) & 31) + 1)
    }

    /// Centre of the quad in chunk-local block units (what the vertex shader computes).
    #[inline]
    pub fn center(self) -> [f32; 3] {
        let g = self.geometry;
        let mut c = [g & 31, (g >> 5) & 31, (g >> 10) & 31].map(|v| v as f32);
        let face = self.face_index().min(5);
        let axis = face / 2;
        let [u, v] = UV_AXES[axis];
        c[u] += (((g >> 15) & 31) + 1) as f32 * 0.5;
        c[v] += (((g >> 20) & 31) + 1) as f32 * 0.5;
        if face.is_multiple_of(2) {
            c[axis] += 1.0;
        }
        c
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn is_eight_bytes() {
        assert_eq!(std::mem::size_of::<PackedQuad>(), 8);
    }

    #[test]
    fn round_trips_every_field_at_its_limits() {
        for face in Face::ALL {
            for (pos, size, block) in [
                ([0, 0, 0], [1, 1], 0u16),
                ([31, 31, 31], [32, 32], u16::MAX),
                ([1, 17, 30], [5, 32], 12),
                ([31, 0, 16], [32, 1], 0x8001),
            ] {
                let q = Quad {
                    pos,
                    size,
                    face,
                    block: BlockId(block),
                };
                let p = PackedQuad::pack(&q);
                assert_eq!(p.unpack(), Some(q));
                assert_eq!(p.geometry >> 28, 0, "reserved bits stay zero");
                assert_eq!(p.block >> 16, 0, "reserved bits stay zero");
                let f = p.with_flags(FLAG_INTERFACE);
                assert_eq!(f.flags(), FLAG_INTERFACE);
                assert_eq!(f.unpack(), Some(q), "flags leave the fields alone");
                assert_eq!(p.ao(), crate::AO_NONE, "no occlusion unless set");
                let a = f.with_ao(0b11_10_01_00);
                assert_eq!((a.ao(), a.flags()), (0b11_10_01_00, FLAG_INTERFACE));
                assert_eq!(a.with_flags(0).ao(), 0b11_10_01_00, "flags keep the AO");
                assert_eq!(a.unpack(), Some(q), "AO leaves the fields alone");
                assert_eq!(a.block >> 24, 0b00_01_10_11, "stored as occlusion");
                assert_eq!(p.face_index(), face as usize);
                assert_eq!(p.area(), u32::from(size[0]) * u32::from(size[1]));
            }
        }
    }

    #[test]
    fn documented_bit_positions() {
        let p = PackedQuad::new([3, 5, 7], 2, 4, Face::NegY, BlockId(9));
        assert_eq!(
            p.geometry,
            3 | 5 << 5 | 7 << 10 | 1 << 15 | 3 << 20 | 3 << 25
        );
        assert_eq!(p.block, 9);
        assert_eq!(
            bytemuck::bytes_of(&p),
            &[p.geometry.to_le_bytes(), 9u32.to_le_bytes()].concat()[..]
        );
    }

    #[test]
    fn bad_face_bits_do_not_unpack() {
        let p = PackedQuad {
            geometry: 6 << 25,
            block: 0,
        };
        assert_eq!(p.unpack(), None);
    }

    #[test]
    fn center_follows_face_and_extent() {
        // +y quad over blocks x 2..4 (V = x, h = 2), z 0..3 (U = z, w = 3) at y = 5.
        let p = PackedQuad::new([2, 5, 0], 3, 2, Face::PosY, BlockId(1));
        assert_eq!(p.center(), [3.0, 6.0, 1.5]);
        let p = PackedQuad::new([2, 5, 0], 3, 2, Face::NegY, BlockId(1));
        assert_eq!(p.center(), [3.0, 5.0, 1.5]);
    }
}
