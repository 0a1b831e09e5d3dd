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

mod cells;
mod draw_order;
mod place;
mod sound;

use cells::{CellIndex, KeyIndex, eye_cell};
use draw_order::{Entry, farthest_key, group_clips, order_by_place};
use sound::SeenPlane;
#[cfg(test)]
use sound::{SOUND, quad_side, safe, seen_planes};

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

// `Split` lives with the stages that carry it to the techniques (`GameDraw::splits`), so
// that `stages` does not reach up into `oit`.
pub(crate) use crate::stages::Split;

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

/// Per frame, what [`Interleaver::order`] learns of a chunk the first time an object
/// needs it: the `[near, mid, far]` distances of its box ([`Surfaces::distances`]), the
/// planes the eye sees and its quads as plane runs ([`plane_runs`], for `split_quads`),
/// those two as ranges of the interleaver's buffers.
#[derive(Clone, Copy, Debug, Default)]
struct ChunkFacts {
    distances: [f64; 3],
    planes: Option<(u32, u32)>,
    /// The runs, and where the boxes of its runs' quads start.
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

/// The most parts an object is cut into: the planes it crosses are taken nearest its centre
/// first while the parts between them (the product over the axes of one more than the cuts
/// along each) stay within this, so every plane is cut where an object crosses up to 63
/// along one axis (a beam through panes) or, say, 7 and 7 along two; each part is clipped
/// by at most two planes an axis.
pub(crate) const MAX_SPLIT_PARTS: usize = 64;

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
    /// Each part's distance as a key that orders farthest first.
    farthest: Vec<u32>,
    /// Room for [`order_by_place`]'s sorts.
    entries: Vec<Entry>,
    spare: Vec<Entry>,
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
    /// Per chunk that needs them, the box of each run's quads, world blocks.
    boxes: Vec<(DVec3, DVec3)>,
    /// The distinct clips of the parts (0: none), and by hash the indices of the others.
    clips: Vec<Clip>,
    clip_ids: std::collections::HashMap<u64, Vec<u32>>,
    /// The view direction (unit; zero: order by distance from the eye instead): objects at
    /// one place go farthest first along it, the order that is exact for particles, which
    /// all face the camera (parallel squares are ordered by their planes).
    forward: DVec3,
    /// The objects by their first part drawn, the parts in draw order, and the runs of
    /// positions in `order` drawn in turn.
    order: Vec<u32>,
    drawn: Vec<u32>,
    /// The place of each part in `drawn`.
    drawn_at: Vec<(u32, u32)>,
    splits: Vec<Split>,
    /// Room for [`group_clips`].
    grouped: Vec<u32>,
    /// Each object's position in `order` (`u32::MAX`: none yet).
    position: Vec<u32>,
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
    /// panes, foam whose face lies in the surface) is cut at them, nearest its centre first,
    /// into at most [`MAX_SPLIT_PARTS`] parts: each part (the object's box between the planes) is
    /// placed on its own and drawn with its clip (the renderer discards the fragments
    /// outside it), so that each lies wholly on one side of each plane it was cut at and
    /// the planes order it exactly. So is an object across chunk borders that no one place
    /// suits (a slab through a pane two chunks hold), at those borders. The order holds
    /// each object once, at its first part's position: a later part is a run that draws
    /// that position again ([`Split::start`]).
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

    /// The last order: the objects by their first part drawn (each once), the runs of
    /// positions in it drawn in turn (an object cut into parts is in one run per part), and
    /// the clips the runs name ([`Split::clip`]; 0 none).
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
        self.clip_ids.clear();
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
            entries,
            spare,
            order,
            drawn,
            drawn_at,
            splits,
            grouped,
            position,
            ..
        } = self;
        order_by_place(places, farthest, (entries, spare), last, drawn, drawn_at);
        group_clips(parts, drawn_at, eye, drawn, grouped);
        // Each object once in the order, at the position of its first part drawn: a later
        // part of it draws that position again, with its own clip. So the order is never
        // longer than the objects, whatever they are cut into, and a game's instance
        // buffers sized for its objects hold it.
        position.clear();
        position.resize(count, u32::MAX);
        order.clear();
        splits.clear();
        for (&p, &(chunk, quad)) in drawn.iter().zip(drawn_at.iter()) {
            let part = &parts[p as usize];
            let at = &mut position[part.object as usize];
            if *at == u32::MAX {
                *at = order.len() as u32;
                order.push(part.object);
            }
            let at = *at;
            match splits.last_mut() {
                Some(s) if (s.chunk, s.quad, s.clip, s.end) == (chunk, quad, part.clip, at) => {
                    s.end += 1;
                }
                _ => splits.push(Split {
                    chunk,
                    quad,
                    start: at,
                    end: at + 1,
                    clip: part.clip,
                }),
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
        self.farthest.push(key);
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
}

#[cfg(test)]
mod tests;

#[cfg(test)]
mod against_all_pairs;
