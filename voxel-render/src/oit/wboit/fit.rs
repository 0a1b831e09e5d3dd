//! How much translucent matter lies in front of each depth: what the fitted WBOIT weight
//! is fitted to.
//!
//! The ideal weight of a translucent layer is the transmittance of everything in front of
//! it: with that weight the weighted average is exact (of two layers, the back one counts
//! `1 − α_front` times as much as the front one). The accumulation pass cannot know it per
//! pixel, but the renderer can estimate it per screen tile, cheaply, from the visible
//! meshes:
//!
//! - once per upload of a chunk, the chunk store sums its translucent quads up per plane,
//!   facing and block (`crate::layers`): the rectangle around those quads, and their
//!   area times the block's optical depth `−ln(1 − α)`; the frame's culling copies the
//!   visible chunks' planes into one buffer;
//! - each frame, every plane that faces the eye (back faces are not drawn; the surface of
//!   the eye's medium, seen from behind, is counted per pixel by the shader) adds, to each of
//!   the `TILES × TILES` screen tiles its projected rectangle overlaps, the optical depth a
//!   ray through the rectangle crosses (optical area / rectangle area) times the share of
//!   the tile it covers, in front of the view depths past the rectangle's farthest point.
//!
//! The result, per tile, is the expected optical depth in front of `PROFILE_LEN` depths
//! spaced evenly in log depth across the translucent depth range in view; the weight is
//! `3000 · e^−τ(d)` ([`super::WeightFunction::Fitted`]). An estimate, not the per-pixel
//! truth: a layer covering a quarter of a tile dims what lies behind it in that tile by a
//! quarter of its optical depth (also where the two do not overlap: the near and far parts
//! of a sea, in different chunks, in one tile), a layer seen at a grazing angle does not
//! dim what lies behind it within its own depth span, and a texel more opaque than its
//! block (a glass frame) counts as its block.
//!
//! The cost is a loop over the planes of the visible translucent meshes (four projected
//! corners each, then the tiles they overlap: 0.06 ms for 2 067 planes in 728 chunks at
//! view distance 32, `cargo bench -p voxel-lab --bench wboit_fit`) and an 8 KiB table in
//! the technique's uniforms;
//! the shader reads eight entries of it (two depths in four tiles, to interpolate across
//! tiles without seams).

use glam::{DVec3, Mat4, Vec2, Vec4};
use voxel_core::ChunkPos;

use crate::layers::Plane;
pub(crate) use crate::layers::layer_depth;

/// Number of distances of the optical-depth profile (log-spaced, ends included).
pub(crate) const PROFILE_LEN: usize = 32;

/// The screen is cut into `TILES × TILES` tiles, each with its own profile.
pub(crate) const TILES: usize = 8;

/// The fitted weight's estimate, with room it keeps from one frame to the next: for the
/// planes seen, and for the next table (fresh allocations of these cost more, in page
/// faults, than the arithmetic: 2 000 planes at view distance 32). A technique keeps one.
#[derive(Debug, Default)]
pub(crate) struct Fitter {
    seen: Vec<Seen>,
    table: Vec<f32>,
}

impl Fitter {
    /// Gives back the table of an earlier fit, to be filled by the next.
    pub(crate) fn recycle(&mut self, fit: WeightFit) {
        self.table = fit.optical_depth;
    }

    /// Fits the weight to the meshes in `layers` seen through `view_proj`
    /// (camera-relative: the eye at the origin) from `eye`, with the camera's `near` and
    /// `far` planes: the view depths the meshes span and, for each screen tile, the
    /// expected optical depth in front of [`PROFILE_LEN`] depths spaced evenly in log depth
    /// across them.
    pub(crate) fn fit<'a>(
        &mut self,
        layers: impl IntoIterator<Item = (ChunkPos, u8, &'a [Plane])>,
        view_proj: Mat4,
        eye: DVec3,
        near: f32,
        far: f32,
    ) -> WeightFit {
        let covered = visible_planes(layers, view_proj, eye, &mut self.seen);
        let table = std::mem::take(&mut self.table);
        fit_planes(&self.seen, covered, table, near, far)
    }
}

/// The fit of the planes `seen`, covering `covered`, into `table` (its room reused).
fn fit_planes(
    seen: &[Seen],
    covered: [Vec2; 2],
    table: Vec<f32>,
    near: f32,
    far: f32,
) -> WeightFit {
    let (mut n, mut f) = seen
        .iter()
        .fold((f32::INFINITY, 0.0f32), |(n, f), (_, _, [a, b])| {
            (n.min(*a), f.max(*b))
        });
    if seen.is_empty() {
        (n, f) = (near, far);
    }
    let range = [n.clamp(near, far), f.clamp(near, far)];
    let step = (range[1] / range[0]).max(1.0).ln() / (PROFILE_LEN - 1) as f32;
    let depths: [f32; PROFILE_LEN] = std::array::from_fn(|k| range[0] * (step * k as f32).exp());
    let mut optical_depth = table;
    optical_depth.clear();
    optical_depth.resize(TILES * TILES * PROFILE_LEN, 0.0);
    let tiles = TILES as f32;
    for &(tau, [lo, hi], [_, far]) in seen.iter() {
        // The plane counts in front of the depths past its farthest point, so that no part
        // of it dims another part of it (a sea seen at a grazing angle): the number of
        // depths not past it (a count of 32 compares, which vectorises, rather than a
        // binary search, whose branches do not).
        let behind: usize = depths.iter().map(|&d| usize::from(d <= far)).sum();
        if behind == PROFILE_LEN {
            continue;
        }
        // The tiles it overlaps (the rectangle lies within 0 to 1: truncation rounds down;
        // `floor` and `ceil` are library calls on baseline x86-64), in tile units.
        let (lo, hi) = (lo * tiles, hi * tiles);
        let first = lo.as_uvec2();
        let last = hi.as_uvec2();
        let last = (last + glam::UVec2::from(hi.cmpgt(last.as_vec2())))
            .min(glam::UVec2::splat(TILES as u32));
        // The share of a tile the rectangle covers, along x or y.
        let share = |t: u32, k: usize| (hi[k].min(t as f32 + 1.0) - lo[k].max(t as f32)).max(0.0);
        for ty in first.y..last.y {
            let tau = tau * share(ty, 1);
            let row = &mut optical_depth[ty as usize * TILES * PROFILE_LEN..];
            for tx in first.x..last.x {
                // Added where the depths behind it start; the running sums below carry it
                // to the depths past (one add per tile instead of one per depth).
                row[tx as usize * PROFILE_LEN + behind] += tau * share(tx, 0);
            }
        }
    }
    for profile in optical_depth.chunks_exact_mut(PROFILE_LEN) {
        let mut sum = 0.0;
        for p in profile {
            sum += *p;
            *p = sum;
        }
    }
    WeightFit {
        range,
        optical_depth,
        covered,
    }
}

/// A plane seen in a frame: its optical depth, screen rectangle and view depth span.
type Seen = (f32, [Vec2; 2], [f32; 2]);

/// Puts into `seen` each plane of `layers` that faces the eye and covers some of the
/// screen, in order; returns the screen rectangle they cover together
/// ([`WeightFit::covered`]). Projected per
/// mesh: the chunk's offset from the eye once (in f64, then small enough for f32), then
/// each corner from the projection's columns (the projection is linear before the
/// divide), a quarter of the multiplications of four full transforms.
fn visible_planes<'a>(
    layers: impl IntoIterator<Item = (ChunkPos, u8, &'a [Plane])>,
    view_proj: Mat4,
    eye: DVec3,
    seen: &mut Vec<Seen>,
) -> [Vec2; 2] {
    seen.clear();
    let columns = [view_proj.x_axis, view_proj.y_axis, view_proj.z_axis];
    let (mut min, mut max) = (Vec2::INFINITY, Vec2::NEG_INFINITY);
    for (pos, level, planes) in layers {
        let origin = DVec3::from(pos.origin().map(|v| v as f64));
        // Chunk-local cells (a level of detail's are wider than a block in x and z).
        let scale = crate::layers::cell_scale(level);
        let eye_local = (eye - origin) / DVec3::from(scale);
        let base = view_proj * (origin - eye).as_vec3().extend(1.0);
        let columns = [0, 1, 2].map(|a| columns[a] * scale[a] as f32);
        for plane in planes {
            if !faces(plane, eye_local) {
                continue;
            }
            let (rect, span) = projection(plane, base, &columns);
            if rect[1].cmpgt(rect[0]).all() {
                // A plane wholly behind the eye is not drawn (its rectangle says "the
                // whole screen" for the estimate, as it always did).
                if span[1] > 0.0 {
                    min = min.min(rect[0]);
                    max = max.max(rect[1]);
                }
                // A clear plane dims nothing and leaves the depth range alone.
                if plane.tau > 0.0 {
                    seen.push((plane.tau, rect, span));
                }
            }
        }
    }
    [min, max]
}

/// Whether the plane's quads face the eye at `eye_local` (chunk-local): only those are
/// drawn (back faces are culled, but for the medium's, counted per pixel by the shader).
fn faces(plane: &Plane, eye_local: DVec3) -> bool {
    let axis = plane.face.axis();
    let at = f64::from(plane.lo[axis]);
    (eye_local[axis] > at) == plane.face.is_positive() && eye_local[axis] != at
}

/// The bounding rectangle of the plane's projection, in screen coordinates (0 to 1, y
/// down; the whole screen when the plane reaches behind the eye), and the view depths it
/// spans. `base` is the chunk's origin in clip space, `columns` the projection's x, y and
/// z columns: a chunk-local point `p` lies at `base + Σ columns[i] · p[i]`.
fn projection(plane: &Plane, base: Vec4, columns: &[Vec4; 3]) -> ([Vec2; 2], [f32; 2]) {
    let (lo, hi) = (plane.lo, plane.hi);
    let origin = base + columns[0] * lo.x + columns[1] * lo.y + columns[2] * lo.z;
    // The rectangle is flat along its face's axis: four corners, spanned along the two
    // others.
    let [ua, va] = voxel_mesh::UV_AXES[plane.face.axis()];
    let du = columns[ua] * (hi[ua] - lo[ua]);
    let dv = columns[va] * (hi[va] - lo[va]);
    // The four corners' clip x, y and w side by side (one SIMD lane each).
    let corner = |k: usize| Vec4::new(0.0, du[k], dv[k], du[k] + dv[k]) + origin[k];
    let (x, y, w) = (corner(0), corner(1), corner(3));
    // Perspective: clip w is the view depth.
    let (near, far) = (w.min_element(), w.max_element());
    let inv = w.max(Vec4::splat(1e-6)).recip();
    let sx = (x * inv + 1.0) * 0.5;
    let sy = (1.0 - y * inv) * 0.5;
    let min = Vec2::new(sx.min_element(), sy.min_element());
    let max = Vec2::new(sx.max_element(), sy.max_element());
    let span = [near.max(0.0), far.max(0.0)];
    if near <= 1e-3 {
        return ([Vec2::ZERO, Vec2::ONE], span);
    }
    (
        [
            min.clamp(Vec2::ZERO, Vec2::ONE),
            max.clamp(Vec2::ZERO, Vec2::ONE),
        ],
        span,
    )
}

/// What the fitted weight is fitted to in a frame (see the module docs).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WeightFit {
    /// Nearest and farthest view depth of the visible translucent meshes.
    pub range: [f32; 2],
    /// For each screen tile (row by row, `TILES` × `TILES`), the expected optical
    /// depth in front of `PROFILE_LEN` depths spaced evenly in log depth across `range`.
    /// Empty: none anywhere.
    pub optical_depth: Vec<f32>,
    /// The screen rectangle (0 to 1, y down) around the planes of quads that face the eye
    /// (the whole screen when one reaches the eye's plane; min > max when none is seen):
    /// where front faces can be drawn. What the composite's scissor is made from when the
    /// eye is in air (from inside a medium back faces are drawn too).
    pub covered: [Vec2; 2],
}

/// The most optical depth the fitted weight falls by: `e^−12`, 6·10⁻⁶ (the weight must
/// stay above fp16's smallest numbers once times α·3000).
pub(crate) const MAX_FITTED_DEPTH: f32 = 12.0;

impl WeightFit {
    /// `[ln n, (PROFILE_LEN − 1) / ln(f / n)]` for the range's ends `n` and `f` (kept
    /// apart and above zero): the table index of view depth `d` is
    /// `(ln d − ln n) · (PROFILE_LEN − 1) / ln(f / n)`, which the shader computes with
    /// one log (these two numbers are in its uniform).
    pub(crate) fn log_mapping(&self) -> [f32; 2] {
        let n = self.range[0].max(1e-4);
        let f = self.range[1].max(n * 1.001);
        [n.ln(), (PROFILE_LEN - 1) as f32 / (f / n).ln()]
    }

    /// The optical depth in front of view depth `d` at `screen` (0 to 1, y down):
    /// interpolated in log depth in the tables of the four tiles around `screen`, then
    /// bilinearly between the tiles' centres (no seams at tile edges), and clamped at the
    /// ends of the range and at `MAX_FITTED_DEPTH`.
    pub fn optical_depth_at(&self, screen: [f32; 2], d: f32) -> f32 {
        if self.optical_depth.len() < TILES * TILES * PROFILE_LEN {
            return 0.0;
        }
        let [log_near, log_scale] = self.log_mapping();
        let x = ((d.ln() - log_near) * log_scale).clamp(0.0, (PROFILE_LEN - 1) as f32);
        let k = (x.floor() as usize).min(PROFILE_LEN - 2);
        let t = x - k as f32;
        let at = |tx: usize, ty: usize| {
            let p = &self.optical_depth[(ty * TILES + tx) * PROFILE_LEN..];
            p[k] + (p[k + 1] - p[k]) * t
        };
        let lerp = |a: f32, b: f32, s: f32| a + (b - a) * s;
        // Tile coordinates of `screen` between the tiles' centres.
        let p = screen.map(|v| (v * TILES as f32 - 0.5).clamp(0.0, (TILES - 1) as f32));
        let [tx, ty] = p.map(|v| (v.floor() as usize).min(TILES - 2));
        let [sx, sy] = [p[0] - tx as f32, p[1] - ty as f32];
        let top = lerp(at(tx, ty), at(tx + 1, ty), sx);
        let bottom = lerp(at(tx, ty + 1), at(tx + 1, ty + 1), sx);
        lerp(top, bottom, sy).min(MAX_FITTED_DEPTH)
    }
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;

    use super::*;
    use crate::Camera;
    use crate::layers;
    use glam::Vec3;
    use voxel_core::{BlockRegistry, Face, blocks};
    use voxel_mesh::PackedQuad;

    fn opacity() -> Vec<f32> {
        BlockRegistry::default()
            .iter()
            .map(|(_, d)| d.opacity)
            .collect()
    }

    /// A `w`×32 sheet of `block` in chunk (0, 0, 0) from x = `x0`, whose +z face is the
    /// plane z = `z` + 1.
    fn sheet(x0: usize, w: usize, z: usize, face: Face, block: voxel_core::BlockId) -> PackedQuad {
        PackedQuad::new([x0, 0, z], w, 32, face, block)
    }

    /// Looking down −z from (16, 16, 30), square screen, fov 60°.
    fn fit_for(quads: &[PackedQuad]) -> WeightFit {
        let cam = Camera::look_at(
            DVec3::new(16.0, 16.0, 30.0),
            DVec3::new(16.0, 16.0, 0.0),
            60.0,
            0.1,
            500.0,
        )
        .unwrap();
        let planes = layers::planes(quads, &opacity());
        let origin = ChunkPos::new(0, 0, 0);
        Fitter::default().fit(
            [(origin, 0, &planes[..])],
            cam.view_proj(1.0),
            cam.eye,
            0.1,
            500.0,
        )
    }

    fn tau_at(fit: &WeightFit, tile: [usize; 2], k: usize) -> f32 {
        fit.optical_depth[(tile[1] * TILES + tile[0]) * PROFILE_LEN + k]
    }

    const GLASS_DEPTH: f32 = 0.223_143_55; // −ln(1 − 0.2)

    #[test]
    fn a_sheet_over_the_whole_screen_dims_what_lies_behind_it_everywhere() {
        // Glass at depth 5 (plane z = 25), water at depth 20 (plane z = 10): both fill
        // the screen (half-widths 16/5 and 16/20 are past tan 30° = 0.577).
        let fit = fit_for(&[
            sheet(0, 32, 24, Face::PosZ, blocks::GLASS),
            sheet(0, 32, 9, Face::PosZ, blocks::WATER),
        ]);
        assert!((fit.range[0] - 5.0).abs() < 1e-3 && (fit.range[1] - 20.0).abs() < 1e-3);
        for ty in 0..TILES {
            for tx in 0..TILES {
                assert_eq!(
                    tau_at(&fit, [tx, ty], 0),
                    0.0,
                    "nothing in front of the glass"
                );
                let behind = tau_at(&fit, [tx, ty], 1);
                assert!((behind - GLASS_DEPTH).abs() < 1e-5, "{behind}");
                // The water lies at the last depth, nothing beyond it counts.
                let last = tau_at(&fit, [tx, ty], PROFILE_LEN - 1);
                assert!((last - GLASS_DEPTH).abs() < 1e-5, "{last}");
            }
        }
        let screen = [0.3, 0.6];
        assert!((fit.optical_depth_at(screen, 20.0) - GLASS_DEPTH).abs() < 1e-5);
        assert_eq!(fit.optical_depth_at(screen, 5.0), 0.0);
    }

    #[test]
    fn faces_turned_away_from_the_eye_do_not_count() {
        let front = fit_for(&[
            sheet(0, 32, 24, Face::PosZ, blocks::GLASS),
            sheet(0, 32, 9, Face::PosZ, blocks::WATER),
        ]);
        let both = fit_for(&[
            sheet(0, 32, 24, Face::PosZ, blocks::GLASS),
            sheet(0, 32, 24, Face::NegZ, blocks::GLASS),
            sheet(0, 32, 9, Face::PosZ, blocks::WATER),
        ]);
        assert_eq!(front, both);
    }

    #[test]
    fn each_block_of_a_plane_counts_where_it_is() {
        // One plane: glass over x 0..16, ice over x 16..32, the left and right halves of
        // the screen (the eye is at x = 16); water behind both.
        let fit = fit_for(&[
            sheet(0, 16, 24, Face::PosZ, blocks::GLASS),
            sheet(16, 16, 24, Face::PosZ, blocks::ICE),
            sheet(0, 32, 9, Face::PosZ, blocks::WATER),
        ]);
        let ice = -(1.0f32 - 0.92).ln();
        for ty in 0..TILES {
            for tx in 0..TILES {
                let tau = tau_at(&fit, [tx, ty], PROFILE_LEN - 1);
                let want = if tx < TILES / 2 { GLASS_DEPTH } else { ice };
                assert!((tau - want).abs() < 1e-4, "tile {tx},{ty}: {tau}");
            }
        }
    }

    #[test]
    fn a_plane_seen_at_a_grazing_angle_does_not_dim_itself() {
        // A water floor (plane y = 10) seen from above and behind its edge.
        let cam = Camera::look_at(
            DVec3::new(16.0, 14.0, 40.0),
            DVec3::new(16.0, 10.0, 0.0),
            60.0,
            0.1,
            500.0,
        )
        .unwrap();
        let quads = [PackedQuad::new(
            [0, 9, 0],
            32,
            32,
            Face::PosY,
            blocks::WATER,
        )];
        let planes = layers::planes(&quads, &opacity());
        let origin = ChunkPos::new(0, 0, 0);
        let fit = Fitter::default().fit(
            [(origin, 0, &planes[..])],
            cam.view_proj(1.0),
            cam.eye,
            0.1,
            500.0,
        );
        assert!(fit.range[1] > 2.0 * fit.range[0], "{:?}", fit.range);
        assert!(fit.optical_depth.iter().all(|&t| t == 0.0));
    }

    #[test]
    fn nothing_in_view_leaves_the_weight_flat() {
        let fit = fit_for(&[]);
        assert_eq!(fit.range, [0.1, 500.0]);
        assert!(fit.optical_depth.iter().all(|&t| t == 0.0));
        assert_eq!(fit.optical_depth_at([0.5, 0.5], 100.0), 0.0);
    }

    /// The fit as first written, the oracle of the faster one: each plane's four corners
    /// transformed in full from world space, its optical depth computed each frame.
    fn oracle(
        meshes: &[(ChunkPos, Vec<PackedQuad>)],
        opacity: &[f32],
        view_proj: Mat4,
        eye: DVec3,
    ) -> Vec<Seen> {
        let mut seen = Vec::new();
        for (pos, quads) in meshes {
            let o = pos.origin().map(|v| v as f64);
            // By facing, position and block: facing, rectangle, optical area.
            type Sum = (Face, DVec3, DVec3, f64);
            let mut planes: BTreeMap<(usize, u8, u16), Sum> = BTreeMap::new();
            for q in quads {
                let u = q.unpack().unwrap();
                let axis = u.face.axis();
                let (min, max) = u.bounds();
                let lo = DVec3::from(o) + DVec3::from(min);
                let hi = DVec3::from(o) + DVec3::from(max);
                let depth = layer_depth(opacity[u.block.index()]);
                let p = planes
                    .entry((u.face as usize, min[axis] as u8, u.block.0))
                    .or_insert((u.face, lo, hi, 0.0));
                p.1 = p.1.min(lo);
                p.2 = p.2.max(hi);
                p.3 += f64::from(q.area()) * depth;
            }
            for (face, lo, hi, optical_area) in planes.into_values() {
                let axis = face.axis();
                if (eye[axis] > lo[axis]) != face.is_positive() || eye[axis] == lo[axis] {
                    continue;
                }
                let [ua, va] = voxel_mesh::UV_AXES[axis];
                let tau = optical_area / ((hi[ua] - lo[ua]) * (hi[va] - lo[va])).max(1.0);
                if tau <= 0.0 {
                    continue;
                }
                let (l, h) = ((lo - eye).as_vec3(), (hi - eye).as_vec3());
                let (mut min, mut max) = (Vec2::INFINITY, Vec2::NEG_INFINITY);
                let (mut near, mut far) = (f32::INFINITY, f32::NEG_INFINITY);
                for i in (0..8).filter(|i| i & (1 << axis) == 0) {
                    let c = Vec3::new(
                        if i & 1 == 0 { l.x } else { h.x },
                        if i & 2 == 0 { l.y } else { h.y },
                        if i & 4 == 0 { l.z } else { h.z },
                    );
                    let clip = view_proj * c.extend(1.0);
                    near = near.min(clip.w);
                    far = far.max(clip.w);
                    let ndc = clip.truncate().truncate() / clip.w.max(1e-6);
                    let screen = Vec2::new(ndc.x + 1.0, 1.0 - ndc.y) * 0.5;
                    min = min.min(screen);
                    max = max.max(screen);
                }
                let rect = if near <= 1e-3 {
                    [Vec2::ZERO, Vec2::ONE]
                } else {
                    [
                        min.clamp(Vec2::ZERO, Vec2::ONE),
                        max.clamp(Vec2::ZERO, Vec2::ONE),
                    ]
                };
                if rect[1].cmpgt(rect[0]).all() {
                    seen.push((tau as f32, rect, [near.max(0.0), far.max(0.0)]));
                }
            }
        }
        seen
    }

    /// Random translucent quads in four chunks far from the origin, seen from random eyes
    /// in and around them: the faster fit sees the oracle's planes, with the same optical
    /// depths, screen rectangles and depth spans within rounding.
    #[test]
    fn the_fit_equals_the_full_transform_of_every_corner() {
        let opacity = opacity();
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = |n: u32| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % u64::from(n)) as u32
        };
        let blocks = [blocks::GLASS, blocks::WATER, blocks::ICE, blocks::RED_GLASS];
        let faces = Face::ALL;
        let base = [1000, 2, -3000];
        let meshes: Vec<(ChunkPos, Vec<PackedQuad>)> = (0..4)
            .map(|c| {
                let pos = ChunkPos::new(base[0] + c % 2, base[1], base[2] + c / 2);
                let quads = (0..60)
                    .map(|_| {
                        let (w, h) = (1 + next(8) as usize, 1 + next(8) as usize);
                        let at = [next(24), next(24), next(24)].map(|v| v as usize);
                        let face = faces[next(6) as usize];
                        PackedQuad::new(at, w, h, face, blocks[next(4) as usize])
                    })
                    .collect();
                (pos, quads)
            })
            .collect();
        let layers: Vec<(ChunkPos, Vec<Plane>)> = meshes
            .iter()
            .map(|(p, q)| (*p, layers::planes(q, &opacity)))
            .collect();
        let centre = DVec3::new(32_032.0, 80.0, -95_968.0);
        let mut compared = 0;
        for _ in 0..40 {
            let mut offset = |n: u32| f64::from(next(n)) - f64::from(n / 2) + 0.37;
            let eye = centre + DVec3::new(offset(160), offset(100), offset(160));
            let target = centre + DVec3::new(offset(40), offset(40), offset(40));
            let Ok(cam) = Camera::look_at(eye, target, 70.0, 0.1, 1000.0) else {
                continue;
            };
            let vp = cam.view_proj(16.0 / 9.0);
            let mut fast = Vec::new();
            visible_planes(
                layers.iter().map(|(p, l)| (*p, 0, &l[..])),
                vp,
                eye,
                &mut fast,
            );
            let want = oracle(&meshes, &opacity, vp, eye);
            assert_eq!(fast.len(), want.len(), "the same planes are seen");
            compared += usize::from(!want.is_empty());
            for ((t, r, s), (wt, wr, ws)) in fast.iter().zip(&want) {
                assert!((t - wt).abs() <= 1e-6 * wt, "tau {t} != {wt}");
                for k in 0..2 {
                    // Rounding of the corners' transform: far below a pixel.
                    assert!(
                        (r[k] - wr[k]).abs().max_element() <= 1e-4,
                        "{r:?} != {wr:?}"
                    );
                    assert!(
                        (s[k] - ws[k]).abs() <= 1e-4 * ws[k].max(1.0),
                        "{s:?} != {ws:?}"
                    );
                }
            }
        }
        assert!(compared > 20, "only {compared} views saw a plane");
    }
}
