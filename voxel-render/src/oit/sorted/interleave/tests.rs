//! The sound tests against rays and hand-built chunk surfaces, and objects placed among
//! chunks and among the quads of one chunk.

use super::draw_order::may_overlap;
use super::*;

/// How a point stands against a chunk's translucent quads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Side {
    /// Drawn before the chunk.
    Behind,
    /// Drawn after it.
    Front,
}

/// The side of ball `b` where one of the sound tests decides it.
fn decide(
    b: Ball,
    o: f64,
    eye: DVec3,
    s: &Surfaces<'_>,
    d: [f64; 3],
    two_sided: bool,
) -> Option<Side> {
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
        [true, _] => Some(Side::Front),
        [false, true] => Some(Side::Behind),
        [false, false] => None,
    }
}

/// Where ball `b` goes among `quads` (a chunk's quads in their exact back-to-front order):
/// the split that the fewest quads' planes disagree with ([`quad_side`]).
fn quad_split(b: Ball, eye: DVec3, origin: [f64; 3], quads: &[PackedQuad], two_sided: bool) -> u32 {
    let sides: Vec<Option<bool>> = quads
        .iter()
        .map(|&q| quad_side(b, eye, origin, q, two_sided))
        .collect();
    let mut cost: i64 = sides.iter().map(|s| i64::from(*s == Some(true))).sum();
    let (mut min, mut at) = (cost, 0);
    for (k, side) in sides.iter().enumerate() {
        cost += match side {
            Some(true) => -1,
            Some(false) => 1,
            None => 0,
        };
        if cost < min {
            (min, at) = (cost, k as u32 + 1);
        }
    }
    at
}

/// The side of ball `b` (its centre at distance `o` from `eye`) against chunk surfaces
/// `s`, whose box spans distances `near..=far` from the eye with its centre at `mid`;
/// `two_sided` when back faces are drawn too.
fn side(b: Ball, o: f64, eye: DVec3, s: &Surfaces<'_>, d: [f64; 3], two_sided: bool) -> Side {
    decide(b, o, eye, s, d, two_sided).unwrap_or(if o > d[1] { Side::Behind } else { Side::Front })
}

fn surfaces<'a>(lo: [f64; 3], hi: [f64; 3], planes: &'a [(Face, u8)]) -> Surfaces<'a> {
    Surfaces {
        lo: DVec3::from(lo),
        hi: DVec3::from(hi),
        origin: [0.0; 3],
        scale: [1.0; 3],
        planes,
        quads: &[],
    }
}

fn point(center: DVec3) -> Ball {
    Ball::sphere(center, 0.0)
}

#[test]
fn a_point_above_a_water_surface_is_in_front_and_below_it_behind() {
    // A water surface at y = 8 (the top faces of blocks at y = 7) over the whole
    // chunk, seen from above at an angle.
    let planes = [(Face::PosY, 8)];
    let s = surfaces([0.0, 8.0, 0.0], [32.0, 8.0, 32.0], &planes);
    let eye = DVec3::new(16.0, 14.0, 40.0);
    let d = s.distances(eye);
    for (p, want) in [
        (DVec3::new(16.0, 10.0, 20.0), Side::Front),
        (DVec3::new(16.0, 8.5, 30.0), Side::Front),
        (DVec3::new(16.0, 4.0, 20.0), Side::Behind),
        (DVec3::new(16.0, 7.9, 31.0), Side::Behind),
    ] {
        let o = p.distance(eye);
        assert_eq!(side(point(p), o, eye, &s, d, false), want, "{p}");
    }
    // Under water looking up (both sides drawn): the surface is in front of a point
    // above it.
    let eye = DVec3::new(16.0, 2.0, 20.0);
    let d = s.distances(eye);
    let p = DVec3::new(16.0, 9.0, 18.0);
    assert_eq!(
        side(point(p), p.distance(eye), eye, &s, d, true),
        Side::Behind
    );
    // A ball through the surface is decided by the box's centre.
    let b = Ball::sphere(DVec3::new(16.0, 8.2, 20.0), 1.0);
    assert_eq!(decide(b, b.center.distance(eye), eye, &s, d, true), None);
}

#[test]
fn between_two_layers_the_centre_decides() {
    let planes = [(Face::PosZ, 5), (Face::PosZ, 21)];
    let s = surfaces([0.0, 0.0, 5.0], [32.0, 32.0, 21.0], &planes);
    let eye = DVec3::new(16.0, 16.0, 60.0);
    let d = s.distances(eye);
    let p = DVec3::new(16.0, 16.0, 12.0);
    // In front of the plane at 5, behind the one at 21: the centre (13) decides.
    assert_eq!(
        side(point(p), p.distance(eye), eye, &s, d, false),
        Side::Behind
    );
    let p = DVec3::new(16.0, 16.0, 14.0);
    assert_eq!(
        side(point(p), p.distance(eye), eye, &s, d, false),
        Side::Front
    );
}

/// Random quads of a chunk and random balls: where a sound test decides, the ray from
/// the eye through any point of the ball agrees (a quad hit before the point means
/// behind, a quad hit beyond it means in front).
#[test]
fn decided_sides_agree_with_rays() {
    let mut seed = 0x1234_5678_9abc_def0u64;
    let mut next = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let faces = Face::ALL;
    let (mut decided, mut checked) = (0, 0);
    for round in 0..400 {
        let two_sided = round % 4 == 0;
        // A few quads: face, plane coordinate, rectangle on the other two axes.
        let quads: Vec<(Face, u8, [f64; 2], [f64; 2])> = (0..1 + round % 5)
            .map(|_| {
                let face = faces[(next() * 6.0) as usize % 6];
                let c = (next() * 33.0) as u8 % 33;
                let a = [next() * 24.0, next() * 24.0];
                (
                    face,
                    c,
                    a,
                    [a[0] + 1.0 + next() * 16.0, a[1] + 1.0 + next() * 16.0],
                )
            })
            .collect();
        let origin = [32.0, -32.0, 0.0];
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for &(face, c, a, b) in &quads {
            let k = face.axis();
            let [u, v] = voxel_mesh::UV_AXES[k];
            let mut q0 = DVec3::ZERO;
            let mut q1 = DVec3::ZERO;
            q0[k] = f64::from(c);
            q1[k] = f64::from(c);
            (q0[u], q0[v], q1[u], q1[v]) = (a[0], a[1], b[0], b[1]);
            let o = DVec3::from(origin);
            lo = lo.min(q0 + o);
            hi = hi.max(q1 + o);
        }
        let mut planes: Vec<(Face, u8)> = quads.iter().map(|q| (q.0, q.1)).collect();
        planes.sort_unstable_by_key(|&(f, c)| (f as u8, c));
        planes.dedup();
        let s = Surfaces {
            lo,
            hi,
            origin,
            scale: [1.0; 3],
            planes: &planes,
            quads: &[],
        };
        let around = |next: &mut dyn FnMut() -> f64| {
            DVec3::new(next() * 64.0, next() * 64.0 - 48.0, next() * 64.0 - 16.0)
        };
        let eye = around(&mut next);
        let d = s.distances(eye);
        for k in 0..200 {
            let center = around(&mut next);
            let radius = if k % 2 == 0 { 0.0 } else { next() * 4.0 };
            let ball = Ball::sphere(center, radius);
            let o = center.distance(eye);
            let Some(got) = decide(ball, o, eye, &s, d, two_sided) else {
                continue;
            };
            decided += 1;
            // Points of the ball: its centre and points on its surface.
            let points: Vec<DVec3> = (0..if radius > 0.0 { 7 } else { 1 })
                .map(|j| {
                    if j == 0 {
                        return center;
                    }
                    let v = DVec3::new(next() - 0.5, next() - 0.5, next() - 0.5);
                    center + v.normalize_or(DVec3::X) * radius * 0.999
                })
                .collect();
            // Every quad the ray eye -> p crosses, and where (t = 1 at p).
            for (p, &(face, c, a, b)) in points
                .iter()
                .flat_map(|p| quads.iter().map(move |q| (*p, q)))
            {
                let k = face.axis();
                let [u, v] = voxel_mesh::UV_AXES[k];
                let plane = origin[k] + f64::from(c);
                let n = if face.is_positive() { 1.0 } else { -1.0 };
                if !two_sided && (eye[k] - plane) * n <= 0.0 {
                    continue;
                }
                let dir = p - eye;
                if dir[k] == 0.0 {
                    continue;
                }
                let t = (plane - eye[k]) / dir[k];
                if t <= 0.0 {
                    continue;
                }
                let x = eye + dir * t;
                let inside = x[u] > origin[u] + a[0]
                    && x[u] < origin[u] + b[0]
                    && x[v] > origin[v] + a[1]
                    && x[v] < origin[v] + b[1];
                if !inside {
                    continue;
                }
                checked += 1;
                let want = if t < 1.0 { Side::Behind } else { Side::Front };
                assert_eq!(got, want, "p {p} eye {eye} quad {face:?} {c} {a:?} {b:?}");
            }
        }
    }
    assert!(
        decided > 20_000 && checked > 1000,
        "{decided} decided, {checked} checked"
    );
}

#[test]
fn objects_go_before_the_first_chunk_they_are_behind() {
    let planes = [(Face::PosY, 7)];
    // Two water chunks in a row along z, the eye above the nearer one.
    let far = Surfaces {
        lo: DVec3::new(0.0, 7.0, -64.0),
        hi: DVec3::new(32.0, 7.0, -32.0),
        origin: [0.0, 0.0, -64.0],
        scale: [1.0; 3],
        planes: &planes,
        quads: &[],
    };
    let near = Surfaces {
        lo: DVec3::new(0.0, 7.0, -32.0),
        hi: DVec3::new(32.0, 7.0, 0.0),
        origin: [0.0, 0.0, -32.0],
        scale: [1.0; 3],
        planes: &planes,
        quads: &[],
    };
    let eye = DVec3::new(16.0, 12.0, 4.0);
    let chunks = [Some(far), None, Some(near)];
    // The middle one draws nothing translucent; its key lies between the others'.
    let positions = [
        ChunkPos::new(0, 0, -2),
        ChunkPos::new(0, 1, -1),
        ChunkPos::new(0, 0, -1),
    ];
    let keys = keys_of(&positions, eye);
    let chunks = ChunkSequence {
        surfaces: &chunks,
        keys: &keys,
        positions: &positions,
    };
    let balls = [
        DVec3::new(16.0, 3.0, -50.0), // under the far water
        DVec3::new(16.0, 9.0, -50.0), // over the far water
        DVec3::new(16.0, 3.0, -10.0), // under the near water
        DVec3::new(16.0, 9.0, -10.0), // over the near water
        DVec3::new(16.0, 11.0, 2.0),  // by the eye
    ]
    .map(|center| Ball::sphere(center, 1.5));
    let (order, splits) = interleave(&balls, eye, &chunks, false, false);
    // Before the far water: what is under it. Before the near water: what lies over
    // the far water and what lies under the near water (each ball lies in one chunk
    // cell: only that cell's chunk is tested; farther chunks come before it, nearer
    // ones after), farthest first.
    let at = |chunk, start, end| Split {
        chunk,
        quad: 0,
        start,
        end,
        clip: 0,
    };
    assert_eq!(splits, vec![at(0, 0, 1), at(2, 1, 3), at(3, 3, 5)]);
    assert_eq!(order[..3], [0, 1, 2]);
    // Over the near water and by the eye: after every chunk (past the last), farthest
    // first.
    assert_eq!(order[3..], [3, 4]);
}

#[test]
fn between_water_and_a_pane_of_one_chunk_an_object_goes_between_their_quads() {
    use voxel_core::BlockId;
    use voxel_mesh::Quad;
    let quad = |pos: [u8; 3], size: [u8; 2], face| {
        PackedQuad::pack(&Quad {
            pos,
            size,
            face,
            block: BlockId(1),
        })
    };
    // Back to front for an eye at z = 40 above: the water surface (top faces of
    // y = 3), then a pane's +z face at z = 21 (blocks z = 20, y 6..10).
    let quads = [
        quad([0, 3, 0], [32, 32], Face::PosY),
        quad([8, 6, 20], [16, 4], Face::PosZ),
    ];
    let planes = quad_planes_of(&quads);
    let s = Surfaces {
        lo: DVec3::new(0.0, 4.0, 0.0),
        hi: DVec3::new(32.0, 10.0, 32.0),
        origin: [0.0; 3],
        scale: [1.0; 3],
        planes: &planes,
        quads: &quads,
    };
    let eye = DVec3::new(16.0, 12.0, 40.0);
    let d = s.distances(eye);
    let ball = |y, z| Ball::sphere(DVec3::new(16.0, y, z), 1.0);
    // Above the water, behind the pane: the planes disagree, the quads split.
    let b = ball(7.0, 12.0);
    assert_eq!(decide(b, b.center.distance(eye), eye, &s, d, false), None);
    assert_eq!(quad_split(b, eye, s.origin, &quads, false), 1);
    let positions = [ChunkPos::new(0, 0, 0)];
    let keys = keys_of(&positions, eye);
    let one = [Some(s)];
    let seq = ChunkSequence {
        surfaces: &one,
        keys: &keys,
        positions: &positions,
    };
    let (order, splits) = interleave(&[b], eye, &seq, false, true);
    assert_eq!(order, [0]);
    let want = Split {
        chunk: 0,
        quad: 1,
        start: 0,
        end: 1,
        clip: 0,
    };
    assert_eq!(splits, [want]);
    // Without splitting, the box's centre decides: the ball is farther, so it is drawn
    // before the whole chunk (under the water: wrong where they overlap).
    let (_, splits) = interleave(&[b], eye, &seq, false, false);
    assert_eq!(splits, [Split { quad: 0, ..want }]);
    // Under the water: before both.
    let b = ball(1.0, 12.0);
    assert_eq!(quad_split(b, eye, s.origin, &quads, false), 0);
    // Above the water and in front of the pane: after both.
    let b = ball(7.0, 30.0);
    assert_eq!(quad_split(b, eye, s.origin, &quads, false), 2);
}

/// The chunk order keys of `positions` for `eye`.
fn keys_of(positions: &[ChunkPos], eye: DVec3) -> Vec<u128> {
    positions
        .iter()
        .map(|&p| voxel_mesh::order::chunk_order_key(p, eye.to_array()))
        .collect()
}

fn quad_planes_of(quads: &[PackedQuad]) -> Vec<(Face, u8)> {
    let mut planes: Vec<(Face, u8)> = quads
        .iter()
        .filter_map(|q| q.unpack())
        .map(|q| (q.face, q.bounds().0[q.face.axis()] as u8))
        .collect();
    planes.sort_unstable_by_key(|&(f, c)| (f as u8, c));
    planes.dedup();
    planes
}

/// One chunk with a water surface (top faces of y = 3) for the eye at `eye`.
fn water_surface<'a>(quads: &'a [PackedQuad], planes: &'a [(Face, u8)]) -> Surfaces<'a> {
    Surfaces {
        lo: DVec3::new(0.0, 4.0, 0.0),
        hi: DVec3::new(32.0, 4.0, 32.0),
        origin: [0.0; 3],
        scale: [1.0; 3],
        planes,
        quads,
    }
}

#[test]
fn an_object_through_a_surface_is_cut_and_each_part_placed_on_its_side() {
    use voxel_core::BlockId;
    use voxel_mesh::Quad;
    let quads = [PackedQuad::pack(&Quad {
        pos: [0, 3, 0],
        size: [32, 32],
        face: Face::PosY,
        block: BlockId(1),
    })];
    let planes = quad_planes_of(&quads);
    let s = water_surface(&quads, &planes);
    let positions = [ChunkPos::new(0, 0, 0)];
    for eye in [DVec3::new(16.0, 9.0, 40.0), DVec3::new(16.0, 1.0, 40.0)] {
        let two_sided = eye.y < 4.0;
        let keys = keys_of(&positions, eye);
        let one = [Some(s)];
        let seq = ChunkSequence {
            surfaces: &one,
            keys: &keys,
            positions: &positions,
        };
        // A cube from y = 3 to 5 through the surface at y = 4.
        let cube = Ball::new(DVec3::new(16.0, 4.0, 16.0), 3f64.sqrt(), Some(DVec3::ONE));
        let mut orderer = Interleaver::default();
        orderer.run(1, |_| cube, eye, &seq, two_sided, true);
        let (order, splits, clips) = orderer.result();
        // Object 0 once in the order, drawn by two runs (one a part).
        assert_eq!(order, [0]);
        assert_eq!(splits.len(), 2, "two parts of object 0: {splits:?}");
        assert!(splits.iter().all(|s| (s.start, s.end) == (0, 1)));
        // The part beyond the surface before its quad, the part on the eye's side after it
        // (past the chunk's last quad: after the chunk).
        let far = splits
            .iter()
            .find(|s| clips[s.clip as usize].iter().any(|c| c.far));
        let near = splits
            .iter()
            .find(|s| clips[s.clip as usize].iter().any(|c| !c.far));
        let (Some(far), Some(near)) = (far, near) else {
            panic!("a part on each side: {splits:?} {clips:?}");
        };
        assert_eq!((far.chunk, far.quad), (0, 0), "beyond: before the surface");
        assert!(
            near.chunk == 1 || near.quad == 1,
            "eye's side: after the surface"
        );
        let clip = &clips[near.clip as usize];
        assert_eq!(clip.len(), 1);
        assert_eq!((clip[0].axis, clip[0].at), (1, 4.0));
        assert_eq!(clip[0].eye_side, if eye.y > 4.0 { 1.0 } else { -1.0 });
        // The same cube without sorted-quads' cut: one place.
        let (order, _) = interleave(&[cube], eye, &seq, two_sided, false);
        assert_eq!(order, [0]);
    }
}

#[test]
fn a_face_lying_in_a_surface_is_on_the_eyes_side_of_it() {
    use voxel_core::BlockId;
    use voxel_mesh::Quad;
    let quads = [PackedQuad::pack(&Quad {
        pos: [0, 3, 0],
        size: [32, 32],
        face: Face::PosY,
        block: BlockId(1),
    })];
    let planes = quad_planes_of(&quads);
    let s = water_surface(&quads, &planes);
    let positions = [ChunkPos::new(0, 0, 0)];
    // Foam resting on the surface: its bottom face in the plane (to 32-bit rounding).
    let foam = Ball::new(
        DVec3::new(16.0, 4.01, 16.0),
        2.0,
        Some(DVec3::new(1.5, f64::from(0.01f32), 1.0)),
    );
    let place = |eye: DVec3| {
        let keys = keys_of(&positions, eye);
        let one = [Some(s)];
        let seq = ChunkSequence {
            surfaces: &one,
            keys: &keys,
            positions: &positions,
        };
        let mut orderer = Interleaver::default();
        orderer.run(1, |_| foam, eye, &seq, eye.y < 4.0, true);
        let (order, splits, clips) = orderer.result();
        assert_eq!(order, [0]);
        (splits.len(), splits.to_vec(), clips.to_vec())
    };
    // From above: wholly on the eye's side, after the surface, not cut.
    let (parts, splits, _) = place(DVec3::new(16.0, 9.0, 40.0));
    assert_eq!(parts, 1);
    assert!(
        splits
            .iter()
            .all(|s| s.clip == 0 && (s.chunk == 1 || s.quad == 1))
    );
    // From below: the face in the plane after the surface (in front), the rest before.
    let (parts, splits, clips) = place(DVec3::new(16.0, 1.0, 40.0));
    assert_eq!(parts, 2);
    for s in &splits {
        let far = clips[s.clip as usize][0].far;
        assert_eq!(far, s.quad == 0 && s.chunk == 0, "{splits:?} {clips:?}");
    }
}

#[test]
fn parts_share_the_fewest_places_their_ranges_allow() {
    let mut o = Interleaver::default();
    let part = |object| Part {
        object,
        ball: point(DVec3::ZERO),
        clip: 0,
    };
    // Ranges (earliest, latest): [1,3], [2,5], [4,6], [6,6], [0,0].
    let ranges = [
        ((1, 0), (3, 0)),
        ((2, 0), (5, 0)),
        ((4, 0), (6, 0)),
        ((6, 0), (6, 0)),
        ((0, 0), (0, 0)),
    ];
    for (i, &r) in ranges.iter().enumerate() {
        o.push_range(part(i as u32), r, 0);
    }
    o.gather();
    for (p, (lo, hi)) in o.places.iter().zip(ranges) {
        assert!(lo <= *p && *p <= hi, "{p:?} outside {lo:?}..{hi:?}");
    }
    let mut distinct = o.places.clone();
    distinct.sort();
    distinct.dedup();
    // 0 alone; 1..3 and 2..5 share 3; 4..6 and 6 share 6: three places, the fewest.
    assert_eq!(distinct, vec![(0, 0), (3, 0), (6, 0)]);
}

#[test]
fn parts_of_one_clip_join_a_run_only_over_parts_they_cannot_overlap() {
    let eye = DVec3::ZERO;
    let ball = |x: f64| Ball::sphere(DVec3::new(x, 0.0, -10.0), 0.5);
    // Farthest first at one place: clips 1, 0, 1, 0 and a last clip-1 part that lies on
    // the screen where the clip-0 part before it does.
    let parts: Vec<Part> = [(-6.0, 1), (-3.0, 0), (0.0, 1), (3.0, 0), (3.2, 1)]
        .into_iter()
        .enumerate()
        .map(|(i, (x, clip))| Part {
            object: i as u32,
            ball: ball(x),
            clip,
        })
        .collect();
    let places = vec![(0u32, 0u32); parts.len()];
    let (mut drawn, mut room) = ((0..parts.len() as u32).collect::<Vec<_>>(), Vec::new());
    group_clips(&parts, &places, eye, &mut drawn, &mut room);
    // Part 2 moves back over part 1 (apart on screen) to join part 0; part 4 stays after
    // part 3, which it overlaps: three runs (clips 1, 0, 1) instead of five.
    assert_eq!(drawn, vec![0, 2, 1, 3, 4]);
    assert!(may_overlap(ball(3.0), ball(3.2), eye));
    assert!(!may_overlap(ball(-3.0), ball(0.0), eye));
    // The eye inside a ball: it covers everything.
    assert!(may_overlap(Ball::sphere(DVec3::ZERO, 1.0), ball(-6.0), eye));
}
