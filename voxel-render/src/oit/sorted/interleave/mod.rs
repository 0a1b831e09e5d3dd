//! Where the sorted techniques draw a game's translucent objects among the chunks.
//!
//! Each object is a ball (its centre and radius, [`crate::stages::TranslucentObject`]).
//! Against a chunk's translucent quads it is **behind** (drawn before the chunk: no part of
//! it can cover a quad of the chunk) or **in front** (drawn after: no quad can cover it).
//! The tests, each sound on its own:
//! - distance: the ball farther from the eye than every point of the quads' box is
//!   behind, nearer than every point is in front;
//! - the box's face planes: the ball outside the box on the eye's side of one of them is in
//!   front (no segment from the eye to the ball meets the box); the ball outside and the
//!   eye on the box's side is behind (no segment from the eye to the box meets the ball);
//! - the quads' planes: the ball on the eye's side of every plane it sees (the planes of
//!   quads facing away are culled, unless both sides are drawn) is in front, on the far
//!   side of every one is behind.
//!
//! - apart: the cones from the eye around the ball and around the box's bounding ball do
//!   not meet (or both sides are proven): any order is right, the chunk constrains nothing.
//!
//! Where no test decides (a ball between two layers of a chunk, or through one),
//! `sorted-quads` weighs each quad's plane (in the chunk's exact back-to-front order) and
//! `sorted` the centre of the box (the ball's centre farther than it: behind). Each object
//! goes to the place in the sequence of chunks (and quads) that the fewest constraints rule
//! out, a decided chunk outweighing any number of quads; objects at the same place go
//! farthest centre first. The order is exact between chunks and for every object that some
//! test decides against each chunk it overlaps on screen, and for `sorted-quads` also
//! among the layers of a chunk where the planes agree; not for an object through a layer
//! (a cube crossing a water surface), nor between objects that overlap in depth (their
//! centres decide).

use glam::DVec3;

use voxel_core::ChunkPos;
#[cfg(test)]
use voxel_core::Face;
#[cfg(test)]
use voxel_mesh::PackedQuad;

use crate::chunks::Surfaces;

/// An object as the order sees it: a ball, and along each axis how far the object
/// reaches from the centre (the ball's radius, or less where its box is known).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Ball {
    /// Centre, world blocks.
    pub center: DVec3,
    /// Radius, blocks (0: a point).
    pub radius: f64,
    /// Reach along each axis from the centre, blocks: at most the radius.
    pub half: DVec3,
}

impl Ball {
    /// A ball of `radius` around `center` that also lies within `half` of it along each
    /// axis, where given. A radius or extent that is not a finite non-negative number
    /// counts as 0.
    pub(crate) fn new(center: DVec3, radius: f64, half: Option<DVec3>) -> Self {
        let clean = |v: f64| if v.is_finite() { v.max(0.0) } else { 0.0 };
        let radius = clean(radius);
        let half = half.map_or(DVec3::splat(radius), |h| {
            DVec3::new(clean(h.x), clean(h.y), clean(h.z)).min(DVec3::splat(radius))
        });
        Self {
            center,
            radius,
            half,
        }
    }

    /// A ball of `radius` around `center`.
    #[cfg(test)]
    pub(crate) fn sphere(center: DVec3, radius: f64) -> Self {
        Self::new(center, radius, None)
    }
}

/// A plane of a chunk's quads as the eye sees it, worked out once per frame: its axis,
/// where it lies (world blocks), its facing (1 or -1 along the axis), and how far the eye
/// is in front of it (along the facing). Planes the eye sees from behind (culled, unless
/// both sides are drawn) or edge-on are left out: they order nothing.
#[derive(Clone, Copy, Debug)]
struct SeenPlane {
    axis: usize,
    at: f64,
    facing: f64,
    eye: f64,
    /// Its index in [`Surfaces::planes`].
    index: u32,
}

/// The planes of `s` the eye at `eye` sees (see [`SeenPlane`]).
fn seen_planes(s: &Surfaces<'_>, eye: DVec3, two_sided: bool, out: &mut Vec<SeenPlane>) {
    out.extend(s.planes.iter().enumerate().filter_map(|(i, &(face, c))| {
        let axis = face.axis();
        let facing = if face.is_positive() { 1.0 } else { -1.0 };
        let at = s.origin[axis] + f64::from(c);
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
fn safe(
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
fn separate(b: Ball, eye: DVec3, s: &Surfaces<'_>) -> bool {
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

// `Split` lives with the stages that carry it to the techniques (`GameDraw::splits`), so
// that `stages` does not reach up into `oit`.
pub(crate) use crate::stages::Split;

/// How strongly a place for an object is ruled out: a chunk-wide sound test against a
/// single quad's plane.
const SOUND: i64 = 1 << 24;

/// How one quad's plane orders it against ball `b` (chunk origin `origin`): `Some(true)`
/// when the ball is on the eye's side (the quad comes before it), `Some(false)` beyond,
/// `None` when the ball crosses the plane or the quad is culled or seen edge-on.
#[cfg(test)]
fn quad_side(
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

/// The visible translucent chunks of a frame in draw order, as [`Interleaver::order`] reads them.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ChunkSequence<'a> {
    /// Each chunk's surfaces (`None`: it draws nothing translucent).
    pub surfaces: &'a [Option<Surfaces<'a>>],
    /// Each chunk's [`voxel_mesh::order::chunk_order_key`] for the frame's eye: the
    /// sequence is sorted by it, largest first (equal keys by position).
    pub keys: &'a [u128],
    /// Each chunk's position.
    pub positions: &'a [ChunkPos],
}

/// The chunk cells a ball touches, inclusive per axis (a ball touching a cell's face
/// touches both cells), and their keys' range for an eye in cell `eye`: the least and
/// the greatest [`voxel_mesh::order::chunk_order_key`] among them.
fn cells_and_keys(b: Ball, eye: [i64; 3]) -> ([[i64; 2]; 3], [u128; 2]) {
    let s = 1.0 / voxel_core::CHUNK_SIZE as f64;
    // Touching a cell's face within rounding counts as touching it (`side_of_plane`).
    let half = |a: usize| b.half[a] + touch(b.half[a]);
    // Most balls lie inside the cell of their centre, off its borders.
    let cell = [
        floor_i64(b.center.x * s),
        floor_i64(b.center.y * s),
        floor_i64(b.center.z * s),
    ];
    let inside = (0..3).all(|a| {
        let lo = cell[a] as f64 * voxel_core::CHUNK_SIZE as f64;
        b.center[a] - half(a) > lo && b.center[a] + half(a) < lo + voxel_core::CHUNK_SIZE as f64
    });
    if inside {
        let k = (0..3)
            .map(|a| {
                let d = (cell[a] - eye[a]).unsigned_abs();
                u128::from(d) * u128::from(d)
            })
            .sum();
        return (cell.map(|c| [c, c]), [k, k]);
    }
    let mut cells = [[0i64; 2]; 3];
    let (mut kmin, mut kmax) = (0u128, 0u128);
    for a in 0..3 {
        // `ceil(x) - 1` is `floor(x)` except on a border, where it is the cell below.
        let lo = ceil_i64((b.center[a] - half(a)) * s) - 1;
        let hi = floor_i64((b.center[a] + half(a)) * s);
        cells[a] = [lo, hi];
        let (dl, dh) = (lo - eye[a], hi - eye[a]);
        let sq = |d: i64| u128::from(d.unsigned_abs()) * u128::from(d.unsigned_abs());
        kmin += if dl <= 0 && dh >= 0 {
            0
        } else {
            sq(dl).min(sq(dh))
        };
        kmax += sq(dl).max(sq(dh));
    }
    (cells, [kmin, kmax])
}

/// The cell bound of a coordinate, clamped just past the `i32` world (as
/// [`voxel_mesh::order::chunk_order_key`] clamps): by truncation, since `floor` and `ceil`
/// are library calls on baseline x86-64.
fn floor_i64(x: f64) -> i64 {
    let x = x.clamp(f64::from(i32::MIN) - 1.0, f64::from(i32::MAX) + 1.0);
    let t = x as i64;
    t - i64::from((t as f64) > x)
}

fn ceil_i64(x: f64) -> i64 {
    let x = x.clamp(f64::from(i32::MIN) - 1.0, f64::from(i32::MAX) + 1.0);
    let t = x as i64;
    t + i64::from((t as f64) < x)
}

/// The eye's chunk cell, as [`voxel_mesh::order::chunk_order_key`] takes it.
fn eye_cell(eye: DVec3) -> [i64; 3] {
    let s = 1.0 / voxel_core::CHUNK_SIZE as f64;
    [
        floor_i64(eye.x * s),
        floor_i64(eye.y * s),
        floor_i64(eye.z * s),
    ]
}

/// A chunk's quads as runs of one plane in their drawn order (index into
/// [`Surfaces::planes`], count), appended to `out`: every quad of a plane stands alike against a ball
/// ([`quad_side`] depends only on the plane), so a split is chosen per run boundary.
fn plane_runs(s: &Surfaces<'_>, out: &mut Vec<(u32, u32)>, boxes: &mut Vec<(DVec3, DVec3)>) {
    let start = out.len();
    let first_box = boxes.len();
    boxes.resize(
        first_box + s.planes.len(),
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
    );
    let o = DVec3::from(s.origin);
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
        let b = &mut boxes[first_box + i];
        b.0 = b.0.min(DVec3::from(lo) + o);
        b.1 = b.1.max(DVec3::from(hi) + o);
        match out[start..].last_mut() {
            Some((p, n)) if *p == i as u32 => *n += 1,
            _ => out.push((i as u32, 1)),
        }
    }
}

/// Whether no ray from `eye` through ball `b`'s box can meet the rectangle `(lo, hi)` of a
/// plane along `axis` (the box of its quads): the box lies wholly on the other side of the
/// eye (the rays through it go away from the plane), or its shadow cast from the eye onto
/// the plane misses the rectangle. Then the plane's quads and the object never overlap on
/// screen and the plane orders nothing. `false` where it cannot tell (the eye within the
/// box's reach along the axis).
fn shadow_misses(b: Ball, eye: DVec3, axis: usize, (lo, hi): (DVec3, DVec3)) -> bool {
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
fn plane_weight(b: Ball, pl: &SeenPlane) -> i64 {
    side_of_plane(b, pl.axis, pl.at, pl.eye * pl.facing)
}

/// Where ball `b` lies against the plane at `at` along `axis`, the eye on the side of sign
/// `eye_side` (nonzero): 1 wholly on the eye's side, -1 wholly beyond, 0 through the
/// plane. A face of the object lying in the plane counts on the eye's side (the rule for
/// equal depths, `stages::OBJECT_DEPTH_BIAS`: foam lying in a water surface is in front
/// of it from either side), so an object beyond the plane that touches it is through it.
fn side_of_plane(b: Ball, axis: usize, at: f64, eye_side: f64) -> i64 {
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
const TOUCH: f64 = 1e-6;

/// [`TOUCH`] for an extent `h`, blocks.
fn touch(h: f64) -> f64 {
    TOUCH * (1.0 + h)
}

/// How many chunks of the sequence have a key above a given one: a table by key when the
/// keys are small (they are squared distances in chunks from the eye's chunk, below
/// 3 · 64² for everything within the largest view distance), else a binary search.
struct KeyIndex<'a> {
    keys: &'a [u128],
    /// `above[k]`: chunks with a key above `k`, for `k` up to the largest key.
    above: Vec<u32>,
}

impl<'a> KeyIndex<'a> {
    /// Largest key a table is made for.
    const TABLE: u128 = 1 << 20;

    fn new(keys: &'a [u128]) -> Self {
        let largest = keys.first().copied().unwrap_or(0);
        let mut above = Vec::new();
        if largest < Self::TABLE {
            // Keys are largest first: walk them from the end.
            above.resize(largest as usize + 1, 0);
            let mut i = keys.len();
            for k in 0..=largest {
                while i > 0 && keys[i - 1] <= k {
                    i -= 1;
                }
                above[k as usize] = i as u32;
            }
        }
        Self { keys, above }
    }

    /// How many chunks have a key above `k` (the index of the first with `k` or less).
    fn above(&self, k: u128) -> usize {
        if self.above.is_empty() {
            return self.keys.partition_point(|&x| x > k);
        }
        if k >= self.above.len() as u128 {
            return 0;
        }
        self.above[k as usize] as usize
    }
}

/// Where each chunk cell stands in the sequence: a grid over the box the sequence's chunks
/// span (a few thousand cells within a view distance), else a map.
struct CellIndex {
    lo: [i64; 3],
    size: [i64; 3],
    grid: Vec<u32>,
    map: std::collections::HashMap<[i64; 3], usize>,
}

impl CellIndex {
    /// Most cells a grid is made for.
    const GRID: i64 = 1 << 22;

    fn new(positions: &[ChunkPos]) -> Self {
        let cell = |p: &ChunkPos| [i64::from(p.x), i64::from(p.y), i64::from(p.z)];
        let (mut lo, mut hi) = ([i64::MAX; 3], [i64::MIN; 3]);
        for p in positions {
            let c = cell(p);
            for a in 0..3 {
                lo[a] = lo[a].min(c[a]);
                hi[a] = hi[a].max(c[a]);
            }
        }
        let size = [0, 1, 2].map(|a| (hi[a] - lo[a] + 1).max(0));
        let mut index = Self {
            lo,
            size,
            grid: Vec::new(),
            map: std::collections::HashMap::new(),
        };
        let cells = size[0].saturating_mul(size[1]).saturating_mul(size[2]);
        if cells <= Self::GRID {
            index.grid = vec![u32::MAX; cells as usize];
            for (i, p) in positions.iter().enumerate() {
                let at = index.slot(cell(p)).unwrap_or(0);
                index.grid[at] = i as u32;
            }
        } else {
            index.map = positions
                .iter()
                .enumerate()
                .map(|(i, p)| (cell(p), i))
                .collect();
        }
        index
    }

    fn slot(&self, c: [i64; 3]) -> Option<usize> {
        let d = [0, 1, 2].map(|a| c[a] - self.lo[a]);
        if (0..3).any(|a| d[a] < 0 || d[a] >= self.size[a]) {
            return None;
        }
        Some((d[0] + self.size[0] * (d[1] + self.size[1] * d[2])) as usize)
    }

    /// The place in the sequence of the chunk in cell `c`, if it is there.
    fn get(&self, c: [i64; 3]) -> Option<usize> {
        if self.grid.is_empty() {
            return self.map.get(&c).copied();
        }
        let i = self.grid[self.slot(c)?];
        (i != u32::MAX).then_some(i as usize)
    }
}

/// Per frame, what [`Interleaver::order`] learns of a chunk the first time an object
/// needs it: the `[near, mid, far]` distances of its box ([`Surfaces::distances`]), the
/// planes the eye sees and its quads as plane runs ([`plane_runs`], for `split_quads`),
/// those two as ranges of the interleaver's buffers.
#[derive(Clone, Copy, Debug, Default)]
struct ChunkFacts {
    distances: [f64; 3],
    planes: Option<(u32, u32)>,
    /// The runs, and where the boxes of its planes' quads start.
    runs: Option<(u32, u32, u32)>,
}

/// [`Interleaver::order`] of `balls` in fresh buffers (for the tests): the objects of the
/// parts in draw order, and the runs.
#[cfg(test)]
pub(crate) fn interleave(
    balls: &[Ball],
    eye: DVec3,
    chunks: &ChunkSequence<'_>,
    two_sided: bool,
    split_quads: bool,
) -> (Vec<u32>, Vec<Split>) {
    let mut orderer = Interleaver::default();
    orderer.run(
        balls.len(),
        |i| balls[i],
        eye,
        chunks,
        two_sided,
        split_quads,
    );
    (orderer.order, orderer.splits)
}

/// The most planes an object is split at (into at most 12 parts, each clipped by at most
/// two planes an axis): a thing crosses a handful of a chunk's planes, not hundreds (a pole
/// through three panes and a chunk border).
pub(crate) const MAX_SPLIT_PLANES: usize = 4;

/// How many times a part is cut again (where its cuts leave it across chunks no one place
/// suits).
const MAX_SPLIT_DEPTH: u32 = 2;

pub(crate) use crate::stages::{Clip, ClipPlane};

/// One piece of an object to draw: the whole of it, or the part between the planes it was
/// split at (`Interleaver`'s clips).
#[derive(Clone, Copy, Debug)]
struct Part {
    object: u32,
    ball: Ball,
    clip: u32,
}

/// Orders a game's objects among the chunks ([`Interleaver::order`]), its buffers kept
/// between frames (thousands of objects a frame would otherwise allocate and fault in
/// megabytes each time): the renderer holds one.
#[derive(Debug, Default)]
pub(crate) struct Interleaver {
    /// The parts drawn: each object, or its pieces where it was split.
    parts: Vec<Part>,
    /// Each part's place (chunk, quad): first the earliest place the fewest constraints
    /// rule out, then the one chosen within its range (`Interleaver::gather`).
    places: Vec<(u32, u32)>,
    /// Each part's latest place as good as its earliest (the same constraints ruled out).
    latest: Vec<(u32, u32)>,
    /// Room for gathering: each part's latest place as a sort key, and the part.
    by_latest: Vec<(u64, u32)>,
    /// Each part's distance as a key that orders farthest first, and the part.
    farthest: Vec<(u32, u32)>,
    /// Room for the radix sort.
    spare: Vec<(u32, u32)>,
    /// The constraints of the object being placed: (chunk, quad after which it applies,
    /// weight, the first quad of its run).
    items: Vec<(u32, u32, i64, u32)>,
    weights: Vec<i64>,
    /// The planes an object crosses in the chunks no sound test decides: (axis, at).
    crossings: Vec<(usize, f64, bool)>,
    /// Per chunk, and the seen planes and runs they name.
    facts: Vec<ChunkFacts>,
    seen: Vec<SeenPlane>,
    runs: Vec<(u32, u32)>,
    /// Per chunk that needs them, the box of each plane's quads, world blocks.
    boxes: Vec<(DVec3, DVec3)>,
    /// The distinct clips of the parts (0: none).
    clips: Vec<Clip>,
    /// The view direction (unit; zero: order by distance from the eye instead): objects at
    /// one place go farthest first along it, the order that is exact for particles, which
    /// all face the camera (parallel squares are ordered by their planes).
    forward: DVec3,
    /// The parts' objects in draw order, their parts in that order, and where runs of them
    /// are drawn.
    order: Vec<u32>,
    drawn: Vec<u32>,
    splits: Vec<Split>,
    /// Room for [`group_clips`].
    grouped: Vec<u32>,
}

/// What [`Interleaver::place`] reads of a frame.
struct Frame<'a, 'c> {
    chunks: &'a ChunkSequence<'c>,
    keys: KeyIndex<'a>,
    cells: CellIndex,
    eye: DVec3,
    eye_cell: [i64; 3],
    last: u32,
    two_sided: bool,
    split_quads: bool,
}

impl Interleaver {
    /// Orders `objects` among the visible translucent `chunks` seen from `eye`:
    /// [`Interleaver::result`] gives the objects in draw order and where runs of them are
    /// drawn (in draw order; the objects after the last run come after every chunk).
    ///
    /// **Which chunks an object is tested against.** The chunks are drawn by
    /// [`voxel_mesh::order::chunk_order_key`], which is exact for a grid of equal cubes:
    /// a chunk that hides part of another has the smaller key (Theorem 3 of
    /// [`voxel_mesh::order`]). A chunk that hides part of the ball hides part of a cell the
    /// ball touches, so its key is below the greatest key of those cells; a chunk the ball
    /// hides part of has a key above their least. So every chunk whose key lies above that
    /// range is rightly drawn before the object, every one below it after, and only the
    /// chunks with keys in the range can constrain it: for a ball inside one cell, that cell's
    /// chunk alone (others of the same key neither hide it nor are hidden); for a ball across
    /// cell borders, the thin shell of chunks at about its distance. Their places in the
    /// sequence are found by binary search. The cost grows with objects (plus the chunks of
    /// each shell, mostly proven apart on screen at once), not with objects times chunks.
    ///
    /// **Where, among those.** Each object goes to the place in that part of the sequence
    /// (and, with `split_quads`, among the quads of its chunks, which are then in exact
    /// back-to-front order) that the fewest constraints rule out: a chunk a sound test puts
    /// wholly behind or in front of the object weighs [`SOUND`]; in a chunk no test decides,
    /// each quad's plane ([`quad_side`]) weighs 1, or without `split_quads` the box's centre
    /// decides with weight 1. Objects at one place go farthest centre first, so those that
    /// share a place are one run: one draw of the game's instances.
    ///
    /// **Objects through a plane** (`split_quads`). An object that reaches through planes
    /// of quads in a chunk no test decides (a cube through a water surface, a pole through
    /// panes, foam whose face lies in the surface) is cut at up to [`MAX_SPLIT_PLANES`] of
    /// them, those nearest its centre: each part (the object's box between the planes) is
    /// placed on its own and drawn with its clip (the renderer discards the fragments
    /// outside it), so that each lies wholly on one side of each plane it was cut at and
    /// the planes order it exactly. So is an object across chunk borders that no one place
    /// suits (a slab through a pane two chunks hold), at those borders. A part appears in
    /// the order as its object again.
    ///
    /// An object whose centre or radius is not finite goes after every chunk, and so, for
    /// `sorted`, does one the eye is inside of (a game's translucent volume seen from within:
    /// its far faces are nearer than any chunk outside it); `sorted-quads` cuts such an
    /// object at the planes it reaches through and places the parts.
    pub(crate) fn order(
        &mut self,
        objects: &[crate::stages::TranslucentObject],
        eye: DVec3,
        chunks: &ChunkSequence<'_>,
        two_sided: bool,
        split_quads: bool,
    ) {
        let ball = |i: usize| {
            let o = &objects[i];
            Ball::new(o.center, o.radius, o.half_extents)
        };
        self.run(objects.len(), ball, eye, chunks, two_sided, split_quads);
    }

    /// Orders objects at one place farthest first along the unit view direction `forward`
    /// from now on (before: by distance from the eye).
    pub(crate) fn look(&mut self, forward: DVec3) {
        self.forward = forward;
    }

    /// The key that orders a part centred at `c` farthest first at its place.
    fn key(&self, c: DVec3, eye: DVec3) -> u32 {
        if self.forward == DVec3::ZERO {
            return farthest_key(c.distance_squared(eye));
        }
        farthest_key((c - eye).dot(self.forward).max(0.0))
    }

    /// The last order: the objects in draw order (an object cut into parts once per part),
    /// where runs of them are drawn, and the clips the runs name ([`Split::clip`]; 0 none).
    pub(crate) fn result(&self) -> (&[u32], &[Split], &[Clip]) {
        (&self.order, &self.splits, &self.clips)
    }

    fn run(
        &mut self,
        count: usize,
        ball: impl Fn(usize) -> Ball,
        eye: DVec3,
        chunks: &ChunkSequence<'_>,
        two_sided: bool,
        split_quads: bool,
    ) {
        let frame = Frame {
            chunks,
            keys: KeyIndex::new(chunks.keys),
            cells: CellIndex::new(chunks.positions),
            eye,
            eye_cell: eye_cell(eye),
            last: chunks.surfaces.len() as u32,
            two_sided,
            split_quads,
        };
        self.facts.clear();
        self.facts
            .resize(chunks.surfaces.len(), ChunkFacts::default());
        self.seen.clear();
        self.runs.clear();
        self.boxes.clear();
        self.parts.clear();
        self.places.clear();
        self.latest.clear();
        self.farthest.clear();
        self.clips.clear();
        self.clips.push(Vec::new());
        let last = frame.last;
        for i in 0..count {
            let b = ball(i);
            let whole = Part {
                object: i as u32,
                ball: b,
                clip: 0,
            };
            // Squared distances order like distances: the root only where a test needs it.
            let o2 = b.center.distance_squared(eye);
            if !o2.is_finite() || !b.radius.is_finite() {
                self.push(whole, (last, 0), u32::MAX);
                continue;
            }
            let inside = o2 < b.radius * b.radius
                && (0..3).all(|a| (b.center[a] - eye[a]).abs() < b.half[a]);
            if inside && !split_quads {
                // The eye is inside it (a volume seen from within, whose far faces are drawn):
                // after every chunk, as what lies nearest.
                self.push(whole, (last, 0), self.key(b.center, eye));
                continue;
            }
            self.crossings.clear();
            let at = self.place(&frame, b, split_quads);
            if self.crossings.is_empty() {
                self.push_range(whole, at, self.key(b.center, eye));
                continue;
            }
            self.split(&frame, whole, &[], 0);
        }
        self.gather();
        let Self {
            parts,
            places,
            farthest,
            spare,
            order,
            drawn,
            splits,
            grouped,
            ..
        } = self;
        order_by_place(places, farthest, spare, last, drawn);
        group_clips(parts, places, eye, drawn, grouped);
        order.clear();
        order.extend(drawn.iter().map(|&p| parts[p as usize].object));
        splits.clear();
        for (n, &p) in drawn.iter().enumerate() {
            let (c, k) = places[p as usize];
            let clip = parts[p as usize].clip;
            let next = drawn
                .get(n + 1)
                .map(|&q| (places[q as usize], parts[q as usize].clip));
            if next != Some(((c, k), clip)) && (c < last || clip != 0 || next.is_some()) {
                splits.push(Split {
                    chunk: c,
                    quad: k,
                    end: n as u32 + 1,
                    clip,
                });
            }
        }
    }

    /// Adds a part at place `at`, with distance key `key` (`farthest_key`).
    fn push(&mut self, part: Part, at: (u32, u32), key: u32) {
        self.push_range(part, (at, at), key);
    }

    /// Adds a part that may go anywhere from place `range.0` to `range.1` (the same
    /// constraints ruled out at each), with distance key `key`.
    fn push_range(&mut self, part: Part, range: ((u32, u32), (u32, u32)), key: u32) {
        self.farthest.push((key, self.parts.len() as u32));
        self.places.push(range.0);
        self.latest.push(range.1);
        self.parts.push(part);
    }

    /// Chooses each part's place within its range so that the parts share as few places
    /// as they can: each place is a run of the game's draws among the chunks' quads, with
    /// a pipeline switch to the game's and back around it. The greedy choice is optimal
    /// (stabbing intervals): by latest place, each part goes where the last run stands if
    /// that lies in its range, else starts a new run at its latest place.
    fn gather(&mut self) {
        if self.places == self.latest {
            return;
        }
        let key = |(c, k): (u32, u32)| u64::from(c) << 32 | u64::from(k);
        self.by_latest.clear();
        self.by_latest.extend(
            self.latest
                .iter()
                .enumerate()
                .map(|(i, &l)| (key(l), i as u32)),
        );
        self.by_latest.sort_unstable();
        let mut run: Option<(u32, u32)> = None;
        for &(_, i) in &self.by_latest {
            let i = i as usize;
            let earliest = self.places[i];
            let at = match run {
                Some(r) if key(r) >= key(earliest) => r,
                _ => self.latest[i],
            };
            run = Some(at);
            self.places[i] = at;
        }
    }

    /// Cuts `whole` at the planes it crosses (`self.crossings`, the nearest
    /// [`MAX_SPLIT_PLANES`] to its centre) into the parts between them, and places each.
    fn split(&mut self, frame: &Frame<'_, '_>, whole: Part, parent: &[ClipPlane], depth: u32) {
        let b = whole.ball;
        let c = b.center;
        let mut crossings = std::mem::take(&mut self.crossings);
        crossings.sort_by_key(|x| (x.0, x.1.to_bits(), x.2));
        // A plane of quads that is also a chunk border is cut as a plane of quads.
        crossings.dedup_by(|x, y| (x.0, x.1) == (y.0, y.1));
        crossings.sort_by(|x, y| (c[x.0] - x.1).abs().total_cmp(&(c[y.0] - y.1).abs()));
        crossings.truncate(MAX_SPLIT_PLANES);
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

    /// The index of `clip` among the frame's clips (added if new).
    fn clip_id(&mut self, clip: Clip) -> u32 {
        if let Some(i) = self.clips.iter().position(|c| *c == clip) {
            return i as u32;
        }
        self.clips.push(clip);
        (self.clips.len() - 1) as u32
    }

    /// The places of ball `b` in the sequence (see [`Interleaver::order`]) that the fewest
    /// constraints rule out: the earliest and the latest of the first range of them (the
    /// same constraints ruled out at every place between); with `collect`, the planes it
    /// reaches through in the chunks no sound test decides go to `self.crossings`.
    fn place(&mut self, f: &Frame<'_, '_>, b: Ball, collect: bool) -> ((u32, u32), (u32, u32)) {
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
                    weights.clear();
                    weights.resize(s.planes.len(), 0);
                    for pl in planes.iter() {
                        let quads = boxes[(first_box + pl.index) as usize];
                        // A plane whose quads the object cannot overlap on screen orders
                        // nothing (the top of a glass wall above a fish behind it).
                        if shadow_misses(b, eye, pl.axis, quads) {
                            continue;
                        }
                        let w = plane_weight(b, pl);
                        weights[pl.index as usize] = w;
                        if w == 0 && collect {
                            crossings.push((pl.axis, pl.at, false));
                        }
                    }
                    let mut k = 0u32;
                    for &(p, n) in runs.iter() {
                        let w = weights[p as usize];
                        if w != 0 {
                            // A run weighs its count; the place after it is after its
                            // last quad.
                            items.push((c32, k + n - 1, w * i64::from(n), k));
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

/// How many parts a part may move back over, at most, to join an earlier run of its clip
/// ([`group_clips`]): the tests stay linear in the parts.
const GROUP_WINDOW: usize = 64;

/// Whether balls `a` and `b` may overlap as seen from `eye`: the cones from the eye around
/// them meet (or the eye is inside one).
fn may_overlap(a: Ball, b: Ball, eye: DVec3) -> bool {
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

/// Groups the parts at each place by clip where the picture stays the same: a part joins
/// the last run of its clip at its place (moving back over the parts drawn since) when it
/// overlaps none of them on screen, so that blending them in the other order changes no
/// pixel. Each run of one clip is one draw of the game's with its own clip (and a switch of
/// pipeline around it): parts of objects cut at a surface or a chunk border would
/// otherwise alternate with whole objects in the farthest-first order.
fn group_clips(
    parts: &[Part],
    places: &[(u32, u32)],
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
        let place = places[drawn[from] as usize];
        let to = from + drawn[from..].partition_point(|&i| places[i as usize] == place);
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
fn farthest_key(d: f64) -> u32 {
    !(d as f32).to_bits()
}

/// Sorts `(key, value)` pairs by key, stably, in three passes of eleven bits (Bevy sorts
/// its transparent phase by a radix sort too): linear in the count, a few times faster
/// than a comparison sort for thousands of objects.
fn radix_sort(v: &mut Vec<(u32, u32)>, other: &mut Vec<(u32, u32)>) {
    other.clear();
    other.resize(v.len(), (0, 0));
    const BITS: u32 = 11;
    const BUCKETS: usize = 1 << BITS;
    let mut counts = vec![0usize; BUCKETS + 1];
    for shift in [0u32, BITS, 2 * BITS] {
        counts.fill(0);
        for &(k, _) in v.iter() {
            counts[((k >> shift) as usize & (BUCKETS - 1)) + 1] += 1;
        }
        if counts[1..].contains(&v.len()) {
            // Every key has the same digit here: nothing moves.
            continue;
        }
        for b in 1..=BUCKETS {
            counts[b] += counts[b - 1];
        }
        for &e in v.iter() {
            let b = (e.0 >> shift) as usize & (BUCKETS - 1);
            other[counts[b]] = e;
            counts[b] += 1;
        }
        std::mem::swap(v, other);
    }
}

/// The objects by place (`places[i]`: chunk, then quad), farthest first at each place:
/// one radix sort by distance (`farthest`: a key that orders farthest first, and the
/// object), then a stable counting sort by chunk (places are chunk indices up to `last`),
/// and within a chunk whose objects go among its quads a stable sort by quad.
fn order_by_place(
    places: &[(u32, u32)],
    farthest: &mut Vec<(u32, u32)>,
    spare: &mut Vec<(u32, u32)>,
    last: u32,
    order: &mut Vec<u32>,
) {
    radix_sort(farthest, spare);
    let mut start = vec![0u32; last as usize + 2];
    for &(c, _) in places {
        start[c as usize + 1] += 1;
    }
    for c in 1..start.len() {
        start[c] += start[c - 1];
    }
    order.clear();
    order.resize(places.len(), 0);
    let mut quads = false;
    for &(_, i) in farthest.iter() {
        let (c, k) = places[i as usize];
        let at = &mut start[c as usize];
        order[*at as usize] = i;
        *at += 1;
        quads |= k > 0;
    }
    if quads {
        // Each chunk's run of objects, by quad (stable: farthest first stays).
        let mut from = 0;
        while from < order.len() {
            let c = places[order[from] as usize].0;
            let to = from + order[from..].partition_point(|&i| places[i as usize].0 == c);
            order[from..to].sort_by_key(|&i| places[i as usize].1);
            from = to;
        }
    }
}

#[cfg(test)]
mod tests;

#[cfg(test)]
mod against_all_pairs;
