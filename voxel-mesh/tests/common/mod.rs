//! Scenes and oracles shared by the order tests and the sort benchmark.

#![allow(dead_code, clippy::unwrap_used, clippy::needless_range_loop)] // each user takes what it needs; axis loops index

use voxel_core::blocks::{AIR, BLUE_GLASS, GLASS, GREEN_GLASS, ICE, RED_GLASS, STONE, WATER};
use voxel_core::{BlockId, BlockRegistry, Chunk};
use voxel_mesh::{Mesher, PackedQuad, UV_AXES};

/// xorshift64* (deterministic, no dependency).
#[derive(Clone, Debug)]
pub struct Rng(pub u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Self(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    pub fn next(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        x.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    /// Uniform in `0..n`.
    pub fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
    pub fn range(&mut self, lo: i64, hi: i64) -> i64 {
        lo + self.below((hi - lo) as u64) as i64
    }
    pub fn chance(&mut self, p: f64) -> bool {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64 <= p
    }
    pub fn pick<T: Copy>(&mut self, v: &[T]) -> T {
        v[self.below(v.len() as u64) as usize]
    }
}

pub const TRANSLUCENT: [BlockId; 6] = [WATER, GLASS, ICE, RED_GLASS, GREEN_GLASS, BLUE_GLASS];

pub fn mesh(chunk: &Chunk) -> Vec<PackedQuad> {
    let reg = BlockRegistry::default();
    let mut m = Mesher::new(&reg);
    m.mesh(chunk, [None; 6]).unwrap().translucent
}

/// Random boxes of translucent types (and some air and stone) in a region of the chunk.
pub fn random_boxes(rng: &mut Rng, boxes: usize, max_size: i64, region: i64) -> Chunk {
    let mut c = Chunk::uniform(AIR);
    let o = rng.range(0, 33 - region);
    for _ in 0..boxes {
        let id = if rng.chance(0.1) {
            AIR
        } else if rng.chance(0.05) {
            STONE
        } else {
            rng.pick(&TRANSLUCENT)
        };
        let min: [usize; 3] = std::array::from_fn(|_| (o + rng.range(0, region)) as usize);
        let max: [usize; 3] = std::array::from_fn(|k| {
            (min[k] as i64 + rng.range(0, max_size))
                .min(31)
                .min(o + region - 1) as usize
        });
        c.fill_box(min, max, id).unwrap();
    }
    c
}

/// A 3D checkerboard of two glass types over `size` blocks along each axis from `o`.
pub fn checkerboard(o: [usize; 3], size: [usize; 3], a: BlockId, b: BlockId) -> Chunk {
    let mut c = Chunk::uniform(AIR);
    for x in 0..size[0] {
        for y in 0..size[1] {
            for z in 0..size[2] {
                let id = if (x + y + z) % 2 == 0 { a } else { b };
                c.set(o[0] + x, o[1] + y, o[2] + z, id).unwrap();
            }
        }
    }
    c
}

/// Where centre sorting fails: a chunk-wide water surface at y = 10 and a glass pillar at
/// x = 20, z = 16, y = 11..15 just above it. (A pillar standing on the water would cut the
/// surface into several quads: the water's face under it meets glass, an interface, which
/// the mesher keeps apart; floating, the surface stays one chunk-wide quad.)
pub fn water_and_pillar() -> Chunk {
    let mut c = Chunk::uniform(AIR);
    c.fill_box([0, 0, 0], [31, 9, 31], WATER).unwrap();
    c.fill_box([20, 11, 16], [20, 14, 16], GLASS).unwrap();
    c
}

/// Water with random small glass and ice objects on and under its surface.
pub fn water_with_objects(rng: &mut Rng) -> Chunk {
    let mut c = Chunk::uniform(AIR);
    let level = rng.range(2, 30) as usize;
    c.fill_box([0, 0, 0], [31, level - 1, 31], WATER).unwrap();
    for _ in 0..rng.range(1, 12) {
        let id = rng.pick(&[GLASS, ICE, RED_GLASS, BLUE_GLASS, AIR]);
        let min = [rng.range(0, 31), rng.range(0, 31), rng.range(0, 31)];
        let min = [min[0] as usize, min[1] as usize, min[2] as usize];
        let max: [usize; 3] = std::array::from_fn(|k| (min[k] + rng.range(0, 5) as usize).min(31));
        c.fill_box(min, max, id).unwrap();
    }
    c
}

/// Glass floors and ceilings (thin horizontal slabs) with walls and gaps.
pub fn floors_and_walls(rng: &mut Rng) -> Chunk {
    let mut c = Chunk::uniform(AIR);
    for _ in 0..rng.range(2, 6) {
        let y = rng.range(0, 32) as usize;
        let (x0, z0) = (rng.range(0, 24) as usize, rng.range(0, 24) as usize);
        let (x1, z1) = (
            (x0 + rng.range(2, 16) as usize).min(31),
            (z0 + rng.range(2, 16) as usize).min(31),
        );
        c.fill_box([x0, y, z0], [x1, y, z1], rng.pick(&TRANSLUCENT))
            .unwrap();
    }
    for _ in 0..rng.range(1, 6) {
        let (x, y0) = (rng.range(0, 32) as usize, rng.range(0, 28) as usize);
        let z0 = rng.range(0, 24) as usize;
        let (y1, z1) = (
            (y0 + rng.range(1, 10) as usize).min(31),
            (z0 + rng.range(1, 12) as usize).min(31),
        );
        let id = rng.pick(&TRANSLUCENT);
        if rng.chance(0.5) {
            c.fill_box([x, y0, z0], [x, y1, z1], id).unwrap();
        } else {
            c.fill_box([z0, y0, x], [z1, y1, x], id).unwrap();
        }
    }
    c
}

/// A glass staircase (each step one block higher and one further), over water.
pub fn stairs(rng: &mut Rng) -> Chunk {
    let mut c = Chunk::uniform(AIR);
    c.fill_box([0, 0, 0], [31, 3, 31], WATER).unwrap();
    let (x0, z0, w) = (
        rng.range(0, 8) as usize,
        rng.range(0, 20) as usize,
        rng.range(1, 8) as usize,
    );
    let id = rng.pick(&[GLASS, ICE, RED_GLASS]);
    for s in 0..rng.range(3, 20) as usize {
        let x = x0 + s;
        let y = 4 + s;
        if x > 31 || y > 31 {
            break;
        }
        c.fill_box([x, 4, z0], [x, y, (z0 + w).min(31)], id)
            .unwrap();
    }
    c
}

/// A quad's box: `(lo, hi, axis, positive)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Q {
    pub lo: [f64; 3],
    pub hi: [f64; 3],
    pub axis: usize,
    pub positive: bool,
}

impl Q {
    pub fn of(q: PackedQuad) -> Self {
        let u = q.unpack().unwrap();
        let axis = u.face.axis();
        let positive = u.face.is_positive();
        let mut lo = u.pos.map(f64::from);
        if positive {
            lo[axis] += 1.0;
        }
        let mut hi = lo;
        let [a, b] = UV_AXES[axis];
        hi[a] += f64::from(u.size[0]);
        hi[b] += f64::from(u.size[1]);
        Self {
            lo,
            hi,
            axis,
            positive,
        }
    }
    pub fn plane(&self) -> f64 {
        self.lo[self.axis]
    }
    fn flat(&self, k: usize) -> bool {
        self.lo[k] == self.hi[k]
    }
    pub fn coincident_overlap(&self, o: &Q) -> bool {
        let [u, v] = UV_AXES[self.axis];
        self.axis == o.axis
            && self.plane() == o.plane()
            && self.positive != o.positive
            && self.lo[u] < o.hi[u]
            && o.lo[u] < self.hi[u]
            && self.lo[v] < o.hi[v]
            && o.lo[v] < self.hi[v]
    }
}

/// Rational `n / d` with `d > 0`; exact for the dyadic eyes the tests use.
#[derive(Clone, Copy)]
struct R(f64, f64);

fn lt(a: R, b: R) -> bool {
    a.0 * b.1 < b.0 * a.1
}

/// Exact pair oracle: whether some ray from `eye` meets the relative interior of `b` and
/// then that of `a` (so `a` must be drawn before `b`). Independent of the library's code
/// paths (point eye, floating rationals, written separately); exact when the eye's
/// coordinates are dyadic with few bits (the tests' eyes are k / 1024). Quads seen edge-on
/// (eye in their plane) are hidden by nothing and hide nothing.
pub fn hides(eye: [f64; 3], a: &Q, b: &Q) -> bool {
    if eye[a.axis] == a.plane() || eye[b.axis] == b.plane() {
        return false;
    }
    if a.axis == b.axis && a.plane() == b.plane() {
        return false;
    }
    // eye = (1 + s) pb - s pa with pa in a, pb in b, s > 0.
    let mut lo = R(0.0, 1.0);
    let mut hi: Option<R> = None;
    let mut eq: Option<R> = None;
    let mut ok = true;
    let mut less = |alpha: f64, beta: f64, lo: &mut R, hi: &mut Option<R>| {
        // s * alpha < beta
        if alpha > 0.0 {
            let r = R(beta, alpha);
            if hi.is_none_or(|h| lt(r, h)) {
                *hi = Some(r);
            }
        } else if alpha < 0.0 {
            let r = R(-beta, -alpha);
            if lt(*lo, r) {
                *lo = r;
            }
        } else if beta <= 0.0 {
            ok = false;
        }
    };
    for k in 0..3 {
        let e = eye[k];
        if a.flat(k) && b.flat(k) {
            let d = b.lo[k] - a.lo[k];
            let r = if d > 0.0 {
                R(e - b.lo[k], d)
            } else {
                R(b.lo[k] - e, -d)
            };
            eq = Some(r);
        } else {
            less(b.lo[k] - a.hi[k], e - b.lo[k], &mut lo, &mut hi);
            less(-(b.hi[k] - a.lo[k]), -(e - b.hi[k]), &mut lo, &mut hi);
        }
    }
    if !ok {
        return false;
    }
    match eq {
        Some(s) => lt(lo, s) && hi.is_none_or(|h| lt(s, h)),
        None => hi.is_none_or(|h| lt(lo, h)),
    }
}

/// Pairs drawn in the wrong order for `eye`: `(i, j)` output positions with `i` drawn
/// before `j` although `i` hides part of `j` (or `i` is the near one of two coincident
/// opposite faces). Empty when the order is exact.
pub fn violations(eye: [f64; 3], order: &[PackedQuad]) -> Vec<(usize, usize)> {
    let q: Vec<Q> = order.iter().map(|&p| Q::of(p)).collect();
    let mut bad = Vec::new();
    for i in 0..q.len() {
        for j in i + 1..q.len() {
            // i is drawn before j: wrong if i hides j.
            if hides(eye, &q[j], &q[i]) {
                bad.push((i, j));
            } else if q[i].coincident_overlap(&q[j]) {
                let p = q[i].plane();
                let e = eye[q[i].axis];
                // The face whose block lies on the far side must come first.
                let first_ok = if e > p {
                    q[i].positive
                } else if e < p {
                    !q[i].positive
                } else {
                    true
                };
                if !first_ok {
                    bad.push((i, j));
                }
            }
        }
    }
    bad
}

/// Ray oracle: pairs `(i, j)` of output positions, `i < j`, such that a ray from `eye`
/// through a random point strictly inside quad `j` crosses quad `i` strictly inside (with
/// a margin) before reaching it: quad `j`, drawn later, is behind quad `i` on that ray.
/// `per_quad` rays per quad; rays through edges are avoided by the margins.
pub fn ray_violations(
    eye: [f64; 3],
    order: &[PackedQuad],
    rng: &mut Rng,
    per_quad: usize,
) -> Vec<(usize, usize)> {
    let q: Vec<Q> = order.iter().map(|&p| Q::of(p)).collect();
    let mut bad = Vec::new();
    let margin = 1e-7;
    for (j, qj) in q.iter().enumerate() {
        if eye[qj.axis] == qj.plane() {
            continue;
        }
        for _ in 0..per_quad {
            // A random point strictly inside quad j.
            let mut p = qj.lo;
            for k in 0..3 {
                if !qj.flat(k) {
                    let t = 0.02 + 0.96 * (rng.below(1 << 20) as f64 / (1 << 20) as f64);
                    p[k] = qj.lo[k] + t * (qj.hi[k] - qj.lo[k]);
                }
            }
            let d = [p[0] - eye[0], p[1] - eye[1], p[2] - eye[2]];
            // Every quad the segment eye -> p crosses strictly inside, before p.
            for (i, qi) in q.iter().enumerate() {
                if i == j || d[qi.axis] == 0.0 {
                    continue;
                }
                let t = (qi.plane() - eye[qi.axis]) / d[qi.axis];
                if !(t > 1e-9 && t < 1.0 - 1e-9) {
                    continue;
                }
                let inside = (0..3).all(|k| {
                    k == qi.axis || {
                        let x = eye[k] + t * d[k];
                        x > qi.lo[k] + margin && x < qi.hi[k] - margin
                    }
                });
                // Quad i is in front of quad j on this ray: j must be drawn first.
                if inside && i < j {
                    bad.push((i, j));
                }
            }
        }
    }
    bad.sort_unstable();
    bad.dedup();
    bad
}

/// One random translucent structure in the box `o..=hi`: a glass house (hollow, walls of
/// one glass or of four stained glasses, a roof), a glass tank full of water, a glass or ice
/// pillar, a stained-glass slab, or a staircase.
pub fn add_structure(rng: &mut Rng, c: &mut Chunk, o: [usize; 3], hi: [usize; 3]) {
    let kind = rng.below(5);
    add_structure_of(rng, c, o, hi, kind);
}

/// [`add_structure`] of a given kind: 0 house, 1 tank, 2 pillar, 3 slab, 4 stairs.
pub fn add_structure_of(rng: &mut Rng, c: &mut Chunk, o: [usize; 3], hi: [usize; 3], kind: u64) {
    let glass = [GLASS, RED_GLASS, GREEN_GLASS, BLUE_GLASS];
    match kind {
        0 => {
            let one = rng.chance(0.5);
            let pick = |rng: &mut Rng| if one { GLASS } else { rng.pick(&glass) };
            let walls = [pick(rng), pick(rng), pick(rng), pick(rng), pick(rng)];
            c.fill_box([o[0], o[1], o[2]], [o[0], hi[1], hi[2]], walls[0])
                .unwrap();
            c.fill_box([hi[0], o[1], o[2]], [hi[0], hi[1], hi[2]], walls[1])
                .unwrap();
            c.fill_box([o[0] + 1, o[1], o[2]], [hi[0] - 1, hi[1], o[2]], walls[2])
                .unwrap();
            c.fill_box([o[0] + 1, o[1], hi[2]], [hi[0] - 1, hi[1], hi[2]], walls[3])
                .unwrap();
            c.fill_box([o[0], hi[1], o[2]], [hi[0], hi[1], hi[2]], walls[4])
                .unwrap();
        }
        1 => {
            c.fill_box(o, hi, GLASS).unwrap();
            c.fill_box(
                [o[0] + 1, o[1] + 1, o[2] + 1],
                [hi[0] - 1, hi[1], hi[2] - 1],
                WATER,
            )
            .unwrap();
        }
        2 => c
            .fill_box(
                [o[0], o[1], o[2]],
                [o[0], hi[1], o[2]],
                rng.pick(&[GLASS, ICE]),
            )
            .unwrap(),
        3 => c
            .fill_box([o[0], o[1], o[2]], [hi[0], o[1], hi[2]], rng.pick(&glass))
            .unwrap(),
        _ => {
            let id = rng.pick(&glass);
            for x in o[0]..=hi[0] {
                let y = (o[1] + x - o[0]).min(hi[1]);
                c.fill_box([x, o[1], o[2]], [x, y, hi[2]], id).unwrap();
            }
        }
    }
}

/// Random translucent structures (see [`add_structure`]), each 3 to 8 blocks a side, placed
/// apart from each other (one air block between any two), until the translucent mesh has at
/// least `target` quads or no more fits; with the mesh.
pub fn structures(rng: &mut Rng, target: usize) -> (Chunk, Vec<PackedQuad>) {
    let mut c = Chunk::uniform(AIR);
    let mut quads = Vec::new();
    for _ in 0..3000 {
        let s = [0; 3].map(|_| rng.range(3, 9) as usize);
        let o: [usize; 3] = std::array::from_fn(|k| rng.range(0, (33 - s[k]) as i64) as usize);
        let hi: [usize; 3] = std::array::from_fn(|k| o[k] + s[k] - 1);
        let free = (o[0].saturating_sub(1)..=(hi[0] + 1).min(31)).all(|x| {
            (o[1].saturating_sub(1)..=(hi[1] + 1).min(31)).all(|y| {
                (o[2].saturating_sub(1)..=(hi[2] + 1).min(31))
                    .all(|z| c.get(x, y, z).unwrap() == AIR)
            })
        });
        if !free {
            continue;
        }
        add_structure(rng, &mut c, o, hi);
        quads = mesh(&c);
        if quads.len() >= target {
            break;
        }
    }
    (c, quads)
}
