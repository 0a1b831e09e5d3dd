//! Quads as boxes, and when one hides another: at an eye (in floating point) and over an
//! open cell of eyes (in integers). The lemmas behind them are in `docs/quad-order.md`.

use crate::{PackedQuad, UV_AXES};

/// A quad as a closed, flat, axis-aligned box in chunk-local block units.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct QBox {
    /// Minimum corner.
    pub(super) lo: [i32; 3],
    /// Maximum corner; `lo[axis] == hi[axis]` is the quad's plane.
    pub(super) hi: [i32; 3],
    /// Normal axis, 0..3.
    pub(super) axis: usize,
    /// Whether the face points along +axis (its block lies below the plane).
    pub(super) positive: bool,
}

impl QBox {
    /// The box of a packed quad. Face bits 6 and 7 (never made by [`PackedQuad::new`]) are
    /// read as -z, as [`PackedQuad::center`] does.
    pub(super) fn of(q: PackedQuad) -> Self {
        let g = q.geometry;
        let mut lo = [g & 31, (g >> 5) & 31, (g >> 10) & 31].map(|v| v as i32);
        let face = q.face_index().min(5);
        let axis = face / 2;
        let positive = face.is_multiple_of(2);
        if positive {
            lo[axis] += 1;
        }
        let mut hi = lo;
        let [u, v] = UV_AXES[axis];
        hi[u] += ((g >> 15) & 31) as i32 + 1;
        hi[v] += ((g >> 20) & 31) as i32 + 1;
        Self {
            lo,
            hi,
            axis,
            positive,
        }
    }

    /// The plane coordinate along the normal axis.
    #[inline]
    pub(super) fn plane(&self) -> i32 {
        self.lo[self.axis]
    }

    /// Squared distance from the centre to `eye` (NaN for a NaN eye).
    pub(super) fn centre_distance2(&self, eye: [f64; 3]) -> f64 {
        (0..3)
            .map(|k| {
                let v = f64::from(self.lo[k] + self.hi[k]) * 0.5 - eye[k];
                v * v
            })
            .sum()
    }

    /// Whether two coplanar quads' footprints share interior points.
    fn footprints_overlap(&self, o: &Self) -> bool {
        let [u, v] = UV_AXES[self.axis];
        self.lo[u] < o.hi[u] && o.lo[u] < self.hi[u] && self.lo[v] < o.hi[v] && o.lo[v] < self.hi[v]
    }

    /// Whether `self` and `o` are opposite faces on one plane with overlapping footprints.
    pub(super) fn ties_with(&self, o: &Self) -> bool {
        self.axis == o.axis
            && self.plane() == o.plane()
            && self.positive != o.positive
            && self.footprints_overlap(o)
    }
}

/// The bounds of an open cell along one axis; `None` for an unbounded side.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Span {
    pub(super) lo: Option<i32>,
    pub(super) hi: Option<i32>,
}

impl Span {
    /// Whether the cell lies above `p` (it is open, so `lo >= p` means every eye in it).
    pub(super) fn above(self, p: i32) -> bool {
        self.lo.is_some_and(|l| l >= p)
    }

    /// Whether the cell lies below `p`.
    pub(super) fn below(self, p: i32) -> bool {
        self.hi.is_some_and(|h| h <= p)
    }
}

/// The open interval of `s > 0` allowed by constraints `s * alpha < beta`, with rational
/// ends in integers.
pub(super) struct SInterval {
    /// Lower end `num / den` (exclusive), `den > 0`.
    pub(super) lo: (i64, i64),
    /// Upper end (exclusive); `None` is +infinity.
    pub(super) hi: Option<(i64, i64)>,
    pub(super) empty: bool,
}

impl SInterval {
    pub(super) fn new() -> Self {
        Self {
            lo: (0, 1),
            hi: None,
            empty: false,
        }
    }

    /// Adds `s * alpha < beta`.
    #[inline]
    pub(super) fn less(&mut self, alpha: i64, beta: i64) {
        match alpha.signum() {
            0 => self.empty |= beta <= 0,
            1 => {
                if self.hi.is_none_or(|h| beta * h.1 < h.0 * alpha) {
                    self.hi = Some((beta, alpha));
                }
            }
            _ => {
                // s > beta / alpha = (-beta) / (-alpha)
                let b = (-beta, -alpha);
                if b.0 * self.lo.1 > self.lo.0 * b.1 {
                    self.lo = b;
                }
            }
        }
    }

    /// Adds `s * alpha > beta`.
    #[inline]
    pub(super) fn greater(&mut self, alpha: i64, beta: i64) {
        self.less(-alpha, -beta);
    }

    pub(super) fn feasible(&self) -> bool {
        !self.empty && self.hi.is_none_or(|h| self.lo.0 * h.1 < h.0 * self.lo.1)
    }
}

/// The region relation (Lemma 2 of `docs/quad-order.md`): whether `b` hides part of `a` from
/// some eye of the open box `cell`, so that `a` must be drawn before `b` for that eye.
/// Exact, in integers. Coplanar quads never hide each other; opposite faces with
/// overlapping footprints get the tie-break instead ([`tie_in`]).
pub(super) fn may_hide_in_cell(a: &QBox, b: &QBox, cell: &[Span; 3]) -> bool {
    if a.axis == b.axis && a.plane() == b.plane() {
        return tie_in(a, b, cell);
    }
    let mut s = SInterval::new();
    for (k, c) in cell.iter().enumerate() {
        let (alo, ahi, blo, bhi) = (
            i64::from(a.lo[k]),
            i64::from(a.hi[k]),
            i64::from(b.lo[k]),
            i64::from(b.hi[k]),
        );
        if alo == ahi && blo == bhi {
            // Parallel planes: E_k = b + s (b - a), strictly inside the cell.
            let d = blo - alo;
            if let Some(lo) = c.lo {
                s.greater(d, i64::from(lo) - blo);
            }
            if let Some(hi) = c.hi {
                s.less(d, i64::from(hi) - blo);
            }
        } else {
            // E_k ranges over the open interval ((1+s) b.lo - s a.hi, (1+s) b.hi - s a.lo).
            if let Some(hi) = c.hi {
                s.less(blo - ahi, i64::from(hi) - blo);
            }
            if let Some(lo) = c.lo {
                s.greater(bhi - alo, i64::from(lo) - bhi);
            }
        }
        if s.empty {
            return false;
        }
    }
    s.feasible()
}

/// The coplanar tie-break over a cell: `a` before `b` when they are opposite faces on one
/// plane with overlapping footprints and `a`'s block lies on the far side of the plane
/// (for a cell above the plane, the positive face, whose block lies below).
pub(super) fn tie_in(a: &QBox, b: &QBox, cell: &[Span; 3]) -> bool {
    let c = cell[a.axis];
    a.ties_with(b) && ((c.above(a.plane()) && a.positive) || (c.below(a.plane()) && !a.positive))
}

/// The coplanar tie-break at a point eye (see [`tie_in`]).
pub(super) fn tie_at(eye: [f64; 3], a: &QBox, b: &QBox) -> bool {
    let (e, p) = (eye[a.axis], f64::from(a.plane()));
    a.ties_with(b) && ((e > p && a.positive) || (e < p && !a.positive))
}

/// The relation at a point (lemma 2 with a one-point cell): whether `b` hides part of `a`
/// from `eye`. Quads seen edge-on hide and are hidden by nothing; coplanar quads never
/// hide each other. Floating point: exact when the eye's coordinates have few significant
/// bits (every product compared below is then exact), otherwise wrong only for eyes
/// within rounding error of the boundary of the set of eyes that see the two quads
/// overlap, where their overlap on screen is far below a pixel.
pub(super) fn hides_at(eye: [f64; 3], a: &QBox, b: &QBox) -> bool {
    let (pa, pb) = (f64::from(a.plane()), f64::from(b.plane()));
    if eye[a.axis] == pa || eye[b.axis] == pb || (a.axis == b.axis && pa == pb) {
        return false;
    }
    // Bounds on s as (numerator, denominator > 0).
    let lt = |x: (f64, f64), y: (f64, f64)| x.0 * y.1 < y.0 * x.1;
    let mut lo = (0.0, 1.0);
    let mut hi: Option<(f64, f64)> = None;
    let mut eq: Option<(f64, f64)> = None;
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
    for (k, &e) in eye.iter().enumerate() {
        let (alo, ahi, blo, bhi) = (
            f64::from(a.lo[k]),
            f64::from(a.hi[k]),
            f64::from(b.lo[k]),
            f64::from(b.hi[k]),
        );
        if alo == ahi && blo == bhi {
            // Parallel planes: s = (e - b) / (b - a).
            let d = blo - alo;
            eq = Some(if d > 0.0 { (e - blo, d) } else { (blo - e, -d) });
        } else {
            less(blo - ahi, e - blo);
            less(alo - bhi, bhi - e);
        }
    }
    ok && match eq {
        Some(s) => lt(lo, s) && hi.is_none_or(|h| lt(s, h)),
        None => hi.is_none_or(|h| lt(lo, h)),
    }
}
