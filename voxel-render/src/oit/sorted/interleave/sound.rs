//! The sound tests of an object against a chunk's translucent quads (see the module docs
//! of `interleave`): the box, the distances and the quads' planes, and the planes an
//! object reaches through.

use glam::DVec3;

#[cfg(test)]
use voxel_mesh::PackedQuad;

use super::Ball;
use crate::chunks::Surfaces;

/// A plane of a chunk's quads as the eye sees it, worked out once per frame: its axis,
/// where it lies (world blocks), its facing (1 or -1 along the axis), and how far the eye
/// is in front of it (along the facing). Planes the eye sees from behind (culled, unless
/// both sides are drawn) or edge-on are left out: they order nothing.
#[derive(Clone, Copy, Debug)]
pub(super) struct SeenPlane {
    pub(super) axis: usize,
    pub(super) at: f64,
    pub(super) facing: f64,
    pub(super) eye: f64,
    /// Its index in [`Surfaces::planes`].
    pub(super) index: u32,
}

/// The planes of `s` the eye at `eye` sees (see [`SeenPlane`]).
pub(super) fn seen_planes(s: &Surfaces<'_>, eye: DVec3, two_sided: bool, out: &mut Vec<SeenPlane>) {
    out.extend(s.planes.iter().enumerate().filter_map(|(i, &(face, c))| {
        let axis = face.axis();
        let facing = if face.is_positive() { 1.0 } else { -1.0 };
        let at = s.plane_at(axis, f64::from(c));
        let e = (eye[axis] - at) * facing;
        ((two_sided || e > 0.0) && e != 0.0).then_some(SeenPlane {
            axis,
            at,
            facing,
            eye: e,
            index: i as u32,
        })
    }));
}

/// Which orders of ball `b` and chunk surfaces `s` the sound tests prove right: `[after
/// the chunk, before it]` (the ball in front, behind). Both: they do not overlap on screen.
/// Whether both are right because they are apart on screen is looked at only with
/// `look_apart`: it matters only where other chunks constrain the ball too (where one
/// chunk alone does, any place it proves, or its planes choose, is right), and without it
/// one order proven by the box or distance ends the tests.
pub(super) fn safe(
    b: Ball,
    o: f64,
    eye: DVec3,
    s: &Surfaces<'_>,
    planes: &[SeenPlane],
    [near, _, far]: [f64; 3],
    look_apart: bool,
) -> [bool; 2] {
    let (p, r, h) = (b.center, b.radius, b.half);
    let (mut front, mut behind) = (o + r < near, o - r > far);
    for a in 0..3 {
        let (lo, hi, ea) = (s.lo[a], s.hi[a], eye[a]);
        // Touching a face of the box counts as reaching it (`side_of_plane`).
        let (below, above) = (
            p[a] + h[a] < lo - touch(h[a]),
            p[a] - h[a] > hi + touch(h[a]),
        );
        front |= (below && ea <= lo) || (above && ea >= hi);
        behind |= (below && ea >= lo) || (above && ea <= hi);
    }
    if !look_apart && (front || behind) {
        return [front, behind];
    }
    // The quads' planes: every seen plane with the ball on the eye's side, or every one
    // with it beyond.
    let (mut eye_side, mut beyond) = (false, false);
    for pl in planes {
        match plane_weight(b, pl) {
            1 => eye_side = true,
            -1 => beyond = true,
            // Through the plane: neither.
            _ => (eye_side, beyond) = (true, true),
        }
    }
    front |= !beyond;
    behind |= !eye_side && beyond;
    // Apart on screen: both orders are right.
    let apart = (front && behind) || (look_apart && separate(b, eye, s));
    [front || apart, behind || apart]
}

/// Whether ball `b` and the box of `s` are apart as seen from `eye`: the cones from the
/// eye around their bounding balls do not meet (then either order is right).
pub(super) fn separate(b: Ball, eye: DVec3, s: &Surfaces<'_>) -> bool {
    let (c, big) = ((s.lo + s.hi) * 0.5, (s.hi - s.lo).length() * 0.5);
    let (u, v) = (c - eye, b.center - eye);
    let (du, dv) = (u.length(), v.length());
    if du <= big || dv <= b.radius {
        return false;
    }
    // The angle between them beyond the sum of the cones' half angles A + B (each below
    // a right angle): its cosine below cos(A + B), without trigonometry.
    let (sa, sb) = (big / du, b.radius / dv);
    let (ca, cb) = ((1.0 - sa * sa).sqrt(), (1.0 - sb * sb).sqrt());
    u.dot(v) / (du * dv) < ca * cb - sa * sb
}

/// How strongly a place for an object is ruled out: a chunk-wide sound test against a
/// single quad's plane.
pub(super) const SOUND: i64 = 1 << 24;

/// How one quad's plane orders it against ball `b` (chunk origin `origin`): `Some(true)`
/// when the ball is on the eye's side (the quad comes before it), `Some(false)` beyond,
/// `None` when the ball crosses the plane or the quad is culled or seen edge-on.
#[cfg(test)]
pub(super) fn quad_side(
    b: Ball,
    eye: DVec3,
    origin: [f64; 3],
    q: PackedQuad,
    two_sided: bool,
) -> Option<bool> {
    let q = q.unpack()?;
    let a = q.face.axis();
    let n = if q.face.is_positive() { 1.0 } else { -1.0 };
    let plane = origin[a] + q.bounds().0[a];
    let e = (eye[a] - plane) * n;
    if (!two_sided && e <= 0.0) || e == 0.0 {
        return None;
    }
    match side_of_plane(b, a, plane, eye[a] - plane) {
        1 => Some(true),
        -1 => Some(false),
        _ => None,
    }
}

/// A chunk's quads as runs of one plane in their drawn order (index into
/// [`Surfaces::planes`], count), appended to `out`, and the box of each run's quads (world
/// blocks) to `boxes`, one per run: every quad of a plane stands alike against a ball
/// ([`quad_side`] depends only on the plane), so a split is chosen per run boundary. The
/// box is a run's, not its plane's: one plane's quads drawn at different places of the
/// order (the side of a glass floor drawn early, the side of the glass layer above it in
/// the same plane drawn after the floor's top) each order only an object whose shadow
/// meets them, so that quads of a plane the object cannot overlap on screen put no
/// constraint on it that no place can meet (issue 52, G1).
pub(super) fn plane_runs(
    s: &Surfaces<'_>,
    out: &mut Vec<(u32, u32)>,
    boxes: &mut Vec<(DVec3, DVec3)>,
) {
    let start = out.len();
    for q in s.quads {
        let Some(q) = q.unpack() else { continue };
        let (lo, hi) = q.bounds();
        let plane = (q.face, lo[q.face.axis()] as u8);
        let Ok(i) = s
            .planes
            .binary_search_by_key(&(plane.0 as u8, plane.1), |&(f, c)| (f as u8, c))
        else {
            continue;
        };
        let (lo, hi) = (s.world(lo), s.world(hi));
        match out[start..].last_mut() {
            Some((p, n)) if *p == i as u32 => {
                *n += 1;
                if let Some(b) = boxes.last_mut() {
                    *b = (b.0.min(lo), b.1.max(hi));
                }
            }
            _ => {
                out.push((i as u32, 1));
                boxes.push((lo, hi));
            }
        }
    }
}

/// Whether no ray from `eye` through ball `b`'s box can meet the rectangle `(lo, hi)` of a
/// plane along `axis` (the box of its quads): the box lies wholly on the other side of the
/// eye (the rays through it go away from the plane), or its shadow cast from the eye onto
/// the plane misses the rectangle. Then the plane's quads and the object never overlap on
/// screen and the plane orders nothing. `false` where it cannot tell (the eye within the
/// box's reach along the axis).
pub(super) fn shadow_misses(b: Ball, eye: DVec3, axis: usize, (lo, hi): (DVec3, DVec3)) -> bool {
    let at = lo[axis];
    let to_plane = at - eye[axis];
    let (near, far) = (b.center[axis] - b.half[axis], b.center[axis] + b.half[axis]);
    let (dn, df) = ((near - eye[axis]) * to_plane, (far - eye[axis]) * to_plane);
    if to_plane == 0.0 {
        return false;
    }
    if dn < 0.0 && df < 0.0 {
        return true;
    }
    // Every point of the box on the plane's side of the eye, off the eye's own plane.
    if dn <= 0.0 || df <= 0.0 {
        return false;
    }
    let [u, v] = [(axis + 1) % 3, (axis + 2) % 3];
    // The centre's shadow on the rectangle: the box's meets it (most objects under a
    // surface that spans the chunk), without the corners.
    let t = to_plane / (b.center[axis] - eye[axis]);
    let inside = |a: usize| {
        let p = eye[a] + (b.center[a] - eye[a]) * t;
        p >= lo[a] && p <= hi[a]
    };
    if inside(u) && inside(v) {
        return false;
    }
    let (mut smin, mut smax) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for k in 0..8 {
        let corner = DVec3::new(
            b.center.x + if k & 1 == 0 { -b.half.x } else { b.half.x },
            b.center.y + if k & 2 == 0 { -b.half.y } else { b.half.y },
            b.center.z + if k & 4 == 0 { -b.half.z } else { b.half.z },
        );
        let t = to_plane / (corner[axis] - eye[axis]);
        for (i, a) in [u, v].into_iter().enumerate() {
            let p = eye[a] + (corner[a] - eye[a]) * t;
            smin[i] = smin[i].min(p);
            smax[i] = smax[i].max(p);
        }
    }
    // Apart on either axis of the plane (by more than rounding).
    [u, v].into_iter().enumerate().any(|(i, a)| {
        let slack = touch(hi[a] - lo[a]);
        smax[i] < lo[a] - slack || smin[i] > hi[a] + slack
    })
}

/// How a seen plane orders ball `b` (see [`quad_side`]), as a weight: 1 when the plane's
/// quads come before the ball, -1 after it, 0 when the ball reaches through it.
pub(super) fn plane_weight(b: Ball, pl: &SeenPlane) -> i64 {
    side_of_plane(b, pl.axis, pl.at, pl.eye * pl.facing)
}

/// Where ball `b` lies against the plane at `at` along `axis`, the eye on the side of sign
/// `eye_side` (nonzero): 1 wholly on the eye's side, -1 wholly beyond, 0 through the
/// plane. A face of the object lying in the plane counts on the eye's side (the rule for
/// equal depths, `stages::OBJECT_DEPTH_BIAS`: foam lying in a water surface is in front
/// of it from either side), so an object beyond the plane that touches it is through it.
pub(super) fn side_of_plane(b: Ball, axis: usize, at: f64, eye_side: f64) -> i64 {
    let s = (b.center[axis] - at) * eye_side.signum();
    let h = b.half[axis];
    // An object's face computed to lie in the plane may miss it by a rounding error (a
    // turned box's extent along the axis).
    let tol = touch(h);
    if s - h >= -tol {
        1
    } else if s + h < -tol {
        -1
    } else {
        0
    }
}

/// How near a plane an object's extent counts as reaching it, relative to the extent (plus
/// a block): a game's sizes are 32-bit floats (foam 0.02 thick, resting on a surface at
/// 0.01, misses it by 2e-10), and the exact methods' tie rule puts faces that near in the
/// plane (`stages::OBJECT_DEPTH_BIAS`).
pub(super) const TOUCH: f64 = 1e-6;

/// [`TOUCH`] for an extent `h`, blocks.
pub(super) fn touch(h: f64) -> f64 {
    TOUCH * (1.0 + h)
}
