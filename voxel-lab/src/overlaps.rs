//! Which pixels show two of a game's objects that interpenetrate: a fish through a cloud
//! of bubbles, two crates pushed into each other. No order of whole objects is right
//! there (each is partly in front of the other), so the sorted techniques' error on such
//! pixels is reported apart from the rest.
//!
//! Two translucent things interpenetrate when their solids intersect: boxes (entities, at
//! any angle) by the separating-axis test of Gottschalk, Lin & Manocha (1996), a particle
//! (a camera-facing square, a box of no depth) likewise. A pixel counts when its centre ray
//! meets both of an intersecting pair. Apart from those, two things whose bounding balls
//! meet are *near*: their solids do not touch, but the sorted techniques order them by their
//! centres, which can be wrong where they overlap on screen (a bubble just under a turned
//! fish, seen from above); the lab counts their pixels apart too.

use glam::DVec3;
use voxel_render::Camera;
use voxel_render::content::Content;

/// A box in world space: centre, and its three axes scaled by the half extents.
#[derive(Clone, Copy, Debug)]
struct Solid {
    center: DVec3,
    axes: [DVec3; 3],
}

impl Solid {
    /// Half the box's extent along unit direction `n`.
    fn reach(&self, n: DVec3) -> f64 {
        self.axes.iter().map(|a| a.dot(n).abs()).sum()
    }

    /// The radius of a ball around the centre holding the box.
    fn radius(&self) -> f64 {
        self.axes.iter().map(|a| a.length()).sum()
    }

    /// Whether the ray `eye + t dir` (t ≥ 0) meets the box (a slab test in its frame).
    fn hit(&self, eye: DVec3, dir: DVec3) -> bool {
        let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
        let o = eye - self.center;
        for axis in self.axes {
            let len2 = axis.length_squared();
            if len2 == 0.0 {
                // No depth along this axis: a square; its plane is another axis' normal.
                continue;
            }
            let (oa, da) = (o.dot(axis) / len2, dir.dot(axis) / len2);
            if da == 0.0 {
                if oa.abs() > 1.0 {
                    return false;
                }
                continue;
            }
            let (a, b) = ((-1.0 - oa) / da, (1.0 - oa) / da);
            t0 = t0.max(a.min(b));
            t1 = t1.min(a.max(b));
        }
        // A flat box (a square) is met where its plane is, inside its outline.
        if let Some(flat) = self.axes.iter().position(|a| a.length_squared() == 0.0) {
            let [u, v] = [(flat + 1) % 3, (flat + 2) % 3].map(|k| self.axes[k]);
            let n = u.cross(v);
            let dn = dir.dot(n);
            if dn == 0.0 {
                return false;
            }
            let t = -o.dot(n) / dn;
            if t < 0.0 {
                return false;
            }
            let q = o + dir * t;
            return q.dot(u).abs() <= u.length_squared() && q.dot(v).abs() <= v.length_squared();
        }
        t0 <= t1
    }
}

/// Whether two boxes intersect: no separating axis among their 15 candidates.
fn intersect(a: &Solid, b: &Solid) -> bool {
    let d = b.center - a.center;
    if d.length() > a.radius() + b.radius() {
        return false;
    }
    let mut axes = Vec::with_capacity(15);
    for s in [a, b] {
        axes.extend(s.axes.iter().filter_map(|x| x.try_normalize()));
    }
    for x in a.axes {
        for y in b.axes {
            if let Some(n) = x.cross(y).try_normalize() {
                axes.push(n);
            }
        }
    }
    // A square's normal (its missing axis) is a candidate too.
    for s in [a, b] {
        if let Some(flat) = s.axes.iter().position(|x| x.length_squared() == 0.0) {
            let n = s.axes[(flat + 1) % 3].cross(s.axes[(flat + 2) % 3]);
            axes.extend(n.try_normalize());
        }
    }
    axes.iter()
        .all(|&n| d.dot(n).abs() <= a.reach(n) + b.reach(n))
}

/// The translucent solids of `content` seen by `camera`: particles (squares facing it),
/// then translucent entities.
fn solids(content: &Content, camera: &Camera) -> Vec<Solid> {
    let [_, right, up] = view_basis(camera);
    content
        .particles
        .iter()
        .map(|p| {
            let s = f64::from(p.half_size);
            Solid {
                center: p.center,
                axes: [right * s, up * s, DVec3::ZERO],
            }
        })
        .chain(
            content
                .entities
                .iter()
                .filter(|e| !e.is_opaque())
                .map(|e| Solid {
                    center: e.center,
                    axes: e.axes(),
                }),
        )
        .collect()
}

/// The pairs of `solids` that intersect (particles, which all face one way, are never a
/// pair among themselves: parallel squares meet only in their plane).
fn intersecting(solids: &[Solid], particles: usize) -> Vec<(usize, usize)> {
    pairs(solids, particles, intersect)
}

/// The pairs of `solids` (an entity and anything) whose bounding balls meet though the
/// solids do not.
fn near(solids: &[Solid], particles: usize) -> Vec<(usize, usize)> {
    pairs(solids, particles, |a, b| {
        a.center.distance(b.center) <= a.radius() + b.radius() && !intersect(a, b)
    })
}

fn pairs(
    solids: &[Solid],
    particles: usize,
    meet: impl Fn(&Solid, &Solid) -> bool,
) -> Vec<(usize, usize)> {
    let mut pairs = Vec::new();
    for j in particles..solids.len() {
        for i in 0..j {
            if meet(&solids[i], &solids[j]) {
                pairs.push((i, j));
            }
        }
    }
    pairs
}

/// What a pixel shows of a game's objects: two that interpenetrate, two near each other,
/// or neither ([`object_mask`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Pair {
    /// No two of them at once (or two apart).
    #[default]
    None,
    /// Two whose bounding balls meet though their solids do not.
    Near,
    /// Two whose solids intersect.
    Interpenetrating,
}

/// Per pixel of a `size` picture of `camera` (row by row): the pair of the game's
/// translucent objects its centre ray meets, interpenetrating ones first.
pub fn object_mask(content: &Content, camera: &Camera, size: (u32, u32)) -> Vec<Pair> {
    let (w, h) = size;
    let mut mask = vec![Pair::None; w as usize * h as usize];
    let solids = solids(content, camera);
    let n = content.particles.len();
    let (crossing, close) = (intersecting(&solids, n), near(&solids, n));
    if crossing.is_empty() && close.is_empty() {
        return mask;
    }
    let [f, right, up] = view_basis(camera);
    let tan_y = (camera.fov_y_deg.to_radians() / 2.0).tan();
    let tan_x = tan_y * f64::from(w) / f64::from(h);
    for y in 0..h {
        for x in 0..w {
            let nx = (f64::from(x) + 0.5) / f64::from(w) * 2.0 - 1.0;
            let ny = 1.0 - (f64::from(y) + 0.5) / f64::from(h) * 2.0;
            let dir = f + right * (nx * tan_x) + up * (ny * tan_y);
            let hits = |k: usize| solids[k].hit(camera.eye, dir);
            let both = |pairs: &[(usize, usize)]| pairs.iter().any(|&(i, j)| hits(i) && hits(j));
            mask[(y * w + x) as usize] = if both(&crossing) {
                Pair::Interpenetrating
            } else if both(&close) {
                Pair::Near
            } else {
                Pair::None
            };
        }
    }
    mask
}

/// Per pixel of a `size` picture of `camera` (row by row): whether its centre ray meets two
/// of the game's translucent objects that interpenetrate.
pub fn overlap_mask(content: &Content, camera: &Camera, size: (u32, u32)) -> Vec<bool> {
    object_mask(content, camera, size)
        .into_iter()
        .map(|p| p == Pair::Interpenetrating)
        .collect()
}

/// The view basis of `Camera::view_proj` (which particles face): the unit forward, right
/// and up directions. Up is built from world up, or from +z looking straight up or down.
pub(crate) fn view_basis(camera: &Camera) -> [DVec3; 3] {
    let f = camera.unit_forward();
    let up = if f.y.abs() > 0.999 {
        DVec3::Z
    } else {
        DVec3::Y
    };
    let right = f.cross(up).normalize();
    [f, right, right.cross(f)]
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;
    use voxel_render::content::{Entity, Particle};

    fn entity(center: DVec3, size: f32, rotation: DQuat) -> Entity {
        Entity {
            center,
            half_extents: [size / 2.0; 3],
            rotation,
            color: [200, 100, 50],
            opacity: 0.5,
            emissive: 0.0,
        }
    }

    #[test]
    fn boxes_intersect_when_no_axis_separates_them() {
        let camera = Camera::look_at(DVec3::new(0.0, 0.0, 10.0), DVec3::ZERO, 60.0, 0.1, 100.0)
            .expect("a valid camera");
        let turned = DQuat::from_rotation_y(0.7) * DQuat::from_rotation_x(0.4);
        let content = Content {
            particles: vec![],
            entities: vec![
                entity(DVec3::ZERO, 2.0, DQuat::IDENTITY),
                // Corner to corner but apart along the diagonal: only a cross axis
                // separates them from the first.
                entity(
                    DVec3::new(1.9, 1.9, 0.0),
                    2.0,
                    DQuat::from_rotation_z(0.785),
                ),
                // Through the first.
                entity(DVec3::new(0.0, -1.2, 0.0), 1.0, turned),
            ],
        };
        let s = solids(&content, &camera);
        assert!(!intersect(&s[0], &s[1]));
        assert!(intersect(&s[0], &s[2]));
        assert_eq!(intersecting(&s, 0), vec![(0, 2)]);
        let mask = overlap_mask(&content, &camera, (256, 144));
        let n = mask.iter().filter(|&&m| m).count();
        assert!(n > 20 && n < 256 * 144 / 8, "{n} pixels");
        // Apart: nothing.
        let apart = Content {
            particles: vec![],
            entities: content.entities[..2].to_vec(),
        };
        assert!(overlap_mask(&apart, &camera, (64, 36)).iter().all(|&m| !m));
    }

    #[test]
    fn a_particle_inside_a_box_interpenetrates_it_one_beside_it_does_not() {
        let camera = Camera::look_at(DVec3::new(0.0, 0.0, 10.0), DVec3::ZERO, 60.0, 0.1, 100.0)
            .expect("a valid camera");
        let particle = |center| Particle {
            center,
            half_size: 0.2,
            color: [255; 3],
            opacity: 0.4,
            emissive: 0.0,
        };
        let content = Content {
            particles: vec![
                particle(DVec3::new(0.3, 0.0, 0.0)),
                particle(DVec3::new(3.0, 0.0, 0.0)),
            ],
            entities: vec![entity(DVec3::ZERO, 2.0, DQuat::IDENTITY)],
        };
        let s = solids(&content, &camera);
        assert_eq!(intersecting(&s, 2), vec![(0, 2)]);
    }
}
