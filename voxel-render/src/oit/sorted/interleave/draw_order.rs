//! The parts in draw order once placed: by place, farthest first at each
//! ([`order_by_place`], a radix sort), and grouped by clip where the picture stays the same
//! ([`group_clips`]).

use glam::DVec3;

use super::{Ball, Part};

/// How many parts a part may move back over, at most, to join an earlier run of its clip
/// ([`group_clips`]): the tests stay linear in the parts.
pub(super) const GROUP_WINDOW: usize = 64;

/// Whether balls `a` and `b` may overlap as seen from `eye`: the cones from the eye around
/// them meet (or the eye is inside one).
pub(super) fn may_overlap(a: Ball, b: Ball, eye: DVec3) -> bool {
    let (u, v) = (a.center - eye, b.center - eye);
    let (du, dv) = (u.length(), v.length());
    if du <= a.radius || dv <= b.radius || !(du * dv).is_normal() {
        return true;
    }
    let (sa, sb) = (a.radius / du, b.radius / dv);
    let (ca, cb) = ((1.0 - sa * sa).sqrt(), (1.0 - sb * sb).sqrt());
    // Two half angles past a right angle together always meet.
    if ca * cb - sa * sb <= -1.0 {
        return true;
    }
    u.dot(v) / (du * dv) >= ca * cb - sa * sb
}

/// Groups the parts at each place (`at`: the place of each part in `drawn`, in draw
/// order) by clip where the picture stays the same: a part joins
/// the last run of its clip at its place (moving back over the parts drawn since) when it
/// overlaps none of them on screen, so that blending them in the other order changes no
/// pixel. Each run of one clip is one draw of the game's with its own clip (and a switch of
/// pipeline around it): parts of objects cut at a surface or a chunk border would
/// otherwise alternate with whole objects in the farthest-first order.
pub(super) fn group_clips(
    parts: &[Part],
    at: &[(u32, u32)],
    eye: DVec3,
    drawn: &mut Vec<u32>,
    grouped: &mut Vec<u32>,
) {
    if parts.iter().all(|p| p.clip == 0) {
        return;
    }
    grouped.clear();
    let mut from = 0;
    while from < drawn.len() {
        let place = at[from];
        let to = from + at[from..].partition_point(|&p| p == place);
        let start = grouped.len();
        for &p in &drawn[from..to] {
            let part = &parts[p as usize];
            // The end of the last run of its clip in this place, if the part may join it.
            let mut at = None;
            for (back, &q) in grouped[start..].iter().enumerate().rev() {
                if grouped.len() - start - back > GROUP_WINDOW {
                    break;
                }
                let other = &parts[q as usize];
                if other.clip == part.clip {
                    at = Some(start + back + 1);
                    break;
                }
                if may_overlap(part.ball, other.ball, eye) {
                    break;
                }
            }
            match at {
                Some(i) if i < grouped.len() => grouped.insert(i, p),
                _ => grouped.push(p),
            }
        }
        from = to;
    }
    std::mem::swap(drawn, grouped);
}

/// A key that orders non-negative distances (or their squares) farthest first: the bits of
/// the 32-bit float order like the number (enough to tell objects apart at one place: 24
/// bits of mantissa).
pub(super) fn farthest_key(d: f64) -> u32 {
    !(d as f32).to_bits()
}

/// Sorts `v` by `key`, stably, in three passes of eleven bits (Bevy sorts its transparent
/// phase by a radix sort too): linear in the count, a few times faster than a comparison
/// sort for thousands of objects.
pub(super) fn radix_sort<T: Copy + Default>(
    v: &mut Vec<T>,
    other: &mut Vec<T>,
    key: impl Fn(&T) -> u32,
) {
    other.clear();
    other.resize(v.len(), T::default());
    const BITS: u32 = 11;
    const BUCKETS: usize = 1 << BITS;
    let mut counts = vec![0usize; BUCKETS + 1];
    for shift in [0u32, BITS, 2 * BITS] {
        counts.fill(0);
        for e in v.iter() {
            counts[((key(e) >> shift) as usize & (BUCKETS - 1)) + 1] += 1;
        }
        if counts[1..].contains(&v.len()) {
            // Every key has the same digit here: nothing moves.
            continue;
        }
        for b in 1..=BUCKETS {
            counts[b] += counts[b - 1];
        }
        for &e in v.iter() {
            let b = (key(&e) >> shift) as usize & (BUCKETS - 1);
            other[counts[b]] = e;
            counts[b] += 1;
        }
        std::mem::swap(v, other);
    }
}

/// A part as [`order_by_place`] sorts it: its distance key (farthest first), the part,
/// its chunk and the quad after which it goes. Sorting these together, not part numbers
/// that look their place up, keeps each pass a walk through memory in order: a million
/// parts' lookups in draw order would each miss the cache.
pub(super) type Entry = [u32; 4];

/// The parts by place (chunk, then quad), farthest first at each place: one radix sort by
/// distance, then a stable counting sort by chunk (places are chunk indices up to `last`),
/// and within a chunk whose parts go among its quads a stable radix sort by quad. Each pass
/// is linear in the parts. `entries` ([`Entry`]; `farthest[i]` is part `i`'s distance key,
/// `places[i]` its place) and `spare` are room; `order` gets the parts in draw order and
/// `at` their places.
pub(super) fn order_by_place(
    places: &[(u32, u32)],
    farthest: &[u32],
    (entries, spare): (&mut Vec<Entry>, &mut Vec<Entry>),
    last: u32,
    order: &mut Vec<u32>,
    at: &mut Vec<(u32, u32)>,
) {
    entries.clear();
    entries.extend(
        farthest
            .iter()
            .zip(places)
            .enumerate()
            .map(|(i, (&key, &(c, k)))| [key, i as u32, c, k]),
    );
    radix_sort(entries, spare, |e| e[0]);
    let mut start = vec![0u32; last as usize + 2];
    for &(c, _) in places {
        start[c as usize + 1] += 1;
    }
    for c in 1..start.len() {
        start[c] += start[c - 1];
    }
    spare.clear();
    spare.resize(entries.len(), Entry::default());
    let mut quads = false;
    for e in entries.iter() {
        let to = &mut start[e[2] as usize];
        spare[*to as usize] = *e;
        *to += 1;
        quads |= e[3] > 0;
    }
    std::mem::swap(entries, spare);
    if quads {
        // Each chunk's run of parts, by quad (stable: farthest first stays).
        let mut from = 0;
        while from < entries.len() {
            let c = entries[from][2];
            let to = from + entries[from..].partition_point(|e| e[2] == c);
            let run = &mut entries[from..to];
            if run.iter().any(|e| e[3] != run[0][3]) {
                if run.len() > 256 {
                    let mut v = run.to_vec();
                    radix_sort(&mut v, spare, |e| e[3]);
                    run.copy_from_slice(&v);
                } else {
                    run.sort_by_key(|e| e[3]);
                }
            }
            from = to;
        }
    }
    order.clear();
    order.extend(entries.iter().map(|e| e[1]));
    at.clear();
    at.extend(entries.iter().map(|e| (e[2], e[3])));
}
