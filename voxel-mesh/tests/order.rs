//! The exact quad order of `voxel_mesh::order` against brute-force oracles, on thousands of
//! chunks meshed by the real mesher and on hand-made scenes of the classes where centre
//! sorting fails; region keys; cycles; the chunk order of the renderer and ours.
//!
//! Oracles (in `common`): `hides` decides exactly, for a point eye with dyadic coordinates,
//! whether some ray meets the inside of one quad and then the inside of another; the ray
//! oracle casts rays from the eye through random points strictly inside each quad and
//! lists the quads they cross first. `oracles_agree` checks the two against each other and
//! against the library's own point relation.

#![allow(clippy::unwrap_used, clippy::needless_range_loop)] // test code

mod common;

use std::collections::BTreeMap;

use common::*;
use voxel_core::blocks::{GLASS, GREEN_GLASS, RED_GLASS, WATER};
use voxel_core::{BlockId, ChunkPos, Face};
use voxel_mesh::PackedQuad;
use voxel_mesh::order::{QuadOrder, RegionKey, SortStats, chunk_order_key, testing};
use voxel_mesh::sort::quads_back_to_front;

/// A dyadic coordinate k / 1024 in `lo..hi`.
fn coord(rng: &mut Rng, lo: f64, hi: f64) -> f64 {
    rng.range((lo * 1024.0) as i64, (hi * 1024.0) as i64) as f64 / 1024.0
}

/// Eyes of every class the order must handle: inside the chunk, near it, far away (1e6
/// blocks), exactly on a quad's plane, exactly on a quad's edge plane, grazing a plane
/// (2^-20 from it), on a lattice corner. All dyadic, so the pair oracle is exact.
fn eyes(rng: &mut Rng, quads: &[PackedQuad], n: usize) -> Vec<[f64; 3]> {
    let mut out = Vec::new();
    for i in 0..n {
        let mut e = [0.0; 3].map(|_| coord(rng, -0.5, 32.5));
        let q = (!quads.is_empty()).then(|| Q::of(quads[rng.below(quads.len() as u64) as usize]));
        match (i % 8, q) {
            (0, _) => {}
            (1, _) => e = [0.0; 3].map(|_| coord(rng, -24.0, 56.0)),
            (2, _) => {
                // Far: 1e6 blocks along a random direction, with a fraction.
                for v in &mut e {
                    *v = [-1.0e6, 16.0 + coord(rng, -8.0, 8.0), 1.0e6][rng.below(3) as usize]
                        + coord(rng, 0.0, 1.0);
                }
            }
            (3, Some(q)) => e[q.axis] = q.plane(),
            (4, Some(q)) => {
                let k = (q.axis + 1 + rng.below(2) as usize) % 3;
                e[k] = if rng.chance(0.5) { q.lo[k] } else { q.hi[k] };
            }
            (5, Some(q)) => {
                let d = if rng.chance(0.5) { 1.0 } else { -1.0 } / (1u64 << 20) as f64;
                e[q.axis] = q.plane() + d;
            }
            (6, _) => e = [0.0; 3].map(|_| rng.range(-2, 35) as f64),
            _ => e = [0.0; 3].map(|_| coord(rng, -6.0, 38.0)),
        }
        out.push(e);
    }
    out
}

/// Strongly connected components (Tarjan, recursive; test sizes are small).
fn sccs(n: usize, edge: impl Fn(usize, usize) -> bool) -> Vec<Vec<usize>> {
    struct T<'a> {
        adj: Vec<Vec<usize>>,
        index: Vec<Option<usize>>,
        low: Vec<usize>,
        on: Vec<bool>,
        stack: Vec<usize>,
        next: usize,
        out: &'a mut Vec<Vec<usize>>,
    }
    fn go(t: &mut T<'_>, v: usize) {
        t.index[v] = Some(t.next);
        t.low[v] = t.next;
        t.next += 1;
        t.stack.push(v);
        t.on[v] = true;
        for i in 0..t.adj[v].len() {
            let w = t.adj[v][i];
            match t.index[w] {
                None => {
                    go(t, w);
                    t.low[v] = t.low[v].min(t.low[w]);
                }
                Some(iw) if t.on[w] => t.low[v] = t.low[v].min(iw),
                _ => {}
            }
        }
        if Some(t.low[v]) == t.index[v] {
            let mut c = Vec::new();
            while let Some(w) = t.stack.pop() {
                t.on[w] = false;
                c.push(w);
                if w == v {
                    break;
                }
            }
            t.out.push(c);
        }
    }
    let mut out = Vec::new();
    let adj = (0..n)
        .map(|i| (0..n).filter(|&j| j != i && edge(i, j)).collect())
        .collect();
    let mut t = T {
        adj,
        index: vec![None; n],
        low: vec![0; n],
        on: vec![false; n],
        stack: Vec::new(),
        next: 0,
        out: &mut out,
    };
    for v in 0..n {
        if t.index[v].is_none() {
            go(&mut t, v);
        }
    }
    out
}

/// The oracle's "must be drawn before" relation at a point eye, tie-breaks included.
fn before(eye: [f64; 3], a: &Q, b: &Q) -> bool {
    if hides(eye, a, b) {
        return true;
    }
    let (e, p) = (eye[a.axis], a.plane());
    a.coincident_overlap(b) && ((e > p && a.positive) || (e < p && !a.positive))
}

/// Quads in non-trivial strongly connected components of the oracle relation: the quads
/// that no order can draw exactly.
fn cyclic_quads(eye: [f64; 3], quads: &[PackedQuad]) -> usize {
    let q: Vec<Q> = quads.iter().map(|&p| Q::of(p)).collect();
    sccs(q.len(), |i, j| before(eye, &q[i], &q[j]))
        .iter()
        .filter(|c| c.len() > 1)
        .map(Vec::len)
        .sum()
}

fn same_multiset(a: &[PackedQuad], b: &[PackedQuad]) -> bool {
    let count = |v: &[PackedQuad]| {
        let mut m = BTreeMap::new();
        for q in v {
            *m.entry((q.geometry, q.block)).or_insert(0) += 1;
        }
        m
    };
    count(a) == count(b)
}

#[derive(Default, Debug)]
struct Tally {
    arrangements: usize,
    sorts: usize,
    quads: usize,
    exact: usize,
    cyclic: usize,
    eye_dependent: usize,
}

/// Sorts `quads` for each eye and checks the order with the pair oracle: exact when the
/// stats say so; when they report cycles, the oracle must find a real cycle too.
fn check(order: &QuadOrder, quads: &[PackedQuad], eyes: &[[f64; 3]], tally: &mut Tally) {
    tally.arrangements += 1;
    let mut out = Vec::new();
    for &eye in eyes {
        let stats = order.sort_into(eye, &mut out);
        assert!(same_multiset(&out, quads), "the order is a permutation");
        tally.sorts += 1;
        tally.quads += quads.len();
        if stats.cycles == 0 {
            let bad = violations(eye, &out);
            assert!(
                bad.is_empty(),
                "eye {eye:?}: {} pairs drawn near before far, first {:?} / {:?} ({stats:?})",
                bad.len(),
                Q::of(out[bad[0].0]),
                Q::of(out[bad[0].1]),
            );
            tally.exact += 1;
        } else {
            let real = cyclic_quads(eye, quads);
            assert!(
                real > 0,
                "eye {eye:?}: cycles reported ({stats:?}) but none exists"
            );
            assert!(
                stats.quads_in_cycles as usize <= real,
                "{stats:?} vs {real}"
            );
            tally.cyclic += 1;
        }
        tally.eye_dependent += usize::from(stats.eye_dependent > 0);
    }
}

#[test]
fn oracles_agree() {
    let mut rng = Rng::new(1);
    let (mut witnessed, mut pairs_true) = (0, 0);
    for _ in 0..60 {
        let c = random_boxes(&mut rng, 10, 6, 16);
        let quads = mesh(&c);
        if quads.is_empty() {
            continue;
        }
        let q: Vec<Q> = quads.iter().map(|&p| Q::of(p)).collect();
        for eye in eyes(&mut rng, &quads, 4) {
            // The library's point relation is the oracle's on dyadic eyes.
            for i in 0..q.len() {
                for j in 0..q.len() {
                    assert_eq!(
                        testing::hides_at(eye, quads[i], quads[j]),
                        hides(eye, &q[i], &q[j]),
                        "eye {eye:?}, {:?} behind {:?}",
                        q[i],
                        q[j]
                    );
                }
            }
            // Every pair a ray witnesses, the pair oracle knows (order = input order, so
            // a ray violation (i, j) is "quad i in front of quad j on some ray").
            let seen = ray_violations(eye, &quads, &mut rng, 40);
            for &(i, j) in &seen {
                assert!(
                    hides(eye, &q[j], &q[i]),
                    "eye {eye:?}: ray sees {:?} in front of {:?}",
                    q[i],
                    q[j]
                );
            }
            // And rays find most of the pairs the oracle knows (sampling, not exact).
            for i in 0..q.len() {
                for j in i + 1..q.len() {
                    if hides(eye, &q[j], &q[i]) {
                        pairs_true += 1;
                        witnessed += usize::from(seen.contains(&(i, j)));
                    }
                }
            }
        }
    }
    assert!(pairs_true > 1000, "{pairs_true}");
    assert!(
        witnessed * 10 > pairs_true * 6,
        "rays witness {witnessed} of {pairs_true} pairs"
    );
}

#[test]
fn centre_sorting_fails_on_water_under_a_glass_pillar_the_exact_order_does_not() {
    // A chunk-wide water surface at y = 10 and a glass pillar at x = 20, z = 16 just above
    // it, the eye a little higher in the same chunk: centre sorting draws the pillar's faces
    // first and blends the water over them; the exact order does not.
    let quads = mesh(&water_and_pillar());
    let water = quads
        .iter()
        .filter(|q| q.block == u32::from(WATER.0))
        .count();
    assert!(water >= 1);
    let eye = [16.5, 13.2, 16.5];
    let mut centre = quads.clone();
    quads_back_to_front(&mut centre, [16.5, 13.2, 16.5]);
    assert!(
        !violations(eye, &centre).is_empty(),
        "centre sorting fails here"
    );
    let order = QuadOrder::new(&quads);
    let mut out = Vec::new();
    let stats = order.sort_into(eye, &mut out);
    assert!(stats.is_exact_in_region());
    assert!(violations(eye, &out).is_empty());
    // The water quad stays one merged quad.
    assert_eq!(
        out.iter().filter(|q| q.block == u32::from(WATER.0)).count(),
        water
    );
}

#[test]
fn random_chunks_are_exact() {
    let mut rng = Rng::new(2);
    let mut tally = Tally::default();
    let start = std::time::Instant::now();
    for i in 0..1500 {
        let n = rng.range(2, 30) as usize;
        let chunk = match i % 7 {
            0 => random_boxes(&mut rng, n / 3 + 2, 8, 24),
            1 => random_boxes(&mut rng, n + 8, 5, 32),
            2 => water_with_objects(&mut rng),
            3 => floors_and_walls(&mut rng),
            4 => stairs(&mut rng),
            5 => structures(&mut rng, 40 + 6 * n).0,
            _ => random_boxes(&mut rng, n / 4 + 3, 12, 20),
        };
        let quads = mesh(&chunk);
        if quads.len() > 220 {
            continue;
        }
        let order = if i % 5 == 4 {
            QuadOrder::pairwise_only(&quads)
        } else {
            QuadOrder::new(&quads)
        };
        let e = eyes(&mut rng, &quads, 8);
        check(&order, &quads, &e, &mut tally);
    }
    println!(
        "random chunks: {tally:?} in {:.2} s",
        start.elapsed().as_secs_f64()
    );
    assert!(
        tally.arrangements > 1200 && tally.exact > tally.sorts * 9 / 10,
        "{tally:?}"
    );
}

#[test]
fn separate_structures_are_ordered_as_objects() {
    // Many structures apart from each other: no free plane splits them all, but they fall
    // apart into objects, ordered by their bounding boxes.
    let mut rng = Rng::new(9);
    let mut tally = Tally::default();
    let mut object_nodes = 0;
    for _ in 0..40 {
        let (_, quads) = structures(&mut rng, 500);
        let order = QuadOrder::new(&quads);
        object_nodes += order.node_count().1;
        let e = eyes(&mut rng, &quads, 4);
        check(&order, &quads, &e, &mut tally);
    }
    println!("structures: {tally:?}, {object_nodes} object nodes");
    assert!(object_nodes >= 20, "{object_nodes}");
    assert!(tally.exact > tally.sorts * 9 / 10, "{tally:?}");
}

#[test]
fn a_pinwheel_of_objects_is_ordered_through_their_quads() {
    // Four bars around a hole, apart from each other, in a pinwheel: no plane splits them
    // and from above the hole their bounding boxes form a cycle of the separating-axis
    // relation; their quads together have none.
    let mut c = voxel_core::Chunk::uniform(voxel_core::blocks::AIR);
    let bars = [
        ([8, 8, 8], [10, 8, 8]),
        ([12, 8, 8], [12, 8, 10]),
        ([10, 8, 12], [12, 8, 12]),
        ([8, 8, 10], [8, 8, 12]),
    ];
    for ((lo, hi), id) in bars.into_iter().zip([
        GLASS,
        RED_GLASS,
        GREEN_GLASS,
        voxel_core::blocks::BLUE_GLASS,
    ]) {
        c.fill_box(lo, hi, id).unwrap();
    }
    let quads = mesh(&c);
    let order = QuadOrder::new(&quads);
    assert!(order.node_count().1 >= 1, "an object node");
    assert_eq!(order.stuck().0, 0, "each bar alone is split by planes");
    let mut rng = Rng::new(10);
    let mut tally = Tally::default();
    let mut e = eyes(&mut rng, &quads, 64);
    let mut grouped = 0;
    for _ in 0..64 {
        // Above and below the hole, and level with the bars inside it.
        let y = [
            coord(&mut rng, 9.5, 40.0),
            coord(&mut rng, -30.0, 7.5),
            coord(&mut rng, 8.0, 9.0),
        ][rng.below(3) as usize];
        e.push([coord(&mut rng, 9.0, 12.0), y, coord(&mut rng, 9.0, 12.0)]);
    }
    for &eye in &e {
        let mut out = Vec::new();
        grouped += usize::from(order.sort_into(eye, &mut out).pairwise_quads > 0);
    }
    check(&order, &quads, &e, &mut tally);
    assert!(grouped > 0, "some eyes order the bars through their quads");
    assert_eq!(tally.cyclic, 0, "{tally:?}");
}

#[test]
fn hand_made_failing_classes_are_exact() {
    // Large merged surfaces with small objects on, under and through them; glass floors
    // and ceilings; stairs; checkerboard patches (many coincident opposite faces).
    let mut rng = Rng::new(3);
    let mut tally = Tally::default();
    let mut scenes = vec![water_and_pillar()];
    for _ in 0..40 {
        scenes.push(water_with_objects(&mut rng));
        scenes.push(floors_and_walls(&mut rng));
        scenes.push(stairs(&mut rng));
    }
    for s in 0..6 {
        let o = [s * 4, 3 + s, 20 - s * 3];
        scenes.push(checkerboard(o, [3 + s % 3, 2, 3], GLASS, RED_GLASS));
    }
    for chunk in &scenes {
        let quads = mesh(chunk);
        let order = QuadOrder::new(&quads);
        let mut e = eyes(&mut rng, &quads, 16);
        e.push([16.5, 11.2, 16.5]);
        check(&order, &quads, &e, &mut tally);
    }
    println!("hand-made: {tally:?}");
    assert_eq!(tally.cyclic, 0, "these scenes hold no cycle");
}

#[test]
fn region_orders_are_exact_in_their_whole_region() {
    // For random eye pairs in one region, the order computed at one is exact at the other,
    // and (when exact for the region) it is the very same order.
    let mut rng = Rng::new(4);
    let (mut pairs, mut checked) = (0, 0);
    for i in 0..400 {
        let chunk = match i % 4 {
            0 => random_boxes(&mut rng, 10, 6, 24),
            1 => water_with_objects(&mut rng),
            2 => floors_and_walls(&mut rng),
            _ => random_boxes(&mut rng, 5, 12, 20),
        };
        let quads = mesh(&chunk);
        if quads.len() > 200 {
            continue;
        }
        let order = QuadOrder::new(&quads);
        for e1 in eyes(&mut rng, &quads, 4) {
            let key = order.region_key(e1);
            let cell = testing::region_cell(&order, key);
            // Another eye of the region: inside its cell, or on its upper plane (an eye on a
            // plane belongs to the interval below it).
            let mut e2 = [0.0; 3];
            for k in 0..3 {
                let (lo, hi) = cell[k];
                let lo = lo.map_or(-1.0e6, f64::from);
                let hi = hi.map_or(1.0e6, f64::from);
                e2[k] = if rng.chance(0.2) && hi < 1.0e6 {
                    hi
                } else {
                    let w = (hi - lo).min(64.0);
                    let base = if lo == -1.0e6 { hi - w } else { lo };
                    base + w * (1 + rng.below(1023)) as f64 / 1024.0
                };
            }
            assert_eq!(order.region_key(e2), key, "{e2:?} in cell {cell:?}");
            let (mut o1, mut o2) = (Vec::new(), Vec::new());
            let s1 = order.sort_into(e1, &mut o1);
            let s2 = order.sort_into(e2, &mut o2);
            pairs += 1;
            if s1.is_exact_in_region() {
                assert!(
                    violations(e2, &o1).is_empty(),
                    "order of {e1:?} fails at {e2:?}"
                );
                assert!(s2.is_exact_in_region());
                assert_eq!(o1, o2, "same region, same order");
                checked += 1;
            }
        }
    }
    assert!(checked * 10 > pairs * 9, "{checked} of {pairs}");
}

#[test]
fn trigger_planes_hold_edge_planes_and_not_every_quad_plane() {
    let glass = BlockId(GLASS.0);
    // Three overlapping parallel panes at x = 1, 2, 3: one trigger (the middle plane)
    // orders all three for every eye.
    let panes: Vec<PackedQuad> = (1..4)
        .map(|x| PackedQuad::new([x, 0, 0], 8, 8, Face::NegX, glass))
        .collect();
    let order = QuadOrder::new(&panes);
    assert_eq!(order.trigger_planes(), [&[2u8][..], &[], &[]]);
    let mut rng = Rng::new(5);
    let mut tally = Tally::default();
    let e = eyes(&mut rng, &panes, 64);
    check(&order, &panes, &e, &mut tally);

    // A wall (x quad) and a floor (y quad) separated only along z: their order flips as
    // the eye crosses the gap z in [4, 6], whose planes are edge planes, not quad planes.
    let wall = PackedQuad::new([5, 0, 0], 8, 4, Face::NegX, glass); // x = 5, y 0..8, z 0..4
    let floor = PackedQuad::new([2, 3, 6], 6, 8, Face::PosY, glass); // y = 4, z 6..12, x 2..10
    let quads = vec![wall, floor];
    let order = QuadOrder::new(&quads);
    let z = order.trigger_planes()[2];
    assert!(
        z.iter().any(|&c| (4..=6).contains(&c)),
        "a trigger in the gap: {z:?}"
    );
    assert!(order.trigger_planes()[0].is_empty() || order.trigger_planes()[1].is_empty());
    let (mut a, mut b) = (Vec::new(), Vec::new());
    // From z < 4 the floor hides the wall, from z > 6 the wall hides the floor.
    let (near_wall, near_floor) = ([9.0, 6.0, 1.0], [9.0, 6.0, 11.0]);
    assert!(
        hides(near_floor, &Q::of(wall), &Q::of(floor))
            || hides(near_wall, &Q::of(floor), &Q::of(wall))
    );
    order.sort_into(near_wall, &mut a);
    order.sort_into(near_floor, &mut b);
    assert!(violations(near_wall, &a).is_empty() && violations(near_floor, &b).is_empty());
    assert_ne!(order.region_key(near_wall), order.region_key(near_floor));

    // On meshed chunks, triggers are far fewer than the coordinates in use and often fewer
    // than the distinct quad planes.
    let (mut triggers, mut planes) = (0, 0);
    for _ in 0..100 {
        let quads = mesh(&floors_and_walls(&mut rng));
        let order = QuadOrder::new(&quads);
        triggers += order
            .trigger_planes()
            .iter()
            .map(|p| p.len())
            .sum::<usize>();
        let mut set = std::collections::BTreeSet::new();
        for &q in &quads {
            let b = Q::of(q);
            set.insert((b.axis, b.plane() as i64));
        }
        planes += set.len();
    }
    println!("floors and walls: {triggers} trigger planes for {planes} quad planes");
    assert!(triggers < planes);
}

#[test]
fn a_still_camera_keeps_its_key_and_a_moving_one_changes_it_only_across_planes() {
    let mut rng = Rng::new(6);
    let quads = mesh(&floors_and_walls(&mut rng));
    let order = QuadOrder::new(&quads);
    let eye = [12.25, 7.5, 30.75];
    assert_eq!(order.region_key(eye), order.region_key(eye));
    // Walk along x from -40 to 72: the key changes exactly at the trigger planes of x.
    let planes = order.trigger_planes()[0].to_vec();
    let mut changes = Vec::new();
    let mut last = order.region_key([-40.0, eye[1], eye[2]]);
    let mut x = -40.0;
    while x < 72.0 {
        x += 1.0 / 8.0;
        let key = order.region_key([x, eye[1], eye[2]]);
        if key != last {
            changes.push(x);
            last = key;
        }
    }
    // The key of an eye on a plane is that of the interval below: the change shows just
    // past each plane.
    let expected: Vec<f64> = planes.iter().map(|&c| f64::from(c) + 1.0 / 8.0).collect();
    assert_eq!(changes, expected);
}

#[test]
fn non_finite_and_far_eyes_never_panic() {
    let mut rng = Rng::new(7);
    let quads = mesh(&random_boxes(&mut rng, 20, 8, 32));
    for order in [QuadOrder::new(&quads), QuadOrder::pairwise_only(&quads)] {
        let mut out = Vec::new();
        for eye in [
            [f64::NAN, 3.0, 4.0],
            [f64::NAN; 3],
            [f64::INFINITY, f64::NEG_INFINITY, 0.5],
            [1.0e300, -1.0e300, 1.0e-300],
            [-0.0, 0.0, 32.0],
        ] {
            let stats = order.sort_into(eye, &mut out);
            assert!(same_multiset(&out, &quads), "{eye:?}: {stats:?}");
        }
        assert_eq!(order.region_key([f64::NAN; 3]), RegionKey([0; 3]));
        // Far eyes are beyond every plane and exact.
        for eye in [[1.0e6 + 0.5, -1.0e6, 7.25], [-3.0e6, 1.0e6, 1.0e6]] {
            let stats = order.sort_into(eye, &mut out);
            if stats.is_exact() {
                assert!(violations(eye, &out).is_empty());
            }
        }
    }
    let empty = QuadOrder::new(&[]);
    let mut out = vec![PackedQuad::default()];
    assert_eq!(
        empty.sort_into([f64::NAN; 3], &mut out),
        SortStats::default()
    );
    assert!(out.is_empty());
}

#[test]
fn garbage_quads_never_panic() {
    // Packed quads the mesher never makes: any bits, crossing each other, faces 6 and 7.
    let mut rng = Rng::new(11);
    for _ in 0..200 {
        let n = rng.below(60) as usize;
        let quads: Vec<PackedQuad> = (0..n)
            .map(|_| PackedQuad {
                geometry: rng.next() as u32,
                block: rng.next() as u32,
            })
            .collect();
        for order in [QuadOrder::new(&quads), QuadOrder::pairwise_only(&quads)] {
            let mut out = Vec::new();
            for eye in [
                [f64::NAN; 3],
                [1.0e9, -3.0, 70.5],
                [31.5, 63.5, 0.25],
                [16.0, 16.0, 16.0],
            ] {
                order.sort_into(eye, &mut out);
                assert!(same_multiset(&out, &quads));
            }
        }
    }
}

/// Three glass pieces (a cube, a block and a beam) whose merged quads form a real cycle
/// from this eye: found by a random search, checked by the oracle.
fn cyclic_scene() -> (Vec<PackedQuad>, [f64; 3]) {
    let mut c = voxel_core::Chunk::uniform(voxel_core::blocks::AIR);
    c.fill_box([13, 8, 10], [16, 11, 13], GLASS).unwrap();
    c.fill_box([9, 10, 8], [11, 14, 11], GLASS).unwrap();
    c.fill_box([9, 9, 8], [13, 9, 8], GLASS).unwrap();
    (mesh(&c), [29.828125, 25.96875, -10.28125])
}

#[test]
fn a_real_cycle_of_voxel_quads_is_reported() {
    let (quads, eye) = cyclic_scene();
    let real = cyclic_quads(eye, &quads);
    assert!(real >= 3, "the oracle finds a cycle of {real} quads");
    for order in [QuadOrder::new(&quads), QuadOrder::pairwise_only(&quads)] {
        let mut out = Vec::new();
        let stats = order.sort_into(eye, &mut out);
        assert!(stats.cycles >= 1 && !stats.is_exact(), "{stats:?}");
        assert_eq!(stats.quads_in_cycles as usize, real);
        assert!(same_multiset(&out, &quads));
        // Outside the cycle everything is in order: each violation involves cycle quads.
        let q: Vec<Q> = out.iter().map(|&p| Q::of(p)).collect();
        let cyc: Vec<usize> = sccs(q.len(), |i, j| before(eye, &q[i], &q[j]))
            .into_iter()
            .filter(|c| c.len() > 1)
            .flatten()
            .collect();
        for (i, j) in violations(eye, &out) {
            assert!(
                cyc.contains(&i) && cyc.contains(&j),
                "{:?} / {:?}",
                q[i],
                q[j]
            );
        }
    }
    // Elsewhere the same quads sort exactly.
    let order = QuadOrder::new(&quads);
    let mut out = Vec::new();
    let stats = order.sort_into([11.5, 40.0, 11.5], &mut out);
    assert!(stats.is_exact() && violations([11.5, 40.0, 11.5], &out).is_empty());
}

/// Chunk boxes `[lo, hi]` of a grid, for the box oracle.
fn chunk_box(p: ChunkPos) -> ([f64; 3], [f64; 3]) {
    let o = p.origin().map(|v| v as f64);
    (o, o.map(|v| v + 32.0))
}

/// Whether a ray from `eye` meets the inside of box `b` and then that of box `a` (boxes
/// with non-empty interiors; exact for dyadic eyes).
fn box_hides(eye: [f64; 3], a: ([f64; 3], [f64; 3]), b: ([f64; 3], [f64; 3])) -> bool {
    let lt = |x: (f64, f64), y: (f64, f64)| x.0 * y.1 < y.0 * x.1;
    let (mut lo, mut hi) = ((0.0, 1.0), None::<(f64, f64)>);
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
    for k in 0..3 {
        less(b.0[k] - a.1[k], eye[k] - b.0[k]);
        less(a.0[k] - b.1[k], b.1[k] - eye[k]);
    }
    ok && hi.is_none_or(|h| lt(lo, h))
}

/// The renderer's chunk draw order: `ChunkStore::visible` sorts by (distance of the chunk
/// centre from the eye in f64, then position), nearest first, and the translucent pass
/// draws that list reversed.
fn renderer_draw_order(chunks: &[ChunkPos], eye: [f64; 3]) -> Vec<ChunkPos> {
    let mut v: Vec<(f64, ChunkPos)> = chunks
        .iter()
        .map(|&p| {
            let o = p.origin().map(|v| v as f64);
            let c: Vec<f64> = (0..3).map(|k| (o[k] - eye[k]) + 16.0).collect();
            ((c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt(), p)
        })
        .collect();
    v.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    v.reverse();
    v.into_iter().map(|(_, p)| p).collect()
}

/// Pairs drawn in the wrong order: a chunk drawn before one that is behind it on a ray.
fn chunk_violations(eye: [f64; 3], order: &[ChunkPos]) -> usize {
    let mut bad = 0;
    for i in 0..order.len() {
        for j in i + 1..order.len() {
            // i drawn first: wrong if i hides part of j.
            bad += usize::from(box_hides(eye, chunk_box(order[j]), chunk_box(order[i])));
        }
    }
    bad
}

#[test]
fn chunk_centre_order_is_exact_for_a_grid() {
    let chunks: Vec<ChunkPos> = (-2..3)
        .flat_map(|x| (-1..2).flat_map(move |y| (-2..2).map(move |z| ChunkPos::new(x, y, z))))
        .collect();
    let mut rng = Rng::new(8);
    let mut eyes = Vec::new();
    for i in 0..600 {
        let mut e = [0.0; 3].map(|_| coord(&mut rng, -100.0, 100.0));
        match i % 5 {
            // On a chunk border plane, edge or corner.
            1 => e[rng.below(3) as usize] = 32.0 * rng.range(-3, 4) as f64,
            2 => {
                e[0] = 32.0 * rng.range(-3, 4) as f64;
                e[2] = 32.0 * rng.range(-3, 4) as f64;
            }
            3 => e = [0.0; 3].map(|_| 32.0 * rng.range(-3, 4) as f64),
            4 => e = [0.0; 3].map(|_| coord(&mut rng, -2000.0, 2000.0)),
            _ => {}
        }
        eyes.push(e);
    }
    let mut ties = 0;
    for eye in eyes {
        let order = renderer_draw_order(&chunks, eye);
        assert_eq!(
            chunk_violations(eye, &order),
            0,
            "renderer order at {eye:?}"
        );
        let mut ours = chunks.clone();
        voxel_mesh::order::chunks_back_to_front(&mut ours, eye);
        assert_eq!(chunk_violations(eye, &ours), 0, "integer order at {eye:?}");
        let keys: Vec<u128> = chunks.iter().map(|&p| chunk_order_key(p, eye)).collect();
        let mut sorted = keys.clone();
        sorted.sort_unstable();
        sorted.dedup();
        ties += keys.len() - sorted.len();
    }
    assert!(ties > 0, "exact ties occur and are harmless");
}

#[test]
fn renderer_chunk_key_rounds_to_a_wrong_tie_far_away_and_the_integer_key_does_not() {
    // The eye 2^-17 past the border between chunks (-1, 0, 0) and (0, 0, 0), 2^23 blocks
    // above them: chunk (0, 0, 0) hides a sliver of chunk (-1, 0, 0), but their f64 centre
    // distances round to the same value and the position tie-break draws (0, 0, 0) first.
    let eye = [1.0 / (1u64 << 17) as f64, (1u64 << 23) as f64, 16.0];
    let (a, b) = (ChunkPos::new(-1, 0, 0), ChunkPos::new(0, 0, 0));
    assert!(
        box_hides(eye, chunk_box(a), chunk_box(b)),
        "b hides part of a"
    );
    assert_eq!(
        renderer_draw_order(&[a, b], eye),
        vec![b, a],
        "the renderer draws b first"
    );
    assert_eq!(chunk_violations(eye, &[b, a]), 1);
    let mut ours = vec![b, a];
    voxel_mesh::order::chunks_back_to_front(&mut ours, eye);
    assert_eq!(ours, vec![a, b]);
    assert!(chunk_order_key(a, eye) > chunk_order_key(b, eye));
}

#[test]
fn chunk_order_key_never_panics() {
    let p = ChunkPos::new(i32::MIN, i32::MAX, 0);
    for eye in [
        [f64::NAN; 3],
        [f64::INFINITY, f64::NEG_INFINITY, 1.0e300],
        [-1.0e300; 3],
    ] {
        let _ = chunk_order_key(p, eye);
    }
}

#[test]
fn coincident_opposite_faces_put_the_far_block_face_first() {
    // Water and glass side by side: the water's +x face and the glass's -x face share a
    // plane. From the glass side the water face (its block beyond the plane) comes first.
    let mut c = voxel_core::Chunk::uniform(voxel_core::blocks::AIR);
    c.fill_box([4, 4, 4], [7, 7, 7], WATER).unwrap();
    c.fill_box([8, 4, 4], [11, 7, 7], GREEN_GLASS).unwrap();
    let quads = mesh(&c);
    let order = QuadOrder::new(&quads);
    for (eye, first) in [
        ([20.0, 6.0, 6.0], Face::PosX),
        ([-5.0, 6.0, 6.0], Face::NegX),
    ] {
        let mut out = Vec::new();
        order.sort_into(eye, &mut out);
        let at8: Vec<Face> = out
            .iter()
            .filter_map(|q| q.unpack())
            .filter(|q| {
                q.face.axis() == 0 && (q.pos[0] == 8 || (q.pos[0] == 7 && q.face == Face::PosX))
            })
            .map(|q| q.face)
            .collect();
        assert_eq!(at8.len(), 2);
        assert_eq!(at8[0], first, "{eye:?}");
        assert!(violations(eye, &out).is_empty());
    }
}
