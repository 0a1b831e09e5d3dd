//! The block texture array, made procedurally at start-up from the registry: one 16×16 layer
//! per block id, with mipmaps. Texture alpha is real: leaves have holes (the cutout pass
//! tests them), glass has an opaque frame around a translucent centre, water and ice are
//! uniformly translucent at their block's opacity.

use voxel_core::{BlockDef, BlockRegistry, RenderClass};

use crate::{Error, GpuContext, Result};

/// Texels along each side of a block texture.
pub const TEXTURE_SIZE: u32 = 16;
/// Mip levels: 16, 8, 4, 2, 1.
pub const MIP_LEVELS: u32 = 5;

/// How a block's texture is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pattern {
    /// Nothing (air).
    Empty,
    /// The base colour with a little brightness noise, alpha = opacity.
    Noise,
    /// Leaves: noise with about a third of the texels fully transparent.
    Leaves,
    /// Glass: a one-texel opaque frame (darker) around a centre of the block's opacity.
    Framed,
    /// One flat colour, alpha the block's opacity for translucent blocks and 1 for others
    /// (cutout blocks solid): `RendererConfig::flat_textures`.
    Flat,
}

impl Pattern {
    /// The pattern of a block: cutout blocks get leaves, translucent blocks whose name
    /// contains "glass" get a frame, others get noise.
    pub fn for_block(def: &BlockDef) -> Pattern {
        match def.class {
            RenderClass::Air => Pattern::Empty,
            RenderClass::Cutout => Pattern::Leaves,
            RenderClass::Translucent if def.name.contains("glass") => Pattern::Framed,
            _ => Pattern::Noise,
        }
    }
}

fn hash(a: u32, b: u32, c: u32) -> u32 {
    let mut h =
        a.wrapping_mul(0x9e37_79b1) ^ b.wrapping_mul(0x85eb_ca77) ^ c.wrapping_mul(0xc2b2_ae3d);
    h ^= h >> 15;
    h = h.wrapping_mul(0x2c1b_3c6d);
    h ^= h >> 12;
    h = h.wrapping_mul(0x297a_2d39);
    h ^ (h >> 15)
}

fn srgb_to_linear(c: u8) -> f32 {
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

/// Level 0 of a block's texture: 16×16 texels, RGBA, linear colour.
pub fn texels(def: &BlockDef, id: u32) -> Vec<[f32; 4]> {
    pattern_texels(def, id, Pattern::for_block(def))
}

/// Level 0 of a block's texture drawn with `pattern`.
pub fn pattern_texels(def: &BlockDef, id: u32, pattern: Pattern) -> Vec<[f32; 4]> {
    let base = def.color.map(srgb_to_linear);
    let n = TEXTURE_SIZE;
    let mut out = Vec::with_capacity((n * n) as usize);
    for y in 0..n {
        for x in 0..n {
            let h = hash(x, y, id);
            // Brightness noise of ±8%: enough to read surfaces, small enough not to
            // dominate the colour.
            let shade = 0.92 + 0.16 * (h & 0xff) as f32 / 255.0;
            let rgb = base.map(|c| c * shade);
            let edge = x == 0 || y == 0 || x == n - 1 || y == n - 1;
            let texel = match pattern {
                Pattern::Empty => [0.0; 4],
                Pattern::Noise => [rgb[0], rgb[1], rgb[2], def.opacity],
                Pattern::Leaves => {
                    // About 35% holes, as hashed texels.
                    let hole = (h >> 8) % 100 < 35;
                    [rgb[0], rgb[1], rgb[2], if hole { 0.0 } else { 1.0 }]
                }
                Pattern::Framed if edge => [base[0] * 0.45, base[1] * 0.45, base[2] * 0.45, 1.0],
                Pattern::Framed => [base[0], base[1], base[2], def.opacity],
                Pattern::Flat => {
                    let a = if def.class == RenderClass::Translucent {
                        def.opacity
                    } else {
                        1.0
                    };
                    [base[0], base[1], base[2], a]
                }
            };
            out.push(texel);
        }
    }
    out
}

/// The mip chain of a level-0 texture, each level the box average of the one above.
pub fn mip_chain(level0: Vec<[f32; 4]>) -> Vec<Vec<[f32; 4]>> {
    let mut levels = vec![level0];
    let mut size = TEXTURE_SIZE as usize;
    while size > 1 {
        let prev = levels.last().map_or(&[][..], Vec::as_slice);
        let half = size / 2;
        let mut next = Vec::with_capacity(half * half);
        for y in 0..half {
            for x in 0..half {
                let mut acc = [0.0f32; 4];
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let t = prev[(2 * y + dy) * size + 2 * x + dx];
                    for c in 0..4 {
                        acc[c] += t[c] * 0.25;
                    }
                }
                next.push(acc);
            }
        }
        levels.push(next);
        size = half;
    }
    levels
}

fn to_rgba8(level: &[[f32; 4]]) -> Vec<u8> {
    level
        .iter()
        .flat_map(|t| {
            [
                linear_to_srgb(t[0]),
                linear_to_srgb(t[1]),
                linear_to_srgb(t[2]),
                (t[3].clamp(0.0, 1.0) * 255.0).round() as u8,
            ]
        })
        .collect()
}

/// The texture array on the GPU and its sampler.
#[derive(Debug)]
pub struct BlockTextures {
    /// View of all layers, for `texture_2d_array<f32>`.
    pub view: wgpu::TextureView,
    /// Repeating sampler: nearest when magnified (the voxel look), trilinear when minified.
    pub sampler: wgpu::Sampler,
}

impl BlockTextures {
    /// Builds and uploads one layer per registered block; `flat`: every block one colour
    /// ([`Pattern::Flat`]).
    pub fn new(ctx: &GpuContext, registry: &BlockRegistry, flat: bool) -> Result<Self> {
        let layers = registry.len() as u32;
        if layers > ctx.caps.limits.max_texture_array_layers {
            return Err(Error::Unsupported(format!(
                "{layers} block types, but the adapter allows {} texture array layers",
                ctx.caps.limits.max_texture_array_layers
            )));
        }
        let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("block_textures"),
            size: wgpu::Extent3d {
                width: TEXTURE_SIZE,
                height: TEXTURE_SIZE,
                depth_or_array_layers: layers,
            },
            mip_level_count: MIP_LEVELS,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba8UnormSrgb,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        for (id, def) in registry.iter() {
            let level0 = if flat && def.class != RenderClass::Air {
                pattern_texels(def, u32::from(id.0), Pattern::Flat)
            } else {
                texels(def, u32::from(id.0))
            };
            for (mip, level) in mip_chain(level0).iter().enumerate() {
                let side = TEXTURE_SIZE >> mip;
                ctx.queue.write_texture(
                    wgpu::TexelCopyTextureInfo {
                        texture: &texture,
                        mip_level: mip as u32,
                        origin: wgpu::Origin3d {
                            x: 0,
                            y: 0,
                            z: u32::from(id.0),
                        },
                        aspect: wgpu::TextureAspect::All,
                    },
                    &to_rgba8(level),
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
        Ok(Self { view, sampler })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use voxel_core::blocks;

    fn def(id: voxel_core::BlockId) -> BlockDef {
        BlockRegistry::default().get(id).unwrap().clone()
    }

    #[test]
    fn leaves_have_holes_and_solid_texels() {
        let t = texels(&def(blocks::LEAVES), 6);
        let holes = t.iter().filter(|t| t[3] == 0.0).count();
        assert!((40..130).contains(&holes), "{holes} holes of 256");
        assert!(t.iter().all(|t| t[3] == 0.0 || t[3] == 1.0));
    }

    #[test]
    fn glass_has_an_opaque_frame_and_a_translucent_centre() {
        let g = def(blocks::RED_GLASS);
        let t = texels(&g, 10);
        assert_eq!(t[0][3], 1.0);
        assert_eq!(t[15][3], 1.0);
        assert_eq!(t[8 * 16 + 8][3], g.opacity);
        let w = texels(&def(blocks::WATER), 7);
        assert!(
            w.iter().all(|t| t[3] == def(blocks::WATER).opacity),
            "water has no frame"
        );
    }

    #[test]
    fn mips_average_down_to_one_texel() {
        let chain = mip_chain(texels(&def(blocks::GLASS), 8));
        assert_eq!(chain.len(), MIP_LEVELS as usize);
        assert_eq!(chain.last().unwrap().len(), 1);
        let mean0: f32 = chain[0].iter().map(|t| t[3]).sum::<f32>() / 256.0;
        assert!((chain[4][0][3] - mean0).abs() < 1e-5);
    }

    #[test]
    fn srgb_round_trips() {
        for v in [0u8, 1, 10, 128, 200, 255] {
            assert_eq!(linear_to_srgb(srgb_to_linear(v)), v);
        }
    }
}
