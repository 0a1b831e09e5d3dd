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
//! [`chunk_order_key`] (see "Order across chunks").
//!
//! # The relation
//!
//! A quad is a closed, flat, axis-aligned box `q = [lo, hi]` with `lo[n] = hi[n]` along its
//! normal axis `n`; `ri(q)` is its relative interior (open in its plane). For an eye `E`,
//! quad `b` *hides* quad `a` when some ray from `E` meets `ri(b)` and then `ri(a)`, with `E`
//! in neither plane (a quad seen edge-on covers no pixel). An order of the quads is
//! **exact** for `E` when it draws `a` before `b` whenever `b` hides `a`: then no pixel
//! blends a farther quad over a nearer one. Rays through edges are measure-zero and do not
//! count; every relation below is witnessed by an open set of rays.
//!
//! Two faces of opposite facing on one plane with overlapping footprints (water's +x face
//! and glass's -x face between a water and a glass block) meet every ray at the same point,
//! so rays do not order them. The *tie-break*: the face whose block lies on the far side of
//! the plane comes first (the back face of the nearer block last), as if each face sat an
//! infinitesimal step inside its own block. Exactness includes it.
//!
//! **Lemma 0 (mesher quads do not cross).** The relative interiors of two translucent
//! quads of [`crate::Mesher`] are disjoint, unless the quads are opposite faces on one
//! plane. Same direction and plane: a unit face belongs to one block, and the greedy cover
//! of one block type's faces does not overlap itself. Parallel planes: disjoint.
//! Perpendicular quads `a`, `b` whose interiors met would share an open piece of the grid
//! line where their planes cross; at a point of it, of the four blocks around the line,
//! `a` makes the two on its block's side of its plane of its type `T_a` and the two others
//! not `T_a` (a translucent type hides itself), and `b` likewise with `T_b`: the block on
//! both quads' block sides is `T_a = T_b`, and the block on `a`'s side but not `b`'s is `T_a`
//! and not `T_b`, a contradiction. The module needs only this property, not the mesher.
//!
//! **Lemma 1 (separating axis).** If `a.hi[k] <= b.lo[k]` and `b` hides `a`, then
//! `E[k] > b.lo[k]`. *Proof.* On the witness ray, the coordinate `k` is affine in the ray
//! parameter; the points `p_b` then `p_a` satisfy `p_a[k] <= a.hi[k] <= b.lo[k] <= p_b[k]`.
//! Equality throughout would need `a` and `b` flat along `k` on one plane (a point of `ri`
//! at `hi[k]` exists only for a quad flat along `k`), and a ray meeting two points of one
//! plane lies in it, with `E` in it: excluded. So `p_a[k] < p_b[k]`, the coordinate falls
//! along the ray, and `E[k] > p_b[k] >= b.lo[k]`. ∎ Hence for an eye in the closed gap
//! `a.hi[k] <= E[k] <= b.lo[k]` neither quad hides the other; two coplanar quads never
//! hide each other; and every pair of quads with disjoint interiors is separated along
//! some axis (for perpendicular or parallel quads that share no interior point).
//!
//! **Lemma 2 (exact pair test).** `b` hides `a` from `E` iff `E` is off both planes and
//! `E = p_b + s (p_b - p_a)` for some `p_a` in `ri(a)`, `p_b` in `ri(b)`, `s > 0` (the ray
//! from `E` through `p_b` reaches `p_a` at parameter `1 + 1/s`; conversely
//! `s = t_b / (t_a - t_b)` from a witness ray). The coordinates separate: `E[k]` ranges over
//! `J_k(s) = (1+s) ri(b)[k] - s ri(a)[k]`, the open interval
//! `((1+s) b.lo - s a.hi, (1+s) b.hi - s a.lo)`, or the point `(1+s) b - s a` when both quads
//! are flat along `k` (parallel planes). For one eye each condition is linear in `s`: an interval of `s` per axis, so the
//! test is O(1). For an open box `C` of eyes (a *cell*), some eye of `C` sees `b` hide `a`
//! iff `J_k(s)` meets `C[k]` for every `k` for one `s > 0` (a box is a product); with integer
//! cell bounds these are linear inequalities in `s` with integer coefficients, decided
//! exactly in integers. This *region relation* contains the relation of every eye of `C`.
//!
//! # The plane tree
//!
//! **Theorem 1 (free planes).** Let the plane `x[k] = c` meet the interior of no quad
//! except those lying in it. Split the quads into `below` (`hi[k] <= c`, not in the plane),
//! `on` and `above`. For `E[k] > c`, drawing `below`, then the faces of `on` whose blocks lie
//! below (`+k` faces), then the other faces of `on`, then `above` is exact for every pair in
//! different parts; symmetrically for `E[k] < c`; for `E[k] = c` any order of the parts is.
//! *Proof.* `ri` of `above` quads lies in `x[k] > c`, of `below` quads in `x[k] < c` (a
//! quad flat at `c` is `on`). A ray from `E` with `E[k] > c` runs through `x[k] > c`, then
//! perhaps the plane, then `x[k] < c`, never back: whatever it meets first is in a part
//! drawn later. Within `on` only tie-breaks order quads, and for `E[k] > c` the blocks of
//! `+k` faces are the far ones. For `E[k] = c` a ray stays in the plane (meeting only `on`
//! quads, edge-on) or leaves it into one open half-space for good: it meets one part. ∎
//!
//! [`QuadOrder::new`] builds a tree: a set lying in one plane is a leaf (ordered by facing
//! when opposite faces overlap, else in any order); otherwise it splits at a free plane
//! (Theorem 1), preferring planes already used (fewer trigger planes), then balanced
//! splits. A sort walks the tree: every node compares the eye's side of one plane, so a
//! sort is O(n) with no comparison of quads at all. The tree is exact for every eye,
//! including eyes on its planes.
//!
//! # Sets no free plane splits
//!
//! Where every plane that would separate a set cuts a quad (a wall through a floor, boxes
//! of several glasses interlocked, many structures staggered across the chunk):
//!
//! - **Objects.** If the set falls apart into *objects* (classes of quads whose closed
//!   boxes touch, merged while two classes' bounding boxes are not separated along any
//!   axis), each object gets its own subtree and the objects are ordered by their bounding
//!   boxes. If boxes `A ⊇ a` and `B ⊇ b` are separated along `k` (`A.hi[k] <= B.lo[k]`) and
//!   `b` hides `a`, then `a`, `b` are separated along `k` too and Lemma 1 gives
//!   `E[k] > b.lo[k] >= B.lo[k]`: the separating-axis relation of the boxes (below) contains
//!   every relation between their quads. Objects it leaves in a cycle are ordered together,
//!   from their quads, as a stuck leaf.
//! - **Stuck leaves** (one object): the *separating-axis relation* over the cell `C` of the
//!   eye's region: `b` may hide `a` when, along every axis separating them, some eye of `C`
//!   lies beyond `b`'s near face. By Lemma 1 it contains the relation of every eye of `C`. It
//!   is computed as bit sets, a row of m quads in O(m / 64) words from per-axis masks
//!   (`lo < v`, `hi > v` for each coordinate `v`), and ordered by Tarjan's strongly
//!   connected components over rows computed as the search reaches each quad (drawing
//!   order falls out of Tarjan's order on the reversed relation). A topological order of it
//!   is exact at every eye of `C`. Its strongly connected groups (a few quads each, when
//!   any) are ordered by the region relation of Lemma 2 (exact in integers, also holding for
//!   every eye of `C`); groups still cyclic, by the relation at the eye itself (counted in
//!   [`SortStats::eye_dependent`]: exact at this eye, not necessarily at every eye of the
//!   region); groups cyclic even there are true cycles. Combining is sound: a pair related
//!   at an eye of `C` lies either in two groups (ordered by the condensation, which
//!   contains it) or in one (ordered by the finer relation, which contains it).
//! - For eyes beyond a leaf's bounding box along all three axes (most chunks, seen from
//!   outside) the relation is the same for the whole octant: the 8 octant orders are
//!   computed when the structure is built, and such a sort copies one.
//!
//! # Regions and trigger planes
//!
//! The trigger planes are (1) the planes of tree nodes that separate children or carry
//! overlapping opposite faces, (2) every coordinate (`lo` and `hi` along each axis) of the
//! quads of stuck leaves, (3) every coordinate of the objects' bounding boxes. The
//! [`RegionKey`] of an eye counts, per axis, the trigger planes strictly below it; a region
//! is the set of eyes with one key: an open cell between consecutive planes, plus the parts
//! of its upper bounding planes (an eye on a plane belongs to the interval below it).
//!
//! **Theorem 2 (regions).** The order [`QuadOrder::sort_into`] returns depends on the eye
//! only through its key (apart from groups counted in [`SortStats::eye_dependent`] or
//! [`SortStats::cycles`]) and is exact at every eye of the region. *Proof.* Every decision
//! is a function of the key: the side of each node's plane (a comparison of key indices),
//! and the cell given to leaves and object nodes (the open box between the trigger planes
//! around the key). For an eye inside the open cell, exactness is Theorems 1, the object
//! argument and the leaf argument above. For an eye on a trigger plane `c` (it takes the
//! order of the interval below): at nodes with plane `c`, Theorem 1 allows any order and
//! faces in the plane are edge-on; the relations used by leaves and objects hold over the
//! open cell below, and contain the relation at the eye on the plane, because that relation
//! is open: a witness ray from an eye off both quads' planes still works from every nearby
//! eye, among them eyes of the cell below (an eye in a quad's plane relates it to nothing).
//! The same holds on lines and corners where planes of several axes meet. ∎
//!
//! *Which planes are needed.* Necessary: for every pair `a`, `b` and eyes `E1` (where `b`
//! hides `a`) and `E2` (where `a` hides `b`), a trigger plane must lie strictly between
//! `E1` and `E2`, or they would share a region and no order is exact at both. Quad planes
//! alone do not suffice: a wall (x quad at x = 5, z in 0..4) and a floor (y quad at y = 4,
//! z in 6..12) that overlap in x and y are separated only along z; eyes `(9, 6, 6 + d)`
//! see the floor hide the wall and eyes `(9, 6, 4 - d)` the wall hide the floor, for every
//! small `d`, so a z plane in `[4, 6]` is needed, and no quad lies in one: its bounds are
//! edge planes. Nor is every quad plane needed: three overlapping parallel panes at
//! x = 1, 2, 3 need the one plane x = 2, which lies in both gaps (the tests check both
//! cases). The set above is sufficient (Theorem 2); the tree's greedy choice of planes
//! reuses them across gaps, but a set of least size is a hitting-set problem this module
//! does not solve exactly. Stuck leaves and objects use all their coordinates, the price of
//! a region relation that is exact at every eye.
//!
//! # Cycles
//!
//! Voxel quads can hide each other in a cycle: a cube, a block and a beam of glass (the
//! test `a_real_cycle_of_voxel_quads_is_reported`) form one from some eyes, and no order
//! of whole quads is exact there (splitting a quad would be). The fallback draws each
//! cyclic group (strongly connected component of the relation at the eye, of more than one
//! quad) in centre-distance order, farthest first; everything else stays exact. Each sort
//! reports [`SortStats::cycles`] and [`SortStats::quads_in_cycles`].
//!
//! # Precision and odd eyes
//!
//! The key compares the eye with integer planes, which is exact in f64 whatever the eye's
//! magnitude (an eye 1e6 blocks away lies beyond every plane and its order is exact; pass
//! `eye - chunk origin` computed in f64). The tree, leaves and objects decide in integers.
//! Only the refinement at the eye itself (rare) computes with the eye in floating point; it
//! is exact for eyes with few significant bits and otherwise errs only for eyes within
//! rounding error of where two quads start to overlap on screen, on sub-pixel overlaps. A
//! NaN coordinate counts as below every plane (key 0) and an infinite one as beyond every
//! plane; refinements at a non-finite eye are skipped (their groups count as cycles). No
//! input makes a sort panic or loop: the work is bounded by the quads, never by the eye.
//!
//! # Cost
//!
//! Per sort: O(n) for the tree; O(m² / 64) word operations for a stuck leaf or object node
//! of m quads or objects, plus the small groups; a copy for octant eyes. Build: O(n · depth)
//! for the tree, 8 leaf orders per leaf. `cargo bench -p voxel-mesh --bench sort` measures
//! it against [`crate::sort::quads_back_to_front`] (results/sort-bench.txt).
//!
//! # Order across chunks
//!
//! **Theorem 3.** For equal cubes of side `L` on a grid, if chunk `B` hides part of chunk
//! `A` from `E` then `|E - c_B| < |E - c_A|` (centres). *Proof.* Two cubes of a grid share
//! their slab along an axis (equal centre coordinates) or are separated along it. On a
//! separating axis with `A` below `B`, Lemma 1 (for boxes) gives
//! `E[k] > B.lo[k] = c_B[k] - L/2`, and `c_B[k] - c_A[k] >= L`, so
//! `E[k] - (c_A[k] + c_B[k]) / 2 > (c_B[k] - c_A[k]) / 2 - L/2 >= 0`: `E[k]` is nearer
//! `c_B[k]`. Summing over axes, strictly nearer `c_B`. ∎ So
//! drawing farthest centre first is exact, and ties in exact arithmetic only join chunks
//! that do not hide each other. In f64, as the renderer computes distances, two related
//! chunks far away can round to one distance (the eye 2^-17 past their shared face and
//! 2^23 blocks above: a test), and the tie-break by position can then draw the hiding chunk
//! first, over a sliver of about 1e-12 radian. [`chunk_order_key`] removes the rounding:
//! the relation between chunks depends only on the sides of the eye with respect to chunk
//! borders (Lemma 1), so the eye can be moved to the centre of the chunk that holds it (an
//! eye on a border can take either neighbour: its relation is contained in both), and the
//! squared distance, in chunks, is an integer.

use std::cmp::Reverse;

use voxel_core::{CHUNK_SIZE, ChunkPos};

use crate::{PackedQuad, UV_AXES};

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

/// A quad as a closed, flat, axis-aligned box in chunk-local block units.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct QBox {
    /// Minimum corner.
    lo: [i32; 3],
    /// Maximum corner; `lo[axis] == hi[axis]` is the quad's plane.
    hi: [i32; 3],
    /// Normal axis, 0..3.
    axis: usize,
    /// Whether the face points along +axis (its block lies below the plane).
    positive: bool,
}

impl QBox {
    /// The box of a packed quad. Face bits 6 and 7 (never made by [`PackedQuad::new`]) are
    /// read as -z, as [`PackedQuad::center`] does.
    fn of(q: PackedQuad) -> Self {
        let g = q.geometry;
        let mut lo = [g & 31, (g >> 5) & 31, (g >> 10) & 31].map(|v| v as i32);
        let face = q.face_index().min(5);
        let axis = face / 2;
        let positive = face.is_multiple_of(2);
        if positive {
            lo[axis] += 1;
        }
        let mut hi = lo;
        let [u, v] = UV_AXES[axis];
        hi[u] += ((g >> 15) & 31) as i32 + 1;
        hi[v] += ((g >> 20) & 31) as i32 + 1;
        Self {
            lo,
            hi,
            axis,
            positive,
        }
    }

    /// The plane coordinate along the normal axis.
    #[inline]
    fn plane(&self) -> i32 {
        self.lo[self.axis]
    }

    /// Squared distance from the centre to `eye` (NaN for a NaN eye).
    fn centre_distance2(&self, eye: [f64; 3]) -> f64 {
        (0..3)
            .map(|k| {
                let v = f64::from(self.lo[k] + self.hi[k]) * 0.5 - eye[k];
                v * v
            })
            .sum()
    }

    /// Whether two coplanar quads' footprints share interior points.
    fn footprints_overlap(&self, o: &Self) -> bool {
        let [u, v] = UV_AXES[self.axis];
        self.lo[u] < o.hi[u] && o.lo[u] < self.hi[u] && self.lo[v] < o.hi[v] && o.lo[v] < self.hi[v]
    }

    /// Whether `self` and `o` are opposite faces on one plane with overlapping footprints.
    fn ties_with(&self, o: &Self) -> bool {
        self.axis == o.axis
            && self.plane() == o.plane()
            && self.positive != o.positive
            && self.footprints_overlap(o)
    }
}

/// The bounds of an open cell along one axis; `None` for an unbounded side.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Span {
    lo: Option<i32>,
    hi: Option<i32>,
}

impl Span {
    /// Whether the cell lies above `p` (it is open, so `lo >= p` means every eye in it).
    fn above(self, p: i32) -> bool {
        self.lo.is_some_and(|l| l >= p)
    }

    /// Whether the cell lies below `p`.
    fn below(self, p: i32) -> bool {
        self.hi.is_some_and(|h| h <= p)
    }
}

/// The open interval of `s > 0` allowed by constraints `s * alpha < beta`, with rational
/// ends in integers.
struct SInterval {
    /// Lower end `num / den` (exclusive), `den > 0`.
    lo: (i64, i64),
    /// Upper end (exclusive); `None` is +infinity.
    hi: Option<(i64, i64)>,
    empty: bool,
}

impl SInterval {
    fn new() -> Self {
        Self {
            lo: (0, 1),
            hi: None,
            empty: false,
        }
    }

    /// Adds `s * alpha < beta`.
    #[inline]
    fn less(&mut self, alpha: i64, beta: i64) {
        match alpha.signum() {
            0 => self.empty |= beta <= 0,
            1 => {
                if self.hi.is_none_or(|h| beta * h.1 < h.0 * alpha) {
                    self.hi = Some((beta, alpha));
                }
            }
            _ => {
                // s > beta / alpha = (-beta) / (-alpha)
                let b = (-beta, -alpha);
                if b.0 * self.lo.1 > self.lo.0 * b.1 {
                    self.lo = b;
                }
            }
        }
    }

    /// Adds `s * alpha > beta`.
    #[inline]
    fn greater(&mut self, alpha: i64, beta: i64) {
        self.less(-alpha, -beta);
    }

    fn feasible(&self) -> bool {
        !self.empty && self.hi.is_none_or(|h| self.lo.0 * h.1 < h.0 * self.lo.1)
    }
}

/// The region relation (lemma 2 of the module docs): whether `b` hides part of `a` from
/// some eye of the open box `cell`, so that `a` must be drawn before `b` for that eye.
/// Exact, in integers. Coplanar quads never hide each other; opposite faces with
/// overlapping footprints get the tie-break instead ([`tie_in`]).
fn may_hide_in_cell(a: &QBox, b: &QBox, cell: &[Span; 3]) -> bool {
    if a.axis == b.axis && a.plane() == b.plane() {
        return tie_in(a, b, cell);
    }
    let mut s = SInterval::new();
    for (k, c) in cell.iter().enumerate() {
        let (alo, ahi, blo, bhi) = (
            i64::from(a.lo[k]),
            i64::from(a.hi[k]),
            i64::from(b.lo[k]),
            i64::from(b.hi[k]),
        );
        if alo == ahi && blo == bhi {
            // Parallel planes: E_k = b + s (b - a), strictly inside the cell.
            let d = blo - alo;
            if let Some(lo) = c.lo {
                s.greater(d, i64::from(lo) - blo);
            }
            if let Some(hi) = c.hi {
                s.less(d, i64::from(hi) - blo);
            }
        } else {
            // E_k ranges over the open interval ((1+s) b.lo - s a.hi, (1+s) b.hi - s a.lo).
            if let Some(hi) = c.hi {
                s.less(blo - ahi, i64::from(hi) - blo);
            }
            if let Some(lo) = c.lo {
                s.greater(bhi - alo, i64::from(lo) - bhi);
            }
        }
        if s.empty {
            return false;
        }
    }
    s.feasible()
}

/// The coplanar tie-break over a cell: `a` before `b` when they are opposite faces on one
/// plane with overlapping footprints and `a`'s block lies on the far side of the plane
/// (for a cell above the plane, the positive face, whose block lies below).
fn tie_in(a: &QBox, b: &QBox, cell: &[Span; 3]) -> bool {
    let c = cell[a.axis];
    a.ties_with(b) && ((c.above(a.plane()) && a.positive) || (c.below(a.plane()) && !a.positive))
}

/// The coplanar tie-break at a point eye (see [`tie_in`]).
fn tie_at(eye: [f64; 3], a: &QBox, b: &QBox) -> bool {
    let (e, p) = (eye[a.axis], f64::from(a.plane()));
    a.ties_with(b) && ((e > p && a.positive) || (e < p && !a.positive))
}

/// The relation at a point (lemma 2 with a one-point cell): whether `b` hides part of `a`
/// from `eye`. Quads seen edge-on hide and are hidden by nothing; coplanar quads never
/// hide each other. Floating point: exact when the eye's coordinates have few significant
/// bits (every product compared below is then exact), otherwise wrong only for eyes
/// within rounding error of the boundary of the set of eyes that see the two quads
/// overlap, where their overlap on screen is far below a pixel.
fn hides_at(eye: [f64; 3], a: &QBox, b: &QBox) -> bool {
    let (pa, pb) = (f64::from(a.plane()), f64::from(b.plane()));
    if eye[a.axis] == pa || eye[b.axis] == pb || (a.axis == b.axis && pa == pb) {
        return false;
    }
    // Bounds on s as (numerator, denominator > 0).
    let lt = |x: (f64, f64), y: (f64, f64)| x.0 * y.1 < y.0 * x.1;
    let mut lo = (0.0, 1.0);
    let mut hi: Option<(f64, f64)> = None;
    let mut eq: Option<(f64, f64)> = None;
    let mut ok = true;
    let mut less = |alpha: f64, beta: f64| {
        if alpha > 0.0 {
            if hi.is_none_or(|h| lt((beta, alpha), h)) {
                hi = Some((beta, alpha));
            }
        } else if alpha < 0.0 {
            if lt(lo, (-beta, -alpha)) {
                lo = (-beta, -alpha);
            }
        } else {
            ok &= beta > 0.0;
        }
    };
    for (k, &e) in eye.iter().enumerate() {
        let (alo, ahi, blo, bhi) = (
            f64::from(a.lo[k]),
            f64::from(a.hi[k]),
            f64::from(b.lo[k]),
            f64::from(b.hi[k]),
        );
        if alo == ahi && blo == bhi {
            // Parallel planes: s = (e - b) / (b - a).
            let d = blo - alo;
            eq = Some(if d > 0.0 { (e - blo, d) } else { (blo - e, -d) });
        } else {
            less(blo - ahi, e - blo);
            less(alo - bhi, bhi - e);
        }
    }
    ok && match eq {
        Some(s) => lt(lo, s) && hi.is_none_or(|h| lt(s, h)),
        None => hi.is_none_or(|h| lt(lo, h)),
    }
}

/// Which region of a [`QuadOrder`]'s trigger planes an eye is in: per axis, how many
/// trigger planes lie strictly below the eye. An eye exactly on a plane shares the key of
/// the open interval below it, whose order is exact on the plane too (module docs).
/// Compare keys of the same [`QuadOrder`] only.
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

/// A node of the plane tree.
#[derive(Clone, Copy, Debug)]
enum Node {
    /// Quads on one plane (stored `start..mid` face +axis, `mid..end` face -axis), the
    /// subtree wholly below the plane and the one wholly above it along `axis`.
    Split {
        axis: u8,
        /// Index of the plane in the axis's trigger planes, or [`NONE`] when the node has
        /// no children and no opposite faces that overlap (then any order is exact).
        trigger: u32,
        below: u32,
        above: u32,
        start: u32,
        mid: u32,
        end: u32,
    },
    /// Quads that no free axis-aligned plane separates and that form one object: ordered
    /// pairwise per region.
    Stuck { leaf: u32 },
    /// Quads that no free axis-aligned plane separates but that fall apart into objects
    /// (see [`objects`]): the objects are ordered pairwise by their bounding boxes per
    /// region, each by its own subtree (`children[first..first + count]`).
    Objects { leaf: u32, first: u32 },
}

/// The precomputed per-chunk structure for exact ordering: build it once when the mesh is
/// uploaded ([`QuadOrder::new`]), compute [`QuadOrder::region_key`] every frame and call
/// [`QuadOrder::sort_into`] when the key differs from the one last sorted for.
#[derive(Clone, Debug)]
pub struct QuadOrder {
    /// The quads, grouped by node.
    quads: Vec<PackedQuad>,
    nodes: Vec<Node>,
    root: u32,
    /// Child nodes of object nodes.
    children: Vec<u32>,
    /// Per node, the range of stored quads of its subtree.
    spans: Vec<(u32, u32)>,
    /// Trigger planes per axis, sorted, distinct.
    planes: [Vec<u8>; 3],
    /// `lut[k][j]`: how many trigger planes of axis `k` lie below `j`, for j in 0..=64.
    lut: [[u8; VALUES]; 3],
    leaves: Vec<Leaf>,
}

impl Default for QuadOrder {
    fn default() -> Self {
        Self::new(&[])
    }
}

/// Work item of the build.
struct Job {
    ids: Vec<u32>,
    parent: u32,
    /// The child's place in its parent: 0 below, 1 above (split nodes), the object's index
    /// (object nodes), unused for the root.
    slot: u32,
}

impl QuadOrder {
    /// Builds the structure for a chunk's translucent quads: the plane tree, its trigger
    /// planes and the pairwise leaves. Do it once per mesh upload.
    pub fn new(quads: &[PackedQuad]) -> Self {
        Self::build(quads, false)
    }

    /// Like [`QuadOrder::new`] but with every quad in one pairwise leaf (no plane tree):
    /// for tests and benchmarks of the pairwise path.
    #[doc(hidden)]
    pub fn pairwise_only(quads: &[PackedQuad]) -> Self {
        Self::build(quads, true)
    }

    fn build(quads: &[PackedQuad], no_tree: bool) -> Self {
        let all: Vec<QBox> = quads.iter().map(|&q| QBox::of(q)).collect();
        let mut out = Self {
            quads: Vec::with_capacity(quads.len()),
            nodes: Vec::new(),
            root: NONE,
            children: Vec::new(),
            spans: Vec::new(),
            planes: Default::default(),
            lut: [[0; VALUES]; 3],
            leaves: Vec::new(),
        };
        // Trigger planes as (axis, coordinate) flags. Node triggers hold coordinates until
        // the planes are known, then indices.
        let mut is_trigger = [[false; MAX_COORD + 1]; 3];
        let mut leaf_boxes = Vec::new();
        let mut jobs = vec![Job {
            ids: (0..quads.len() as u32).collect(),
            parent: NONE,
            slot: 0,
        }];
        while let Some(mut job) = jobs.pop() {
            if job.ids.is_empty() {
                continue;
            }
            let node = out.nodes.len() as u32;
            let here = out.quads.len() as u32;
            out.spans.push((here, here));
            match out.nodes.get_mut(job.parent as usize) {
                None => out.root = node,
                Some(Node::Split { below, above, .. }) => {
                    *(if job.slot == 0 { below } else { above }) = node;
                }
                Some(Node::Objects { first, .. }) => {
                    out.children[(*first + job.slot) as usize] = node;
                }
                Some(Node::Stuck { .. }) => unreachable!("leaves have no children"),
            }
            let first = all[job.ids[0] as usize];
            let coplanar = job.ids.iter().all(|&i| {
                let b = &all[i as usize];
                b.axis == first.axis && b.plane() == first.plane()
            });
            let split = if coplanar {
                Some((first.axis, first.plane()))
            } else if no_tree {
                None
            } else {
                best_split(&all, &job.ids, &is_trigger)
            };
            let objects = if split.is_none() && !no_tree {
                objects(&all, &job.ids)
            } else {
                Vec::new()
            };
            if objects.len() > 1 {
                // Every plane that could separate cuts a quad, but the quads fall apart into
                // objects: an object leaf over their bounding boxes (whose coordinates are
                // trigger planes), each object a child.
                let boxes: Vec<QBox> = objects
                    .iter()
                    .map(|(_, (lo, hi))| QBox {
                        lo: *lo,
                        hi: *hi,
                        axis: 0,
                        positive: false,
                    })
                    .collect();
                for b in &boxes {
                    for k in 0..3 {
                        is_trigger[k][b.lo[k] as usize] = true;
                        is_trigger[k][b.hi[k] as usize] = true;
                    }
                }
                let first = out.children.len() as u32;
                out.children
                    .extend(std::iter::repeat_n(NONE, objects.len()));
                out.nodes.push(Node::Objects {
                    leaf: out.leaves.len() as u32,
                    first,
                });
                out.leaves.push(Leaf::new(0, boxes, true, true));
                // Pushed in reverse so that object i is built (and stored) i-th.
                for (i, (ids, _)) in objects.into_iter().enumerate().rev() {
                    jobs.push(Job {
                        ids,
                        parent: node,
                        slot: i as u32,
                    });
                }
                continue;
            }
            let Some((axis, c)) = split else {
                // Stuck: every plane that could separate cuts a quad. A pairwise leaf,
                // sorted by (axis, plane, facing) so that coplanar groups are ranges; all
                // its coordinates are trigger planes.
                job.ids.sort_by_key(|&i| {
                    let b = &all[i as usize];
                    (b.axis, b.plane(), !b.positive, i)
                });
                let start = out.quads.len() as u32;
                let boxes: Vec<QBox> = job.ids.iter().map(|&i| all[i as usize]).collect();
                for b in &boxes {
                    for k in 0..3 {
                        is_trigger[k][b.lo[k] as usize] = true;
                        is_trigger[k][b.hi[k] as usize] = true;
                    }
                }
                out.quads.extend(job.ids.iter().map(|&i| quads[i as usize]));
                out.spans[node as usize].1 = out.quads.len() as u32;
                out.nodes.push(Node::Stuck {
                    leaf: out.leaves.len() as u32,
                });
                leaf_boxes.push((out.leaves.len(), start, boxes));
                out.leaves.push(Leaf::default());
                continue;
            };
            let (mut below, mut pos, mut neg, mut above) = (vec![], vec![], vec![], vec![]);
            for &i in &job.ids {
                let b = &all[i as usize];
                if b.axis == axis && b.plane() == c {
                    if b.positive {
                        pos.push(i);
                    } else {
                        neg.push(i);
                    }
                } else if b.hi[axis] <= c {
                    below.push(i);
                } else {
                    debug_assert!(b.lo[axis] >= c, "a split plane cuts no quad");
                    above.push(i);
                }
            }
            let start = out.quads.len() as u32;
            out.quads
                .extend(pos.iter().chain(&neg).map(|&i| quads[i as usize]));
            let mid = start + pos.len() as u32;
            let end = out.quads.len() as u32;
            out.spans[node as usize].1 = end;
            // The plane is a trigger when it separates children, or when opposite faces on
            // it overlap (their tie-break depends on the side of the eye).
            let needs = !below.is_empty()
                || !above.is_empty()
                || (!pos.is_empty() && !neg.is_empty() && opposite_overlap(&all, &pos, &neg, axis));
            if needs {
                is_trigger[axis][c as usize] = true;
            }
            out.nodes.push(Node::Split {
                axis: axis as u8,
                trigger: if needs { c as u32 } else { NONE },
                below: NONE,
                above: NONE,
                start,
                mid,
                end,
            });
            jobs.push(Job {
                ids: below,
                parent: node,
                slot: 0,
            });
            jobs.push(Job {
                ids: above,
                parent: node,
                slot: 1,
            });
        }
        // Trigger planes, their look-up tables, node triggers as plane indices.
        for ((planes, lut), flags) in out.planes.iter_mut().zip(&mut out.lut).zip(&is_trigger) {
            *planes = (0..=MAX_COORD as u8)
                .filter(|&c| flags[usize::from(c)])
                .collect();
            let mut n = 0u8;
            for (j, l) in lut.iter_mut().enumerate() {
                *l = n;
                if flags.get(j) == Some(&true) {
                    n += 1;
                }
            }
        }
        for node in &mut out.nodes {
            if let Node::Split { axis, trigger, .. } = node
                && *trigger != NONE
            {
                *trigger = u32::from(out.lut[usize::from(*axis)][*trigger as usize]);
            }
        }
        for (leaf, start, boxes) in leaf_boxes {
            out.leaves[leaf] = Leaf::new(start, boxes, false, true);
        }
        // Subtree spans: children come after their parents.
        for n in (0..out.nodes.len()).rev() {
            let kids: Vec<u32> = match out.nodes[n] {
                Node::Split { below, above, .. } => vec![below, above],
                Node::Objects { leaf, first } => {
                    let count = out.leaves[leaf as usize].boxes.len() as u32;
                    out.children[first as usize..(first + count) as usize].to_vec()
                }
                Node::Stuck { .. } => Vec::new(),
            };
            for c in kids.into_iter().filter(|&c| c != NONE) {
                out.spans[n].1 = out.spans[n].1.max(out.spans[c as usize].1);
            }
        }
        out
    }

    /// Number of quads.
    pub fn len(&self) -> usize {
        self.quads.len()
    }

    /// Whether there are no quads.
    pub fn is_empty(&self) -> bool {
        self.quads.is_empty()
    }

    /// The quads in storage order (grouped by tree node).
    pub fn quads(&self) -> &[PackedQuad] {
        &self.quads
    }

    /// The trigger planes of each axis, chunk-local, sorted: the order can change only
    /// where the eye crosses one of them.
    pub fn trigger_planes(&self) -> [&[u8]; 3] {
        [&self.planes[0], &self.planes[1], &self.planes[2]]
    }

    /// Stuck leaves (single objects that no free plane separates) and the quads in them.
    pub fn stuck(&self) -> (usize, usize) {
        let stuck = self.leaves.iter().filter(|l| !l.objects);
        (stuck.clone().count(), stuck.map(|l| l.boxes.len()).sum())
    }

    /// Number of tree nodes, and of those the object nodes.
    pub fn node_count(&self) -> (usize, usize) {
        let objects = self
            .nodes
            .iter()
            .filter(|n| matches!(n, Node::Objects { .. }))
            .count();
        (self.nodes.len(), objects)
    }

    /// The region of an eye in chunk-local block units (eye minus chunk origin, computed in
    /// f64). Exact: it only compares the eye with integer planes. A NaN coordinate counts
    /// as below every plane, an infinite one as beyond every plane.
    #[inline]
    pub fn region_key(&self, eye_local: [f64; 3]) -> RegionKey {
        RegionKey(std::array::from_fn(|k| {
            let e = eye_local[k];
            // Integer planes c < e are those c < ceil(e), for e in (0, 64].
            let j = if e > 0.0 {
                (e.ceil() as usize).min(VALUES - 1)
            } else {
                0
            };
            self.lut[k][j]
        }))
    }

    /// Writes the quads into `out` (cleared first) back to front for the eye (chunk-local
    /// block units). Exact for every eye of the eye's region when
    /// [`SortStats::is_exact_in_region`] holds, and at this eye when
    /// [`SortStats::is_exact`] holds; see the module docs. Never panics, whatever the eye.
    pub fn sort_into(&self, eye_local: [f64; 3], out: &mut Vec<PackedQuad>) -> SortStats {
        out.clear();
        out.reserve(self.quads.len());
        let mut stats = SortStats::default();
        if self.root == NONE {
            return stats;
        }
        let key = self.region_key(eye_local);
        let cell = self.cell(key);
        // Tasks: a node, a range of stored quads (tagged by the top bit) or a range of
        // `extra`, quads ordered on the way (tagged by the next bit).
        const RANGE: u64 = 1 << 63;
        const EXTRA: u64 = 1 << 62;
        let range = |s: u32, e: u32| RANGE | u64::from(s) << 32 | u64::from(e);
        let mut stack: Vec<u64> = Vec::with_capacity(64);
        let mut scratch = Vec::new();
        let mut extra: Vec<PackedQuad> = Vec::new();
        stack.push(u64::from(self.root));
        while let Some(t) = stack.pop() {
            if t & (RANGE | EXTRA) != 0 {
                let (s, e) = (((t >> 32) as u32 & 0x3fff_ffff) as usize, t as u32 as usize);
                let from = if t & RANGE != 0 { &self.quads } else { &extra };
                out.extend_from_slice(&from[s..e]);
                continue;
            }
            match self.nodes[t as usize] {
                Node::Split {
                    axis,
                    trigger,
                    below,
                    above,
                    start,
                    mid,
                    end,
                } => {
                    let eye_above =
                        trigger != NONE && u32::from(key.0[usize::from(axis)]) > trigger;
                    // Eye above: the subtree below, the faces whose blocks lie below the
                    // plane (+axis, far), the others, the subtree above. Pushed reversed.
                    let (first, last) = if eye_above {
                        (below, above)
                    } else {
                        (above, below)
                    };
                    let (r1, r2) = if eye_above {
                        (range(start, mid), range(mid, end))
                    } else {
                        (range(mid, end), range(start, mid))
                    };
                    if last != NONE {
                        stack.push(u64::from(last));
                    }
                    stack.push(r2);
                    stack.push(r1);
                    if first != NONE {
                        stack.push(u64::from(first));
                    }
                }
                Node::Stuck { leaf } => {
                    let leaf = &self.leaves[leaf as usize];
                    scratch.clear();
                    let s = leaf.order(&cell, Some(eye_local), &mut scratch);
                    stats.add(s.unwrap_or_default());
                    let quads = &self.quads[leaf.start as usize..];
                    out.extend(scratch.iter().map(|&i| quads[i as usize]));
                }
                Node::Objects { leaf, first } => {
                    let (seq, groups) = self.leaves[leaf as usize].object_order(&cell);
                    let mut tasks = Vec::with_capacity(seq.len());
                    for v in seq {
                        let Some(group) = group_of(v, &groups) else {
                            tasks.push(u64::from(self.children[(first + v) as usize]));
                            continue;
                        };
                        // Objects whose boxes the separating axes leave cyclic: their quads
                        // together, by the exact relation.
                        let mut quads = Vec::new();
                        for &o in group {
                            let (s, e) = self.spans[self.children[(first + o) as usize] as usize];
                            quads.extend_from_slice(&self.quads[s as usize..e as usize]);
                        }
                        let mut boxes: Vec<(QBox, PackedQuad)> =
                            quads.iter().map(|&q| (QBox::of(q), q)).collect();
                        boxes.sort_by_key(|(b, q)| (b.axis, b.plane(), !b.positive, q.geometry));
                        quads = boxes.iter().map(|b| b.1).collect();
                        let group =
                            Leaf::new(0, boxes.into_iter().map(|b| b.0).collect(), false, false);
                        scratch.clear();
                        let s = group.order(&cell, Some(eye_local), &mut scratch);
                        stats.add(s.unwrap_or_default());
                        let at = extra.len() as u32;
                        extra.extend(scratch.iter().map(|&i| quads[i as usize]));
                        tasks.push(EXTRA | u64::from(at) << 32 | u64::from(extra.len() as u32));
                    }
                    stack.extend(tasks.into_iter().rev());
                }
            }
        }
        stats
    }

    /// The open cell of a region key.
    fn cell(&self, key: RegionKey) -> [Span; 3] {
        std::array::from_fn(|k| {
            let (p, i) = (&self.planes[k], usize::from(key.0[k]));
            Span {
                lo: i
                    .checked_sub(1)
                    .and_then(|j| p.get(j))
                    .map(|&c| i32::from(c)),
                hi: p.get(i).map(|&c| i32::from(c)),
            }
        })
    }
}

/// A stuck leaf: quads that no free plane separates, sorted by (axis, plane, facing), with
/// the bit masks that give a row of the separating-axis relation in O(m / 64) words.
#[derive(Clone, Debug, Default)]
struct Leaf {
    /// Index of the leaf's first quad among the stored ones (quad leaves).
    start: u32,
    /// Whether the boxes are the bounding boxes of objects (interior-disjoint components
    /// of an object node) rather than quads.
    objects: bool,
    boxes: Vec<QBox>,
    /// Words per bit set over the leaf's quads.
    words: usize,
    /// `masks[((k * 2 + w) * MASK_VALUES + v + 1) * words..][..words]`: the quads whose
    /// `lo[k] < v` (w = 0) or whose `hi[k] > v` (w = 1), for v in -1..=64.
    masks: Vec<u64>,
    /// Per quad and axis, the offsets of its masks `lo < hi[k]` and `hi > lo[k]`.
    offsets: Vec<[[usize; 2]; 3]>,
    /// Per quad, the range of its coplanar group.
    group: Vec<(u32, u32)>,
    /// Per quad, `tie_list[tie_start[i]..tie_start[i + 1]]`: the opposite coplanar quads
    /// whose footprints overlap its own.
    tie_start: Vec<u32>,
    tie_list: Vec<u32>,
    /// Bounding box of the leaf.
    bbox: Bounds,
    /// For eyes beyond the bounding box along every axis (octant bit k: above along k),
    /// the order, precomputed; `None` where it needs the eye itself.
    octants: [Option<Vec<u32>>; 8],
}

impl Leaf {
    /// A leaf over `boxes` (quads, or objects' bounding boxes), with its octant orders
    /// precomputed when `octants` is set.
    fn new(start: u32, boxes: Vec<QBox>, objects: bool, octants: bool) -> Self {
        let m = boxes.len();
        let words = m.div_ceil(64);
        let offset = |k: usize, hi: bool, v: i32| {
            ((k * 2 + usize::from(hi)) * MASK_VALUES + (v + 1) as usize) * words
        };
        // Each box enters `lo < v` at v = lo + 1 and `hi > v` at v = hi - 1; cumulative ORs
        // up (lo) and down (hi) the values fill in the rest.
        let mut masks = vec![0u64; 3 * 2 * MASK_VALUES * words];
        for (i, b) in boxes.iter().enumerate() {
            let bit = 1u64 << (i % 64);
            for k in 0..3 {
                masks[offset(k, false, b.lo[k] + 1) + i / 64] |= bit;
                masks[offset(k, true, b.hi[k] - 1) + i / 64] |= bit;
            }
        }
        for k in 0..3 {
            for v in 0..=VALUES as i32 - 1 {
                let (from, to) = (offset(k, false, v - 1), offset(k, false, v));
                for w in 0..words {
                    masks[to + w] |= masks[from + w];
                }
            }
            for v in (-1..VALUES as i32 - 1).rev() {
                let (from, to) = (offset(k, true, v + 1), offset(k, true, v));
                for w in 0..words {
                    masks[to + w] |= masks[from + w];
                }
            }
        }
        let offsets = boxes
            .iter()
            .map(|b| std::array::from_fn(|k| [offset(k, false, b.hi[k]), offset(k, true, b.lo[k])]))
            .collect();
        let mut group = vec![(0, 0); m];
        let mut tie_start = vec![0u32; m + 1];
        let mut tie_list = Vec::new();
        let mut g = 0;
        while g < m {
            let mut e = g + 1;
            while !objects
                && e < m
                && boxes[e].axis == boxes[g].axis
                && boxes[e].plane() == boxes[g].plane()
            {
                e += 1;
            }
            for i in g..e {
                group[i] = (g as u32, e as u32);
                tie_list.extend(
                    (g..e)
                        .filter(|&j| boxes[i].ties_with(&boxes[j]))
                        .map(|j| j as u32),
                );
                tie_start[i + 1] = tie_list.len() as u32;
            }
            g = e;
        }
        let mut bbox = ([i32::MAX; 3], [i32::MIN; 3]);
        for b in &boxes {
            for k in 0..3 {
                bbox.0[k] = bbox.0[k].min(b.lo[k]);
                bbox.1[k] = bbox.1[k].max(b.hi[k]);
            }
        }
        let mut leaf = Self {
            start,
            objects,
            boxes,
            words,
            masks,
            offsets,
            group,
            tie_start,
            tie_list,
            bbox,
            octants: Default::default(),
        };
        if !octants {
            return leaf;
        }
        let octants = std::array::from_fn(|o| {
            let cell = leaf.octant_cell(o);
            if leaf.objects {
                let (seq, groups) = leaf.components(&cell);
                groups.is_empty().then_some(seq)
            } else {
                let mut order = Vec::new();
                leaf.order(&cell, None, &mut order).map(|_| order)
            }
        });
        leaf.octants = octants;
        leaf
    }

    /// The cell of all eyes beyond the bounding box along every axis, on the sides of
    /// octant `o`.
    fn octant_cell(&self, o: usize) -> [Span; 3] {
        std::array::from_fn(|k| {
            if o >> k & 1 == 1 {
                Span {
                    lo: Some(self.bbox.1[k]),
                    hi: None,
                }
            } else {
                Span {
                    lo: None,
                    hi: Some(self.bbox.0[k]),
                }
            }
        })
    }

    /// The octant of a cell that lies beyond the bounding box along every axis.
    fn octant_of(&self, cell: &[Span; 3]) -> Option<usize> {
        let mut o = 0;
        for (k, c) in cell.iter().enumerate() {
            if c.above(self.bbox.1[k]) {
                o |= 1 << k;
            } else if !c.below(self.bbox.0[k]) {
                return None;
            }
        }
        Some(o)
    }

    /// Writes the leaf-local indices of the quads into `out` in drawing order for the eyes
    /// of `cell` (and the eye itself where the cell does not decide). `None` when the eye
    /// is needed but not given.
    fn order(
        &self,
        cell: &[Span; 3],
        eye: Option<[f64; 3]>,
        out: &mut Vec<u32>,
    ) -> Option<SortStats> {
        let mut stats = SortStats {
            pairwise_quads: self.boxes.len() as u32,
            ..SortStats::default()
        };
        if let Some(order) = self.octant_order(cell) {
            out.extend_from_slice(order);
            return Some(stats);
        }
        let (seq, groups) = self.components(cell);
        for v in seq {
            match group_of(v, &groups) {
                None => out.push(v),
                Some(g) => stats.add(refine(&self.boxes, g, cell, eye, out)?),
            }
        }
        Some(stats)
    }

    /// The precomputed order of an octant cell that contains `cell`, if any: then it is
    /// exact in `cell`.
    fn octant_order(&self, cell: &[Span; 3]) -> Option<&Vec<u32>> {
        self.octant_of(cell).and_then(|o| self.octants[o].as_ref())
    }

    /// The order of an object leaf's objects for the cell: the sequence, in which groups of
    /// objects that the separating-axis relation leaves cyclic appear as placeholders (see
    /// [`group_of`]), and the groups.
    fn object_order(&self, cell: &[Span; 3]) -> (Vec<u32>, Vec<Vec<u32>>) {
        match self.octant_order(cell) {
            Some(seq) => (seq.clone(), Vec::new()),
            None => self.components(cell),
        }
    }

    fn mask_offset(&self, k: usize, hi: bool, v: i32) -> usize {
        ((k * 2 + usize::from(hi)) * MASK_VALUES + (v + 1) as usize) * self.words
    }

    /// A row of the separating-axis relation over the open cell `cell` (module docs), as a
    /// bit set over the leaf's quads: with `pred`, the quads `a` that quad `i` may hide
    /// (they must be drawn before it); otherwise the quads `b` that may hide quad `i` (drawn
    /// after it). Tie-breaks included, coplanar quads otherwise excluded.
    ///
    /// Per axis k a pair passes when the quads are not separated along k (open intervals
    /// overlap), or when they are and some eye of the cell lies beyond the near face of the
    /// hiding quad `b`: for `a` wholly below `b` (`a.hi <= b.lo`), above `b.lo`; for `a`
    /// wholly above, below `b.hi`. The cell is a box, so eyes chosen per axis make one eye.
    /// (For a leaf of the tree every coordinate is a trigger plane, so the whole open cell
    /// lies on one side of each, and "some eye" is "every eye".)
    fn relation_row(&self, i: usize, cell: &[Span; 3], pred: bool, row: &mut [u64]) {
        let words = self.words;
        let (g0, g1) = self.group[i];
        let q = &self.boxes[i];
        let all = |o: usize| &self.masks[o..o + words];
        let row = &mut row[..words];
        if pred {
            // With x = {lo < q.hi} and y = {hi > q.lo} (so !x: wholly above q, !y: wholly
            // below), an axis passes (x & y) | (!y & some eye of the cell above q.lo) | (!x &
            // some eye below q.hi): x | !y, !x | y, or everything (never neither, as
            // q.lo <= q.hi and the cell is not empty). As (x ^ f) | (y ^ g), with x = y = all
            // ones for everything.
            let ones = all(self.mask_offset(0, false, VALUES as i32 - 1));
            let mut axes: [(&[u64], &[u64], u64, u64); 3] = [(ones, ones, 0, 0); 3];
            for (k, (ax, c)) in axes.iter_mut().zip(cell).enumerate() {
                let above = c.hi.is_none_or(|h| q.lo[k] < h);
                let below = c.lo.is_none_or(|l| q.hi[k] > l);
                let [xo, yo] = self.offsets[i][k];
                match (above, below) {
                    (true, false) => *ax = (all(xo), all(yo), 0, u64::MAX),
                    (false, true) => *ax = (all(xo), all(yo), u64::MAX, 0),
                    _ => {}
                }
            }
            let [(x0, y0, f0, g0), (x1, y1, f1, g1), (x2, y2, f2, g2)] = axes;
            let (x0, y0, x1, y1, x2, y2) = (
                &x0[..words],
                &y0[..words],
                &x1[..words],
                &y1[..words],
                &x2[..words],
                &y2[..words],
            );
            for w in 0..words {
                row[w] = ((x0[w] ^ f0) | (y0[w] ^ g0))
                    & ((x1[w] ^ f1) | (y1[w] ^ g1))
                    & ((x2[w] ^ f2) | (y2[w] ^ g2));
            }
        } else {
            // b wholly above q (!x) needs some eye of the cell above b.lo (b.lo < c.hi);
            // b wholly below (!y) needs some eye below b.hi (b.hi > c.lo).
            let ones = all(self.mask_offset(0, false, VALUES as i32 - 1));
            let mut axes: [[&[u64]; 4]; 3] = [[ones; 4]; 3];
            for (k, (ax, c)) in axes.iter_mut().zip(cell).enumerate() {
                let [xo, yo] = self.offsets[i][k];
                let lo = c.hi.map_or(ones, |h| all(self.mask_offset(k, false, h)));
                let hi = c.lo.map_or(ones, |l| all(self.mask_offset(k, true, l)));
                *ax = [all(xo), all(yo), lo, hi];
            }
            let [[x0, y0, l0, h0], [x1, y1, l1, h1], [x2, y2, l2, h2]] = axes;
            for w in 0..words {
                let f = |x: u64, y: u64, l: u64, h: u64| (x & y) | (!x & l) | (!y & h);
                row[w] = f(x0[w], y0[w], l0[w], h0[w])
                    & f(x1[w], y1[w], l1[w], h1[w])
                    & f(x2[w], y2[w], l2[w], h2[w]);
            }
        }
        let m = self.boxes.len();
        if !m.is_multiple_of(64) {
            row[words - 1] &= (1u64 << (m % 64)) - 1;
        }
        clear_bits(row, g0 as usize, g1 as usize);
        // Tie partners are coplanar, so inside the group's words.
        for &j in &self.tie_list[self.tie_start[i] as usize..self.tie_start[i + 1] as usize] {
            let (a, b) = if pred { (j, i as u32) } else { (i as u32, j) };
            if tie_in(&self.boxes[a as usize], &self.boxes[b as usize], cell) {
                row[j as usize / 64] |= 1u64 << (j % 64);
            }
        }
    }

    /// Tarjan's strongly connected components of the separating-axis relation over the
    /// cell, searched over predecessor rows computed when a quad is first reached, so that
    /// components come out in drawing order (every component after the ones it may hide):
    /// the sequence of single quads and placeholders of groups (see [`group_of`]), and the
    /// groups.
    ///
    /// Roots go farthest first (by the sum over axes of the integer distance from the quad
    /// to the cell), so that most quads find their predecessors done: they are their own
    /// component and leave at once without keeping their row; only quads with pending
    /// predecessors keep theirs, on the stack. Edges back to Tarjan's stack are looked for
    /// when a quad is reached only: an edge to a quad reached later cannot lower its low
    /// link, which starts at its own index.
    fn components(&self, cell: &[Span; 3]) -> (Vec<u32>, Vec<Vec<u32>>) {
        let m = self.boxes.len();
        let words = self.words;
        let mut out = Vec::with_capacity(m);
        // Counting sort of the roots by distance to the cell, farthest first.
        let dist = |q: &QBox| -> usize {
            (0..3)
                .map(|k| {
                    let c = cell[k];
                    match (c.lo, c.hi) {
                        (Some(l), _) if l >= q.hi[k] => (l - q.hi[k]) as usize,
                        (_, Some(h)) if h <= q.lo[k] => (q.lo[k] - h) as usize,
                        _ => 0,
                    }
                })
                .sum()
        };
        const BUCKETS: usize = 3 * (MAX_COORD + 1) + 1;
        let mut count = [0u32; BUCKETS + 1];
        let keys: Vec<u8> = self
            .boxes
            .iter()
            .map(|q| (BUCKETS - 1 - dist(q).min(BUCKETS - 1)) as u8)
            .collect();
        for &b in &keys {
            count[usize::from(b) + 1] += 1;
        }
        for i in 1..=BUCKETS {
            count[i] += count[i - 1];
        }
        let mut roots = vec![0u32; m];
        for (i, &b) in keys.iter().enumerate() {
            roots[count[usize::from(b)] as usize] = i as u32;
            count[usize::from(b)] += 1;
        }

        let mut t = Tarjan {
            index: vec![u32::MAX; m],
            low: vec![0; m],
            next: 0,
            tstack: Vec::new(),
            on_tstack: vec![0; words],
            groups: Vec::new(),
        };
        let mut visited = vec![0u64; words];
        // Search stack: (quad, scan cursor, offset of its row in `rows`).
        let mut stack: Vec<(u32, usize, usize)> = Vec::new();
        let mut rows: Vec<u64> = Vec::new();
        let mut buf = vec![0u64; words];
        for &r in &roots {
            if t.index[r as usize] != u32::MAX {
                continue;
            }
            let mut reach = Some(r);
            loop {
                if let Some(v) = reach.take() {
                    // First reached: its row, its edges back to Tarjan's stack, whether it
                    // has predecessors not reached yet.
                    let vi = v as usize;
                    t.index[vi] = t.next;
                    t.low[vi] = t.next;
                    t.next += 1;
                    visited[vi / 64] |= 1u64 << (vi % 64);
                    self.relation_row(vi, cell, true, &mut buf);
                    let (mut back, mut pending) = (0u64, 0u64);
                    for ((r, s), vis) in buf.iter().zip(&t.on_tstack).zip(&visited) {
                        back |= r & s;
                        pending |= r & !vis;
                    }
                    if back != 0 {
                        for (w, (r, s)) in buf.iter().zip(&t.on_tstack).enumerate() {
                            let mut bits = r & s;
                            while bits != 0 {
                                let u = w * 64 + bits.trailing_zeros() as usize;
                                t.low[vi] = t.low[vi].min(t.index[u]);
                                bits &= bits - 1;
                            }
                        }
                    }
                    t.tstack.push(v);
                    t.on_tstack[vi / 64] |= 1u64 << (vi % 64);
                    if pending != 0 {
                        stack.push((v, 0, rows.len()));
                        rows.extend_from_slice(&buf);
                        continue;
                    }
                    // No predecessor left to reach: finished at once.
                    t.finish(v, &mut out);
                    if let Some(&(p, ..)) = stack.last() {
                        t.low[p as usize] = t.low[p as usize].min(t.low[vi]);
                    }
                }
                let Some(top) = stack.last_mut() else { break };
                let (v, off) = (top.0, top.2);
                if let Some(w) = next_unvisited(&rows[off..off + words], &visited, &mut top.1) {
                    reach = Some(w);
                    continue;
                }
                stack.pop();
                rows.truncate(off);
                t.finish(v, &mut out);
                if let Some(&(p, ..)) = stack.last() {
                    t.low[p as usize] = t.low[p as usize].min(t.low[v as usize]);
                }
            }
        }
        (out, t.groups)
    }
}

/// The group a placeholder of [`Leaf::components`]'s sequence stands for (`u32::MAX -
/// group number`), or `None` for a plain index.
fn group_of(v: u32, groups: &[Vec<u32>]) -> Option<&[u32]> {
    let g = (u32::MAX - v) as usize;
    groups.get(g).map(Vec::as_slice)
}

/// Tarjan's bookkeeping for [`Leaf::components`].
struct Tarjan {
    index: Vec<u32>,
    low: Vec<u32>,
    next: u32,
    /// Tarjan's stack, as a list and as a bit set.
    tstack: Vec<u32>,
    on_tstack: Vec<u64>,
    /// Components of more than one quad, to refine.
    groups: Vec<Vec<u32>>,
}

impl Tarjan {
    /// Tarjan's step when `v` is finished: if it roots a component, pops the component and
    /// writes it to `out` (a group as the placeholder `u32::MAX - group number`).
    fn finish(&mut self, v: u32, out: &mut Vec<u32>) {
        if self.low[v as usize] != self.index[v as usize] {
            return;
        }
        let Some(at) = self.tstack.iter().rposition(|&w| w == v) else {
            return;
        };
        for &w in &self.tstack[at..] {
            self.on_tstack[w as usize / 64] &= !(1u64 << (w % 64));
        }
        if at + 1 == self.tstack.len() {
            out.push(v);
        } else {
            let mut g = self.tstack[at..].to_vec();
            g.sort_unstable();
            out.push(u32::MAX - self.groups.len() as u32);
            self.groups.push(g);
        }
        self.tstack.truncate(at);
    }
}

/// Clears bits `from..to` of a bit set.
fn clear_bits(row: &mut [u64], from: usize, to: usize) {
    if from >= to {
        return;
    }
    let (w0, w1) = (from / 64, (to - 1) / 64);
    let head = u64::MAX << (from % 64);
    let tail = u64::MAX >> (63 - (to - 1) % 64);
    if w0 == w1 {
        row[w0] &= !(head & tail);
    } else {
        row[w0] &= !head;
        row[w0 + 1..w1].fill(0);
        row[w1] &= !tail;
    }
}

/// The first set bit of `row & !visited` from word `*cur` on (which it advances).
#[inline]
fn next_unvisited(row: &[u64], visited: &[u64], cur: &mut usize) -> Option<u32> {
    while *cur < row.len() {
        let w = row[*cur] & !visited[*cur];
        if w != 0 {
            return Some((*cur * 64) as u32 + w.trailing_zeros());
        }
        *cur += 1;
    }
    None
}

/// Orders a group that the separating-axis relation leaves cyclic: by the exact relation
/// over the cell, then, for groups still cyclic, by the relation at the eye (counted as
/// eye-dependent), then by centre distance (counted as a cycle). `None` when the eye is
/// needed but not given.
fn refine(
    boxes: &[QBox],
    group: &[u32],
    cell: &[Span; 3],
    eye: Option<[f64; 3]>,
    out: &mut Vec<u32>,
) -> Option<SortStats> {
    let mut stats = SortStats::default();
    let adjacency = |members: &[u32], rel: &dyn Fn(&QBox, &QBox) -> bool| -> Vec<Vec<u32>> {
        (0..members.len())
            .map(|i| {
                let a = &boxes[members[i] as usize];
                (0..members.len() as u32)
                    .filter(|&j| j as usize != i && rel(a, &boxes[members[j as usize] as usize]))
                    .collect()
            })
            .collect()
    };
    let by_cell = adjacency(group, &|a, b| may_hide_in_cell(a, b, cell));
    for comp in tarjan(&by_cell).iter().rev() {
        if let [only] = comp[..] {
            out.push(group[only as usize]);
            continue;
        }
        let eye = eye?;
        let members: Vec<u32> = comp.iter().map(|&c| group[c as usize]).collect();
        stats.eye_dependent += 1;
        let comps = if eye.iter().all(|e| e.is_finite()) {
            let at_eye = adjacency(&members, &|a, b| hides_at(eye, a, b) || tie_at(eye, a, b));
            tarjan(&at_eye)
        } else {
            // No eye to refine with: the whole group falls back.
            vec![(0..members.len() as u32).collect()]
        };
        for c in comps.iter().rev() {
            if let [only] = c[..] {
                out.push(members[only as usize]);
                continue;
            }
            stats.cycles += 1;
            stats.quads_in_cycles += c.len() as u32;
            let mut c: Vec<u32> = c.iter().map(|&i| members[i as usize]).collect();
            // Farthest centre first; a NaN distance sorts first, deterministically.
            c.sort_by_cached_key(|&i| {
                (
                    Reverse(boxes[i as usize].centre_distance2(eye).to_bits()),
                    i,
                )
            });
            out.extend_from_slice(&c);
        }
    }
    Some(stats)
}

/// A bounding box: minimum and maximum corners.
type Bounds = ([i32; 3], [i32; 3]);

/// Splits the quads `ids` into objects: the classes of quads whose closed boxes chain
/// together by touching or overlapping, merged while the bounding boxes of two classes are
/// not separated along any axis (so that any two objects' boxes are). Each with its
/// bounding box, in order of smallest member.
fn objects(all: &[QBox], ids: &[u32]) -> Vec<(Vec<u32>, Bounds)> {
    let n = ids.len();
    let (mut lo, mut hi) = ([i32::MAX; 3], [i32::MIN; 3]);
    for &i in ids {
        let b = &all[i as usize];
        for k in 0..3 {
            lo[k] = lo[k].min(b.lo[k]);
            hi[k] = hi[k].max(b.hi[k]);
        }
    }
    let dim = [0, 1, 2].map(|k| (hi[k] - lo[k] + 1) as usize);
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn find(p: &mut [u32], mut x: u32) -> u32 {
        while p[x as usize] != x {
            p[x as usize] = p[p[x as usize] as usize];
            x = p[x as usize];
        }
        x
    }
    fn union(p: &mut [u32], a: u32, b: u32) {
        let (a, b) = (find(p, a), find(p, b));
        p[a.max(b) as usize] = a.min(b);
    }
    // Closed integer boxes that meet share a lattice point: union through a lattice grid.
    let mut grid = vec![u32::MAX; dim[0] * dim[1] * dim[2]];
    for (j, &i) in ids.iter().enumerate() {
        let b = &all[i as usize];
        for x in b.lo[0]..=b.hi[0] {
            for y in b.lo[1]..=b.hi[1] {
                for z in b.lo[2]..=b.hi[2] {
                    let at = (((x - lo[0]) as usize * dim[1]) + (y - lo[1]) as usize) * dim[2]
                        + (z - lo[2]) as usize;
                    match grid[at] {
                        u32::MAX => grid[at] = j as u32,
                        o => union(&mut parent, j as u32, o),
                    }
                }
            }
        }
    }
    let bounds = |members: &[u32]| {
        let (mut lo, mut hi) = ([i32::MAX; 3], [i32::MIN; 3]);
        for &j in members {
            let b = &all[ids[j as usize] as usize];
            for k in 0..3 {
                lo[k] = lo[k].min(b.lo[k]);
                hi[k] = hi[k].max(b.hi[k]);
            }
        }
        (lo, hi)
    };
    let not_separated = |a: &Bounds, b: &Bounds| (0..3).all(|k| a.0[k] < b.1[k] && b.0[k] < a.1[k]);
    loop {
        let mut classes: std::collections::BTreeMap<u32, Vec<u32>> = Default::default();
        for j in 0..n as u32 {
            classes.entry(find(&mut parent, j)).or_default().push(j);
        }
        let classes: Vec<(u32, Bounds)> = classes
            .into_iter()
            .map(|(root, members)| (root, bounds(&members)))
            .collect();
        let mut merged = false;
        for a in 0..classes.len() {
            for b in a + 1..classes.len() {
                if not_separated(&classes[a].1, &classes[b].1) {
                    union(&mut parent, classes[a].0, classes[b].0);
                    merged = true;
                }
            }
        }
        if !merged {
            break;
        }
    }
    let mut classes: std::collections::BTreeMap<u32, Vec<u32>> = Default::default();
    for j in 0..n as u32 {
        classes
            .entry(find(&mut parent, j))
            .or_default()
            .push(ids[j as usize]);
    }
    classes
        .into_values()
        .map(|members| {
            let (mut lo, mut hi) = ([i32::MAX; 3], [i32::MIN; 3]);
            for &i in &members {
                let b = &all[i as usize];
                for k in 0..3 {
                    lo[k] = lo[k].min(b.lo[k]);
                    hi[k] = hi[k].max(b.hi[k]);
                }
            }
            (members, (lo, hi))
        })
        .collect()
}

/// Whether some positive quad of `pos` and negative quad of `neg` (all on one plane) share
/// footprint area.
fn opposite_overlap(all: &[QBox], pos: &[u32], neg: &[u32], axis: usize) -> bool {
    let [u, v] = UV_AXES[axis];
    let mut grid = [0u64; MAX_COORD + 1];
    for &i in pos {
        let b = &all[i as usize];
        let bits = span_bits(b.lo[v], b.hi[v]);
        for r in b.lo[u]..b.hi[u] {
            grid[r as usize] |= bits;
        }
    }
    neg.iter().any(|&i| {
        let b = &all[i as usize];
        let bits = span_bits(b.lo[v], b.hi[v]);
        (b.lo[u]..b.hi[u]).any(|r| grid[r as usize] & bits != 0)
    })
}

fn span_bits(lo: i32, hi: i32) -> u64 {
    let w = (hi - lo) as u32;
    let ones = if w >= 64 { u64::MAX } else { (1u64 << w) - 1 };
    ones << lo
}

/// The free plane that best splits `ids`, as (axis, coordinate): no quad's relative
/// interior crosses it, and at least two of below / on / above are non-empty. Prefers
/// planes that are already triggers, then balanced splits, then planes holding quads.
fn best_split(
    all: &[QBox],
    ids: &[u32],
    is_trigger: &[[bool; MAX_COORD + 1]; 3],
) -> Option<(usize, i32)> {
    let m = ids.len() as i32;
    let mut best: Option<((bool, i32, bool), usize, i32)> = None;
    for k in 0..3 {
        let mut hi_at = [0i32; MAX_COORD + 1];
        let mut lo_at = [0i32; MAX_COORD + 1];
        let mut on_at = [0i32; MAX_COORD + 1];
        let (mut min_c, mut max_c) = (MAX_COORD as i32, 0);
        for &i in ids {
            let b = &all[i as usize];
            hi_at[b.hi[k] as usize] += 1;
            lo_at[b.lo[k] as usize] += 1;
            if b.axis == k {
                on_at[b.lo[k] as usize] += 1;
            }
            min_c = min_c.min(b.lo[k]);
            max_c = max_c.max(b.hi[k]);
        }
        // le_hi: quads with hi <= c; ge_lo: quads with lo >= c.
        let mut le_hi = 0;
        let mut ge_lo = m;
        for c in 0..=max_c {
            le_hi += hi_at[c as usize];
            if c > 0 {
                ge_lo -= lo_at[c as usize - 1];
            }
            if c < min_c {
                continue;
            }
            let on = on_at[c as usize];
            let below = le_hi - on;
            let above = ge_lo - on;
            if below + above + on != m {
                continue; // some quad straddles c
            }
            if [below, on, above].iter().filter(|&&n| n > 0).count() < 2 {
                continue;
            }
            let score = (is_trigger[k][c as usize], -below.max(above), on > 0);
            if best.is_none_or(|(s, _, _)| score > s) {
                best = Some((score, k, c));
            }
        }
    }
    best.map(|(_, k, c)| (k, c))
}

/// Strongly connected components of a small graph, sinks first (Tarjan, iterative).
fn tarjan(succ: &[Vec<u32>]) -> Vec<Vec<u32>> {
    let m = succ.len();
    const UNSEEN: u32 = u32::MAX;
    let mut index = vec![UNSEEN; m];
    let mut low = vec![0u32; m];
    let mut on_stack = vec![false; m];
    let mut stack: Vec<u32> = Vec::new();
    let mut comps = Vec::new();
    let mut next = 0u32;
    // Call stack: (node, next successor position).
    let mut calls: Vec<(u32, usize)> = Vec::new();
    for root in 0..m as u32 {
        if index[root as usize] != UNSEEN {
            continue;
        }
        calls.push((root, 0));
        while let Some(&mut (v, ref mut pos)) = calls.last_mut() {
            let vu = v as usize;
            if *pos == 0 && index[vu] == UNSEEN {
                index[vu] = next;
                low[vu] = next;
                next += 1;
                stack.push(v);
                on_stack[vu] = true;
            }
            if let Some(&w) = succ[vu].get(*pos) {
                *pos += 1;
                let wu = w as usize;
                if index[wu] == UNSEEN {
                    calls.push((w, 0));
                } else if on_stack[wu] {
                    low[vu] = low[vu].min(index[wu]);
                }
                continue;
            }
            calls.pop();
            if let Some(&(p, _)) = calls.last() {
                let pu = p as usize;
                low[pu] = low[pu].min(low[vu]);
            }
            if low[vu] == index[vu] {
                let mut comp = Vec::new();
                while let Some(w) = stack.pop() {
                    on_stack[w as usize] = false;
                    comp.push(w);
                    if w == v {
                        break;
                    }
                }
                comp.sort_unstable();
                comps.push(comp);
            }
        }
    }
    comps
}

/// The draw-order key of a chunk for an eye in world block coordinates: sort by it,
/// largest (farthest) first, ties in any order. It is the squared distance, in chunks,
/// between the chunk and the chunk that holds the eye, so it is computed in integers and
/// changes only when the eye crosses a chunk border; exact for a grid of equal cubes (see
/// "Order across chunks" in the module docs). Never panics: a NaN coordinate counts as 0,
/// far and infinite eyes are clamped beyond every `i32` chunk.
pub fn chunk_order_key(pos: ChunkPos, eye: [f64; 3]) -> u128 {
    let s = CHUNK_SIZE as f64;
    let p = [pos.x, pos.y, pos.z];
    (0..3)
        .map(|k| {
            let e = ((eye[k] / s).floor() as i64)
                .clamp(i64::from(i32::MIN) - 1, i64::from(i32::MAX) + 1);
            let d = u128::from((i64::from(p[k]) - e).unsigned_abs());
            d * d
        })
        .sum()
}

/// Sorts chunks back to front by [`chunk_order_key`] (farthest first), ties by position.
pub fn chunks_back_to_front(chunks: &mut [ChunkPos], eye: [f64; 3]) {
    chunks.sort_by_cached_key(|&p| (Reverse(chunk_order_key(p, eye)), p));
}

/// Internals exposed for the integration tests; not part of the API.
#[doc(hidden)]
pub mod testing {
    use super::*;

    /// The relation at a point: whether `b` hides part of `a` from `eye`.
    pub fn hides_at(eye: [f64; 3], a: PackedQuad, b: PackedQuad) -> bool {
        super::hides_at(eye, &QBox::of(a), &QBox::of(b))
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Mesher;
    use voxel_core::blocks::{AIR, GLASS, RED_GLASS, WATER};
    use voxel_core::{BlockRegistry, Chunk, Face};

    /// xorshift64*.
    struct Rng(u64);

    impl Rng {
        fn next(&mut self) -> u64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
        }
        fn below(&mut self, n: u64) -> u64 {
            self.next() % n
        }
        /// A dyadic coordinate in `lo..hi`.
        fn coord(&mut self, lo: f64, hi: f64) -> f64 {
            lo + ((hi - lo) * 1024.0 * (self.below(1 << 20) as f64 / (1 << 20) as f64)).floor()
                / 1024.0
        }
    }

    fn random_quads(rng: &mut Rng) -> Vec<PackedQuad> {
        let mut c = Chunk::uniform(AIR);
        for _ in 0..1 + rng.below(8) {
            let id = [GLASS, RED_GLASS, WATER, AIR][rng.below(4) as usize];
            let lo = [0; 3].map(|_| 4 + rng.below(12) as usize);
            let hi = lo.map(|v| v + rng.below(5) as usize);
            c.fill_box(lo, hi, id).unwrap_or_default();
        }
        let reg = BlockRegistry::default();
        Mesher::new(&reg)
            .mesh(&c, [None; 6])
            .map(|m| m.translucent)
            .unwrap_or_default()
    }

    /// A random open cell with integer bounds (possibly unbounded), and an eye inside it.
    fn random_cell(rng: &mut Rng) -> ([Span; 3], [f64; 3]) {
        let mut cell = [Span { lo: None, hi: None }; 3];
        let mut eye = [0.0; 3];
        for k in 0..3 {
            let a = 2 + rng.below(20) as i32;
            let b = a + 1 + rng.below(4) as i32;
            cell[k] = match rng.below(4) {
                0 => Span {
                    lo: None,
                    hi: Some(b),
                },
                1 => Span {
                    lo: Some(a),
                    hi: None,
                },
                _ => Span {
                    lo: Some(a),
                    hi: Some(b),
                },
            };
            let lo = cell[k].lo.map_or(f64::from(b) - 40.0, f64::from);
            let hi = cell[k].hi.map_or(f64::from(a) + 40.0, f64::from);
            eye[k] = rng.coord(lo, hi).max(lo + 1.0 / 1024.0);
        }
        (cell, eye)
    }

    /// The relation at a point, with the tie-breaks of planes that the cell does not
    /// straddle (the structure makes every tie plane a trigger plane, so its cells never
    /// straddle one; these tests draw cells at random).
    fn before_at(eye: [f64; 3], a: &QBox, b: &QBox, cell: &[Span; 3]) -> bool {
        let c = cell[a.axis];
        let straddled = !c.above(a.plane()) && !c.below(a.plane());
        hides_at(eye, a, b) || (tie_at(eye, a, b) && !straddled)
    }

    #[test]
    fn the_region_relation_contains_the_relation_at_every_eye_of_the_cell() {
        let mut rng = Rng(7);
        let mut related = 0;
        for _ in 0..200 {
            let quads: Vec<QBox> = random_quads(&mut rng).into_iter().map(QBox::of).collect();
            for _ in 0..4 {
                let (cell, _) = random_cell(&mut rng);
                for _ in 0..4 {
                    let (_, eye) = {
                        // Another eye of the same cell.
                        let mut e = [0.0; 3];
                        for k in 0..3 {
                            let lo = cell[k].lo.map_or(-60.0, f64::from);
                            let hi = cell[k].hi.map_or(90.0, f64::from);
                            e[k] = (rng.coord(lo, hi)).max(lo + 1.0 / 1024.0);
                        }
                        ((), e)
                    };
                    for a in &quads {
                        for b in &quads {
                            if before_at(eye, a, b, &cell) {
                                related += 1;
                                assert!(
                                    may_hide_in_cell(a, b, &cell),
                                    "{a:?} {b:?} {cell:?} {eye:?}"
                                );
                            }
                        }
                    }
                }
            }
        }
        assert!(related > 1000, "{related}");
    }

    #[test]
    fn leaves_order_exactly_for_any_cell() {
        // Cells whose bounds need not be the leaf's coordinates (as for groups of objects):
        // the order must hold at every eye of the cell when exact for the region, and at the
        // eye itself otherwise.
        let mut rng = Rng(8);
        let (mut sorts, mut region_exact) = (0, 0);
        for _ in 0..300 {
            let mut boxes: Vec<QBox> = random_quads(&mut rng).into_iter().map(QBox::of).collect();
            if boxes.is_empty() {
                continue;
            }
            boxes.sort_by_key(|b| (b.axis, b.plane(), !b.positive, b.lo, b.hi));
            let leaf = Leaf::new(0, boxes.clone(), false, true);
            for _ in 0..6 {
                let (cell, eye) = random_cell(&mut rng);
                let mut order = Vec::new();
                let Some(stats) = leaf.order(&cell, Some(eye), &mut order) else {
                    panic!("the eye was given");
                };
                let mut sorted = order.clone();
                sorted.sort_unstable();
                assert_eq!(sorted, (0..boxes.len() as u32).collect::<Vec<_>>());
                sorts += 1;
                let eyes: Vec<[f64; 3]> = if stats.is_exact_in_region() {
                    region_exact += 1;
                    (0..4)
                        .map(|_| {
                            let mut e = eye;
                            for k in 0..3 {
                                let lo = cell[k].lo.map_or(eye[k] - 50.0, f64::from);
                                let hi = cell[k].hi.map_or(eye[k] + 50.0, f64::from);
                                e[k] = rng.coord(lo, hi).max(lo + 1.0 / 1024.0);
                            }
                            e
                        })
                        .chain([eye])
                        .collect()
                } else if stats.is_exact() {
                    vec![eye]
                } else {
                    continue;
                };
                for e in eyes {
                    for (i, &a) in order.iter().enumerate() {
                        for &b in &order[..i] {
                            // b is drawn before a: wrong if b must come after a.
                            assert!(
                                !before_at(e, &boxes[a as usize], &boxes[b as usize], &cell),
                                "cell {cell:?} eye {e:?}: {:?} before {:?}",
                                boxes[b as usize],
                                boxes[a as usize]
                            );
                        }
                    }
                }
            }
        }
        assert!(
            sorts > 1000 && region_exact > sorts / 4,
            "{sorts} {region_exact}"
        );
    }

    #[test]
    fn interval_of_s() {
        let mut s = SInterval::new();
        s.less(1, 3); // s < 3
        s.greater(2, 2); // s > 1
        assert!(s.feasible());
        s.less(3, 3); // s < 1
        assert!(!s.feasible());
        let mut s = SInterval::new();
        s.less(0, 0); // 0 < 0: never
        assert!(!s.feasible());
        let mut s = SInterval::new();
        s.less(-1, 5); // s > -5: no bound above 0
        assert!(s.feasible());
    }

    #[test]
    fn region_keys_count_planes_strictly_below() {
        let glass = GLASS;
        let quads = [
            PackedQuad::new([1, 0, 0], 4, 4, Face::NegX, glass),
            PackedQuad::new([2, 0, 0], 4, 4, Face::NegX, glass),
            PackedQuad::new([3, 0, 0], 4, 4, Face::NegX, glass),
        ];
        let order = QuadOrder::new(&quads);
        assert_eq!(order.trigger_planes()[0], &[2]);
        let key = |x: f64| order.region_key([x, 0.5, 0.5]).0[0];
        assert_eq!(
            [
                key(-1.0e9),
                key(1.5),
                key(2.0),
                key(2.0 + 1e-12),
                key(1e300)
            ],
            [0, 0, 0, 1, 1]
        );
        assert_eq!(
            [key(f64::NAN), key(f64::INFINITY), key(f64::NEG_INFINITY)],
            [0, 1, 0]
        );
    }

    #[test]
    fn bit_ranges_clear() {
        for (from, to) in [(0, 0), (0, 1), (3, 64), (63, 65), (10, 200), (64, 128)] {
            let mut row = [u64::MAX; 4];
            clear_bits(&mut row, from, to);
            for i in 0..256 {
                let set = row[i / 64] >> (i % 64) & 1 == 1;
                assert_eq!(set, !(from..to).contains(&i), "{from}..{to} at {i}");
            }
        }
    }

    #[test]
    fn objects_are_classes_with_separated_boxes() {
        let mut rng = Rng(9);
        for _ in 0..100 {
            let all: Vec<QBox> = random_quads(&mut rng).into_iter().map(QBox::of).collect();
            let ids: Vec<u32> = (0..all.len() as u32).collect();
            if ids.is_empty() {
                continue;
            }
            let objs = objects(&all, &ids);
            let mut seen: Vec<u32> = objs.iter().flat_map(|o| o.0.clone()).collect();
            seen.sort_unstable();
            assert_eq!(seen, ids);
            for (i, a) in objs.iter().enumerate() {
                for b in &objs[i + 1..] {
                    let separated = (0..3).any(|k| a.1.1[k] <= b.1.0[k] || b.1.1[k] <= a.1.0[k]);
                    assert!(separated, "{a:?} {b:?}");
                    // Quads of different objects never touch.
                    for &p in &a.0 {
                        for &q in &b.0 {
                            let (p, q) = (&all[p as usize], &all[q as usize]);
                            assert!((0..3).any(|k| p.hi[k] < q.lo[k] || q.hi[k] < p.lo[k]));
                        }
                    }
                }
            }
        }
    }
}
