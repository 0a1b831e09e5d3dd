//! The generator's state ([`Gen`]): the boxes placed so far (each a block type over a box
//! of the local space, the last one winning where they overlap), the translucent types to
//! draw from, the queries on the boxes (the class at a point, whether an opaque block lies
//! between two points) with the small vector helpers, and the [`Features`] measured on the
//! final boxes.

use super::{Features, SplitMix64};

/// Size of the local box the parts are placed in.
pub(super) const L: i32 = 48;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Class {
    Opaque,
    Cutout,
    Translucent,
}

#[derive(Clone, Debug)]
pub(super) struct GenBox {
    pub(super) block: String,
    pub(super) class: Class,
    pub(super) min: [i32; 3],
    pub(super) max: [i32; 3],
}

impl GenBox {
    pub(super) fn center(&self) -> [f64; 3] {
        [0, 1, 2].map(|k| (f64::from(self.min[k]) + f64::from(self.max[k]) + 1.0) / 2.0)
    }
    pub(super) fn dims(&self) -> [i32; 3] {
        [0, 1, 2].map(|k| self.max[k] - self.min[k] + 1)
    }
    pub(super) fn contains(&self, p: [f64; 3]) -> bool {
        (0..3).all(|k| p[k] >= f64::from(self.min[k]) && p[k] < f64::from(self.max[k]) + 1.0)
    }
    pub(super) fn radius(&self) -> f64 {
        let d = self.dims();
        let s: f64 = d.iter().map(|&v| f64::from(v) * f64::from(v)).sum();
        s.sqrt() / 2.0
    }
}

pub(super) const OPAQUE: [&str; 5] = ["stone", "dirt", "grass", "sand", "wood"];
pub(super) const GROUND: [&str; 4] = ["stone", "dirt", "grass", "sand"];

/// `x` on the grid of odd multiples of 1/128: exact in f64 and in decimal, and never an
/// integer, so that only a deliberate snap puts the eye on a block plane.
pub(super) fn off_grid(x: f64) -> f64 {
    ((x * 64.0).floor() + 0.5) / 64.0
}

pub(super) fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
pub(super) fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
pub(super) fn scale(a: [f64; 3], s: f64) -> [f64; 3] {
    a.map(|v| v * s)
}
pub(super) fn length(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

pub(super) struct Gen {
    pub(super) rng: SplitMix64,
    pub(super) boxes: Vec<GenBox>,
    /// Translucent types to draw from: name and opacity.
    pub(super) pool: Vec<(String, f32)>,
    /// Extra types: name, colour, opacity.
    pub(super) extras: Vec<(String, [u8; 3], f32)>,
    pub(super) features: Features,
    pub(super) ground: bool,
    /// A large translucent horizontal surface: (min, max) of its box.
    pub(super) surface: Option<([i32; 3], [i32; 3])>,
    pub(super) stack: Option<(usize, usize, usize)>, // first box, count, axis
    pub(super) floor: Option<usize>,
    pub(super) ceiling: Option<usize>,
    /// Boxes beyond the floor or ceiling, to look at through it.
    pub(super) beyond: Vec<usize>,
}

impl Gen {
    pub(super) fn push(
        &mut self,
        block: &str,
        class: Class,
        min: [i32; 3],
        max: [i32; 3],
    ) -> usize {
        self.boxes.push(GenBox {
            block: block.to_owned(),
            class,
            min,
            max,
        });
        self.boxes.len() - 1
    }

    pub(super) fn translucent(&mut self) -> String {
        let i = self.rng.next_u64() as usize % self.pool.len();
        self.pool[i].0.clone()
    }

    /// The class of the block at `p` (last box wins, as the scene file fills them).
    pub(super) fn class_at(&self, p: [f64; 3]) -> Option<Class> {
        self.boxes
            .iter()
            .rev()
            .find(|b| b.contains(p))
            .map(|b| b.class)
    }

    /// Whether an opaque block lies on the segment from `a` to `b` (sampled every 1/4
    /// block, inside the scene's bounds only).
    pub(super) fn blocked(&self, a: [f64; 3], b: [f64; 3]) -> bool {
        let (lo, hi) = self.bounds();
        let d = sub(b, a);
        // Clip the segment to the bounds (slab test).
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        for k in 0..3 {
            if d[k] == 0.0 {
                if a[k] < lo[k] || a[k] > hi[k] {
                    return false;
                }
                continue;
            }
            let (u, v) = ((lo[k] - a[k]) / d[k], (hi[k] - a[k]) / d[k]);
            t0 = t0.max(u.min(v));
            t1 = t1.min(u.max(v));
        }
        if t0 >= t1 {
            return false;
        }
        let len = length(d) * (t1 - t0);
        let steps = (len * 4.0).ceil().min(4000.0) as usize;
        (0..=steps).any(|i| {
            let t = t0 + (t1 - t0) * i as f64 / steps.max(1) as f64;
            self.class_at(add(a, scale(d, t))) == Some(Class::Opaque)
        })
    }

    fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for b in &self.boxes {
            for k in 0..3 {
                lo[k] = lo[k].min(f64::from(b.min[k]));
                hi[k] = hi[k].max(f64::from(b.max[k]) + 1.0);
            }
        }
        (lo, hi)
    }

    /// Translucent boxes, by index.
    pub(super) fn translucent_boxes(&self) -> Vec<usize> {
        (0..self.boxes.len())
            .filter(|&i| self.boxes[i].class == Class::Translucent)
            .collect()
    }

    /// The features measured on the final geometry.
    pub(super) fn finish_features(&mut self, eye: [f64; 3]) {
        let f = &mut self.features;
        f.boxes = self.boxes.len() as u32;
        f.opaque = self.boxes.iter().any(|b| b.class == Class::Opaque);
        f.cutout = self.boxes.iter().any(|b| b.class == Class::Cutout);
        f.eye_inside = self
            .boxes
            .iter()
            .rev()
            .find(|b| b.contains(eye))
            .is_some_and(|b| b.class == Class::Translucent);
        f.eye_on_plane = self
            .boxes
            .iter()
            .filter(|b| b.class == Class::Translucent)
            .any(|b| {
                (0..3).any(|k| eye[k] == f64::from(b.min[k]) || eye[k] == f64::from(b.max[k]) + 1.0)
            });
        let mut used: Vec<&str> = self
            .boxes
            .iter()
            .filter(|b| b.class == Class::Translucent)
            .map(|b| b.block.as_str())
            .collect();
        used.sort_unstable();
        used.dedup();
        f.translucent_types = used.len() as u32;
        let opacity = |name: &str| {
            self.pool
                .iter()
                .find(|(n, _)| n == name)
                .map_or(1.0, |(_, o)| *o)
        };
        f.min_opacity = used.iter().map(|n| opacity(n)).fold(1.0, f32::min);
        f.max_opacity = used.iter().map(|n| opacity(n)).fold(0.0, f32::max);
        f.extra_types = self
            .extras
            .iter()
            .filter(|(n, _, _)| used.contains(&n.as_str()))
            .count() as u32;
    }
}
