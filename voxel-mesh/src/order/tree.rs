//! The plane tree of a chunk's quads: its build (free planes, objects, stuck leaves and the
//! trigger planes) and the sort that walks it.

use super::leaf::Leaf;
use super::objects::objects;
use super::relation::{QBox, Span};
use super::scc::group_of;
use super::{MAX_COORD, NONE, RegionKey, SortStats, VALUES};
use crate::{PackedQuad, UV_AXES};

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
    /// [`SortStats::is_exact`] holds; see Theorem 2 of `docs/quad-order.md`. Never panics,
    /// whatever the eye.
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
    pub(super) fn cell(&self, key: RegionKey) -> [Span; 3] {
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
