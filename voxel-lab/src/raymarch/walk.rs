//! One ray's walk through the blocks (Amanatides & Woo's DDA): the face rules at each
//! boundary, the cutout test, and the media the ray passes through.

use std::hash::{Hash, Hasher};

use glam::DVec3;
use voxel_core::{BlockId, CHUNK_SIZE, Chunk, Face, RenderClass};

use super::light::Light;
use super::{RayMarcher, RayResult, Shading, Surface};

impl RayMarcher {
    /// Marches one ray from `eye` along `dir` (whose component along the view axis is 1,
    /// so that the ray parameter is the view depth) between `near` and `far`.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn march(
        &self,
        eye: DVec3,
        dir: DVec3,
        near: f64,
        far: f64,
        medium: Option<BlockId>,
        shading: &Shading,
        light: &Light,
        want_color: bool,
        particles: &[u32],
    ) -> RayResult {
        let hits = if self.content.is_empty() {
            Vec::new()
        } else {
            self.content_hits(eye, dir, near, far, particles, light)
        };
        let mut next_hit = 0;
        let mut content_end = false;
        let mut hasher = std::collections::hash_map::DefaultHasher::new();
        let mut faces = std::collections::hash_map::DefaultHasher::new();
        let mut layers: Vec<[f64; 4]> = Vec::new();
        let mut end: Option<(Surface, [f64; 3])> = None;
        let mut boundary: Option<f64> = None;

        // In the eye's medium the ray starts inside a volume, at the eye: what it meets on the
        // way to the medium's first surface is seen through the part of the way in front of
        // it, as everything inside a volume is.
        let eye_volume = light
            .fog
            .as_ref()
            .filter(|f| f.density > 0.0)
            .map(|f| Volume {
                start: 0.0,
                color: f.color,
                absorption: f.density,
            });
        let mut walker = Walker {
            eye,
            dir,
            near,
            far,
            medium,
            volume: eye_volume,
            shading,
            light,
            want_color,
            layers: &mut layers,
            end: &mut end,
            boundary: &mut boundary,
            hasher: &mut hasher,
            faces: &mut faces,
        };
        // Clip the walk to the loaded chunks' box (and the far plane): outside it every
        // block is air.
        let (lo, hi) = self.bounds;
        let (mut t0, mut t1) = (0.0f64, far);
        let mut entry_axis = None;
        for a in 0..3 {
            let (o, d) = (eye[a], dir[a]);
            let (l, h) = (lo[a] as f64, hi[a] as f64);
            if d == 0.0 {
                if o < l || o >= h {
                    t1 = -1.0;
                }
                continue;
            }
            let (ta, tb) = if d > 0.0 {
                ((l - o) / d, (h - o) / d)
            } else {
                ((h - o) / d, (l - o) / d)
            };
            if ta > t0 {
                t0 = ta;
                entry_axis = Some(a);
            }
            t1 = t1.min(tb);
        }
        if t0 <= t1 && !self.chunks.is_empty() {
            let start = eye + dir * t0;
            let mut cell = [0i64; 3];
            let mut step = [0i64; 3];
            let mut t_max = [f64::INFINITY; 3];
            let mut t_delta = [f64::INFINITY; 3];
            for a in 0..3 {
                let d = dir[a];
                let mut c = start[a].floor() as i64;
                if entry_axis.is_some() {
                    // Entering the box: the first cell is inside it.
                    c = c.clamp(lo[a], hi[a] - 1);
                }
                cell[a] = c;
                if d > 0.0 {
                    step[a] = 1;
                    t_max[a] = ((c + 1) as f64 - eye[a]) / d;
                    t_delta[a] = 1.0 / d;
                } else if d < 0.0 {
                    step[a] = -1;
                    t_max[a] = (c as f64 - eye[a]) / d;
                    t_delta[a] = -1.0 / d;
                }
            }
            let mut prev = self.get(cell);
            if Self::content_until(&hits, &mut next_hit, t0, &mut walker) {
                content_end = true;
            } else if let Some(axis) = entry_axis {
                // The ray enters the box from air through a face along `axis`.
                self.crossing(
                    &CrossingCtx {
                        from: BlockId::AIR,
                        to: prev,
                        to_cell: cell,
                        axis,
                        step: step[axis],
                        t: t0,
                    },
                    &mut walker,
                );
            }
            let s = CHUNK_SIZE as i64;
            let chunk_of = |cell: &[i64; 3]| cell.map(|v| v.div_euclid(s));
            let mut here = chunk_of(&cell);
            let mut blocks = self.chunk_blocks(here);
            while walker.end.is_none() && !content_end {
                if blocks.is_none() && prev == BlockId::AIR {
                    // An absent chunk is air: jump to the last cell before it is left.
                    let origin = here.map(|c| c * s);
                    let exit = |a: usize| {
                        let plane = if step[a] > 0 {
                            origin[a] + s
                        } else {
                            origin[a]
                        };
                        (plane as f64 - eye[a]) / dir[a]
                    };
                    let t_exit = (0..3)
                        .filter(|&a| step[a] != 0)
                        .map(exit)
                        .fold(f64::INFINITY, f64::min);
                    if t_exit > t1 {
                        break;
                    }
                    for a in 0..3 {
                        // Never back: at an exact cell boundary `floor` can name the cell
                        // the ray has just left.
                        let v = (eye[a] + dir[a] * t_exit).floor() as i64;
                        let v = match step[a] {
                            1 => v.max(cell[a]),
                            -1 => v.min(cell[a]),
                            _ => cell[a],
                        };
                        cell[a] = v.clamp(origin[a], origin[a] + s - 1);
                        if step[a] > 0 {
                            t_max[a] = ((cell[a] + 1) as f64 - eye[a]) / dir[a];
                        } else if step[a] < 0 {
                            t_max[a] = (cell[a] as f64 - eye[a]) / dir[a];
                        }
                    }
                }
                let axis = if t_max[0] <= t_max[1] && t_max[0] <= t_max[2] {
                    0
                } else if t_max[1] <= t_max[2] {
                    1
                } else {
                    2
                };
                let t = t_max[axis];
                if Self::content_until(&hits, &mut next_hit, t.min(t1), &mut walker) {
                    content_end = true;
                    break;
                }
                // The crossing out of the loaded box (into the air of absent chunks, where
                // the mesher closes a volume with faces) is a crossing too: `t_max` and `t1`
                // are computed apart and may differ by a rounding.
                if t > t1 + 1e-9 * t1.abs().max(1.0) {
                    break;
                }
                cell[axis] += step[axis];
                t_max[axis] += t_delta[axis];
                let now = chunk_of(&cell);
                if now != here {
                    here = now;
                    blocks = self.chunk_blocks(here);
                }
                let b = blocks.map_or(BlockId::AIR, |c| {
                    let l = cell.map(|v| v.rem_euclid(s) as usize);
                    c[Chunk::dense_index(l[0], l[1], l[2])]
                });
                let ctx = CrossingCtx {
                    from: prev,
                    to: b,
                    to_cell: cell,
                    axis,
                    step: step[axis],
                    t,
                };
                self.crossing(&ctx, &mut walker);
                prev = b;
            }
        }
        if !content_end
            && walker.end.is_none()
            && Self::content_until(&hits, &mut next_hit, far, &mut walker)
        {
            content_end = true;
        }
        if !content_end && walker.end.is_none() {
            // Into the sky: a volume the ray is still in ends where the loaded blocks do; the
            // eye's own passage, which no surface ended, at the far plane (where the
            // renderer's boundary lies when nothing is drawn).
            let own_passage = medium.is_some() && walker.boundary.is_none();
            walker.absorb_to(if own_passage { far } else { t1.min(far) });
        }
        let end_surface = end.map(|(s, _)| s);
        end_surface.map(|s| s.plane()).hash(&mut hasher);
        let content_color = content_end.then(|| hits[next_hit - 1].color);
        let mut result = RayResult {
            color: [0.0; 3],
            end: end_surface,
            signature: hasher.finish(),
            layer_faces: faces.finish(),
            content_end,
        };
        if !want_color {
            return result;
        }
        // Front to back over the background (the opaque colour, or the sky).
        let background = content_color.unwrap_or_else(|| end.map_or(light.sky, |(_, c)| c));
        let mut acc = [0.0f64; 4];
        for l in &layers {
            let k = 1.0 - acc[3];
            for c in 0..3 {
                acc[c] += k * l[c] * l[3];
            }
            acc[3] += k * l[3];
        }
        result.color = std::array::from_fn(|c| acc[c] + (1.0 - acc[3]) * background[c]);
        result
    }

    /// The faces on the boundary the ray crosses from block `from` into block `to`: the
    /// face of `to` toward the ray (a front face) and, from inside a medium, the face of
    /// `from` (a back face). Returns whether the ray ended here.
    fn crossing(&self, x: &CrossingCtx, w: &mut Walker<'_>) -> bool {
        let depth_ok = |t: f64| t >= w.near && t <= w.far;
        if !depth_ok(x.t) {
            return false;
        }
        let (ca, cb) = (self.class(x.from), self.class(x.to));
        // The translucent type each cell holds (a waterlogged block's cell holds its medium).
        let (ha, hb) = (self.holds(x.from), self.holds(x.to));
        let p = w.eye + w.dir * x.t;
        // The volume the ray was in, up to here.
        w.absorb_to(x.t);
        // The faces of `to` facing the ray (their normal points back along the step): its
        // own opaque or cutout face, then (where a cutout texel lets it through) the face of
        // the translucent type it holds, unless `from` holds that type too.
        let front_face = face_of(x.axis, x.step < 0);
        let (u, v) = face_uv(p, x.axis);
        if ca != RenderClass::Opaque && matches!(cb, RenderClass::Opaque | RenderClass::Cutout) {
            let surface = Surface {
                block: x.to_cell,
                face: front_face,
                id: x.to,
            };
            let a = self.albedo(x.to, front_face, u, v, w.shading.texturing);
            if cb == RenderClass::Opaque || a[3] >= CUTOUT_ALPHA_TEST {
                let color = if w.want_color {
                    self.lit(surface, p, a, w.light, w.shading)
                } else {
                    [0.0; 3]
                };
                *w.end = Some((surface, color));
                return true;
            }
        }
        if let Some(t) = hb
            && ca != RenderClass::Opaque
            && ha != Some(t)
        {
            let surface = Surface {
                block: x.to_cell,
                face: front_face,
                id: t,
            };
            if Some(t) == w.medium && w.boundary.is_none() {
                w.set_boundary(x.t, surface);
            }
            let a = self.albedo(t, front_face, u, v, w.shading.texturing);
            w.layer(self, surface, p, a);
        }
        // From inside a medium the renderer draws translucent back faces too: the face of
        // the type `from` holds, where `to` neither hides it nor holds that type.
        if let Some(m) = w.medium
            && let Some(t) = ha
            && cb != RenderClass::Opaque
            && hb != Some(t)
        {
            let back = Surface {
                block: [0, 1, 2].map(|a| x.to_cell[a] - if a == x.axis { x.step } else { 0 }),
                face: face_of(x.axis, x.step > 0),
                id: t,
            };
            let first = t == m && w.boundary.is_none();
            if first {
                w.set_boundary(x.t, back);
            }
            // It counts when it is the medium's, not toward another translucent type, and
            // the first surface of the medium the ray meets.
            if first && hb.is_none() {
                let a = self.albedo(t, back.face, u, v, w.shading.texturing);
                w.layer(self, back, p, a);
            }
        }
        // The volume of the block entered, unless the eye's own passage goes on (the eye's
        // medium, from the eye).
        let own_passage = w.medium.is_some() && w.boundary.is_none();
        if !own_passage {
            w.volume = self
                .media
                .get(x.to.index())
                .copied()
                .flatten()
                .filter(|m| m.absorption > 0.0)
                .map(|m| Volume {
                    start: x.t,
                    color: m.color.map(|c| c * w.light.medium_light),
                    absorption: m.absorption,
                });
        }
        false
    }
}

/// The alpha test of the cutout pass (`shaders/opaque.wgsl`).
const CUTOUT_ALPHA_TEST: f64 = 0.5;

/// The face along `axis` whose normal points to + (`positive`) or −.
fn face_of(axis: usize, positive: bool) -> Face {
    Face::ALL[axis * 2 + usize::from(!positive)]
}

/// Face coordinates (U, V) of a point on a face along `axis`.
fn face_uv(p: DVec3, axis: usize) -> (f64, f64) {
    (p[(axis + 1) % 3], p[(axis + 2) % 3])
}

/// One boundary crossing.
struct CrossingCtx {
    from: BlockId,
    to: BlockId,
    to_cell: [i64; 3],
    axis: usize,
    step: i64,
    t: f64,
}

/// The state of one ray's walk.
pub(super) struct Walker<'a> {
    eye: DVec3,
    dir: DVec3,
    near: f64,
    far: f64,
    medium: Option<BlockId>,
    /// The volume the ray is in since the last layer (none in the eye's own medium).
    volume: Option<Volume>,
    pub(super) shading: &'a Shading,
    pub(super) light: &'a Light,
    pub(super) want_color: bool,
    pub(super) layers: &'a mut Vec<[f64; 4]>,
    end: &'a mut Option<(Surface, [f64; 3])>,
    boundary: &'a mut Option<f64>,
    pub(super) hasher: &'a mut std::collections::hash_map::DefaultHasher,
    pub(super) faces: &'a mut std::collections::hash_map::DefaultHasher,
}

/// A medium: linear colour, absorption per block as a volume and as the fog an eye inside
/// it sees (`BlockDef::eye_absorption`).
#[derive(Clone, Copy, Debug)]
pub(super) struct Medium {
    pub(super) color: [f64; 3],
    pub(super) absorption: f64,
    pub(super) fog: f64,
}

/// A volume the ray is in: since `start` (a ray parameter), lit colour and absorption.
#[derive(Clone, Copy, Debug)]
struct Volume {
    start: f64,
    color: [f64; 3],
    absorption: f64,
}

impl Walker<'_> {
    /// The way through the volume the ray is in, up to `t`: one layer that keeps
    /// `exp(−σ d)` of what lies behind over its `d` blocks.
    pub(super) fn absorb_to(&mut self, t: f64) {
        if let Some(v) = &mut self.volume {
            let d = (t - v.start) * self.dir.length();
            if d > 0.0 && self.want_color {
                let keep = (-v.absorption * d).exp();
                self.layers
                    .push([v.color[0], v.color[1], v.color[2], 1.0 - keep]);
            }
            v.start = v.start.max(t);
        }
    }

    /// The medium's first surface (it ends the eye's passage through the medium; the
    /// signature notes it, since the path changes where it does).
    fn set_boundary(&mut self, t: f64, s: Surface) {
        *self.boundary = Some(t);
        (1u8, s.plane()).hash(self.hasher);
    }

    /// A blended layer.
    fn layer(&mut self, m: &RayMarcher, s: Surface, p: DVec3, a: [f64; 4]) {
        s.plane().hash(self.hasher);
        s.hash(self.faces);
        if a[3] <= 0.0 {
            return;
        }
        if self.want_color {
            let c = m.lit(s, p, a, self.light, self.shading);
            self.layers.push([c[0], c[1], c[2], a[3].clamp(0.0, 1.0)]);
        }
    }
}
