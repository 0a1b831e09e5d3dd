//! The third exact reference: a CPU voxel ray march that shares no mesh, no rasteriser and
//! no GPU with the techniques. Each pixel's ray (through the pixel centre, in f64) walks the
//! world's blocks (Amanatides & Woo's DDA, skipping absent chunks), applies the documented
//! face rules at every block boundary it crosses, the cutout alpha test, the model for an
//! eye inside a translucent volume (`voxel_render::medium`), the lighting, per-vertex
//! ambient occlusion computed from the blocks themselves, fog, blending and tonemapping.
//!
//! What it shares with the renderer is the specification, not the code: the face rules,
//! the AO rule and curve ([`voxel_render::low_level::AO_DEPTH`]), the Lambert-plus-ambient lighting,
//! the fog constant and the tonemap curve. Block colours come from the registry; in
//! [`Texturing::Flat`] (each block one colour, what the renderer draws with
//! `RendererConfig::flat_textures`) it agrees with the GPU references to 1/255 off
//! geometric edges; in [`Texturing::Nearest`] it samples level 0 of the block textures
//! with nearest filtering (the GPU filters minified textures, so only close views agree).
//!
//! [`RayMarcher::compare`] checks a GPU picture against it: a pixel whose colours differ
//! is marched again around its centre to tell whether a geometric edge passes there (the
//! rasteriser decides such pixels), and a pixel where the GPU drew no opaque surface is
//! checked for closed geometry all around it (a crack).

mod blocks;
mod compare;
mod hits;
mod light;
mod walk;

use std::collections::HashMap;
use std::hash::Hash;
use std::sync::Arc;

use glam::DVec3;
use rayon::prelude::*;
use voxel_core::{BlockId, CHUNK_SIZE, ChunkPos, Face, RenderClass, World};
use voxel_render::{Camera, Image, RendererConfig};

use voxel_render::content::Content;

use blocks::srgb_to_linear;
pub use compare::{Comparison, DifferingPixel, EDGE_RADIUS_PX};
use hits::Bins;
use light::Light;
use light::output;
use walk::Medium;

/// How the ray march colours a block face.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Texturing {
    /// Each block one colour, alpha its opacity (1 for opaque and cutout blocks): what the
    /// renderer draws with `RendererConfig::flat_textures`.
    Flat,
    /// Level 0 of the block textures, nearest texel (leaves' holes, glass frames).
    Nearest,
}

/// The lighting and shading the ray march reproduces (from a [`RendererConfig`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shading {
    /// Direction towards the sun (normalised here).
    pub sun_dir: [f32; 3],
    /// Ambient share.
    pub ambient: f32,
    /// Brightness of the light (scales every lit colour, not the sky).
    pub brightness: f32,
    /// Sky colour, linear.
    pub sky: [f32; 3],
    /// Ambient-occlusion strength (0 to 1).
    pub ao_strength: f32,
    /// Texture mode.
    pub texturing: Texturing,
}

impl Shading {
    /// The shading of a renderer made with `config`.
    pub fn of(config: &RendererConfig) -> Self {
        Self {
            sun_dir: config.sun_dir,
            ambient: config.ambient,
            brightness: config.brightness,
            sky: config.sky,
            ao_strength: config.ao_strength,
            texturing: if config.flat_textures {
                Texturing::Flat
            } else {
                Texturing::Nearest
            },
        }
    }
}

/// One surface a ray meets: which face of which block, whether it counts as a blended
/// layer or ends the ray.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Surface {
    /// The block whose face it is.
    pub block: [i64; 3],
    /// The face.
    pub face: Face,
    /// The block type.
    pub id: BlockId,
}

impl Surface {
    /// The chunk holding the block, and the block's coordinates in it.
    pub fn chunk_and_local(&self) -> (ChunkPos, [i64; 3]) {
        let s = CHUNK_SIZE as i64;
        let c = self.block.map(|v| v.div_euclid(s));
        (
            ChunkPos::new(c[0] as i32, c[1] as i32, c[2] as i32),
            self.block.map(|v| v.rem_euclid(s)),
        )
    }

    /// The plane the face lies in, as (face, coordinate along its axis): what makes two
    /// faces the same surface for edge finding (a merged quad is one plane of one type).
    pub(super) fn plane(&self) -> (Face, i64, BlockId) {
        let axis = self.face.axis();
        let c = self.block[axis] + i64::from(self.face.is_positive());
        (self.face, c, self.id)
    }
}

/// What one ray found.
#[derive(Clone, Debug, Default)]
pub struct RayResult {
    /// Linear HDR colour after fog, before tonemapping.
    pub color: [f64; 3],
    /// The surface that ended the ray (opaque, or cutout passing the alpha test).
    pub end: Option<Surface>,
    /// Hash of the sequence of surfaces met (blended layers and the end, by plane and type).
    pub signature: u64,
    /// Hash of the blended layers' unit faces (which block's face each is).
    pub layer_faces: u64,
    /// The ray ended on an opaque entity of the game's content.
    pub content_end: bool,
}

/// A ray-marched picture.
#[derive(Debug)]
pub struct RayMarched {
    /// The picture (RGBA8, sRGB), like a renderer's output.
    pub image: Image,
    /// Per pixel: the surface the centre ray ended on.
    pub end: Vec<Option<Surface>>,
    /// Per pixel: the centre ray's signature.
    pub signature: Vec<u64>,
    /// Per pixel: the centre ray's blended unit faces.
    pub layer_faces: Vec<u64>,
    /// Per pixel: the centre ray ended on an opaque entity.
    pub content_end: Vec<bool>,
}

/// The world as the ray march reads it: dense chunks, classes, colours, textures.
#[derive(Debug)]
pub struct RayMarcher {
    chunks: HashMap<ChunkPos, Arc<[BlockId]>>,
    /// Bounds of the loaded chunks in blocks: min inclusive, max exclusive.
    bounds: ([i64; 3], [i64; 3]),
    classes: Vec<RenderClass>,
    /// The renderer's block textures (level 0) for [`Texturing::Nearest`], and per block
    /// the flat colour and opacity for [`Texturing::Flat`].
    textures: voxel_render::textures::TextureSet,
    flat: Vec<[f64; 4]>,
    /// Per block: the medium a ray inside it is in (a translucent block's own, a cutout
    /// block's [`voxel_core::BlockDef::medium`]): linear colour, absorption per block and
    /// the fog an eye inside it sees.
    media: Vec<Option<Medium>>,
    /// Per block: the medium a cutout block stands in.
    medium_of: Vec<Option<BlockId>>,
    /// A game's particles and entities ([`voxel_render::content`]).
    content: Content,
    /// The world's light field, when it is drawn lit ([`RayMarcher::with_light`]).
    light: Option<Arc<voxel_core::LightField>>,
    /// With sun shadows ([`RayMarcher::with_sun_shadows`]): the blocks' sun filters.
    sun: Option<voxel_core::SunFilters>,
}

impl RayMarcher {
    /// Reads `world`'s chunks into dense arrays.
    pub fn new(world: &World) -> Self {
        let registry = world.registry();
        let chunks: HashMap<ChunkPos, Arc<[BlockId]>> = world
            .iter()
            .filter(|(_, c)| c.as_uniform() != Some(BlockId::AIR))
            .map(|(p, c)| (p, Arc::from(c.to_dense())))
            .collect();
        let s = CHUNK_SIZE as i64;
        let mut lo = [i64::MAX; 3];
        let mut hi = [i64::MIN; 3];
        for p in chunks.keys() {
            let o = p.origin();
            for a in 0..3 {
                lo[a] = lo[a].min(o[a]);
                hi[a] = hi[a].max(o[a] + s);
            }
        }
        if chunks.is_empty() {
            (lo, hi) = ([0; 3], [0; 3]);
        }
        let defs: Vec<_> = registry.iter().map(|(id, d)| (id, d.clone())).collect();
        Self {
            chunks,
            bounds: (lo, hi),
            classes: defs.iter().map(|(_, d)| d.class).collect(),
            medium_of: defs.iter().map(|(_, d)| d.medium).collect(),
            textures: voxel_render::textures::TextureSet::new(registry, false),
            flat: defs
                .iter()
                .map(|(_, d)| {
                    let [r, g, b] = d.color.map(srgb_to_linear);
                    let a = if d.class == RenderClass::Translucent {
                        // Opacity as the texture stores it: 8 bits.
                        (f64::from(d.opacity).clamp(0.0, 1.0) * 255.0).round() / 255.0
                    } else {
                        1.0
                    };
                    [r, g, b, a]
                })
                .collect(),
            media: defs
                .iter()
                .map(|(id, d)| {
                    let own = |d: &voxel_core::BlockDef| Medium {
                        color: d.color.map(srgb_to_linear),
                        absorption: f64::from(d.absorption),
                        fog: f64::from(d.eye_absorption()),
                    };
                    match d.class {
                        RenderClass::Translucent => Some(own(d)),
                        RenderClass::Cutout => d
                            .medium
                            .filter(|&m| m != *id)
                            .and_then(|m| registry.get(m).ok())
                            .map(own),
                        _ => None,
                    }
                })
                .collect(),
            content: Content::default(),
            light: None,
            sun: None,
        }
    }

    /// Lit by `light`, the world's light field (`docs/light.md`): each face takes the light
    /// of its corners by the lit mesher's rules, read from the field here (the mean of the
    /// open, known cells in front around each corner; a translucent face its front cell's),
    /// interpolated over the face as the renderer's triangles do, and shades with
    /// `max(sky light × the sky's light, block light)`.
    pub fn with_light(self, light: Arc<voxel_core::LightField>) -> Self {
        Self {
            light: Some(light),
            ..self
        }
    }

    /// With sun shadows (`Renderer::set_sun_shadows`, on a lit world): the sun's share of
    /// a lit face's light is what reaches the point along the ray toward the sun, marched
    /// through the world's blocks by [`voxel_core::SunFilters::march`] from the point moved
    /// a thousandth of a block along the face's normal, instead of the sky light.
    pub fn with_sun_shadows(self, registry: &voxel_core::BlockRegistry) -> Self {
        Self {
            sun: Some(voxel_core::SunFilters::new(registry)),
            ..self
        }
    }

    /// Reads `world`'s chunks and draws `content` (a game's particles and entities) too.
    pub fn with_content(world: &World, content: &Content) -> Self {
        Self {
            content: content.clone(),
            ..Self::new(world)
        }
    }

    /// The ray through the point `(x, y)` of a `width` × `height` picture of `camera` (in
    /// pixels from the top left; a pixel's centre is at `+0.5`).
    #[allow(clippy::too_many_arguments)]
    pub fn ray(
        &self,
        camera: &Camera,
        width: u32,
        height: u32,
        shading: &Shading,
        x: f64,
        y: f64,
        want_color: bool,
    ) -> RayResult {
        Picture::new(self, camera, (width, height), shading).march(x, y, want_color)
    }

    /// Marches every pixel of a `width` × `height` picture of `camera` (the camera the
    /// renderer drew with: `Renderer::drawn_camera`), on rayon's threads.
    pub fn render(
        &self,
        camera: &Camera,
        width: u32,
        height: u32,
        shading: &Shading,
    ) -> RayMarched {
        let (w, h) = (width as usize, height as usize);
        let picture = Picture::new(self, camera, (width, height), shading);
        let centres: Vec<RayResult> = (0..w * h)
            .into_par_iter()
            .map(|i| picture.march((i % w) as f64 + 0.5, (i / w) as f64 + 0.5, true))
            .collect();
        let mut rgba = Vec::with_capacity(w * h * 4);
        for c in &centres {
            rgba.extend(c.color.map(output));
            rgba.push(255);
        }
        RayMarched {
            image: Image {
                width,
                height,
                rgba,
            },
            end: centres.iter().map(|c| c.end).collect(),
            signature: centres.iter().map(|c| c.signature).collect(),
            layer_faces: centres.iter().map(|c| c.layer_faces).collect(),
            content_end: centres.iter().map(|c| c.content_end).collect(),
        }
    }
}

/// A picture of a camera to march: its projection, lighting and content bins, made once
/// for all its rays.
struct Picture<'a> {
    marcher: &'a RayMarcher,
    camera: &'a Camera,
    shading: &'a Shading,
    projection: Projection,
    light: Light,
    bins: Bins,
}

impl<'a> Picture<'a> {
    fn new(
        marcher: &'a RayMarcher,
        camera: &'a Camera,
        (width, height): (u32, u32),
        shading: &'a Shading,
    ) -> Self {
        let projection = Projection::new(camera, width, height);
        let light = Light::new(marcher, camera, shading);
        let bins = Bins::new(&marcher.content, camera, &projection, &light);
        Self {
            marcher,
            camera,
            shading,
            projection,
            light,
            bins,
        }
    }

    /// Marches the ray through `(x, y)` (pixels from the top left).
    fn march(&self, x: f64, y: f64, want_color: bool) -> RayResult {
        let camera = self.camera;
        self.marcher.march(
            camera.eye,
            self.projection.dir(x, y),
            camera.near,
            camera.far,
            camera.medium,
            self.shading,
            &self.light,
            want_color,
            self.bins.at(x, y),
        )
    }
}

/// The renderer's projection: ray directions through points of the picture.
struct Projection {
    forward: DVec3,
    right: DVec3,
    up: DVec3,
    size: (f64, f64),
}

pub(crate) use crate::overlaps::view_basis;

impl Projection {
    fn new(camera: &Camera, width: u32, height: u32) -> Self {
        let [f, right, up] = view_basis(camera);
        let tan_y = (camera.fov_y_deg.to_radians() / 2.0).tan();
        let aspect = f64::from(width) / f64::from(height);
        Self {
            forward: f,
            right: right * tan_y * aspect,
            up: up * tan_y,
            size: (f64::from(width), f64::from(height)),
        }
    }

    /// The direction through `(x, y)` (pixels from the top left), scaled so that its
    /// component along the view axis is 1: the ray parameter is the view depth.
    fn dir(&self, x: f64, y: f64) -> DVec3 {
        let ndc_x = x / self.size.0 * 2.0 - 1.0;
        let ndc_y = 1.0 - y / self.size.1 * 2.0;
        self.forward + self.right * ndc_x + self.up * ndc_y
    }

    /// The pixel coordinates of the point `v` (relative to the eye), if in front of it.
    fn pixel(&self, v: DVec3) -> Option<(f64, f64)> {
        let z = v.dot(self.forward);
        if z <= 1e-9 {
            return None;
        }
        let ndc_x = v.dot(self.right) / self.right.length_squared() / z;
        let ndc_y = v.dot(self.up) / self.up.length_squared() / z;
        Some((
            (ndc_x + 1.0) / 2.0 * self.size.0,
            (1.0 - ndc_y) / 2.0 * self.size.1,
        ))
    }
}

/// "chunk (x, y, z) block (x, y, z) face F id N", or "sky".
pub fn describe(surface: Option<Surface>) -> String {
    match surface {
        None => "sky".into(),
        Some(s) => {
            let (c, l) = s.chunk_and_local();
            format!(
                "chunk ({}, {}, {}) block ({}, {}, {}) face {:?} id {}",
                c.x, c.y, c.z, l[0], l[1], l[2], s.face, s.id.0
            )
        }
    }
}
