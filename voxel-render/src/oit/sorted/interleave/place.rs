//! Where each object goes: the place in the sequence of chunks (and quads) that the fewest
//! constraints rule out ([`Interleaver::place`]), and the cut of an object through planes
//! no one place suits into parts placed on their own ([`Interleaver::split`]).

use glam::DVec3;

use super::cells::cells_and_keys;
use super::sound::{SOUND, plane_runs, plane_weight, safe, seen_planes, shadow_misses, touch};
use super::{Ball, Clip, ClipPlane, Frame, Interleaver, MAX_SPLIT_DEPTH, MAX_SPLIT_PARTS, Part};

/// A plane's weight in [`Interleaver::place`] where the eye does not see it.
const UNSEEN: i64 = i64::MIN;

impl Interleaver {
    /// Cuts `whole` at the planes it crosses (`self.crossings`; nearest its centre first, as
    /// many as keep the parts within [`MAX_SPLIT_PARTS`]) into the parts between them, and
    /// places each.
    pub(super) fn split(
        &mut self,
        frame: &Frame<'_, '_>,
        whole: Part,
        parent: &[ClipPlane],
        depth: u32,
    ) {
        let b = whole.ball;
        let c = b.center;
        let mut crossings = std::mem::take(&mut self.crossings);
        crossings.sort_by_key(|x| (x.0, x.1.to_bits(), x.2));
        // A plane of quads that is also a chunk border is cut as a plane of quads.
        crossings.dedup_by(|x, y| (x.0, x.1) == (y.0, y.1));
        crossings.sort_by(|x, y| (c[x.0] - x.1).abs().total_cmp(&(c[y.0] - y.1).abs()));
        // Nearest first, while the parts (the product of cuts + 1 over the axes) fit.
        let mut per_axis = [1usize; 3];
        let kept = crossings
            .iter()
            .take_while(|&&(axis, ..)| {
                per_axis[axis] += 1;
                per_axis.iter().product::<usize>() <= MAX_SPLIT_PARTS
            })
            .count();
        crossings.truncate(kept);
        // Per axis: the box's ends and the cuts between them.
        let mut bounds: [Vec<(f64, bool)>; 3] = Default::default();
        for a in 0..3 {
            let mut cuts: Vec<(f64, bool)> = crossings
                .iter()
                .filter(|&&(axis, ..)| axis == a)
                .map(|&(_, at, border)| (at, border))
                .collect();
            cuts.sort_by(|x, y| x.0.total_cmp(&y.0));
            // A cut the box touches within rounding (`TOUCH`) bounds it.
            let lo = cuts
                .first()
                .map_or(c[a] - b.half[a], |&(at, _)| at.min(c[a] - b.half[a]));
            let hi = cuts
                .last()
                .map_or(c[a] + b.half[a], |&(at, _)| at.max(c[a] + b.half[a]));
            bounds[a] = std::iter::once((lo, false))
                .chain(cuts)
                .chain(std::iter::once((hi, false)))
                .collect();
        }
        let eye = frame.eye;
        // The cells between consecutive bounds: per axis the interval's index.
        let n = bounds.each_ref().map(|v| v.len() - 1);
        for i in 0..n[0] * n[1] * n[2] {
            let index = [i % n[0], i / n[0] % n[1], i / (n[0] * n[1])];
            let (mut lo, mut hi) = (DVec3::ZERO, DVec3::ZERO);
            let mut clip = Vec::new();
            let mut empty = false;
            for a in 0..3 {
                let (j, v) = (index[a], &bounds[a]);
                let (mut l, mut h) = (v[j].0, v[j + 1].0);
                // A bound that is a cut (not the box's own end) clips the part. On the
                // far side of a cut the part keeps what lies strictly beyond it: its box
                // stops a hair short, so that the planes order it as wholly beyond. At a
                // chunk border (no quad lies in it) both parts stop short of it, so that
                // neither reaches into the other's chunk.
                let hair = 4.0 * touch(b.half[a]);
                for (end, is_upper) in [(j, false), (j + 1, true)] {
                    let is_cut = end > 0 && end < v.len() - 1;
                    if !is_cut {
                        continue;
                    }
                    let (at, border) = v[end];
                    let eye_side = if eye[a] >= at { 1.0 } else { -1.0 };
                    // Below an upper cut, above a lower one.
                    let far = (eye_side > 0.0) == is_upper;
                    if (far || border) && is_upper {
                        h = at - hair;
                    } else if far || border {
                        l = at + hair;
                    }
                    clip.push(ClipPlane {
                        axis: a,
                        at,
                        eye_side,
                        far,
                    });
                }
                empty |= h < l;
                lo[a] = l;
                hi[a] = h;
            }
            if empty {
                continue;
            }
            let half = (hi - lo) * 0.5;
            let center = lo + half;
            let ball = Ball::new(
                center,
                half.length().min(b.radius + (center - c).length()),
                Some(half),
            );
            let clip: Clip = parent.iter().copied().chain(clip).collect();
            // A part may still meet planes no one place suits (the chunk borders it spans,
            // where its own cuts left none): cut it once more.
            let again = depth + 1 < MAX_SPLIT_DEPTH && clip.len() + 2 <= 6;
            self.crossings.clear();
            let range = self.place(frame, ball, again);
            let part = Part {
                object: whole.object,
                ball,
                clip: 0,
            };
            if again && !self.crossings.is_empty() {
                self.split(frame, part, &clip, depth + 1);
                continue;
            }
            let clip = self.clip_id(clip);
            let key = self.key(center, eye);
            self.push_range(Part { clip, ..part }, range, key);
        }
        self.crossings = crossings;
    }

    /// The index of `clip` among the frame's clips (added if new), found by its hash: a
    /// frame may cut a million parts at hundreds of distinct clips.
    fn clip_id(&mut self, clip: Clip) -> u32 {
        use std::hash::{Hash, Hasher};
        if clip.is_empty() {
            return 0;
        }
        let mut h = std::hash::DefaultHasher::new();
        for c in &clip {
            (c.axis, c.at.to_bits(), c.eye_side.to_bits(), c.far).hash(&mut h);
        }
        let key = h.finish();
        let clips = &mut self.clips;
        let ids = self.clip_ids.entry(key).or_default();
        if let Some(&i) = ids.iter().find(|&&i| clips[i as usize] == clip) {
            return i;
        }
        let i = clips.len() as u32;
        clips.push(clip);
        ids.push(i);
        i
    }

    /// The places of ball `b` in the sequence (see [`Interleaver::order`]) that the fewest
    /// constraints rule out: the earliest and the latest of the first range of them (the
    /// same constraints ruled out at every place between); with `collect`, the planes it
    /// reaches through in the chunks no sound test decides go to `self.crossings`.
    pub(super) fn place(
        &mut self,
        f: &Frame<'_, '_>,
        b: Ball,
        collect: bool,
    ) -> ((u32, u32), (u32, u32)) {
        let Self {
            items,
            weights,
            facts,
            seen,
            runs,
            boxes,
            crossings,
            ..
        } = self;
        let (chunks, eye, last) = (f.chunks, f.eye, f.last);
        let (cells, [kmin, kmax]) = cells_and_keys(b, f.eye_cell);
        // The part of the sequence whose keys lie in [kmin, kmax] (largest first).
        let first = f.keys.above(kmax);
        let end = match kmin.checked_sub(1) {
            Some(k) => f.keys.above(k),
            None => chunks.keys.len(),
        };
        let single = (0..3).all(|a| cells[a][0] == cells[a][1]);
        let range = if single {
            // One cell: its chunk, if it is in the sequence; else no chunk constrains.
            match f.cells.get([cells[0][0], cells[1][0], cells[2][0]]) {
                Some(at) if (first..end).contains(&at) => at..at + 1,
                _ => first..first,
            }
        } else {
            first..end
        };
        if range.is_empty() {
            // Nothing constrains it: after the chunks of larger keys.
            let mut at = range.start as u32;
            while at < last && chunks.surfaces[at as usize].is_none() {
                at += 1;
            }
            return ((at, 0), (at, 0));
        }
        let o = b.center.distance(eye);
        // The constraints in draw order: (chunk, quad after which it applies, weight:
        // positive when the item must come before the object, negative after it).
        items.clear();
        for c in range.clone() {
            let Some(s) = &chunks.surfaces[c] else {
                continue;
            };
            let fc = &mut facts[c];
            let (from, to) = *fc.planes.get_or_insert_with(|| {
                fc.distances = s.distances(eye);
                let from = seen.len() as u32;
                seen_planes(s, eye, f.two_sided, seen);
                (from, seen.len() as u32)
            });
            let (d, planes) = (fc.distances, &seen[from as usize..to as usize]);
            let c32 = c as u32;
            match safe(b, o, eye, s, planes, d, range.len() > 1) {
                // Apart on screen: any place is right.
                [true, true] => {}
                [true, false] => items.push((c32, 0, SOUND, 0)),
                [false, true] => items.push((c32, 0, -SOUND, 0)),
                [false, false] if f.split_quads => {
                    let (from, to, first_box) = *fc.runs.get_or_insert_with(|| {
                        let (from, first_box) = (runs.len() as u32, boxes.len() as u32);
                        plane_runs(s, runs, boxes);
                        (from, runs.len() as u32, first_box)
                    });
                    let runs = &runs[from as usize..to as usize];
                    // Each seen plane's weight (`UNSEEN`: a plane not seen, which orders
                    // nothing).
                    weights.clear();
                    weights.resize(s.planes.len(), UNSEEN);
                    for pl in planes.iter() {
                        weights[pl.index as usize] = plane_weight(b, pl);
                    }
                    let mut k = 0u32;
                    for (r, &(p, n)) in runs.iter().enumerate() {
                        let w = weights[p as usize];
                        let (face, at) = s.planes[p as usize];
                        let axis = face.axis();
                        // A run whose quads the object cannot overlap on screen orders
                        // nothing (the top of a glass wall above a fish behind it; the side
                        // of a floor below a thing lying on it, in the plane of the side of
                        // a layer above): its box first, then, where that meets the
                        // object's shadow, its quads one by one.
                        let meets =
                            |(lo, hi): (DVec3, DVec3)| !shadow_misses(b, eye, axis, (lo, hi));
                        let seen_quads = || {
                            let run = &s.quads[(k as usize).min(s.quads.len())
                                ..((k + n) as usize).min(s.quads.len())];
                            n == 1
                                || run.iter().filter_map(|q| q.unpack()).any(|q| {
                                    let (lo, hi) = q.bounds();
                                    meets((s.world(lo), s.world(hi)))
                                })
                        };
                        if w != UNSEEN && meets(boxes[first_box as usize + r]) && seen_quads() {
                            if w != 0 {
                                // A run weighs its count; the place after it is after its
                                // last quad.
                                items.push((c32, k + n - 1, w * i64::from(n), k));
                            } else if collect {
                                crossings.push((axis, s.plane_at(axis, f64::from(at)), false));
                            }
                        }
                        k += n;
                    }
                }
                [false, false] => items.push((c32, 0, if o > d[1] { -1 } else { 1 }, 0)),
            }
        }
        // Before everything in range, every item that must come before the object is
        // violated; passing an item changes the cost by its weight.
        let mut cost: i64 = items.iter().map(|it| it.2.max(0)).sum();
        let (mut min, mut at) = (cost, (range.start as u32, 0));
        let mut after = 0;
        for (i, &(c, k, w, _)) in items.iter().enumerate() {
            cost -= w;
            if cost < min {
                // Just after the item: after the whole chunk where it stood for it.
                let whole = w.abs() == SOUND || !f.split_quads;
                (min, at) = (cost, if whole { (c + 1, 0) } else { (c, k + 1) });
                after = i + 1;
            }
        }
        // The places from there on rule out as few until the first item that must come
        // after the object (none that must come before can follow: the cost would fall
        // below its least): just before that item, before its whole chunk where it
        // stood for it; past the chunks in range where none follows.
        let latest = match items[after..].iter().find(|it| it.2 < 0) {
            Some(&(c, _, w, first)) => {
                let whole = w.abs() == SOUND || !f.split_quads;
                if whole { (c, 0) } else { (c, first) }
            }
            None => (range.end as u32, 0),
        };
        if collect && min > 0 && !single {
            // No one place meets every chunk the object spans (a slab through a pane that
            // two chunks hold, each with its own layers): the parts in each cell meet their
            // own chunk's.
            for (a, &[lo, hi]) in cells.iter().enumerate() {
                for cell in lo + 1..=hi {
                    crossings.push((a, (cell * voxel_core::CHUNK_SIZE as i64) as f64, true));
                }
            }
        }
        let place = |(c, k): (u32, u32)| {
            // After quads `..k` of chunk `c`; past the end of a chunk is before the next
            // one.
            let mut at = match chunks.surfaces.get(c as usize).and_then(Option::as_ref) {
                Some(s) if k as usize >= s.quads.len() && k > 0 => (c + 1, 0),
                _ => (c, k),
            };
            // Chunks with nothing translucent draw nothing: the next one that does.
            while at.0 < last && chunks.surfaces[at.0 as usize].is_none() {
                at = (at.0 + 1, 0);
            }
            at
        };
        let at = place(at);
        (at, place(latest).max(at))
    }
}
