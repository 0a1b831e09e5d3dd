//! The block textures: a texture array made at start-up from the registry, one layer per
//! distinct face texture, and a table of the layer each block's top, bottom and sides
//! sample. A face group draws the image the game gave it ([`voxel_core::BlockDef::images`])
//! or else the block's procedural [`Pattern`] (leaves with holes, glass with a frame, grass
//! with soil sides). Every layer has one size, the largest image's (16 at least: the
//! patterns'), smaller ones scaled by repeating texels; mipmaps average in linear colour,
//! weighted by alpha. Texels are stored as sRGB (`Rgba8UnormSrgb`): the GPU decodes them.

use std::path::Path;

use voxel_core::{
    BlockDef, BlockId, BlockImage, BlockRegistry, Face, FaceGroup, Pattern, RenderClass,
};
use wgpu::util::DeviceExt;

use crate::readback::Image;
use crate::{Error, GpuContext, Result};

/// Texels along each side of a procedural texture.
pub(crate) const TEXTURE_SIZE: u32 = 16;

fn hash(a: u32, b: u32, c: u32) -> u32 {
    let mut h =
        a.wrapping_mul(0x9e37_79b1) ^ b.wrapping_mul(0x85eb_ca77) ^ c.wrapping_mul(0xc2b2_ae3d);
    h ^= h >> 15;
    h = h.wrapping_mul(0x2c1b_3c6d);
    h ^= h >> 12;
    h = h.wrapping_mul(0x297a_2d39);
    h ^ (h >> 15)
}

/// An 8-bit sRGB channel as linear colour.
pub fn srgb_to_linear(c: u8) -> f32 {
    let c = f32::from(c) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// A linear colour channel as 8-bit sRGB (how the texture stores it).
pub fn linear_to_srgb(c: f32) -> u8 {
    let c = c.clamp(0.0, 1.0);
    let s = if c <= 0.003_130_8 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0).round() as u8
}

/// How one face texture is drawn procedurally.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Drawn {
    /// Nothing (air).
    Empty,
    /// One flat colour, alpha the block's opacity for translucent blocks and 1 for others
    /// (`RendererConfig::flat_textures`).
    Flat,
    /// The block's pattern as the face group sees it.
    Pattern(Pattern, FaceGroup),
}

/// Level 0 of a procedural texture: [`TEXTURE_SIZE`]² texels, RGBA, linear colour, rows top
/// to bottom.
fn pattern_texels(def: &BlockDef, id: u32, drawn: Drawn) -> Vec<[f32; 4]> {
    let base = def.color.map(srgb_to_linear);
    let n = TEXTURE_SIZE;
    let mut out = Vec::with_capacity((n * n) as usize);
    for y in 0..n {
        for x in 0..n {
            let h = hash(x, y, id);
            // Brightness noise of ±8%: enough to read surfaces, small enough not to
            // dominate the colour.
            let shade = 0.92 + 0.16 * (h & 0xff) as f32 / 255.0;
            let noisy = |c: [f32; 3], a: f32| [c[0] * shade, c[1] * shade, c[2] * shade, a];
            let edge = x == 0 || y == 0 || x == n - 1 || y == n - 1;
            let texel = match drawn {
                Drawn::Empty => [0.0; 4],
                Drawn::Flat => {
                    let a = if def.class == RenderClass::Translucent {
                        def.opacity
                    } else {
                        1.0
                    };
                    [base[0], base[1], base[2], a]
                }
                Drawn::Pattern(Pattern::Noise, _) => noisy(base, def.opacity),
                Drawn::Pattern(Pattern::Leaves, _) => {
                    // About 35% holes, as hashed texels.
                    let hole = (h >> 8) % 100 < 35;
                    noisy(base, if hole { 0.0 } else { 1.0 })
                }
                Drawn::Pattern(Pattern::Framed, _) if edge => {
                    [base[0] * 0.45, base[1] * 0.45, base[2] * 0.45, 1.0]
                }
                Drawn::Pattern(Pattern::Framed, _) => [base[0], base[1], base[2], def.opacity],
                Drawn::Pattern(Pattern::Grass { soil }, group) => {
                    // The fringe hangs 3 to 5 texels down the sides, hashed per column
                    // so that it reads as grass, not as a stripe.
                    let fringe = 3 + (hash(x, 0, id ^ 0x5eed) % 3);
                    let grass = match group {
                        FaceGroup::Top => true,
                        FaceGroup::Side => y < fringe,
                        FaceGroup::Bottom => false,
                    };
                    let c = if grass {
                        base
                    } else {
                        soil.map(srgb_to_linear)
                    };
                    noisy(c, def.opacity)
                }
            };
            out.push(texel);
        }
    }
    out
}

fn encode(t: [f32; 4]) -> [u8; 4] {
    [
        linear_to_srgb(t[0]),
        linear_to_srgb(t[1]),
        linear_to_srgb(t[2]),
        (t[3].clamp(0.0, 1.0) * 255.0).round() as u8,
    ]
}

/// `src` (a square of `from` texels a side) scaled up to `to` texels a side by repeating
/// each texel, so that its look does not change.
fn upscale(src: &[[u8; 4]], from: u32, to: u32) -> Vec<[u8; 4]> {
    let k = to / from;
    let mut out = Vec::with_capacity((to * to) as usize);
    for y in 0..to {
        for x in 0..to {
            out.push(src[((y / k) * from + x / k) as usize]);
        }
    }
    out
}

/// Where a face texture comes from: identical sources share a layer.
#[derive(Clone, PartialEq)]
enum Source<'a> {
    Image(&'a BlockImage),
    Drawn(BlockId, Drawn),
}

/// The face textures of a registry on the CPU: level 0 of every layer, and the layer each
/// block's face groups sample. What [`BlockTextures`] uploads, and what a CPU reference
/// (the lab's ray march) samples to see what the GPU sees.
#[derive(Clone, Debug, PartialEq)]
pub struct TextureSet {
    size: u32,
    layers: Vec<Vec<[u8; 4]>>,
    table: Vec<[u32; 3]>,
}

impl TextureSet {
    /// The textures of every block of `registry`; `flat`: every block one colour (its base
    /// colour, alpha its opacity when translucent and 1 otherwise), images and patterns
    /// ignored (`RendererConfig::flat_textures`).
    pub fn new(registry: &BlockRegistry, flat: bool) -> Self {
        let size = if flat {
            TEXTURE_SIZE
        } else {
            registry
                .iter()
                .flat_map(|(_, d)| FaceGroup::ALL.map(|g| d.images.get(g).map(BlockImage::size)))
                .flatten()
                .fold(TEXTURE_SIZE, u32::max)
        };
        let mut sources: Vec<(Source<'_>, &BlockDef)> = Vec::new();
        let mut table = Vec::with_capacity(registry.len());
        for (id, def) in registry.iter() {
            let groups = FaceGroup::ALL.map(|group| {
                let source = match (def.class, flat, def.images.get(group)) {
                    (RenderClass::Air, ..) => Source::Drawn(BlockId::AIR, Drawn::Empty),
                    (_, true, _) => Source::Drawn(id, Drawn::Flat),
                    (_, false, Some(image)) => Source::Image(image),
                    // Only grass draws its face groups differently.
                    (_, false, None) => {
                        let g = match def.pattern {
                            Pattern::Grass { .. } => group,
                            _ => FaceGroup::Side,
                        };
                        Source::Drawn(id, Drawn::Pattern(def.pattern, g))
                    }
                };
                match sources.iter().position(|(s, _)| *s == source) {
                    Some(i) => i as u32,
                    None => {
                        sources.push((source, def));
                        sources.len() as u32 - 1
                    }
                }
            });
            table.push(groups);
        }
        let layers = sources
            .iter()
            .map(|(source, def)| match source {
                Source::Image(image) => {
                    let texels: Vec<[u8; 4]> = image
                        .rgba()
                        .chunks_exact(4)
                        .map(|t| [t[0], t[1], t[2], t[3]])
                        .collect();
                    upscale(&texels, image.size(), size)
                }
                Source::Drawn(id, drawn) => {
                    let texels: Vec<[u8; 4]> = pattern_texels(def, u32::from(id.0), *drawn)
                        .into_iter()
                        .map(encode)
                        .collect();
                    upscale(&texels, TEXTURE_SIZE, size)
                }
            })
            .collect();
        Self {
            size,
            layers,
            table,
        }
    }

    /// Texels along each side of every layer.
    pub fn size(&self) -> u32 {
        self.size
    }

    /// Mip levels of every layer: down to 1 × 1.
    pub(crate) fn mip_levels(&self) -> u32 {
        self.size.ilog2() + 1
    }

    /// Number of layers.
    pub(crate) fn layer_count(&self) -> usize {
        self.layers.len()
    }

    /// Level 0 of layer `i`: sRGB colour and alpha, rows top to bottom.
    #[cfg(test)]
    pub(crate) fn layer(&self, i: usize) -> &[[u8; 4]] {
        &self.layers[i]
    }

    /// The layers of block `id`'s top, bottom and side faces (layer 0, air's, for an id
    /// the registry does not hold).
    pub(crate) fn layers_of(&self, id: BlockId) -> [u32; 3] {
        self.table.get(id.index()).copied().unwrap_or([0; 3])
    }

    /// The layer `face` of block `id` samples.
    pub(crate) fn layer_of(&self, id: BlockId, face: Face) -> u32 {
        self.layers_of(id)[FaceGroup::of(face) as usize]
    }

    /// The level-0 texel (sRGB colour, alpha) `face` of block `id` shows at face
    /// coordinates `(u, v)`: world coordinates along the face's U and V axes (±x: y, z;
    /// ±y: z, x; ±z: x, y), as the quads' texture coordinates run. Nearest texel, as the
    /// GPU magnifies; what `albedo()` in `shaders/common.wgsl` samples.
    pub fn texel(&self, id: BlockId, face: Face, u: f64, v: f64) -> [u8; 4] {
        let (s, t) = image_coords(face, u, v);
        let n = f64::from(self.size);
        let at = |c: f64| ((c.rem_euclid(1.0) * n).floor() as u32).min(self.size - 1);
        let layer = self.layer_of(id, face) as usize;
        self.layers[layer][(at(t) * self.size + at(s)) as usize]
    }

    /// Every level of layer `i`, level 0 first, each the average of 2 × 2 texels of the one
    /// above in linear colour, weighted by alpha (a transparent texel's colour does not
    /// bleed into its neighbours'; where all four are transparent, their plain average).
    pub(crate) fn mip_chain(&self, i: usize) -> Vec<Vec<[u8; 4]>> {
        let mut levels = vec![self.layers[i].clone()];
        let mut size = self.size as usize;
        while size > 1 {
            let prev = levels.last().map_or(&[][..], Vec::as_slice);
            let half = size / 2;
            let mut next = Vec::with_capacity(half * half);
            for y in 0..half {
                for x in 0..half {
                    let quad = [(0, 0), (1, 0), (0, 1), (1, 1)]
                        .map(|(dx, dy)| prev[(2 * y + dy) * size + 2 * x + dx]);
                    next.push(average(&quad));
                }
            }
            levels.push(next);
            size = half;
        }
        levels
    }
}

/// The alpha-weighted average of texels, in linear colour.
fn average(texels: &[[u8; 4]; 4]) -> [u8; 4] {
    let alpha: f32 = texels.iter().map(|t| f32::from(t[3])).sum();
    let mut rgb = [0.0f32; 3];
    for t in texels {
        let w = if alpha > 0.0 {
            f32::from(t[3]) / alpha
        } else {
            0.25
        };
        for c in 0..3 {
            rgb[c] += srgb_to_linear(t[c]) * w;
        }
    }
    encode([rgb[0], rgb[1], rgb[2], alpha / (4.0 * 255.0)])
}

/// Image coordinates `(s, t)` in blocks (s to the right, t down the image; the image
/// repeats once per block) of the point at face coordinates `(u, v)` of `face`: side
/// faces upright and seen from outside, top and bottom with s along +x and t along +z.
/// The WGSL twin is `image_uv()` in `shaders/common.wgsl`.
pub(crate) fn image_coords(face: Face, u: f64, v: f64) -> (f64, f64) {
    match face {
        // U = y, V = z; seen from +x, right is −z.
        Face::PosX => (-v, -u),
        Face::NegX => (v, -u),
        // U = z, V = x.
        Face::PosY | Face::NegY => (v, u),
        // U = x, V = y; seen from +z, right is +x.
        Face::PosZ => (u, -v),
        Face::NegZ => (-u, -v),
    }
}

/// Reads a PNG file as a block image ([`BlockImage`]: square, a power of two up to
/// [`voxel_core::MAX_IMAGE_SIZE`] a side; 8-bit grey, RGB or RGBA, palettes expanded,
/// 16-bit reduced to 8). Errors name the file and say what is wrong.
pub fn load_block_image(path: &Path) -> Result<BlockImage> {
    let image = Image::load_png_within(path, voxel_core::MAX_IMAGE_SIZE)?;
    BlockImage::new(image.width, image.height, image.rgba).map_err(|e| Error::Image {
        path: path.to_owned(),
        error: e,
    })
}

/// The texture array on the GPU, its sampler, and the table of each block's layers.
#[derive(Debug)]
pub struct BlockTextures {
    /// View of all layers, for `texture_2d_array<f32>`.
    pub view: wgpu::TextureView,
    /// Repeating sampler: nearest when magnified (the voxel look), trilinear when minified.
    pub sampler: wgpu::Sampler,
    /// Per block id, the layers of its top, bottom and side faces (`array<u32>`, three a
    /// block).
    pub layers: wgpu::Buffer,
    /// What `layers` holds, for devices that read it from a texture (`crate::QuadFetch`).
    pub table: Vec<u32>,
}

/// Layers of the block textures' array for `needed` layers: one more where wgpu's GL backend
/// (GLES, WebGL2) would take the square array for a cube map, which it does for 1 layer
/// (a plain 2D texture) and for every multiple of 6 (a cube map array), so that the shaders'
/// `texture_2d_array` sampled nothing there and the world was black (a registry of 16
/// blocks, the default and `BlockRegistry::with_lights`'s three, has 18 layers). The spare
/// layer is never sampled.
pub(crate) fn array_layers(needed: u32) -> u32 {
    if needed <= 1 || needed.is_multiple_of(6) {
        needed.max(1) + 1
    } else {
        needed
    }
}

impl BlockTextures {
    /// Builds and uploads the textures of `registry` ([`TextureSet::new`]), in an array of
    /// [`array_layers`] layers. More layers than the adapter's texture arrays hold is an
    /// error.
    pub fn new(ctx: &GpuContext, registry: &BlockRegistry, flat: bool) -> Result<Self> {
        let set = TextureSet::new(registry, flat);
        let layers = array_layers(set.layer_count() as u32);
        if layers > ctx.caps.limits.max_texture_array_layers {
            return Err(Error::Unsupported(format!(
                "{layers} distinct block face textures, but the adapter allows {} texture array layers",
                ctx.caps.limits.max_texture_array_layers
            )));
        }
        let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("block_textures"),
            size: wgpu::Extent3d {
                width: set.size(),
                height: set.size(),
                depth_or_array_layers: layers,
            },
            mip_level_count: set.mip_levels(),
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba8UnormSrgb,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        for layer in 0..set.layer_count() {
            for (mip, level) in set.mip_chain(layer).iter().enumerate() {
                let side = set.size() >> mip;
                ctx.queue.write_texture(
                    wgpu::TexelCopyTextureInfo {
                        texture: &texture,
                        mip_level: mip as u32,
                        origin: wgpu::Origin3d {
                            x: 0,
                            y: 0,
                            z: layer as u32,
                        },
                        aspect: wgpu::TextureAspect::All,
                    },
                    bytemuck::cast_slice(level),
                    wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(4 * side),
                        rows_per_image: Some(side),
                    },
                    wgpu::Extent3d {
                        width: side,
                        height: side,
                        depth_or_array_layers: 1,
                    },
                );
            }
        }
        let table: Vec<u32> = registry
            .iter()
            .flat_map(|(id, _)| set.layers_of(id))
            .collect();
        let layers = ctx
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("block_layers"),
                contents: bytemuck::cast_slice(&table),
                usage: wgpu::BufferUsages::STORAGE,
            });
        let view = texture.create_view(&wgpu::TextureViewDescriptor {
            label: Some("block_textures_view"),
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        let sampler = ctx.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("block_sampler"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            address_mode_w: wgpu::AddressMode::Repeat,
            mag_filter: wgpu::FilterMode::Nearest,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            ..Default::default()
        });
        Ok(Self {
            view,
            sampler,
            layers,
            table,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use voxel_core::{FaceImages, blocks};

    fn set() -> TextureSet {
        TextureSet::new(&BlockRegistry::default(), false)
    }

    fn level0(id: BlockId, face: Face) -> Vec<[u8; 4]> {
        let s = set();
        s.layer(s.layer_of(id, face) as usize).to_vec()
    }

    #[test]
    fn leaves_have_holes_and_solid_texels() {
        let t = level0(blocks::LEAVES, Face::PosX);
        let holes = t.iter().filter(|t| t[3] == 0).count();
        assert!((40..130).contains(&holes), "{holes} holes of 256");
        assert!(t.iter().all(|t| t[3] == 0 || t[3] == 255));
    }

    #[test]
    fn glass_has_an_opaque_frame_and_a_translucent_centre() {
        let r = BlockRegistry::default();
        let g = r.get(blocks::RED_GLASS).unwrap();
        let t = level0(blocks::RED_GLASS, Face::PosZ);
        assert_eq!(t[0][3], 255);
        assert_eq!(t[15][3], 255);
        assert_eq!(t[8 * 16 + 8][3], (g.opacity * 255.0).round() as u8);
        let water = r.get(blocks::WATER).unwrap().opacity;
        let w = level0(blocks::WATER, Face::PosY);
        assert!(
            w.iter().all(|t| t[3] == (water * 255.0).round() as u8),
            "water has no frame"
        );
    }

    #[test]
    fn grass_has_a_top_soil_sides_with_a_fringe_and_a_soil_bottom() {
        let s = set();
        let [top, bottom, side] = s.layers_of(blocks::GRASS);
        assert!(top != side && side != bottom && top != bottom);
        // Other blocks share one layer for all their faces.
        let [a, b, c] = s.layers_of(blocks::STONE);
        assert!(a == b && b == c);
        let green = |t: [u8; 4]| t[1] > t[0] + 30;
        let side = s.layer(side as usize);
        // The side's first row (its top edge) is grass, its last row soil.
        assert!(side[..16].iter().all(|&t| green(t)));
        assert!(side[15 * 16..].iter().all(|&t| !green(t)));
        assert!(s.layer(top as usize).iter().all(|&t| green(t)));
        assert!(s.layer(bottom as usize).iter().all(|&t| !green(t)));
        // The top edge of a side face (u near 1 along y) shows the fringe.
        for face in [Face::PosX, Face::NegX, Face::PosZ, Face::NegZ] {
            let (along_y_top, along_y_bottom) = match face {
                Face::PosX | Face::NegX => ((0.97, 0.5), (0.03, 0.5)),
                _ => ((0.5, 0.97), (0.5, 0.03)),
            };
            assert!(green(s.texel(
                blocks::GRASS,
                face,
                along_y_top.0,
                along_y_top.1
            )));
            assert!(!green(s.texel(
                blocks::GRASS,
                face,
                along_y_bottom.0,
                along_y_bottom.1
            )));
        }
    }

    #[test]
    fn images_replace_the_pattern_per_face_group_scaled_to_the_largest() {
        let mut r = BlockRegistry::default();
        let checker = |a: [u8; 4], b: [u8; 4]| {
            let rgba = (0..4)
                .flat_map(|i| if i == 0 || i == 3 { a } else { b })
                .collect();
            BlockImage::new(2, 2, rgba).unwrap()
        };
        let red = checker([255, 0, 0, 255], [255, 255, 255, 255]);
        let blue = BlockImage::new(32, 32, [0, 0, 255, 255].repeat(32 * 32)).unwrap();
        let id = r
            .register(
                voxel_core::BlockDef::new("crate", [1, 2, 3], 1.0).with_images(FaceImages {
                    top: Some(red.clone()),
                    side: Some(blue),
                    bottom: None,
                }),
            )
            .unwrap();
        let again = r
            .register(
                voxel_core::BlockDef::new("crate2", [1, 2, 3], 1.0)
                    .with_images(FaceImages::all(red)),
            )
            .unwrap();
        let s = TextureSet::new(&r, false);
        assert_eq!(s.size(), 32, "the largest image sets the size");
        assert_eq!(s.mip_levels(), 6);
        let [top, bottom, side] = s.layers_of(id);
        assert_eq!(s.layers_of(again)[0], top, "one image, one layer");
        // The 2x2 checker, scaled to 32: four 16x16 squares.
        let t = s.layer(top as usize);
        assert_eq!(t[0], [255, 0, 0, 255]);
        assert_eq!(t[15 * 32 + 15], [255, 0, 0, 255]);
        assert_eq!(t[16], [255, 255, 255, 255]);
        assert_eq!(t[31 * 32 + 31], [255, 0, 0, 255]);
        assert!(
            s.layer(side as usize)
                .iter()
                .all(|&t| t == [0, 0, 255, 255])
        );
        // The bottom keeps the pattern (noise of the base colour), scaled up.
        let b = s.layer(bottom as usize);
        assert_eq!(b[0], b[1], "a pattern texel covers 2x2");
        // Flat textures ignore images: one 16x16 layer of the base colour per block.
        let flat = TextureSet::new(&r, true);
        assert_eq!(flat.size(), 16);
        let [a, b2, c] = flat.layers_of(id);
        assert!(a == b2 && b2 == c);
        assert!(flat.layer(a as usize).iter().all(|&t| t == [1, 2, 3, 255]));
    }

    #[test]
    fn image_coordinates_stand_side_images_upright() {
        // On every side face the first image row is at the block's top.
        for (face, top) in [
            (Face::PosX, (0.99, 0.5)),
            (Face::NegX, (0.99, 0.5)),
            (Face::PosZ, (0.5, 0.99)),
            (Face::NegZ, (0.5, 0.99)),
        ] {
            let (_, t) = image_coords(face, top.0, top.1);
            assert!(t.rem_euclid(1.0) < 0.02, "{face:?}: t {t}");
        }
        // Seen from outside, s grows to the right: +z face right is +x, -z face right is -x.
        let s = |face, u, v| image_coords(face, u, v).0.rem_euclid(1.0);
        assert!(s(Face::PosZ, 0.2, 0.5) < s(Face::PosZ, 0.8, 0.5));
        assert!(s(Face::NegZ, 0.2, 0.5) > s(Face::NegZ, 0.8, 0.5));
        assert!(s(Face::PosX, 0.5, 0.2) > s(Face::PosX, 0.5, 0.8));
        assert!(s(Face::NegX, 0.5, 0.2) < s(Face::NegX, 0.5, 0.8));
    }

    #[test]
    fn mips_average_by_alpha_down_to_one_texel() {
        let s = set();
        let glass = s.layer_of(blocks::GLASS, Face::PosX) as usize;
        let chain = s.mip_chain(glass);
        assert_eq!(chain.len(), 5);
        assert_eq!(chain.last().unwrap().len(), 1);
        let mean0: f32 = chain[0].iter().map(|t| f32::from(t[3])).sum::<f32>() / 256.0;
        assert!((f32::from(chain[4][0][3]) - mean0).abs() <= 2.0);
        // A transparent texel's colour does not bleed.
        let texels = [
            [255, 0, 0, 255],
            [0, 0, 255, 0],
            [255, 0, 0, 255],
            [0, 0, 255, 0],
        ];
        assert_eq!(average(&texels), [255, 0, 0, 128]);
        assert_eq!(average(&[[0, 0, 0, 0]; 4]), [0, 0, 0, 0]);
    }

    #[test]
    fn srgb_round_trips() {
        for v in [0u8, 1, 10, 128, 200, 255] {
            assert_eq!(linear_to_srgb(srgb_to_linear(v)), v);
        }
    }

    #[test]
    fn the_array_is_never_one_layer_or_a_multiple_of_six() {
        assert_eq!(array_layers(0), 2);
        assert_eq!(array_layers(1), 2);
        assert_eq!(array_layers(15), 15);
        assert_eq!(array_layers(18), 19);
        assert_eq!(array_layers(6), 7);
        for n in 0..200 {
            let a = array_layers(n);
            assert!(a >= n && a > 1 && !a.is_multiple_of(6), "{n} -> {a}");
        }
    }

    #[test]
    fn the_default_registry_needs_few_layers() {
        // 12 blocks and air; grass has three faces, 13 + 2 layers, all different.
        let s = set();
        assert_eq!(s.layer_count(), 15);
        let distinct: std::collections::HashSet<&[[u8; 4]]> =
            (0..s.layer_count()).map(|i| s.layer(i)).collect();
        assert_eq!(distinct.len(), 15);
    }
}
