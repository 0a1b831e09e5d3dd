//! Exact back-to-front order of a chunk's translucent quads, re-sorted only when the eye
//! crosses a plane that can change it; exact back-to-front order of chunks.
//!
//! Centre-distance sorting ([`crate::sort`]) is not exact on greedy-merged voxel quads: a
//! chunk-wide water quad lying *behind* a small glass face can have its centre nearer the
//! eye (water surface at y = 10, a glass pillar on it, eye at (16.5, 11.2, 16.5): the
//! pillar is drawn first and the water blended over it). This module orders the quads as
//! rectangles in space, whatever their facing, so the order stays exact when back faces
//! are drawn too.
//!
//! # Use, per chunk
//!
//! ```
//! use voxel_mesh::order::{QuadOrder, RegionKey};
//! # let quads: Vec<voxel_mesh::PackedQuad> = Vec::new();
//! // When the translucent mesh is uploaded:
//! let order = QuadOrder::new(&quads);
//! let mut sorted_for: Option<RegionKey> = None;
//! let mut gpu = Vec::new();
//! // Every frame: the eye in chunk-local block units, computed in f64 (eye - chunk origin).
//! let eye_local = [3.5, 40.25, -7.0];
//! let key = order.region_key(eye_local);
//! if sorted_for != Some(key) {
//!     let stats = order.sort_into(eye_local, &mut gpu);
//!     // Upload `gpu` in place of the chunk's translucent quads; report stats.cycles.
//!     // Where the order holds for the whole region, sort again only when the key changes;
//!     // otherwise (rare, see `SortStats::eye_dependent`) also when the eye moves.
//!     sorted_for = stats.is_exact_in_region().then_some(key);
//! }
//! ```
//!
//! A still camera sorts nothing; a moving one sorts a chunk when it crosses one of that
//! chunk's [`QuadOrder::trigger_planes`]. Chunks are drawn farthest first by
//! [`chunk_order_key`] ([`chunks_back_to_front`]).
//!
//! # How
//!
//! A quad is a flat axis-aligned box; quad `b` *hides* quad `a` from an eye when a ray from
//! the eye meets `b` and then `a`, and an order is exact when it draws `a` before `b`
//! whenever `b` hides `a`. [`QuadOrder::new`] puts a chunk's quads in a tree of *free
//! planes* (planes that cut no quad): a sort walks it comparing the eye's side of each
//! plane, O(n) with no comparison of quads. Quads that no free plane separates fall apart
//! into objects, ordered by their bounding boxes, or form a stuck leaf, ordered by a
//! separating-axis relation over the eye's region (bit sets and Tarjan's strongly
//! connected components), refined in integers by the exact relation over the region and,
//! rarely, at the eye itself ([`SortStats::eye_dependent`]). The order depends on the eye
//! only through its [`RegionKey`], so a chunk is sorted again only when the eye crosses a
//! trigger plane. Quads that hide each other in a true cycle (no order of whole quads is
//! exact) are drawn in centre-distance order and counted ([`SortStats::cycles`]).
//! [`chunk_order_key`] is an integer distance in chunks, exact for a grid of equal cubes.
//!
//! The definitions, lemmas and proofs (the relation, the plane tree, objects and stuck
//! leaves, regions and trigger planes, cycles, precision, cost, order across chunks) are
//! in the repository's [`docs/quad-order.md`](../../../docs/quad-order.md).
//!
//! Files: `relation` (quads as boxes; the relation at an eye and over a cell), `tree` (the
//! plane tree: its build and its sort), `objects` (a set of quads split into objects),
//! `leaf` (stuck leaves: the separating-axis relation as bit sets), `scc` (strongly
//! connected components and the order of cyclic groups), `chunks` (order across chunks).

mod chunks;
mod leaf;
mod objects;
mod relation;
mod scc;
#[cfg(test)]
mod tests;
mod tree;

pub use chunks::{chunk_order_key, chunks_back_to_front};
pub use tree::QuadOrder;

/// "No node" / "not a trigger plane".
const NONE: u32 = u32::MAX;

/// Coordinates of quads are 0..=32 for quads the mesher makes; garbage packed quads can
/// reach 63. Keys, masks and look-up tables cover 0..=63 so that no input indexes out of
/// range.
const MAX_COORD: usize = 63;
/// Number of look-up values per axis: coordinates 0..=63 and 64.
const VALUES: usize = MAX_COORD + 2;
/// Number of mask values per axis: -1..=64.
const MASK_VALUES: usize = VALUES + 1;

/// Which region of a [`QuadOrder`]'s trigger planes an eye is in: per axis, how many
/// trigger planes lie strictly below the eye. An eye exactly on a plane shares the key of
/// the open interval below it, whose order is exact on the plane too (Theorem 2 of
/// `docs/quad-order.md`). Compare keys of the same [`QuadOrder`] only.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct RegionKey(pub [u8; 3]);

/// What a sort met, for the renderer to count and report.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SortStats {
    /// Cycles met: groups of quads (strongly connected components, of more than one quad,
    /// of the relation at the eye itself, tie-breaks included) that no order draws exactly.
    /// Each is drawn in centre-distance order, farthest first.
    pub cycles: u32,
    /// Quads in those groups.
    pub quads_in_cycles: u32,
    /// Groups whose order is exact at this eye but not at every eye of its region (the
    /// relation over the region is cyclic there, the relation at the eye is not). While it
    /// is non-zero, re-sort when the eye moves, not only when the region key changes.
    pub eye_dependent: u32,
    /// Quads ordered pairwise (in stuck leaves, and in groups of objects ordered through
    /// their quads); a diagnostic of cost.
    pub pairwise_quads: u32,
}

impl SortStats {
    /// Whether the order is exact at the eye it was computed for.
    pub fn is_exact(&self) -> bool {
        self.cycles == 0
    }

    /// Whether the order is exact at every eye of the region it was computed for.
    pub fn is_exact_in_region(&self) -> bool {
        self.cycles == 0 && self.eye_dependent == 0
    }

    fn add(&mut self, o: SortStats) {
        self.cycles += o.cycles;
        self.quads_in_cycles += o.quads_in_cycles;
        self.eye_dependent += o.eye_dependent;
        self.pairwise_quads += o.pairwise_quads;
    }
}

/// Internals exposed for the integration tests; not part of the API.
#[doc(hidden)]
pub mod testing {
    use super::relation::{QBox, may_hide_in_cell};
    use super::{QuadOrder, RegionKey};
    use crate::PackedQuad;

    /// The relation at a point: whether `b` hides part of `a` from `eye`.
    pub fn hides_at(eye: [f64; 3], a: PackedQuad, b: PackedQuad) -> bool {
        super::relation::hides_at(eye, &QBox::of(a), &QBox::of(b))
    }

    /// The region relation: whether `b` may hide part of `a` from some eye of the region
    /// `key` of `order` (tie-breaks included).
    pub fn may_hide_in_region(
        order: &QuadOrder,
        key: RegionKey,
        a: PackedQuad,
        b: PackedQuad,
    ) -> bool {
        may_hide_in_cell(&QBox::of(a), &QBox::of(b), &order.cell(key))
    }

    /// The open cell of a region: per axis `(lo, hi)`, `None` for unbounded.
    pub fn region_cell(order: &QuadOrder, key: RegionKey) -> [(Option<i32>, Option<i32>); 3] {
        order.cell(key).map(|s| (s.lo, s.hi))
    }
}
