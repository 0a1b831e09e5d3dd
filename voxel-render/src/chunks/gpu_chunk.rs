//! A chunk on the GPU ([`GpuChunk`]) and the summary of its translucent mesh seen from
//! afar ([`Surfaces`]).

use glam::DVec3;
use voxel_core::{ChunkPos, Face};
use voxel_mesh::PackedQuad;

use super::MeshKind;
use crate::arena::Alloc;
use crate::layers::{self, Plane};

/// A chunk on the GPU: where its meshes are, and what techniques derive from.
#[derive(Debug)]
pub struct GpuChunk {
    /// Where it starts (a chunk's position; for a chunk of a level of detail, the
    /// full-detail chunk at its first block).
    pub(super) pos: ChunkPos,
    /// Its level of detail: 0 for a chunk, else its cells are `2^level` blocks wide in x and
    /// z ([`voxel_core::level_scale`]).
    pub(super) level: u8,
    pub(super) meshes: [Option<Alloc>; 3],
    /// The translucent quads in their current GPU order, kept for techniques that derive
    /// something from them (sorting, the fitted WBOIT weight).
    pub(super) translucent: Vec<PackedQuad>,
    /// The box of the translucent quads, chunk-local blocks (min, max).
    pub(super) translucent_bounds: Option<([f64; 3], [f64; 3])>,
    /// The distinct planes of the translucent quads: face and chunk-local coordinate along
    /// its axis.
    pub(super) translucent_planes: Vec<(Face, u8)>,
    /// Whether a translucent quad is of a volume (a block type with absorption).
    pub(super) volume: bool,
    /// Where its light lies, for a lit chunk (`None`: drawn unlit).
    pub(super) light: Option<super::light::ChunkLight>,
    /// Changes with every upload of the chunk.
    pub(super) generation: u64,
    /// The mesher's order of the translucent quads while the GPU draws them in another
    /// (`None`: the GPU holds the mesher's order).
    pub(super) mesher_order: Option<Vec<PackedQuad>>,
    /// A technique's order put aside when the mesher's was restored, with the stamp it
    /// had: the technique draws it again without sorting ([`super::ChunkStore::reapply_order`]).
    pub(super) set_aside: Option<(Vec<PackedQuad>, u64)>,
    /// Changes whenever the GPU order of the translucent quads is written (an upload, a
    /// re-sort, the mesher's order restored): what a technique that wrote an order checks
    /// its order is still the one drawn.
    pub(super) order_stamp: u64,
}

impl GpuChunk {
    /// Where the mesh of `kind` lives, if not empty.
    pub fn mesh(&self, kind: MeshKind) -> Option<Alloc> {
        self.meshes[kind as usize]
    }

    /// Where the chunk is.
    pub(crate) fn pos(&self) -> ChunkPos {
        self.pos
    }

    /// Its level of detail (0: a chunk).
    pub fn level(&self) -> u8 {
        self.level
    }

    /// Blocks per cell along x, y and z.
    pub(crate) fn scale(&self) -> [f64; 3] {
        crate::layers::cell_scale(self.level)
    }

    /// Whether the translucent mesh has a face of a volume (a block type with absorption,
    /// [`voxel_core::BlockDef::absorption`]).
    pub(crate) fn has_volume(&self) -> bool {
        self.volume
    }

    /// The translucent quads in their current GPU order.
    pub(crate) fn translucent_quads(&self) -> &[PackedQuad] {
        &self.translucent
    }

    /// The box the translucent quads span, in world blocks (min, max).
    pub(crate) fn translucent_bounds(&self) -> Option<([f64; 3], [f64; 3])> {
        let o = self.pos.origin().map(|v| v as f64);
        let s = self.scale();
        self.translucent_bounds.map(|(lo, hi)| {
            (
                [0, 1, 2].map(|a| lo[a] * s[a] + o[a]),
                [0, 1, 2].map(|a| hi[a] * s[a] + o[a]),
            )
        })
    }

    /// The translucent quads as the sorted techniques order a game's objects against them
    /// (`oit::sorted::interleave`): their box and their distinct planes, world blocks.
    pub(crate) fn translucent_surfaces(&self) -> Option<Surfaces<'_>> {
        let (lo, hi) = self.translucent_bounds()?;
        Some(Surfaces {
            lo: DVec3::from(lo),
            hi: DVec3::from(hi),
            origin: self.pos.origin().map(|v| v as f64),
            scale: self.scale(),
            planes: &self.translucent_planes,
            quads: &self.translucent,
        })
    }

    /// A number that changes with every upload (remesh) of this chunk, never repeated by
    /// the store.
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// Changes whenever the GPU order of the translucent quads is written.
    pub(crate) fn order_stamp(&self) -> u64 {
        self.order_stamp
    }
}

/// A chunk's translucent quads seen from afar: their box and their planes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Surfaces<'a> {
    /// The box's lowest corner, world blocks.
    pub lo: DVec3,
    /// The box's highest corner, world blocks.
    pub hi: DVec3,
    /// The chunk's origin, world blocks.
    pub origin: [f64; 3],
    /// Blocks per cell along x, y and z (1 but in a level of detail).
    pub scale: [f64; 3],
    /// The distinct planes: which way the quads face, chunk-local coordinate on the axis.
    pub planes: &'a [(Face, u8)],
    /// The quads, in their drawn order.
    pub quads: &'a [PackedQuad],
}

impl Surfaces<'_> {
    /// World blocks of the chunk-local point `local` (cells).
    pub(crate) fn world(&self, local: [f64; 3]) -> DVec3 {
        DVec3::from([0, 1, 2].map(|a| self.origin[a] + local[a] * self.scale[a]))
    }

    /// World coordinate along `axis` of the chunk-local plane `at` (cells).
    pub(crate) fn plane_at(&self, axis: usize, at: f64) -> f64 {
        self.origin[axis] + at * self.scale[axis]
    }

    /// Distances from `eye` to the box: its nearest point, its centre, its farthest corner.
    pub(crate) fn distances(&self, eye: DVec3) -> [f64; 3] {
        let near = eye.clamp(self.lo, self.hi).distance(eye);
        let mid = ((self.lo + self.hi) * 0.5).distance(eye);
        let far = (eye - self.lo).abs().max((eye - self.hi).abs()).length();
        [near, mid, far]
    }
}

/// The distinct planes (facing, position along its axis) of a translucent mesh, sorted,
/// from its layers (a layer is a plane, facing and block: every quad lies in one).
pub(super) fn distinct_planes(layers: &[Plane]) -> Vec<(Face, u8)> {
    let mut planes: Vec<(Face, u8)> = layers
        .iter()
        .map(|p| (p.face, p.lo[p.face.axis()] as u8))
        .collect();
    planes.sort_unstable_by_key(|&(f, c)| (f as u8, c));
    planes.dedup();
    planes
}

/// The box a translucent mesh spans, chunk-local blocks, from its layers.
pub(super) fn layers_bounds(layers: &[Plane]) -> Option<([f64; 3], [f64; 3])> {
    let (lo, hi) = layers::bounds(layers)?;
    Some((lo.as_dvec3().to_array(), hi.as_dvec3().to_array()))
}
