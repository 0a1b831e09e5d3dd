//! Stuck leaves: quads (or objects' bounding boxes) that no free plane separates, ordered
//! by the separating-axis relation over the eye's cell, computed as bit sets.

use super::objects::Bounds;
use super::relation::{QBox, Span, tie_in};
use super::scc::{Tarjan, group_of, refine};
use super::{MASK_VALUES, MAX_COORD, SortStats, VALUES};

/// A stuck leaf: quads that no free plane separates, sorted by (axis, plane, facing), with
/// the bit masks that give a row of the separating-axis relation in O(m / 64) words.
#[derive(Clone, Debug, Default)]
pub(super) struct Leaf {
    /// Index of the leaf's first quad among the stored ones (quad leaves).
    pub(super) start: u32,
    /// Whether the boxes are the bounding boxes of objects (interior-disjoint components
    /// of an object node) rather than quads.
    pub(super) objects: bool,
    pub(super) boxes: Vec<QBox>,
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
    pub(super) fn new(start: u32, boxes: Vec<QBox>, objects: bool, octants: bool) -> Self {
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
    pub(super) fn order(
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
    pub(super) fn object_order(&self, cell: &[Span; 3]) -> (Vec<u32>, Vec<Vec<u32>>) {
        match self.octant_order(cell) {
            Some(seq) => (seq.clone(), Vec::new()),
            None => self.components(cell),
        }
    }

    fn mask_offset(&self, k: usize, hi: bool, v: i32) -> usize {
        ((k * 2 + usize::from(hi)) * MASK_VALUES + (v + 1) as usize) * self.words
    }

    /// A row of the separating-axis relation over the open cell `cell`
    /// (`docs/quad-order.md`), as a bit set over the leaf's quads: with `pred`, the quads
    /// `a` that quad `i` may hide (they must be drawn before it); otherwise the quads `b`
    /// that may hide quad `i` (drawn after it). Tie-breaks included, coplanar quads
    /// otherwise excluded.
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

/// Clears bits `from..to` of a bit set.
pub(super) fn clear_bits(row: &mut [u64], from: usize, to: usize) {
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
