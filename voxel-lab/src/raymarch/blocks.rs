//! The blocks as the ray march reads them: lookups, classes, colours and textures, and
//! ambient occlusion from the blocks themselves.

use voxel_core::{BlockId, CHUNK_SIZE, Chunk, ChunkPos, Face, RenderClass};

use super::{RayMarcher, Texturing};

pub(super) fn srgb_to_linear(c: u8) -> f64 {
    let c = f64::from(c) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The brightness factor of an AO value (0 to 3) at `strength`.
fn ao_brightness(value: u8, strength: f64) -> f64 {
    1.0 - strength * f64::from(voxel_render::low_level::AO_DEPTH) * f64::from(3 - value) / 3.0
}

/// The cell in front of face `face` of the block at `b`, and for each of the face's corners
/// (u0, v0), (u1, v0), (u0, v1), (u1, v1) the cells around it in front of the face: the two
/// sides (along U, along V) and the diagonal, what ambient occlusion and smooth light read.
fn corner_cells(b: [i64; 3], face: Face) -> ([i64; 3], [[[i64; 3]; 3]; 4]) {
    let axis = face.axis();
    let (ua, va) = ((axis + 1) % 3, (axis + 2) % 3);
    let n = face.normal();
    let front = [0, 1, 2].map(|a| b[a] + i64::from(n[a]));
    let corners = [(-1, -1), (1, -1), (-1, 1), (1, 1)].map(|(du, dv)| {
        let mut s1 = front;
        s1[ua] += du;
        let mut s2 = front;
        s2[va] += dv;
        let mut c = s1;
        c[va] += dv;
        [s1, s2, c]
    });
    (front, corners)
}

/// Whether the renderer splits a face of corner AO values `v` (in the order of
/// [`RayMarcher::ao_values`]) along the diagonal (1,0)-(0,1): where those corners are
/// brighter in sum (`quad_vertex` in `common.wgsl`).
pub(super) fn flipped(v: [u8; 4]) -> bool {
    u16::from(v[1]) + u16::from(v[2]) > u16::from(v[0]) + u16::from(v[3])
}

/// A value given at the corners (u0, v0), (u1, v0), (u0, v1), (u1, v1) at face coordinates
/// `(s, t)` (0 to 1), interpolated over the two triangles the renderer draws the face as.
pub(super) fn interpolate(c: [f64; 4], flip: bool, s: f64, t: f64) -> f64 {
    let [b00, b10, b01, b11] = c;
    if flip {
        // Diagonal (1,0)-(0,1).
        if s + t <= 1.0 {
            b00 + s * (b10 - b00) + t * (b01 - b00)
        } else {
            b11 + (1.0 - s) * (b01 - b11) + (1.0 - t) * (b10 - b11)
        }
    } else if s >= t {
        // Diagonal (0,0)-(1,1): triangle (00, 10, 11).
        b00 + s * (b10 - b00) + t * (b11 - b10)
    } else {
        // Triangle (00, 11, 01).
        b00 + t * (b01 - b00) + s * (b11 - b01)
    }
}

impl RayMarcher {
    /// The blocks of the chunk at chunk coordinates `c`, if it holds any.
    pub(super) fn chunk_blocks(&self, c: [i64; 3]) -> Option<&[BlockId]> {
        let pos = ChunkPos::new(
            i32::try_from(c[0]).ok()?,
            i32::try_from(c[1]).ok()?,
            i32::try_from(c[2]).ok()?,
        );
        self.chunks.get(&pos).map(|c| &**c)
    }

    /// The block at `p` (air outside the loaded chunks).
    pub(super) fn get(&self, p: [i64; 3]) -> BlockId {
        let s = CHUNK_SIZE as i64;
        let c = p.map(|v| v.div_euclid(s));
        let Some(chunk) = self
            .chunks
            .get(&ChunkPos::new(c[0] as i32, c[1] as i32, c[2] as i32))
        else {
            return BlockId::AIR;
        };
        let l = p.map(|v| v.rem_euclid(s) as usize);
        chunk[Chunk::dense_index(l[0], l[1], l[2])]
    }

    pub(super) fn class(&self, id: BlockId) -> RenderClass {
        self.classes
            .get(id.index())
            .copied()
            .unwrap_or(RenderClass::Air)
    }

    fn opaque(&self, p: [i64; 3]) -> bool {
        self.class(self.get(p)) == RenderClass::Opaque
    }

    /// Colour (linear) and alpha of face `face` of block `id` at face coordinates `(u, v)`
    /// (in blocks along the face's U and V axes).
    pub(super) fn albedo(
        &self,
        id: BlockId,
        face: Face,
        u: f64,
        v: f64,
        texturing: Texturing,
    ) -> [f64; 4] {
        match texturing {
            Texturing::Flat => self.flat[id.index()],
            Texturing::Nearest => {
                // Stored as 8-bit sRGB and 8-bit alpha.
                let t = self.textures.texel(id, face, u, v);
                [
                    srgb_to_linear(t[0]),
                    srgb_to_linear(t[1]),
                    srgb_to_linear(t[2]),
                    f64::from(t[3]) / 255.0,
                ]
            }
        }
    }

    /// The AO brightness at face coordinates `(s, t)` in 0..1 of the unit face `face` of
    /// the block at `b`: each corner's value from the opaque blocks around it in the layer
    /// in front, interpolated over the triangle the renderer's diagonal rule picks.
    pub(super) fn ao(&self, b: [i64; 3], face: Face, s: f64, t: f64, strength: f64) -> f64 {
        if strength == 0.0 {
            return 1.0;
        }
        let values = self.ao_values(b, face);
        let [b00, b10, b01, b11] = values.map(|v| ao_brightness(v, strength));
        interpolate([b00, b10, b01, b11], flipped(values), s, t)
    }

    /// The AO values (3 open .. 0) of the corners (u0, v0), (u1, v0), (u0, v1), (u1, v1) of
    /// face `face` of the block at `b`.
    pub(super) fn ao_values(&self, b: [i64; 3], face: Face) -> [u8; 4] {
        corner_cells(b, face).1.map(|[s1, s2, c]| {
            let (s1, s2, c) = (self.opaque(s1), self.opaque(s2), self.opaque(c));
            if s1 && s2 {
                0
            } else {
                3 - u8::from(s1) - u8::from(s2) - u8::from(c)
            }
        })
    }

    /// The light of the corners (u0, v0), (u1, v0), (u0, v1), (u1, v1) of face `face` of the
    /// block at `b` (`id`), sky then block channels, by the lit mesher's rules
    /// (`docs/light.md`, "Meshing light"), read from `field`: a translucent face takes its
    /// front cell's at every corner; another the mean (rounded half up) of the cells in
    /// front around the corner that are not opaque and are lit (the diagonal not when both
    /// sides are opaque), 0 where none is.
    pub(super) fn corner_lights(
        &self,
        field: &voxel_core::LightField,
        b: [i64; 3],
        face: Face,
        id: BlockId,
    ) -> [[u16; 6]; 4] {
        let (front, corners) = corner_cells(b, face);
        let counted = |p: [i64; 3]| -> Option<[u16; 6]> {
            if self.opaque(p) {
                return None;
            }
            let [x, y, z] = p.map(|v| i32::try_from(v).ok());
            let l = field.get(voxel_core::WorldPos::new(x?, y?, z?))?;
            let [sr, sg, sb] = l.sky.map(u16::from);
            let [br, bg, bb] = l.block.map(u16::from);
            Some([sr, sg, sb, br, bg, bb])
        };
        if self.class(id) == RenderClass::Translucent {
            return [counted(front).unwrap_or([0; 6]); 4];
        }
        corners.map(|[s1, s2, c]| {
            let walled = self.opaque(s1) && self.opaque(s2);
            let cells = [Some(front), Some(s1), Some(s2), (!walled).then_some(c)];
            let lit: Vec<[u16; 6]> = cells.into_iter().flatten().filter_map(counted).collect();
            if lit.is_empty() {
                return [0; 6];
            }
            let k = lit.len() as u16;
            std::array::from_fn(|ch| (lit.iter().map(|l| l[ch]).sum::<u16>() + k / 2) / k)
        })
    }

    /// The block whose medium a cutout block `id` stands in.
    pub(super) fn medium_block(&self, id: BlockId) -> Option<BlockId> {
        self.medium_of.get(id.index()).copied().flatten()
    }

    /// The translucent type a cell of block `id` holds: its own, or the medium it stands in
    /// (a waterlogged block's cell holds its water, the mesher's rule).
    pub(super) fn holds(&self, id: BlockId) -> Option<BlockId> {
        match self.class(id) {
            RenderClass::Translucent => Some(id),
            RenderClass::Cutout => self.medium_block(id),
            _ => None,
        }
    }
}
