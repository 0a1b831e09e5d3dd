//! The camera of a scene: the eye inside a translucent volume, grazing a large surface or
//! aimed at a box (a stack along its axis, through a floor or ceiling, a distant telephoto
//! view); the eye snapped onto a face plane; the near and far planes and the field of view.

use voxel_render::low_level::{MAX_FAR, MAX_FOV_DEG, MIN_FOV_DEG, MIN_NEAR};

use super::boxes::{Class, Gen, L, add, length, off_grid, scale, sub};

impl Gen {
    /// A random unit vector, flattened towards the horizontal by `flat` (1: uniform).
    fn direction(&mut self, flat: f64) -> [f64; 3] {
        loop {
            let v = [
                self.rng.range(-1.0, 1.0),
                self.rng.range(-1.0, 1.0) * flat,
                self.rng.range(-1.0, 1.0),
            ];
            let l = length(v);
            if l > 0.1 && l <= 1.0 {
                return scale(v, 1.0 / l);
            }
        }
    }

    fn good_eye(&self, eye: [f64; 3], target: [f64; 3]) -> bool {
        !matches!(
            self.class_at(eye),
            Some(Class::Opaque) | Some(Class::Cutout)
        ) && !self.blocked(eye, target)
    }

    /// A point inside box `i`, off the block grid.
    fn point_in(&mut self, i: usize) -> [f64; 3] {
        let b = self.boxes[i].clone();
        [0, 1, 2].map(|k| {
            let lo = f64::from(b.min[k]) + 0.1;
            let hi = f64::from(b.max[k]) + 0.9;
            off_grid(self.rng.range(lo, hi))
        })
    }

    /// The camera: eye, target, fov, near, far.
    pub(super) fn camera(&mut self) -> ([f64; 3], [f64; 3], f64, f64, f64) {
        let r = self.rng.unit();
        let (mut eye, target, mut fov) = if r < 0.2 {
            self.inside()
        } else if r < 0.35 {
            self.grazing()
        } else {
            self.aimed()
        };
        if self.rng.chance(0.2) {
            self.snap_to_plane(&mut eye, target);
        }
        // Never exactly at the target (a zero view direction).
        let mut target = target;
        if length(sub(target, eye)) < 0.25 {
            target = add(eye, [0.0, 0.0, -8.0]);
        }
        let distance = length(sub(target, eye));
        // Near: log-uniform over [0.01, 1], on a decimal grid.
        let near = if self.rng.chance(0.5) {
            f64::from(self.rng.int(100, 999)) / 10_000.0
        } else {
            f64::from(self.rng.int(100, 1000)) / 1000.0
        };
        let r = self.rng.unit();
        let mut far = f64::from(if r < 0.5 {
            self.rng.int(64, 400)
        } else if r < 0.8 {
            self.rng.int(400, 2000)
        } else {
            self.rng.int(2000, 5000)
        });
        if self.features.distant {
            far = far.max((distance + 150.0).ceil()).min(5000.0);
        } else if self.rng.chance(0.08) && distance.floor() + 0.5 > near + 0.5 {
            far = distance.floor() + f64::from(self.rng.int(0, 3)) + 0.5;
            self.features.far_cuts = true;
        }
        if !self.features.distant {
            let r = self.rng.unit();
            fov = f64::from(if r < 0.8 {
                self.rng.int(35, 100)
            } else if r < 0.9 {
                self.rng.int(110, 170)
            } else {
                self.rng.int(10, 34)
            });
        }
        let fov = fov.clamp(MIN_FOV_DEG, MAX_FOV_DEG);
        let near = near.max(MIN_NEAR);
        let far = far.min(MAX_FAR);
        self.features.near = near;
        self.features.far = far;
        self.features.fov = fov;
        self.features.distance = distance;
        (eye, target, fov, near, far)
    }

    fn inside(&mut self) -> ([f64; 3], [f64; 3], f64) {
        let volumes: Vec<usize> = self
            .translucent_boxes()
            .into_iter()
            .filter(|&i| self.boxes[i].dims().iter().all(|&d| d >= 2))
            .collect();
        let i = if volumes.is_empty() || self.rng.chance(0.3) {
            // A body of water engulfing part of the scene.
            let d = [
                self.rng.int(4, 16),
                self.rng.int(3, 12),
                self.rng.int(4, 16),
            ];
            let min = self.place(d, 0);
            let max = [0, 1, 2].map(|k| min[k] + d[k] - 1);
            let t = if self.rng.chance(0.6) {
                "water".to_owned()
            } else {
                self.translucent()
            };
            self.features.solid_volumes = true;
            self.push(&t, Class::Translucent, min, max)
        } else {
            *self.rng.pick(&volumes)
        };
        let mut eye = self.point_in(i);
        for _ in 0..20 {
            if self.class_at(eye) == Some(Class::Translucent) {
                break;
            }
            eye = self.point_in(i);
        }
        let others: Vec<usize> = self
            .translucent_boxes()
            .into_iter()
            .filter(|&j| j != i)
            .collect();
        let target = if !others.is_empty() && self.rng.chance(0.7) {
            let j = *self.rng.pick(&others);
            self.boxes[j].center()
        } else {
            let d = self.direction(0.6);
            add(eye, scale(d, 10.0))
        };
        (eye, target.map(off_grid), 60.0)
    }

    fn grazing(&mut self) -> ([f64; 3], [f64; 3], f64) {
        let (min, max) = match self.surface {
            Some(s) => s,
            None => {
                let (sx, sz) = (self.rng.int(30, L), self.rng.int(30, L));
                let thick = self.rng.int(1, 4);
                let y0 = self.rng.int(2, 10);
                let (x0, z0) = (self.rng.int(0, L - sx), self.rng.int(0, L - sz));
                let min = [x0, y0, z0];
                let max = [x0 + sx - 1, y0 + thick - 1, z0 + sz - 1];
                let t = if self.rng.chance(0.6) {
                    "water".to_owned()
                } else {
                    self.translucent()
                };
                self.push(&t, Class::Translucent, min, max);
                if thick == 1 {
                    self.features.thin_sheets = true;
                } else {
                    self.features.solid_volumes = true;
                }
                (min, max)
            }
        };
        self.features.grazing = true;
        let top = f64::from(max[1]) + 1.0;
        let (x0, x1) = (f64::from(min[0]), f64::from(max[0]) + 1.0);
        let (z0, z1) = (f64::from(min[2]), f64::from(max[2]) + 1.0);
        // From near one edge across to the other, along x or z (either way), with a
        // sideways drift.
        let along_x = self.rng.chance(0.5);
        let flip = self.rng.chance(0.5);
        let (a0, a1, b0, b1) = if along_x {
            (x0, x1, z0, z1)
        } else {
            (z0, z1, x0, x1)
        };
        let (mut s, mut e) = (
            a0 + (a1 - a0) * self.rng.range(0.0, 0.15),
            a0 + (a1 - a0) * self.rng.range(0.85, 1.0),
        );
        if flip {
            std::mem::swap(&mut s, &mut e);
        }
        let bs = b0 + (b1 - b0) * self.rng.range(0.2, 0.8);
        let be = b0 + (b1 - b0) * self.rng.range(0.2, 0.8);
        let r = self.rng.unit();
        let h = if r < 0.6 {
            self.rng.range(0.02, 0.6)
        } else if r < 0.85 {
            -self.rng.range(0.02, 0.6)
        } else {
            0.0
        };
        let eye_y = if h == 0.0 { top } else { off_grid(top + h) };
        let dist = (e - s).abs();
        let slope = self.rng.range(0.005, 0.08);
        let ty = if h >= 0.0 {
            eye_y - slope * dist
        } else {
            eye_y + slope * dist
        };
        let (eye, target) = if along_x {
            ([off_grid(s), eye_y, off_grid(bs)], [e, ty, be])
        } else {
            ([off_grid(bs), eye_y, off_grid(s)], [be, ty, e])
        };
        if h == 0.0 {
            self.features.eye_on_plane = true;
        }
        (eye, target.map(off_grid), 60.0)
    }

    fn aimed(&mut self) -> ([f64; 3], [f64; 3], f64) {
        let translucent = self.translucent_boxes();
        if translucent.is_empty() {
            let t = self.translucent();
            let i = self.push(&t, Class::Translucent, [20, 20, 20], [24, 24, 24]);
            return self.aim_at(i, None);
        }
        let r = self.rng.unit();
        if let (Some((first, count, axis)), true) = (self.stack, r < 0.45) {
            // The stack: along its axis, or from anywhere.
            let mid = first + count / 2;
            let along = self.rng.chance(0.7).then_some((first, count, axis));
            return self.aim_at(mid, along);
        }
        if (self.floor.is_some() || self.ceiling.is_some()) && r < 0.7 && !self.beyond.is_empty() {
            // Through the floor or ceiling at what lies beyond it.
            let j = *self.rng.pick(&self.beyond.clone());
            let below = self
                .floor
                .is_some_and(|f| self.boxes[j].max[1] < self.boxes[f].min[1]);
            let target = self.boxes[j].center().map(off_grid);
            for _ in 0..40 {
                let d = self.direction(1.0);
                let d = [
                    d[0],
                    d[1].abs().max(0.3) * if below { 1.0 } else { -1.0 },
                    d[2],
                ];
                let d = scale(d, 1.0 / length(d));
                let eye = add(target, scale(d, self.rng.range(6.0, 24.0))).map(off_grid);
                if self.good_eye(eye, target) {
                    return (eye, target, 60.0);
                }
            }
        }
        let i = *self.rng.pick(&translucent);
        self.aim_at(i, None)
    }

    /// Looks at box `i`; with `along`, from the end of the stack (first, count, axis).
    fn aim_at(
        &mut self,
        i: usize,
        along: Option<(usize, usize, usize)>,
    ) -> ([f64; 3], [f64; 3], f64) {
        let target = self.boxes[i].center().map(off_grid);
        let distant = along.is_none() && self.rng.chance(0.1);
        let mut eye = target;
        for _ in 0..40 {
            eye = if let Some((first, count, axis)) = along {
                let (a, b) = (&self.boxes[first], &self.boxes[first + count - 1]);
                let (lo, hi) = (f64::from(a.min[axis]), f64::from(b.max[axis]) + 1.0);
                let mut e = target;
                let back = self.rng.range(1.5, 20.0);
                e[axis] = if self.rng.chance(0.5) {
                    lo - back
                } else {
                    hi + back
                };
                for (k, v) in e.iter_mut().enumerate() {
                    if k != axis {
                        *v += self.rng.range(-3.0, 3.0);
                    }
                }
                e.map(off_grid)
            } else {
                let d = self.direction(0.7);
                let dist = if distant {
                    f64::from(self.rng.int(200, 2000))
                } else if self.rng.chance(0.75) {
                    self.rng.range(4.0, 40.0)
                } else {
                    self.rng.range(1.5, 4.0)
                };
                add(target, scale(d, dist)).map(off_grid)
            };
            if self.good_eye(eye, target) {
                break;
            }
        }
        let fov = if distant {
            self.features.distant = true;
            let dist = length(sub(target, eye));
            let radius = self.boxes[i].radius().max(2.0);
            // Twice the target's angular size (small-angle: no atan), in 1/100 degrees.
            let deg = 2.0 * 2.4 * radius / dist * (180.0 / std::f64::consts::PI);
            (deg * 100.0).round().clamp(50.0, 2000.0) / 100.0
        } else {
            60.0
        };
        (eye, target, fov)
    }

    /// Moves one coordinate of the eye exactly onto the nearest face plane of a
    /// translucent box along that axis, when the eye stays in a clear place.
    fn snap_to_plane(&mut self, eye: &mut [f64; 3], target: [f64; 3]) {
        let axis = self.rng.int(0, 2) as usize;
        let mut planes: Vec<f64> = self
            .translucent_boxes()
            .iter()
            .flat_map(|&i| {
                let b = &self.boxes[i];
                [f64::from(b.min[axis]), f64::from(b.max[axis]) + 1.0]
            })
            .collect();
        planes.sort_by(|a, b| (a - eye[axis]).abs().total_cmp(&(b - eye[axis]).abs()));
        for p in planes.into_iter().take(4) {
            let mut e = *eye;
            e[axis] = p;
            if length(sub(target, e)) > 0.5 && self.good_eye(e, target) {
                *eye = e;
                return;
            }
        }
    }
}
