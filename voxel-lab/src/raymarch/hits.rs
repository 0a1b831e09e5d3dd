//! A game's content on a ray: the particles binned per picture tile, the squares and
//! boxes a ray meets.

use std::hash::Hash;

use glam::DVec3;
use voxel_render::Camera;

use super::blocks::srgb_to_linear;
use super::light::Light;
use super::walk::Walker;
use super::{Projection, RayMarcher};
use crate::content::box_normal;
use voxel_render::content::Content;

impl RayMarcher {
    /// The game surfaces the ray from `eye` along `dir` meets between `near` and `far`, by
    /// distance: the particles `particles` (indices) and every entity.
    pub(super) fn content_hits(
        &self,
        eye: DVec3,
        dir: DVec3,
        near: f64,
        far: f64,
        particles: &[u32],
        light: &Light,
    ) -> Vec<ContentHit> {
        let mut hits = Vec::new();
        let [forward, right, up] = light.basis;
        for &i in particles {
            let Some(p) = self.content.particles.get(i as usize) else {
                continue;
            };
            // The square lies in the plane through its centre facing the camera.
            let t = (p.center - eye).dot(forward) / dir.dot(forward);
            if !(t >= near && t <= far) {
                continue;
            }
            let q = eye + dir * t - p.center;
            let s = f64::from(p.half_size);
            if q.dot(right).abs() > s || q.dot(up).abs() > s {
                continue;
            }
            // Lit, plus its own light (`content.wgsl`).
            let l = light.sky() + f64::from(p.emissive);
            hits.push(ContentHit {
                t,
                color: p.color.map(|c| srgb_to_linear(c) * l),
                alpha: f64::from(p.opacity.clamp(0.0, 1.0)),
                opaque: false,
                id: (1, i, 0),
            });
        }
        for (i, e) in self.content.entities.iter().enumerate() {
            // In the box's frame, scaled to the unit cube: the slab test.
            let axes = e.axes();
            let o = eye - e.center;
            let (mut t_in, mut t_out, mut face) = (f64::NEG_INFINITY, f64::INFINITY, (0, 0.0));
            for (a, axis) in axes.iter().enumerate() {
                let len2 = axis.length_squared();
                let (oa, da) = (o.dot(*axis) / len2, dir.dot(*axis) / len2);
                if da == 0.0 {
                    if oa.abs() > 1.0 {
                        t_in = f64::INFINITY;
                    }
                    continue;
                }
                let (t0, t1) = ((-1.0 - oa) / da, (1.0 - oa) / da);
                let (lo, hi, sign) = if t0 < t1 {
                    (t0, t1, -1.0)
                } else {
                    (t1, t0, 1.0)
                };
                if lo > t_in {
                    t_in = lo;
                    face = (a, sign);
                }
                t_out = t_out.min(hi);
            }
            // The face the ray enters through (back faces are culled), in view; from
            // inside a translucent box, the face it leaves through (the GPU draws the
            // far faces of a box the eye is in).
            if t_in > t_out {
                continue;
            }
            if t_in < 0.0 && t_out > 0.0 && !e.is_opaque() {
                let exit = axes
                    .iter()
                    .enumerate()
                    .filter_map(|(a, axis)| {
                        let len2 = axis.length_squared();
                        let (oa, da) = (o.dot(*axis) / len2, dir.dot(*axis) / len2);
                        (da != 0.0).then(|| {
                            let t = (da.signum() - oa) / da;
                            (t, a, da.signum())
                        })
                    })
                    .min_by(|x, y| x.0.total_cmp(&y.0));
                if let Some((t, a, sign)) = exit
                    && t >= near
                    && t <= far
                {
                    let normal = box_normal(e.rotation, a, sign);
                    let l = light.on(normal) + f64::from(e.emissive);
                    hits.push(ContentHit {
                        t,
                        color: e.color.map(|c| srgb_to_linear(c) * l),
                        alpha: f64::from(e.opacity.clamp(0.0, 1.0)),
                        opaque: false,
                        id: (2, i as u32, a as u8 * 2 + u8::from(sign > 0.0)),
                    });
                }
                continue;
            }
            if !(t_in >= near && t_in <= far) {
                continue;
            }
            let normal = box_normal(e.rotation, face.0, face.1);
            let l = light.on(normal) + f64::from(e.emissive);
            hits.push(ContentHit {
                t: t_in,
                color: e.color.map(|c| srgb_to_linear(c) * l),
                alpha: f64::from(e.opacity.clamp(0.0, 1.0)),
                opaque: e.is_opaque(),
                id: (2, i as u32, face.0 as u8 * 2 + u8::from(face.1 > 0.0)),
            });
        }
        hits.sort_by(|a, b| a.t.total_cmp(&b.t));
        hits
    }

    /// Adds the content hits before `t` (from `next` on) to the walk: translucent ones as
    /// layers; an opaque one ends the ray (returns true).
    pub(super) fn content_until(
        hits: &[ContentHit],
        next: &mut usize,
        t: f64,
        w: &mut Walker<'_>,
    ) -> bool {
        // At equal depth an object is in front of a block's face (on the eye's side of it):
        // the object's hit counts OBJECT_DEPTH_BIAS nearer, as the GPU's exact methods
        // count it.
        let bias = 1.0 - f64::from(voxel_render::stages::OBJECT_DEPTH_BIAS);
        while let Some(h) = hits.get(*next) {
            if h.t * bias >= t {
                break;
            }
            *next += 1;
            h.id.hash(w.hasher);
            w.absorb_to(h.t);
            if h.opaque {
                return true;
            }
            h.id.hash(w.faces);
            if w.want_color && h.alpha > 0.0 {
                w.layers.push([h.color[0], h.color[1], h.color[2], h.alpha]);
            }
        }
        false
    }
}

/// The particles whose squares may cover each 16 × 16 pixel tile of a picture, so that a
/// ray tests a few of them, not thousands.
pub(super) struct Bins {
    cols: usize,
    cells: Vec<Vec<u32>>,
}

const BIN_PX: f64 = 16.0;

impl Bins {
    pub(super) fn new(
        content: &Content,
        camera: &Camera,
        projection: &Projection,
        light: &Light,
    ) -> Self {
        let (w, h) = projection.size;
        let cols = (w / BIN_PX).ceil().max(1.0) as usize;
        let rows = (h / BIN_PX).ceil().max(1.0) as usize;
        let mut cells = vec![Vec::new(); cols * rows];
        let [_, right, up] = light.basis;
        for (i, p) in content.particles.iter().enumerate() {
            let s = f64::from(p.half_size);
            let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)].map(|(a, b)| {
                projection.pixel(p.center + right * (a * s) + up * (b * s) - camera.eye)
            });
            // A square reaching behind the eye: every tile (rare).
            let (x0, y0, x1, y1) = if corners.iter().all(Option::is_some) {
                let c = corners.map(|c| c.unwrap_or_default());
                let xs = c.map(|c| c.0);
                let ys = c.map(|c| c.1);
                let min = |v: [f64; 4]| v.iter().copied().fold(f64::INFINITY, f64::min);
                let max = |v: [f64; 4]| v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                (min(xs) - 1.0, min(ys) - 1.0, max(xs) + 1.0, max(ys) + 1.0)
            } else if corners.iter().any(Option::is_some) {
                (0.0, 0.0, w, h)
            } else {
                continue;
            };
            if x1 < 0.0 || y1 < 0.0 || x0 > w || y0 > h {
                continue;
            }
            let tile = |v: f64, n: usize| ((v.max(0.0) / BIN_PX) as usize).min(n - 1);
            for ty in tile(y0, rows)..=tile(y1, rows) {
                for tx in tile(x0, cols)..=tile(x1, cols) {
                    cells[ty * cols + tx].push(i as u32);
                }
            }
        }
        Self { cols, cells }
    }

    /// The particles that may cover pixel point `(x, y)`.
    pub(super) fn at(&self, x: f64, y: f64) -> &[u32] {
        let (tx, ty) = (
            (x.max(0.0) / BIN_PX) as usize,
            (y.max(0.0) / BIN_PX) as usize,
        );
        let rows = self.cells.len() / self.cols;
        self.cells
            .get(ty.min(rows - 1) * self.cols + tx.min(self.cols - 1))
            .map_or(&[], Vec::as_slice)
    }
}

/// A game surface on a ray.
#[derive(Clone, Copy, Debug)]
pub(super) struct ContentHit {
    pub(super) t: f64,
    /// Lit colour, linear.
    pub(super) color: [f64; 3],
    alpha: f64,
    opaque: bool,
    /// (1 particle / 2 entity, index, face): the signature's identity of the surface.
    id: (u8, u32, u8),
}
