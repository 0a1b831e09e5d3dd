//! Strongly connected components: the bookkeeping of the search over a leaf's bit-set
//! relation, Tarjan's algorithm on small graphs, and the order of a group the
//! separating-axis relation leaves cyclic.

use std::cmp::Reverse;

use super::SortStats;
use super::relation::{QBox, Span, hides_at, may_hide_in_cell, tie_at};

/// The group a placeholder of the sequence of a leaf's components stands for (`u32::MAX -
/// group number`), or `None` for a plain index.
pub(super) fn group_of(v: u32, groups: &[Vec<u32>]) -> Option<&[u32]> {
    let g = (u32::MAX - v) as usize;
    groups.get(g).map(Vec::as_slice)
}

/// Tarjan's bookkeeping for the search over a leaf's relation (`Leaf::components`).
pub(super) struct Tarjan {
    pub(super) index: Vec<u32>,
    pub(super) low: Vec<u32>,
    pub(super) next: u32,
    /// Tarjan's stack, as a list and as a bit set.
    pub(super) tstack: Vec<u32>,
    pub(super) on_tstack: Vec<u64>,
    /// Components of more than one quad, to refine.
    pub(super) groups: Vec<Vec<u32>>,
}

impl Tarjan {
    /// Tarjan's step when `v` is finished: if it roots a component, pops the component and
    /// writes it to `out` (a group as the placeholder `u32::MAX - group number`).
    pub(super) fn finish(&mut self, v: u32, out: &mut Vec<u32>) {
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

/// Orders a group that the separating-axis relation leaves cyclic: by the exact relation
/// over the cell, then, for groups still cyclic, by the relation at the eye (counted as
/// eye-dependent), then by centre distance (counted as a cycle). `None` when the eye is
/// needed but not given.
pub(super) fn refine(
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
