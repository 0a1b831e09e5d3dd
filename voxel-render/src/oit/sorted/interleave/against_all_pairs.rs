//! The fast order against the all-pairs one it replaces, on random scenes of chunks with
//! meshed water and glass and random objects (points, small balls, balls across chunk
//! borders, large ones), with one- and two-sided drawing, with and without splitting
//! quads.

use super::*;
use std::sync::Arc;
use voxel_core::{BlockRegistry, Chunk, Neighbourhood, blocks};
use voxel_mesh::Mesher;
use voxel_mesh::order::{QuadOrder, chunk_order_key};

/// An object's place, and what decided it (see [`all_pairs`]).
type Placed = ((u32, u32), Vec<(u32, Option<u32>)>);

/// The order before: every object against every chunk (the oracle of this test).
/// Each object's place, and what decided it: `(chunk, None)` for a chunk a sound test
/// decided, `(chunk, Some(quad))` for a quad whose plane did.
fn all_pairs(
    balls: &[Ball],
    eye: DVec3,
    chunks: &[Option<Surfaces<'_>>],
    two_sided: bool,
    split_quads: bool,
) -> Vec<Placed> {
    let mut out = Vec::new();
    for &b in balls {
        let o = b.center.distance(eye);
        let mut items: Vec<(u32, u32, i64)> = Vec::new();
        for (c, s) in chunks.iter().enumerate() {
            let Some(s) = s else { continue };
            let c = c as u32;
            let d = s.distances(eye);
            match safe(
                b,
                o,
                eye,
                s,
                &{
                    let mut v = Vec::new();
                    seen_planes(s, eye, two_sided, &mut v);
                    v
                },
                d,
                true,
            ) {
                [true, true] => {}
                [true, false] => items.push((c, 0, SOUND)),
                [false, true] => items.push((c, 0, -SOUND)),
                [false, false] if split_quads => {
                    for (k, &q) in s.quads.iter().enumerate() {
                        match quad_side(b, eye, s.origin, q, two_sided) {
                            Some(true) => items.push((c, k as u32, 1)),
                            Some(false) => items.push((c, k as u32, -1)),
                            None => {}
                        }
                    }
                }
                [false, false] => items.push((c, 0, if o > d[1] { -1 } else { 1 })),
            }
        }
        let mut cost: i64 = items.iter().map(|it| it.2.max(0)).sum();
        let (mut min, mut at) = (cost, (0, 0));
        for &(c, k, w) in items.iter() {
            cost -= w;
            if cost < min {
                let whole = w.abs() == SOUND || !split_quads;
                (min, at) = (cost, if whole { (c + 1, 0) } else { (c, k + 1) });
            }
        }
        let decided = items
            .iter()
            .map(|&(c, k, w)| (c, (w.abs() == 1 && split_quads).then_some(k)))
            .collect();
        out.push((at, decided));
    }
    out
}

/// What rays from `eye` through points of ball `b` (its centre and points on its
/// surface) demand of its place among `chunks`: `(chunk, quad, before)` for each quad
/// a ray crosses, `before` when it crosses it in front of the point (the object must
/// be drawn before that quad), else after it.
fn witnessed(
    b: Ball,
    eye: DVec3,
    chunks: &[Option<Surfaces<'_>>],
    two_sided: bool,
    next: &mut impl FnMut() -> u64,
) -> Vec<(u32, u32, bool)> {
    let points: Vec<DVec3> = (0..if b.radius > 0.0 { 9 } else { 1 })
        .map(|j| {
            if j == 0 {
                return b.center;
            }
            let r = |n: u64| (n % 2001) as f64 / 1000.0 - 1.0;
            let v = DVec3::new(r(next()), r(next()), r(next()));
            // On the ball, moved into the box (nearer the centre: still in the ball).
            let on = v.normalize_or(DVec3::X) * b.radius * 0.999;
            b.center + on.clamp(-b.half * 0.999, b.half * 0.999)
        })
        .collect();
    let mut out = Vec::new();
    for (c, s) in chunks.iter().enumerate() {
        let Some(s) = s else { continue };
        for (k, q) in s.quads.iter().enumerate() {
            let Some(q) = q.unpack() else { continue };
            let (lo, hi) = q.bounds();
            let a = q.face.axis();
            let [u, v] = voxel_mesh::UV_AXES[a];
            let plane = s.origin[a] + lo[a];
            let n = if q.face.is_positive() { 1.0 } else { -1.0 };
            if !two_sided && (eye[a] - plane) * n <= 0.0 {
                continue;
            }
            for p in &points {
                let dir = *p - eye;
                if dir[a] == 0.0 {
                    continue;
                }
                let t = (plane - eye[a]) / dir[a];
                if t <= 0.0 || (t - 1.0).abs() < 1e-9 {
                    continue;
                }
                let x = eye + dir * t;
                let inside = x[u] > s.origin[u] + lo[u]
                    && x[u] < s.origin[u] + hi[u]
                    && x[v] > s.origin[v] + lo[v]
                    && x[v] < s.origin[v] + hi[v];
                if inside {
                    out.push((c as u32, k as u32, t < 1.0));
                }
            }
        }
    }
    out
}

/// Whether place `p` (after quads `..p.1` of chunk `p.0`) meets every demand.
fn meets(p: (u32, u32), demands: &[(u32, u32, bool)]) -> bool {
    demands.iter().all(|&(c, k, before)| {
        if before {
            p.0 < c || (p.0 == c && p.1 <= k)
        } else {
            p.0 > c || (p.0 == c && p.1 > k)
        }
    })
}

#[test]
fn where_the_sound_tests_decide_the_fast_order_agrees_with_all_pairs() {
    let registry = Arc::new(BlockRegistry::default());
    let mut mesher = Mesher::new(&registry);
    let mut seed = 0x0bad_cafe_1234_5678u64;
    let mut next = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        seed
    };
    let (mut checked, mut decided, mut straddling, mut cut) = (0, 0, 0, 0);
    for round in 0..64u64 {
        let two_sided = round % 3 == 0;
        let split_quads = round % 2 == 0;
        let eye = DVec3::new(
            (next() % 96) as f64 - 48.0 + 0.37,
            (next() % 64) as f64 - 16.0 + 0.61,
            (next() % 96) as f64 - 48.0 + 0.13,
        );
        // Chunks around the eye with a few boxes of water and glass each.
        let mut meshes = Vec::new();
        for x in -2..=2 {
            for y in -1..=1 {
                for z in -2..=2 {
                    if next() % 3 != 0 {
                        continue;
                    }
                    let mut c = Chunk::default();
                    for _ in 0..1 + next() % 3 {
                        let id = [blocks::WATER, blocks::GLASS, blocks::RED_GLASS]
                            [(next() % 3) as usize];
                        let lo = [0, 1, 2].map(|_| (next() % 32) as usize);
                        let size = [0, 1, 2].map(|_| (next() % 12) as usize);
                        for bx in lo[0]..(lo[0] + size[0] + 1).min(32) {
                            for by in lo[1]..(lo[1] + size[1] + 1).min(32) {
                                for bz in lo[2]..(lo[2] + size[2] + 1).min(32) {
                                    c.set(bx, by, bz, id).unwrap();
                                }
                            }
                        }
                    }
                    let m = mesher.mesh(&c, Neighbourhood::from_fn(|_| None)).unwrap();
                    if m.translucent.is_empty() {
                        continue;
                    }
                    meshes.push((ChunkPos::new(x, y, z), m.translucent));
                }
            }
        }
        meshes.sort_by_key(|(p, _)| (std::cmp::Reverse(chunk_order_key(*p, eye.to_array())), *p));
        // Each chunk's quads in exact back-to-front order, its planes and box.
        let mut sorted = Vec::new();
        for (p, quads) in &meshes {
            let origin = p.origin().map(|v| v as f64);
            let local = [0, 1, 2].map(|k| eye[k] - origin[k]);
            let mut out = Vec::new();
            QuadOrder::new(quads).sort_into(local, &mut out);
            let mut planes: Vec<(Face, u8)> = out
                .iter()
                .filter_map(|q| q.unpack())
                .map(|q| (q.face, q.bounds().0[q.face.axis()] as u8))
                .collect();
            planes.sort_unstable_by_key(|&(f, c)| (f as u8, c));
            planes.dedup();
            let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
            for q in out.iter().filter_map(|q| q.unpack()) {
                let (a, b) = q.bounds();
                lo = lo.min(DVec3::from(a) + DVec3::from(origin));
                hi = hi.max(DVec3::from(b) + DVec3::from(origin));
            }
            sorted.push((origin, out, planes, lo, hi));
        }
        let surfaces: Vec<Option<Surfaces<'_>>> = sorted
            .iter()
            .map(|(origin, quads, planes, lo, hi)| {
                Some(Surfaces {
                    lo: *lo,
                    hi: *hi,
                    origin: *origin,
                    scale: [1.0; 3],
                    planes,
                    quads,
                })
            })
            .collect();
        let positions: Vec<ChunkPos> = meshes.iter().map(|m| m.0).collect();
        let keys: Vec<u128> = positions
            .iter()
            .map(|&p| chunk_order_key(p, eye.to_array()))
            .collect();
        let seq = ChunkSequence {
            surfaces: &surfaces,
            keys: &keys,
            positions: &positions,
        };
        let balls: Vec<Ball> = (0..200)
            .map(|k| {
                let center = DVec3::new(
                    (next() % 128) as f64 - 64.0 + (next() % 1000) as f64 / 1000.0,
                    (next() % 96) as f64 - 32.0 + (next() % 1000) as f64 / 1000.0,
                    (next() % 128) as f64 - 64.0 + (next() % 1000) as f64 / 1000.0,
                );
                let radius = [0.0, 0.3, 2.5, 9.0][k % 4];
                // Some objects flat along an axis: slabs whose ball is far larger.
                let half = (k % 3 == 0).then(|| {
                    let mut h = DVec3::splat(radius);
                    h[k / 3 % 3] = radius * 0.05;
                    h
                });
                Ball::new(center, radius, half)
            })
            .collect();
        let old = all_pairs(&balls, eye, &surfaces, two_sided, split_quads);
        let (order, splits) = interleave(&balls, eye, &seq, two_sided, split_quads);
        // The new place of each object, from the splits; an object cut into parts where it
        // reaches through a plane (sorted-quads) is drawn by one run per part, and no
        // single place of it is compared (the parts are tested on their own).
        let mut new = vec![(surfaces.len() as u32, 0u32); balls.len()];
        let mut parts = vec![0u32; balls.len()];
        assert!(order.len() <= balls.len(), "each object once in the order");
        for s in &splits {
            for &i in &order[s.start as usize..s.end as usize] {
                new[i as usize] = (s.chunk, s.quad);
                parts[i as usize] += 1;
            }
        }
        for (i, &b) in balls.iter().enumerate() {
            if parts[i] > 1 {
                cut += 1;
                continue;
            }
            if !(0..3).all(|a| {
                (b.center[a] - b.half[a]).div_euclid(32.0)
                    == (b.center[a] + b.half[a]).div_euclid(32.0)
            }) {
                straddling += 1;
            }
            // What rays demand where the all-pairs order had a decision.
            let (old_place, decisions) = &old[i];
            let demands: Vec<(u32, u32, bool)> = witnessed(b, eye, &surfaces, two_sided, &mut next)
                .into_iter()
                .filter(|&(c, k, _)| {
                    decisions.contains(&(c, None)) || decisions.contains(&(c, Some(k)))
                })
                .collect();
            decided += demands.len();
            // Places past the last quad of a chunk mean before the next one.
            let norm = |p: (u32, u32)| match surfaces.get(p.0 as usize) {
                Some(Some(s)) if p.1 as usize >= s.quads.len() && p.1 > 0 => (p.0 + 1, 0),
                _ => p,
            };
            if !demands.is_empty() && meets(norm(*old_place), &demands) {
                checked += 1;

                assert!(
                    meets(new[i], &demands),
                    "round {round}, ball {b:?}, eye {eye}: all pairs {:?} meets what rays demand, the fast order {:?} does not ({demands:?})",
                    norm(*old_place),
                    new[i]
                );
            }
        }
    }
    assert!(
        checked > 1400 && decided > 8000 && straddling > 2000 && cut > 100,
        "{checked} {decided} {straddling} {cut}"
    );
}
