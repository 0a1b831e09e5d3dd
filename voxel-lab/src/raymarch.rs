//! The third exact reference: a CPU voxel ray march that shares no mesh, no rasteriser and
//! no GPU with the techniques. Each pixel's ray (through the pixel centre, in f64) walks the
//! world's blocks (Amanatides & Woo's DDA, skipping absent chunks), applies the documented
//! face rules at every block boundary it crosses, the cutout alpha test, the model for an
//! eye inside a translucent volume (`voxel_render::medium`), the lighting, per-vertex
//! ambient occlusion computed from the blocks themselves, fog, blending and tonemapping.
//!
//! What it shares with the renderer is the specification, not the code: the face rules,
//! the AO rule and curve ([`voxel_render::AO_DEPTH`]), the Lambert-plus-ambient lighting,
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

use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::sync::Arc;

use glam::DVec3;
use rayon::prelude::*;
use voxel_core::{BlockId, CHUNK_SIZE, Chunk, ChunkPos, Face, RenderClass, World};
use voxel_render::{Camera, Image, RendererConfig};

use crate::content::{Content, box_normal, face_light, particle_light};

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
    fn plane(&self) -> (Face, i64, BlockId) {
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
    /// block's [`voxel_core::BlockDef::medium`]): linear colour and absorption per block.
    media: Vec<Option<Medium>>,
    /// Per block: the medium a cutout block stands in.
    medium_of: Vec<Option<BlockId>>,
    /// A game's particles and entities ([`crate::content`]).
    content: Content,
}

fn srgb_to_linear(c: u8) -> f64 {
    let c = f64::from(c) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The tonemap of `shaders/tonemap.wgsl` (values up to the shoulder unchanged, then a
/// smooth roll-off towards 1), then sRGB encoding and 8-bit rounding.
fn output(x: f64) -> u8 {
    let shoulder = f64::from(voxel_render::TONEMAP_SHOULDER);
    let t = if x <= shoulder {
        x.max(0.0)
    } else {
        let room = 1.0 - shoulder;
        shoulder + room * (1.0 - (-(x - shoulder) / room).exp())
    };
    let s = if t <= 0.003_130_8 {
        t * 12.92
    } else {
        1.055 * t.powf(1.0 / 2.4) - 0.055
    };
    (s.clamp(0.0, 1.0) * 255.0).round() as u8
}

/// The brightness factor of an AO value (0 to 3) at `strength`.
fn ao_brightness(value: u8, strength: f64) -> f64 {
    1.0 - strength * f64::from(voxel_render::AO_DEPTH) * f64::from(3 - value) / 3.0
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
        }
    }

    /// Reads `world`'s chunks and draws `content` (a game's particles and entities) too.
    pub fn with_content(world: &World, content: &Content) -> Self {
        Self {
            content: content.clone(),
            ..Self::new(world)
        }
    }

    /// The game surfaces the ray from `eye` along `dir` meets between `near` and `far`, by
    /// distance: the particles `particles` (indices) and every entity.
    fn content_hits(
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
            let l = particle_light(light.sun, light.ambient);
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
                    let l = face_light(normal, light.sun, light.ambient);
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
            let l = face_light(normal, light.sun, light.ambient);
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
    fn content_until(hits: &[ContentHit], next: &mut usize, t: f64, w: &mut Walker<'_>) -> bool {
        // At equal depth a block's face is in front of an object's: the object's hit
        // counts OBJECT_DEPTH_BIAS farther, as the GPU's exact methods count it.
        let bias = 1.0 + f64::from(voxel_render::stages::OBJECT_DEPTH_BIAS);
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

    /// The blocks of the chunk at chunk coordinates `c`, if it holds any.
    fn chunk_blocks(&self, c: [i64; 3]) -> Option<&[BlockId]> {
        let pos = ChunkPos::new(
            i32::try_from(c[0]).ok()?,
            i32::try_from(c[1]).ok()?,
            i32::try_from(c[2]).ok()?,
        );
        self.chunks.get(&pos).map(|c| &**c)
    }

    /// The block at `p` (air outside the loaded chunks).
    fn get(&self, p: [i64; 3]) -> BlockId {
        let s = CHUNK_SIZE as i64;
        let c = p.map(|v| v.div_euclid(s));
        let Some(chunk) = self
            .chunks
            .get(&ChunkPos::new(c[0] as i32, c[1] as i32, c[2] as i32))
        else {
            return BlockId::AIR;
        };
        let l = p.map(|v| v.rem_euclid(s) as usize);
        chunk[Chunk::dense_index(l[0], l[1], l[2])]
    }

    fn class(&self, id: BlockId) -> RenderClass {
        self.classes
            .get(id.index())
            .copied()
            .unwrap_or(RenderClass::Air)
    }

    fn opaque(&self, p: [i64; 3]) -> bool {
        self.class(self.get(p)) == RenderClass::Opaque
    }

    /// Colour (linear) and alpha of face `face` of block `id` at face coordinates `(u, v)`
    /// (in blocks along the face's U and V axes).
    fn albedo(&self, id: BlockId, face: Face, u: f64, v: f64, texturing: Texturing) -> [f64; 4] {
        match texturing {
            Texturing::Flat => self.flat[id.index()],
            Texturing::Nearest => {
                // Stored as 8-bit sRGB and 8-bit alpha.
                let t = self.textures.texel(id, face, u, v);
                [
                    srgb_to_linear(t[0]),
                    srgb_to_linear(t[1]),
                    srgb_to_linear(t[2]),
                    f64::from(t[3]) / 255.0,
                ]
            }
        }
    }

    /// The AO brightness at face coordinates `(s, t)` in 0..1 of the unit face `face` of
    /// the block at `b`: each corner's value from the opaque blocks around it in the layer
    /// in front, interpolated over the triangle the renderer's diagonal rule picks.
    fn ao(&self, b: [i64; 3], face: Face, s: f64, t: f64, strength: f64) -> f64 {
        if strength == 0.0 {
            return 1.0;
        }
        let axis = face.axis();
        let (ua, va) = ((axis + 1) % 3, (axis + 2) % 3);
        let n = face.normal();
        let front = [0, 1, 2].map(|a| b[a] + i64::from(n[a]));
        let value = |du: i64, dv: i64| -> u8 {
            let mut s1 = front;
            s1[ua] += du;
            let mut s2 = front;
            s2[va] += dv;
            let mut c = s1;
            c[va] += dv;
            let (s1, s2, c) = (self.opaque(s1), self.opaque(s2), self.opaque(c));
            if s1 && s2 {
                0
            } else {
                3 - u8::from(s1) - u8::from(s2) - u8::from(c)
            }
        };
        let v00 = value(-1, -1);
        let v10 = value(1, -1);
        let v01 = value(-1, 1);
        let v11 = value(1, 1);
        let [b00, b10, b01, b11] = [v00, v10, v01, v11].map(|v| ao_brightness(v, strength));
        if u16::from(v10) + u16::from(v01) > u16::from(v00) + u16::from(v11) {
            // Diagonal (1,0)-(0,1).
            if s + t <= 1.0 {
                b00 + s * (b10 - b00) + t * (b01 - b00)
            } else {
                b11 + (1.0 - s) * (b01 - b11) + (1.0 - t) * (b10 - b11)
            }
        } else if s >= t {
            // Diagonal (0,0)-(1,1): triangle (00, 10, 11).
            b00 + s * (b10 - b00) + t * (b11 - b10)
        } else {
            // Triangle (00, 11, 01).
            b00 + t * (b01 - b00) + s * (b11 - b01)
        }
    }

    /// Marches one ray from `eye` along `dir` (whose component along the view axis is 1,
    /// so that the ray parameter is the view depth) between `near` and `far`.
    #[allow(clippy::too_many_arguments)]
    fn march(
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
        let mut end_t = far;

        let mut walker = Walker {
            eye,
            dir,
            near,
            far,
            medium,
            volume: None,
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
                end_t = hits[next_hit - 1].t;
            } else if let Some(axis) = entry_axis {
                // The ray enters the box from air through a face along `axis`.
                let ended = self.crossing(
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
                if ended {
                    end_t = t0;
                }
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
                    end_t = hits[next_hit - 1].t;
                    break;
                }
                if t > t1 {
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
                if self.crossing(&ctx, &mut walker) {
                    end_t = t;
                }
                prev = b;
            }
        }
        if !content_end
            && walker.end.is_none()
            && Self::content_until(&hits, &mut next_hit, far, &mut walker)
        {
            content_end = true;
            end_t = hits[next_hit - 1].t;
        }
        if !content_end && walker.end.is_none() {
            // Into the sky: a volume the ray is still in ends where the loaded blocks do.
            walker.absorb_to(t1.min(far));
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
        let mut color: [f64; 3] = std::array::from_fn(|c| acc[c] + (1.0 - acc[3]) * background[c]);
        // Fog of the medium over the way to its first surface (or the end).
        if let Some(fog) = &light.fog {
            let depth = boundary.unwrap_or(end_t).min(end_t);
            let transmittance = (-fog.density * depth * dir.length()).exp();
            for (c, f) in color.iter_mut().zip(fog.color) {
                *c = f * (1.0 - transmittance) + *c * transmittance;
            }
        }
        result.color = color;
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
        let p = w.eye + w.dir * x.t;
        // The volume the ray was in, up to here.
        w.absorb_to(x.t);
        // A cutout block standing in a medium hides the medium's faces toward it.
        let stands_in = |cutout: BlockId, medium: BlockId| {
            self.class(cutout) == RenderClass::Cutout && self.medium_block(cutout) == Some(medium)
        };
        // The face of `to` facing the ray: its normal points back along the step.
        let front_face = face_of(x.axis, x.step < 0);
        let front = cb != RenderClass::Air
            && !(ca == RenderClass::Opaque || (cb == RenderClass::Translucent && x.from == x.to))
            && !stands_in(x.from, x.to);
        let mut ended = false;
        if front {
            let surface = Surface {
                block: x.to_cell,
                face: front_face,
                id: x.to,
            };
            let (u, v) = face_uv(p, x.axis);
            let a = self.albedo(x.to, front_face, u, v, w.shading.texturing);
            match cb {
                RenderClass::Opaque => ended = true,
                RenderClass::Cutout => ended = a[3] >= CUTOUT_ALPHA_TEST,
                _ => {}
            }
            if ended {
                let color = if w.want_color {
                    self.lit(surface, p, a, w)
                } else {
                    [0.0; 3]
                };
                *w.end = Some((surface, color));
                return true;
            }
            if cb == RenderClass::Translucent {
                if Some(x.to) == w.medium && w.boundary.is_none() {
                    w.set_boundary(x.t, surface);
                }
                w.layer(self, surface, p, a);
            }
        }
        // From inside a medium the renderer draws translucent back faces too.
        if let Some(m) = w.medium
            && ca == RenderClass::Translucent
            && !(cb == RenderClass::Opaque || x.from == x.to || stands_in(x.to, x.from))
        {
            let back = Surface {
                block: [0, 1, 2].map(|a| x.to_cell[a] - if a == x.axis { x.step } else { 0 }),
                face: face_of(x.axis, x.step > 0),
                id: x.from,
            };
            let first = x.from == m && w.boundary.is_none();
            if first {
                w.set_boundary(x.t, back);
            }
            // It counts when it is the medium's, not toward another translucent type, and
            // the first surface of the medium the ray meets.
            if first && cb != RenderClass::Translucent {
                let (u, v) = face_uv(p, x.axis);
                let a = self.albedo(x.from, back.face, u, v, w.shading.texturing);
                w.layer(self, back, p, a);
            }
        }
        // The volume of the block entered, unless the eye's own passage goes on (the
        // medium's fog stands for it).
        let own_passage = w.medium.is_some() && w.boundary.is_none();
        w.volume = self
            .media
            .get(x.to.index())
            .copied()
            .flatten()
            .filter(|m| m.absorption > 0.0 && !own_passage)
            .map(|m| Volume {
                start: x.t,
                color: m.color.map(|c| c * w.light.medium_light),
                absorption: m.absorption,
            });
        ended
    }

    /// The block whose medium a cutout block `id` stands in.
    fn medium_block(&self, id: BlockId) -> Option<BlockId> {
        self.medium_of.get(id.index()).copied().flatten()
    }

    /// The lit colour of `surface` at point `p` with albedo `a`.
    fn lit(&self, surface: Surface, p: DVec3, a: [f64; 4], w: &Walker<'_>) -> [f64; 3] {
        let face = surface.face;
        let n = face.normal();
        let sun = w.light.sun;
        let n_dot_l =
            (f64::from(n[0]) * sun[0] + f64::from(n[1]) * sun[1] + f64::from(n[2]) * sun[2])
                .max(0.0);
        let ambient = f64::from(w.shading.ambient);
        let light = ambient + (1.0 - ambient) * n_dot_l;
        let translucent = self.class(surface.id) == RenderClass::Translucent;
        let shade = if translucent {
            1.0
        } else {
            let axis = face.axis();
            let (ua, va) = ((axis + 1) % 3, (axis + 2) % 3);
            let s = (p[ua] - surface.block[ua] as f64).clamp(0.0, 1.0);
            let t = (p[va] - surface.block[va] as f64).clamp(0.0, 1.0);
            self.ao(surface.block, face, s, t, f64::from(w.shading.ao_strength))
        };
        [
            a[0] * light * shade,
            a[1] * light * shade,
            a[2] * light * shade,
        ]
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
        let light = Light::new(self, camera, shading);
        let projection = Projection::new(camera, width, height);
        let bins = Bins::new(&self.content, camera, &projection, &light);
        self.march(
            camera.eye,
            projection.dir(x, y),
            camera.near,
            camera.far,
            camera.medium,
            shading,
            &light,
            want_color,
            bins.at(x, y),
        )
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
        let projection = Projection::new(camera, width, height);
        let light = Light::new(self, camera, shading);
        let bins = Bins::new(&self.content, camera, &projection, &light);
        let march = |x: f64, y: f64, color: bool| {
            self.march(
                camera.eye,
                projection.dir(x, y),
                camera.near,
                camera.far,
                camera.medium,
                shading,
                &light,
                color,
                bins.at(x, y),
            )
        };
        let centres: Vec<RayResult> = (0..w * h)
            .into_par_iter()
            .map(|i| march((i % w) as f64 + 0.5, (i / w) as f64 + 0.5, true))
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

/// The renderer's projection: ray directions through points of the picture.
struct Projection {
    forward: DVec3,
    right: DVec3,
    up: DVec3,
    size: (f64, f64),
}

impl Projection {
    fn new(camera: &Camera, width: u32, height: u32) -> Self {
        let f = camera.unit_forward();
        // The view basis of `Camera::view_proj`.
        let up = if f.y.abs() > 0.999 {
            DVec3::Z
        } else {
            DVec3::Y
        };
        let right = f.cross(up).normalize();
        let tan_y = (camera.fov_y_deg.to_radians() / 2.0).tan();
        let aspect = f64::from(width) / f64::from(height);
        Self {
            forward: f,
            right: right * tan_y * aspect,
            up: right.cross(f) * tan_y,
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

/// The particles whose squares may cover each 16 × 16 pixel tile of a picture, so that a
/// ray tests a few of them, not thousands.
struct Bins {
    cols: usize,
    cells: Vec<Vec<u32>>,
}

const BIN_PX: f64 = 16.0;

impl Bins {
    fn new(content: &Content, camera: &Camera, projection: &Projection, light: &Light) -> Self {
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
    fn at(&self, x: f64, y: f64) -> &[u32] {
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
struct Walker<'a> {
    eye: DVec3,
    dir: DVec3,
    near: f64,
    far: f64,
    medium: Option<BlockId>,
    /// The volume the ray is in since the last layer (none in the eye's own medium).
    volume: Option<Volume>,
    shading: &'a Shading,
    light: &'a Light,
    want_color: bool,
    layers: &'a mut Vec<[f64; 4]>,
    end: &'a mut Option<(Surface, [f64; 3])>,
    boundary: &'a mut Option<f64>,
    hasher: &'a mut std::collections::hash_map::DefaultHasher,
    faces: &'a mut std::collections::hash_map::DefaultHasher,
}

/// A medium: linear colour, absorption per block.
#[derive(Clone, Copy, Debug)]
struct Medium {
    color: [f64; 3],
    absorption: f64,
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
    fn absorb_to(&mut self, t: f64) {
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

    /// The medium's first surface (it ends the fog; the signature notes it, since the fog
    /// changes where it does).
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
            let c = m.lit(s, p, a, self);
            self.layers.push([c[0], c[1], c[2], a[3].clamp(0.0, 1.0)]);
        }
    }
}

/// Per-picture lighting: the sun, the sky, the medium's fog.
struct Light {
    sun: DVec3,
    ambient: f64,
    sky: [f64; 3],
    fog: Option<Fog>,
    /// What a medium's colour is lit by: a face turned to the sky.
    medium_light: f64,
    /// The camera's forward, right and up (unit): particles face the camera.
    basis: [DVec3; 3],
}

struct Fog {
    color: [f64; 3],
    density: f64,
}

impl Light {
    fn new(m: &RayMarcher, camera: &Camera, shading: &Shading) -> Self {
        let s = shading.sun_dir.map(f64::from);
        let sun = DVec3::from(s).try_normalize().unwrap_or(DVec3::Y);
        let ambient = f64::from(shading.ambient);
        let medium_light = ambient + (1.0 - ambient) * sun.y.max(0.0);
        let fog = camera
            .medium
            .and_then(|id| m.media.get(id.index()).copied().flatten())
            .map(|look| Fog {
                color: look.color.map(|c| c * medium_light),
                density: look.absorption,
            });
        let f = camera.unit_forward();
        let up = if f.y.abs() > 0.999 {
            DVec3::Z
        } else {
            DVec3::Y
        };
        let right = f.cross(up).normalize();
        Self {
            sun,
            ambient,
            sky: shading.sky.map(f64::from),
            fog,
            medium_light,
            basis: [f, right, right.cross(f)],
        }
    }
}

/// A game surface on a ray.
#[derive(Clone, Copy, Debug)]
struct ContentHit {
    t: f64,
    /// Lit colour, linear.
    color: [f64; 3],
    alpha: f64,
    opaque: bool,
    /// (1 particle / 2 entity, index, face): the signature's identity of the surface.
    id: (u8, u32, u8),
}

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
/// `voxel_render::OPAQUE_EXPANSION_PX`, by 1/64 px).
pub const EDGE_RADIUS_PX: f64 = 1.0 / 32.0;

impl RayMarcher {
    /// Compares a ray-marched picture (of `camera`, the renderer's drawn camera, with
    /// `shading`) with a GPU picture of the same scene, and with the GPU's opaque depth
    /// (reverse-Z, 0 where nothing opaque was drawn) for cracks. A pixel whose colours
    /// differ by more than 1/255 is marched again at 96 points around its centre within
    /// [`EDGE_RADIUS_PX`]: if one meets other surfaces or ends on another block's face, an
    /// edge passes there (a face's edge, where faces the eye cannot see may touch the
    /// visible one at the same depth) and the pixel is on an edge; otherwise it counts as
    /// differing.
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
        let projection = &Projection::new(camera, width, height);
        let light = &Light::new(self, camera, shading);
        let bins = &Bins::new(&self.content, camera, projection, light);
        // Rays around a pixel's centre within the edge radius: 32 angles on circles of a
        // quarter, half and the whole radius, dense enough to meet the thin sliver of a
        // face seen at a grazing angle.
        let ring = |i: usize| {
            let (x, y) = ((i % w) as f64 + 0.5, (i / w) as f64 + 0.5);
            (0..96).map(move |k| {
                let angle = f64::from(k % 32) * std::f64::consts::TAU / 32.0;
                let radius = EDGE_RADIUS_PX * f64::from(1 << (k / 32)) / 4.0;
                let (dx, dy) = (angle.cos() * radius, angle.sin() * radius);
                self.march(
                    camera.eye,
                    projection.dir(x + dx, y + dy),
                    camera.near,
                    camera.far,
                    camera.medium,
                    shading,
                    light,
                    false,
                    bins.at(x + dx, y + dy),
                )
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
            let mut seam = false;
            let near_edge = ring(i).any(|r| {
                seam |= r.layer_faces != ray.layer_faces[i];
                r.signature != ray.signature[i] || r.end != ray.end[i]
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
