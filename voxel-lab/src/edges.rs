//! Which pixels lie on a translucent quad's edge, to within the rasterizer's precision.
//!
//! An exact order of quads (`sorted-quads`) and an exact per-pixel order of fragments (the
//! reference) see the same fragments, because both rasterize the same triangles. Where a
//! pixel centre lies within a few 1/256 of a pixel of an edge where three or more quads
//! meet (the top of a wall of stacked sheets, a face ending on another face), the
//! rasterizer's sub-pixel snapping gives the pixel fragments of quads whose true surface
//! the ray just misses. Their depths there are extrapolations of their planes, which may
//! order them differently from the quads' true order in space. The lab reports an exact
//! order's error twice: over every pixel, and over the pixels farther than [`EDGE_PX`]
//! from every translucent quad edge (where the order alone decides the colour).

use glam::{DMat4, DVec3};
use voxel_core::World;
use voxel_mesh::{Mesher, UV_AXES};
use voxel_render::{Camera, Image};

use crate::overlaps::Pair;

/// A pixel centre closer than this to a quad edge (in pixels) is an edge pixel: 16 times
/// the 1/256-pixel snapping of the rasterizer, which leaves room for the f32 vertex
/// transform.
pub const EDGE_PX: f64 = 1.0 / 16.0;

/// Largest number of differing pixels classified; past it, the rest count as off edges
/// (an order that wrong is not an edge effect).
pub const MAX_CLASSIFIED: usize = 4096;

/// The edges of every translucent quad of a world, seen by one camera at one size.
#[derive(Debug)]
pub struct Edges {
    segments: Vec<(DVec3, DVec3)>,
    eye: DVec3,
    inverse: DMat4,
    size: (u32, u32),
    /// World units per pixel per unit of distance from the eye (vertical).
    pixel_angle: f64,
}

impl Edges {
    /// The translucent quad edges of `world` (meshed against neighbours), for `camera`
    /// rendering at `size`. Chunks the mesher rejects add no edges.
    pub fn new(world: &World, camera: &Camera, size: (u32, u32)) -> Self {
        let mut mesher = Mesher::new(world.registry());
        let mut segments = Vec::new();
        for (pos, chunk) in world.iter() {
            let Ok(meshes) = mesher.mesh(chunk, world.neighbourhood(pos)) else {
                continue;
            };
            let o = DVec3::from(pos.origin().map(|v| v as f64));
            for q in meshes.translucent.iter().filter_map(|q| q.unpack()) {
                let axis = q.face.axis();
                let [ua, va] = UV_AXES[axis];
                let mut corner = DVec3::from(q.pos.map(f64::from)) + o;
                if q.face.is_positive() {
                    corner[axis] += 1.0;
                }
                let mut u = DVec3::ZERO;
                u[ua] = f64::from(q.size[0]);
                let mut v = DVec3::ZERO;
                v[va] = f64::from(q.size[1]);
                let c = [corner, corner + u, corner + u + v, corner + v];
                for i in 0..4 {
                    segments.push((c[i], c[(i + 1) % 4]));
                }
            }
        }
        let aspect = f64::from(size.0) / f64::from(size.1);
        Self {
            segments,
            eye: camera.eye,
            inverse: camera.view_proj(aspect).as_dmat4().inverse(),
            size,
            pixel_angle: 2.0 * (camera.fov_y_deg.to_radians() / 2.0).tan() / f64::from(size.1),
        }
    }

    /// The view direction through the centre of pixel `(x, y)`.
    fn ray(&self, x: u32, y: u32) -> DVec3 {
        let (w, h) = (f64::from(self.size.0), f64::from(self.size.1));
        let nx = (f64::from(x) + 0.5) / w * 2.0 - 1.0;
        let ny = 1.0 - (f64::from(y) + 0.5) / h * 2.0;
        // Camera-relative view-projection: points are relative to the eye.
        let near = self.inverse.project_point3(DVec3::new(nx, ny, 1.0));
        let far = self.inverse.project_point3(DVec3::new(nx, ny, 0.5));
        (far - near).normalize_or_zero()
    }

    /// Distance in pixels from the centre of pixel `(x, y)` to the nearest translucent
    /// quad edge in front of the eye (infinite when there is none).
    pub fn distance_px(&self, x: u32, y: u32) -> f64 {
        let d = self.ray(x, y);
        let mut best = f64::INFINITY;
        for &(a, b) in &self.segments {
            let (a, b) = (a - self.eye, b - self.eye);
            let Some((t, gap)) = ray_segment(d, a, b) else {
                continue;
            };
            best = best.min(gap / (t * self.pixel_angle));
        }
        best
    }

    /// Whether pixel `(x, y)` is an edge pixel ([`EDGE_PX`]).
    pub fn is_edge(&self, x: u32, y: u32) -> bool {
        self.distance_px(x, y) < EDGE_PX
    }
}

/// The ray from the origin along unit `d` against segment `a`–`b`: the ray parameter of
/// their closest approach and the gap there; `None` when that lies behind the eye.
fn ray_segment(d: DVec3, a: DVec3, b: DVec3) -> Option<(f64, f64)> {
    let e = b - a;
    let ee = e.dot(e);
    let de = d.dot(e);
    let da = d.dot(a);
    let ea = e.dot(a);
    // Minimise |t d − (a + s e)| for t ≥ 0, s in [0, 1].
    let denom = ee - de * de;
    let s = if denom > 1e-12 {
        ((de * da - ea) / denom).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let p = a + e * s;
    let t = d.dot(p).max(0.0);
    if t <= 1e-9 {
        return None;
    }
    Some((t, (d * t - p).length()))
}

/// Where an exact order's error against the reference stands: the largest channel error
/// over the pixels off translucent quad edges and off pixels showing two of a game's
/// objects that interpenetrate or nearly touch ([`crate::overlaps`]), and how many pixels
/// off by more than 1/255 lie on each (an edge first).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct OffEdges {
    /// The largest channel error elsewhere (1/255).
    pub max: u32,
    /// Pixels off by more than 1/255 on a quad edge.
    pub on_edges: u32,
    /// Pixels off by more than 1/255 on interpenetrating objects.
    pub on_overlaps: u32,
    /// Pixels off by more than 1/255 on objects near each other (their bounding balls meet,
    /// their solids do not: the centre order can be wrong there).
    pub on_near: u32,
    /// Pixels off by more than 8/255 elsewhere (the order of quads and planes is wrong there,
    /// or two objects' centres are).
    pub over_8: u32,
}

/// [`OffEdges`] of `test` against `reference`, with `edges` and the objects' mask `objects`
/// (one [`Pair`] a pixel, row by row; empty: none).
pub fn error_off_edges(
    edges: &Edges,
    objects: &[Pair],
    reference: &Image,
    test: &Image,
) -> OffEdges {
    let mut out = OffEdges::default();
    let mut classified = 0usize;
    for y in 0..reference.height {
        for x in 0..reference.width {
            let (p, q) = (reference.pixel(x, y), test.pixel(x, y));
            let err = (0..3)
                .map(|c| u32::from(p[c].abs_diff(q[c])))
                .max()
                .unwrap_or(0);
            if err <= 1 {
                continue;
            }
            classified += 1;
            let pair = objects
                .get((y * reference.width + x) as usize)
                .copied()
                .unwrap_or(Pair::None);
            if classified <= MAX_CLASSIFIED && edges.is_edge(x, y) {
                out.on_edges += 1;
            } else if pair == Pair::Interpenetrating {
                out.on_overlaps += 1;
            } else if pair == Pair::Near {
                out.on_near += 1;
            } else {
                out.max = out.max.max(err);
                out.over_8 += u32::from(err > 8);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ray_segment_distances() {
        let d = DVec3::Z;
        // A segment crossing the ray at t = 5.
        let (t, gap) =
            ray_segment(d, DVec3::new(-1.0, 0.0, 5.0), DVec3::new(1.0, 0.0, 5.0)).unwrap();
        assert!((t - 5.0).abs() < 1e-12 && gap < 1e-12);
        // Passing 0.5 beside it.
        let (t, gap) =
            ray_segment(d, DVec3::new(-1.0, 0.5, 3.0), DVec3::new(1.0, 0.5, 3.0)).unwrap();
        assert!((t - 3.0).abs() < 1e-12 && (gap - 0.5).abs() < 1e-12);
        // Ending short of it: the nearest end counts.
        let (_, gap) =
            ray_segment(d, DVec3::new(1.0, 0.0, 2.0), DVec3::new(3.0, 0.0, 2.0)).unwrap();
        assert!((gap - 1.0).abs() < 1e-12);
        // Behind the eye.
        assert!(ray_segment(d, DVec3::new(-1.0, 0.0, -2.0), DVec3::new(1.0, 0.0, -2.0)).is_none());
    }

    #[test]
    fn distances_in_pixels() {
        // One glass block, its +z face 4 blocks ahead: 100 px span 2 tan(30°) · 4 blocks.
        let scene = crate::scene::parse(
            "name = \"one block\"\n\
             [[boxes]]\nblock = \"glass\"\nmin = [0, 0, 0]\nmax = [0, 0, 0]\n\
             [[cameras]]\neye = [0.5, 0.5, 5.0]\ntarget = [0.5, 0.5, 0.0]\nfov = 60.0\n",
        )
        .unwrap();
        let edges = Edges::new(&scene.world, &scene.cameras[0], (100, 100));
        let px_per_block = 100.0 / (2.0 * 30f64.to_radians().tan() * 4.0);
        // The face's right edge (x = 1) lies 0.5 blocks right of the centre, x = 50.
        let edge_x = 50.0 + 0.5 * px_per_block;
        for x in [49u32, 55, 60, 61, 62, 70] {
            let want = (f64::from(x) + 0.5 - edge_x).abs();
            let got = edges.distance_px(x, 49);
            // Near the face's edge the face is the nearest; its far twin (z = 0) is
            // 5/4 as far from the centre on screen and projects inside.
            if want < 5.0 {
                // Within 3 %: the gap is measured across the ray, not in the image plane.
                assert!(
                    (got - want).abs() < 0.01 + 0.03 * want,
                    "x {x}: {got} px, want {want}"
                );
            }
        }
        assert!(!edges.is_edge(49, 49), "the middle of the face");
        assert!(edges.distance_px(0, 0) > 20.0, "the corner of the picture");
    }
}
