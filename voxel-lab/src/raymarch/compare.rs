//! Checking a GPU picture against the ray march: the differing pixels, and whether a
//! geometric edge or a crack explains each.

use voxel_core::RenderClass;
use voxel_render::{Camera, Image};

use super::{Picture, RayMarched, RayMarcher, RayResult, Shading, Surface, describe};

/// Where a ray march and a GPU picture differ.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Comparison {
    /// Pixels compared.
    pub pixels: usize,
    /// Pixels whose colours differ by more than 1/255 where an edge passes within
    /// [`EDGE_RADIUS_PX`] of the centre (the rasteriser decides those).
    pub differing_on_edges: usize,
    /// Pixels off edges whose colours differ by more than 1/255 where two merged
    /// translucent quads meet within [`EDGE_RADIUS_PX`] of the centre: at a T-junction
    /// (one quad's corner on the other's edge) the rasteriser can leave a sliver of
    /// sub-pixel width that neither covers, so that the layer is missing at a pixel whose
    /// centre falls in it. Translucent quads cannot grow over it as opaque ones do (the
    /// overlap would blend twice); the README counts these.
    pub translucent_seams: usize,
    /// Pixels off edges and seams whose largest channel difference exceeds 1/255.
    pub differing: usize,
    /// The largest channel difference off edges (1/255).
    pub max_abs_err_off_edges: u8,
    /// Pixels where the GPU drew no opaque surface but opaque geometry closes all around
    /// the centre (within [`EDGE_RADIUS_PX`]).
    pub cracks: usize,
    /// The first differing pixels (at most 10), with the surface the ray ended on.
    pub worst: Vec<DifferingPixel>,
}

/// One pixel where the ray march and the GPU differ off edges.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct DifferingPixel {
    /// Pixel coordinates.
    pub x: u32,
    /// Pixel coordinates.
    pub y: u32,
    /// Largest channel difference (1/255).
    pub diff: u8,
    /// Ray march and GPU colours.
    pub ray: [u8; 3],
    /// GPU colour.
    pub gpu: [u8; 3],
    /// Where the ray ended: "chunk (x, y, z) block (x, y, z) face F block-type N", or "sky".
    pub surface: String,
}

/// How close to a pixel's centre a geometric edge must pass for the pixel to count as on
/// the edge, in pixels: the GPU samples the centre, and where an edge passes this close
/// the rasteriser's rules decide (its sub-pixel snapping moves vertices by up to 1/512 px
/// with 8 sub-pixel bits, and the opaque quads' growth against cracks,
/// `voxel_render::low_level::OPAQUE_EXPANSION_PX`, by 1/64 px).
pub const EDGE_RADIUS_PX: f64 = 1.0 / 32.0;

impl RayMarcher {
    /// Compares a ray-marched picture (of `camera`, the renderer's drawn camera, with
    /// `shading`) with a GPU picture of the same scene, and with the GPU's opaque depth
    /// (reverse-Z, 0 where nothing opaque was drawn) for cracks. A pixel whose colours
    /// differ by more than 1/255 is marched again at 96 points around its centre within
    /// [`EDGE_RADIUS_PX`]: if one meets other surfaces or ends on a face of another plane or
    /// block type, an edge passes there (a face's edge, where faces the eye cannot see may
    /// touch the visible one at the same depth) and the pixel is on an edge; otherwise it
    /// counts as differing.
    pub fn compare(
        &self,
        ray: &RayMarched,
        camera: &Camera,
        shading: &Shading,
        gpu: &Image,
        gpu_depth: Option<&[f32]>,
    ) -> Comparison {
        let mut c = Comparison {
            pixels: ray.end.len(),
            ..Comparison::default()
        };
        let (width, height) = (ray.image.width, ray.image.height);
        let w = width as usize;
        let picture = &Picture::new(self, camera, (width, height), shading);
        // Rays around a pixel's centre within the edge radius: 32 angles on circles of a
        // quarter, half and the whole radius, dense enough to meet the thin sliver of a
        // face seen at a grazing angle.
        let ring = |i: usize| {
            let (x, y) = ((i % w) as f64 + 0.5, (i / w) as f64 + 0.5);
            (0..96).map(move |k| {
                let angle = f64::from(k % 32) * std::f64::consts::TAU / 32.0;
                let radius = EDGE_RADIUS_PX * f64::from(1 << (k / 32)) / 4.0;
                let (dx, dy) = (angle.cos() * radius, angle.sin() * radius);
                picture.march(x + dx, y + dy, false)
            })
        };
        let opaque_end =
            |r: Option<Surface>| r.is_some_and(|s| self.class(s.id) == RenderClass::Opaque);
        let closed = |r: &RayResult| r.content_end || opaque_end(r.end);
        for i in 0..ray.end.len() {
            // A crack: the GPU drew no opaque surface where opaque geometry closes all
            // around the centre.
            if let Some(depth) = gpu_depth
                && depth.get(i).is_some_and(|&d| d <= 0.0)
                && (ray.content_end[i] || opaque_end(ray.end[i]))
                && ring(i).all(|r| closed(&r))
            {
                c.cracks += 1;
            }
            let a = &ray.image.rgba[i * 4..i * 4 + 3];
            let b = &gpu.rgba[i * 4..i * 4 + 3];
            let diff = a
                .iter()
                .zip(b)
                .map(|(x, y)| x.abs_diff(*y))
                .max()
                .unwrap_or(0);
            if diff <= 1 {
                c.max_abs_err_off_edges = c.max_abs_err_off_edges.max(diff);
                continue;
            }
            // An edge is where the surfaces change: another plane or block type met or
            // ended on (the signature), or another block of the same plane shaded otherwise;
            // not another block of the same type in the same plane shaded alike (with flat
            // textures, a far floor's blocks, which a pixel's ring spans under water and
            // far away, draw as one surface).
            let plane = |s: Option<Surface>| s.map(|s| s.plane());
            // The shading of a face's corners (ambient occlusion): where two faces of one
            // plane shade differently, the rasteriser's interpolation decides too.
            let corners = |s: Option<Surface>| {
                s.filter(|s| self.class(s.id) != RenderClass::Translucent)
                    .map(|s| {
                        [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
                            .map(|(u, v)| self.ao(s.block, s.face, u, v, 1.0).to_bits())
                    })
            };
            let mut seam = false;
            let near_edge = ring(i).any(|r| {
                seam |= r.layer_faces != ray.layer_faces[i];
                r.signature != ray.signature[i]
                    || plane(r.end) != plane(ray.end[i])
                    || (r.end != ray.end[i] && corners(r.end) != corners(ray.end[i]))
            });
            if near_edge {
                c.differing_on_edges += 1;
                continue;
            }
            if seam {
                c.translucent_seams += 1;
                continue;
            }
            c.max_abs_err_off_edges = c.max_abs_err_off_edges.max(diff);
            c.differing += 1;
            if c.worst.len() < 10 {
                c.worst.push(DifferingPixel {
                    x: (i % w) as u32,
                    y: (i / w) as u32,
                    diff,
                    ray: [a[0], a[1], a[2]],
                    gpu: [b[0], b[1], b[2]],
                    surface: if ray.content_end[i] {
                        "an entity of the game's content".into()
                    } else {
                        describe(ray.end[i])
                    },
                });
            }
        }
        c
    }
}
