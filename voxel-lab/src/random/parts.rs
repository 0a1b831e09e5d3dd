//! The blocks of a scene, placed as boxes: the opaque ground, random boxes, a large
//! surface with small objects, a glass floor or ceiling with objects beyond it, a stack of
//! sheets, and the extra block types put to use.

use super::boxes::{Class, GROUND, Gen, L, OPAQUE};

impl Gen {
    fn random_box_dims(&mut self) -> ([i32; 3], u8) {
        let r = self.rng.unit();
        if r < 0.4 {
            let axis = self.rng.int(0, 2) as usize;
            let mut d = [0; 3].map(|_| self.rng.int(2, 20));
            d[axis] = 1;
            (d, 0)
        } else if r < 0.75 {
            ([0; 3].map(|_| self.rng.int(2, 12)), 1)
        } else {
            ([0; 3].map(|_| self.rng.int(1, 3)), 2)
        }
    }

    pub(super) fn place(&mut self, d: [i32; 3], y_min: i32) -> [i32; 3] {
        [
            self.rng.int(0, L - d[0]),
            self.rng.int(y_min, (L - d[1]).max(y_min)),
            self.rng.int(0, L - d[2]),
        ]
    }

    pub(super) fn parts(&mut self) {
        let y_min = if self.ground {
            let g = GROUND[self.rng.int(0, 3) as usize];
            self.push(g, Class::Opaque, [0, 0, 0], [L - 1, 0, L - 1]);
            1
        } else {
            0
        };
        // Random boxes.
        for _ in 0..self.rng.int(2, 7) {
            let (d, shape) = self.random_box_dims();
            let min = self.place(d, y_min);
            let max = [0, 1, 2].map(|k| min[k] + d[k] - 1);
            let r = self.rng.unit();
            if r < 0.6 {
                let t = self.translucent();
                self.push(&t, Class::Translucent, min, max);
                match shape {
                    0 => self.features.thin_sheets = true,
                    1 => self.features.solid_volumes = true,
                    _ => {}
                }
            } else if r < 0.8 {
                let o = *self.rng.pick(&OPAQUE);
                self.push(o, Class::Opaque, min, max);
            } else {
                self.push("leaves", Class::Cutout, min, max);
            }
        }
        // A large surface with small objects.
        if self.rng.chance(0.3) {
            self.large_surface(y_min);
        }
        // A glass floor and/or ceiling.
        if self.rng.chance(0.3) {
            self.floor_ceiling(y_min);
        }
        // A stack.
        if self.rng.chance(0.35) {
            self.stack(y_min);
        }
        if self.rng.chance(0.15) && !self.boxes.iter().any(|b| b.class == Class::Cutout) {
            let d = [0; 3].map(|_| self.rng.int(2, 6));
            let min = self.place(d, y_min);
            let max = [0, 1, 2].map(|k| min[k] + d[k] - 1);
            self.push("leaves", Class::Cutout, min, max);
        }
    }

    fn large_surface(&mut self, y_min: i32) {
        let (sx, sz) = (self.rng.int(24, L), self.rng.int(24, L));
        let thick = if self.rng.chance(0.7) {
            1
        } else {
            self.rng.int(2, 4)
        };
        let y0 = self.rng.int(y_min + 2, y_min + 20);
        let x0 = self.rng.int(0, L - sx);
        let z0 = self.rng.int(0, L - sz);
        let min = [x0, y0, z0];
        let max = [x0 + sx - 1, y0 + thick - 1, z0 + sz - 1];
        if self.rng.chance(0.7) {
            let t = self.translucent();
            self.push(&t, Class::Translucent, min, max);
            self.surface = Some((min, max));
            if thick == 1 {
                self.features.thin_sheets = true;
            }
        } else {
            let o = *self.rng.pick(&OPAQUE);
            self.push(o, Class::Opaque, min, max);
        }
        self.features.large_surface = true;
        let top = y0 + thick;
        for _ in 0..self.rng.int(3, 12) {
            let d = [self.rng.int(1, 3), self.rng.int(1, 2), self.rng.int(1, 3)];
            let x = self.rng.int(x0, x0 + sx - d[0]);
            let z = self.rng.int(z0, z0 + sz - d[2]);
            let r = self.rng.unit();
            let y = if r < 0.6 {
                top
            } else if r < 0.8 {
                top - 1
            } else {
                y0 - d[1]
            };
            let min = [x, y, z];
            let max = [x + d[0] - 1, y + d[1] - 1, z + d[2] - 1];
            let r = self.rng.unit();
            if r < 0.75 {
                let t = self.translucent();
                self.push(&t, Class::Translucent, min, max);
            } else if r < 0.9 {
                let o = *self.rng.pick(&OPAQUE);
                self.push(o, Class::Opaque, min, max);
            } else {
                self.push("leaves", Class::Cutout, min, max);
            }
        }
    }

    fn floor_ceiling(&mut self, y_min: i32) {
        let r = self.rng.unit();
        let (floor, ceiling) = (r < 0.75, r >= 0.5);
        let s = self.rng.int(20, L);
        let (x0, z0) = (self.rng.int(0, L - s), self.rng.int(0, L - s));
        let thick = if self.rng.chance(0.8) { 1 } else { 2 };
        let yf = self.rng.int(y_min + 4, y_min + 16);
        let yc = if floor {
            yf + thick + self.rng.int(4, 14)
        } else {
            self.rng.int(y_min + 10, y_min + 30)
        };
        let kind = |g: &mut Self| {
            if g.rng.chance(0.5) {
                "glass".to_owned()
            } else {
                g.translucent()
            }
        };
        if floor {
            let t = kind(self);
            let i = self.push(
                &t,
                Class::Translucent,
                [x0, yf, z0],
                [x0 + s - 1, yf + thick - 1, z0 + s - 1],
            );
            self.floor = Some(i);
            self.features.glass_floor = true;
            for _ in 0..self.rng.int(1, 4) {
                let d = [0; 3].map(|_| self.rng.int(1, 4));
                let x = self.rng.int(x0, x0 + s - d[0]);
                let z = self.rng.int(z0, z0 + s - d[2]);
                let y = self.rng.int((yf - 8).max(y_min), yf - d[1]);
                let b = self.beyond_box([x, y, z], d);
                self.beyond.push(b);
            }
        }
        if ceiling {
            let t = kind(self);
            let i = self.push(
                &t,
                Class::Translucent,
                [x0, yc, z0],
                [x0 + s - 1, yc + thick - 1, z0 + s - 1],
            );
            self.ceiling = Some(i);
            self.features.glass_ceiling = true;
            for _ in 0..self.rng.int(1, 3) {
                let d = [0; 3].map(|_| self.rng.int(1, 4));
                let x = self.rng.int(x0, x0 + s - d[0]);
                let z = self.rng.int(z0, z0 + s - d[2]);
                let y = self.rng.int(yc + thick, yc + thick + 6);
                let b = self.beyond_box([x, y, z], d);
                self.beyond.push(b);
            }
        }
        if thick == 1 {
            self.features.thin_sheets = true;
        }
    }

    fn beyond_box(&mut self, min: [i32; 3], d: [i32; 3]) -> usize {
        let max = [0, 1, 2].map(|k| min[k] + d[k] - 1);
        if self.rng.chance(0.6) {
            let t = self.translucent();
            self.push(&t, Class::Translucent, min, max)
        } else {
            let o = *self.rng.pick(&OPAQUE);
            self.push(o, Class::Opaque, min, max)
        }
    }

    fn stack(&mut self, y_min: i32) {
        let r = self.rng.unit();
        let layers = if r < 0.5 {
            self.rng.int(2, 8)
        } else if r < 0.8 {
            self.rng.int(9, 24)
        } else {
            self.rng.int(25, 64)
        };
        let spacing = self.rng.int(1, 3);
        let axis = self.rng.int(0, 2) as usize;
        // 2 to 4 different types in turn (touching sheets of one type would merge).
        let n_types = self.rng.int(2, 4) as usize;
        let mut types: Vec<String> = Vec::new();
        while types.len() < n_types.min(self.pool.len()) {
            let t = self.translucent();
            if !types.contains(&t) {
                types.push(t);
            }
        }
        let (w, h) = (self.rng.int(3, 16), self.rng.int(3, 16));
        let mut base = [0; 3];
        let others: Vec<usize> = (0..3).filter(|&k| k != axis).collect();
        base[others[0]] = self.rng.int(0, L - w);
        base[others[1]] = self.rng.int(0, L - h);
        base[axis] = self.rng.int(0, 8);
        if axis == 1 {
            base[1] += y_min;
        } else if others[0] == 1 {
            base[1] = self.rng.int(y_min, L - w);
        } else if others[1] == 1 {
            base[1] = self.rng.int(y_min, L - h);
        }
        let first = self.boxes.len();
        for j in 0..layers {
            let mut min = base;
            min[axis] += j * spacing;
            let mut max = min;
            max[others[0]] += w - 1;
            max[others[1]] += h - 1;
            let t = types[j as usize % types.len()].clone();
            self.push(&t, Class::Translucent, min, max);
        }
        self.stack = Some((first, layers as usize, axis));
        self.features.stack_layers = layers as u32;
        self.features.stack_spacing = spacing as u32;
        self.features.thin_sheets = true;
    }

    /// Makes sure every extra type is used: an unused one takes over a random translucent
    /// box outside the stack (whose touching sheets must keep alternating), or gets a
    /// small sheet of its own.
    pub(super) fn use_extras(&mut self) {
        let stack = self
            .stack
            .map_or(0..0, |(first, count, _)| first..first + count);
        for e in 0..self.extras.len() {
            let name = self.extras[e].0.clone();
            if self.boxes.iter().any(|b| b.block == name) {
                continue;
            }
            let free: Vec<usize> = self
                .translucent_boxes()
                .into_iter()
                .filter(|i| !stack.contains(i))
                .collect();
            if free.is_empty() {
                let d = [self.rng.int(2, 10), self.rng.int(2, 10), 1];
                let min = self.place(d, 1);
                let max = [0, 1, 2].map(|k| min[k] + d[k] - 1);
                self.push(&name, Class::Translucent, min, max);
            } else {
                let i = *self.rng.pick(&free);
                self.boxes[i].block = name;
            }
        }
    }
}
