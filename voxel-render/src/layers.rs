//! A chunk's translucent quads summed up per plane, facing and block: what the fitted
//! WBOIT weight's per-frame estimate reads (`oit::wboit::fit`, a module above this one),
//! and the boxes MBOIT's depth warp spans.
//!
//! The chunk store sums each translucent mesh up once, when it is uploaded, and keeps the
//! planes region by region next to the records its culling walks (`ChunkStore::cull`); a
//! frame that asks for them gets the visible chunks' planes copied into one buffer
//! ([`VisibleLayers`]) by that same walk. So the estimate
//! reads memory in order, with no lookup per chunk: at view distance 32 a lookup per
//! chunk in a hash map cost more than the estimate itself.

use std::collections::BTreeMap;

use glam::{DVec3, Vec3};
use voxel_core::{ChunkPos, Face};
use voxel_mesh::PackedQuad;

/// Optical depth of the most opaque layer the estimate counts (`α` 0.99); a fully opaque
/// translucent block would otherwise hide everything behind it for the weight.
pub(crate) const MAX_LAYER_DEPTH: f64 = 4.605;

/// The optical depth `−ln(1 − α)` of one layer of opacity `alpha`, at most
/// [`MAX_LAYER_DEPTH`].
pub(crate) fn layer_depth(alpha: f32) -> f64 {
    (-f64::from(1.0 - alpha.clamp(0.0, 1.0)).ln()).min(MAX_LAYER_DEPTH)
}

/// The quads of one block in a mesh that lie in one plane and face one way.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Plane {
    /// Which way the quads face.
    pub face: Face,
    /// Chunk-local rectangle around the quads (flat along the face's axis): small whole
    /// numbers, exact in `f32`.
    pub lo: Vec3,
    /// Its other corner.
    pub hi: Vec3,
    /// The optical depth a ray through the rectangle crosses: the quads' area times their
    /// block's optical depth, over the rectangle's area (view-independent, so summed up
    /// once per mesh rather than each frame). A clear block's plane has 0: it is drawn, so
    /// the composite's rectangle must hold it.
    pub tau: f32,
}

/// A plane's key while summing a mesh up: facing, position along its axis, block.
type PlaneKey = (usize, u8, u16);
/// A plane's sum while summing a mesh up: facing, rectangle (chunk-local), optical area.
type PlaneSum = (Face, DVec3, DVec3, f64);

/// Sums up the translucent `quads` of a chunk per plane, facing and block, in a fixed
/// order (the same sums in the same order every time); `opacity` is indexed by block id
/// (a block past its end counts as clear).
pub(crate) fn planes(quads: &[PackedQuad], opacity: &[f32]) -> Vec<Plane> {
    let mut planes: BTreeMap<PlaneKey, PlaneSum> = BTreeMap::new();
    for q in quads {
        let Some(u) = q.unpack() else { continue };
        let alpha = opacity.get(u.block.index()).copied().unwrap_or(0.0);
        let depth = layer_depth(alpha);
        let axis = u.face.axis();
        let (min, max) = u.bounds();
        let (lo, hi) = (DVec3::from(min), DVec3::from(max));
        let key = (u.face as usize, min[axis] as u8, u.block.0);
        let plane = planes.entry(key).or_insert((u.face, lo, hi, 0.0));
        plane.1 = plane.1.min(lo);
        plane.2 = plane.2.max(hi);
        plane.3 += f64::from(q.area()) * depth;
    }
    planes
        .into_values()
        .map(|(face, lo, hi, optical_area)| {
            let [ua, va] = voxel_mesh::UV_AXES[face.axis()];
            let area = (hi[ua] - lo[ua]) * (hi[va] - lo[va]);
            Plane {
                face,
                lo: lo.as_vec3(),
                hi: hi.as_vec3(),
                tau: (optical_area / area.max(1.0)) as f32,
            }
        })
        .collect()
}

/// The box around `planes` (each the box of its quads), chunk-local blocks: the box of the
/// mesh they sum up.
pub(crate) fn bounds(planes: &[Plane]) -> Option<(Vec3, Vec3)> {
    planes
        .iter()
        .map(|p| (p.lo, p.hi))
        .reduce(|(lo, hi), (a, b)| (lo.min(a), hi.max(b)))
}

/// The planes of a frame's visible translucent chunks, chunk by chunk, in one buffer
/// (filled by the chunk store's culling when asked for).
#[derive(Clone, Debug, Default)]
pub(crate) struct LayerBuffer {
    /// Each chunk, its level of detail and the end of its planes in `planes` (its start is
    /// the previous end).
    runs: Vec<(ChunkPos, u8, u32)>,
    planes: Vec<Plane>,
}

impl LayerBuffer {
    /// Empties it, keeping its room.
    pub(crate) fn clear(&mut self) {
        self.runs.clear();
        self.planes.clear();
    }

    /// Adds the chunk at `pos` of level of detail `level` with its `planes` (nothing when it
    /// has none).
    pub(crate) fn push(&mut self, pos: ChunkPos, level: u8, planes: &[Plane]) {
        if !planes.is_empty() {
            self.planes.extend_from_slice(planes);
            self.runs.push((pos, level, self.planes.len() as u32));
        }
    }

    /// A view of what it holds.
    pub(crate) fn view(&self) -> VisibleLayers<'_> {
        VisibleLayers {
            runs: &self.runs,
            planes: &self.planes,
        }
    }
}

/// The planes of the visible translucent chunks of a frame (see [`LayerBuffer`]).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct VisibleLayers<'a> {
    runs: &'a [(ChunkPos, u8, u32)],
    planes: &'a [Plane],
}

impl<'a> VisibleLayers<'a> {
    /// Each chunk, its level of detail and its planes (chunk-local cells).
    pub(crate) fn iter(&self) -> impl Iterator<Item = (ChunkPos, u8, &'a [Plane])> + 'a {
        let planes = self.planes;
        let mut start = 0;
        self.runs.iter().map(move |&(pos, level, end)| {
            let run = &planes[start as usize..end as usize];
            start = end;
            (pos, level, run)
        })
    }

    /// The box of each chunk's translucent mesh, world blocks.
    pub(crate) fn boxes(&self) -> impl Iterator<Item = (DVec3, DVec3)> + 'a {
        self.iter().filter_map(|(pos, level, planes)| {
            let origin = DVec3::from(pos.origin().map(|v| v as f64));
            let scale = DVec3::from(cell_scale(level));
            let (lo, hi) = bounds(planes)?;
            Some((
                origin + lo.as_dvec3() * scale,
                origin + hi.as_dvec3() * scale,
            ))
        })
    }
}

/// Blocks per cell along x, y and z at level of detail `level` (a level's cells are
/// `2^level` blocks wide in x and z, one high).
pub(crate) fn cell_scale(level: u8) -> [f64; 3] {
    let s = voxel_core::level_scale(level) as f64;
    [s, 1.0, s]
}

#[cfg(test)]
impl VisibleLayers<'_> {
    /// Number of planes.
    fn len(&self) -> usize {
        self.planes.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use voxel_core::{BlockRegistry, blocks};

    #[test]
    fn quads_of_one_block_in_one_plane_sum_up_to_one_rectangle() {
        let opacity: Vec<f32> = BlockRegistry::default()
            .iter()
            .map(|(_, d)| d.opacity)
            .collect();
        // Two 4×4 glass quads in the plane z = 3 (a gap between them), one water quad in
        // it, one glass quad facing the other way.
        let quads = [
            PackedQuad::new([0, 0, 2], 4, 4, Face::PosZ, blocks::GLASS),
            PackedQuad::new([8, 0, 2], 4, 4, Face::PosZ, blocks::GLASS),
            PackedQuad::new([0, 8, 2], 2, 2, Face::PosZ, blocks::WATER),
            PackedQuad::new([0, 0, 2], 4, 4, Face::NegZ, blocks::GLASS),
        ];
        let planes = planes(&quads, &opacity);
        assert_eq!(planes.len(), 3);
        let glass = planes
            .iter()
            .find(|p| p.face == Face::PosZ && p.hi.x == 12.0)
            .unwrap();
        assert_eq!(
            (glass.lo, glass.hi),
            (Vec3::new(0.0, 0.0, 3.0), Vec3::new(12.0, 4.0, 3.0))
        );
        // 32 of the rectangle's 48 unit squares are glass.
        let want = 32.0 / 48.0 * layer_depth(opacity[blocks::GLASS.index()]);
        assert!((f64::from(glass.tau) - want).abs() < 1e-6, "{}", glass.tau);

        let mut buffer = LayerBuffer::default();
        buffer.push(ChunkPos::new(1, 2, 3), 0, &planes);
        buffer.push(ChunkPos::new(4, 5, 6), 0, &[]);
        buffer.push(ChunkPos::new(7, 8, 9), 0, &planes[..1]);
        let runs: Vec<_> = buffer.view().iter().map(|(p, _, r)| (p, r.len())).collect();
        assert_eq!(
            runs,
            [(ChunkPos::new(1, 2, 3), 3), (ChunkPos::new(7, 8, 9), 1)]
        );
        assert_eq!(buffer.view().len(), 4);
    }
}
