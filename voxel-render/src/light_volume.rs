//! The light field around the eye on the GPU, for a game's content and its own shaders
//! (`docs/light.md`, "Light for a game's things"): two 3D textures over a region of up to
//! [`MAX_LIGHT_CHUNKS`] chunks an axis, the sky light and the block light of each cell
//! (RGB, as [`voxel_core::LightField`] holds them), each texel's alpha 1 where light enters
//! the cell and 0 where it does not (an opaque block, a chunk not read). The colour is
//! stored multiplied by that alpha, so that one filtered sample divided by its alpha is the
//! mean of the open cells around a point only: the smooth light the mesher gives the
//! world's faces, where a wall next to a point does not darken it.
//!
//! The shaders read it through [`light_wgsl`]'s `voxel_light` and `voxel_shade`, from the
//! bind group the renderer hands every game stage (`GameFrame::light`), of layout
//! `Renderer::light_layout`.

use std::sync::Arc;

use voxel_core::{BlockRegistry, CHUNK_SIZE, Chunk, ChunkPos, LightChunk, LightLayer, World};

use crate::error::{Error, Result};
use crate::sun::SunRegion;

/// The most chunks the light volume spans along an axis (128 blocks: 16 MiB for both
/// textures).
pub const MAX_LIGHT_CHUNKS: u32 = 4;

/// Where the light volume reads a chunk's light: [`voxel_core::LightField::shared`], or
/// a lit `ChunkStreamer`'s `light_chunk`.
pub type ChunkLight<'a> = &'a dyn Fn(ChunkPos) -> Option<Arc<LightChunk>>;

/// WGSL declaring the light volume's bindings at group `group` and the functions that read
/// it, for a game's shaders (the content stages use it at group 2). Positions are
/// camera-relative, as `GameFrame::view_proj` takes them:
///
/// - `voxel_light(p) -> VoxelLight`: the sky light and the block light at `p` (RGB, 0 to
///   1, linear), the mean of the open cells of the 2 × 2 × 2 around it; outside the
///   volume, without one, or where no cell around `p` is open: full sky light and no
///   block light, the light of a world drawn unlit.
/// - `voxel_shade(p, n) -> vec3<f32>`: what a surface of unit normal `n` at `p` is lit
///   with, the world's faces' shading without ambient occlusion: the sky's light (Lambert
///   with the sun plus ambient, times the brightness: day and night) times the sky light,
///   or the block light where brighter, per channel. A zero `n` is lit as a face turned to
///   the sky. Multiply a linear colour by it.
///
/// A surface samples best half a block in front of it (`p + n * 0.5`): in the cell its
/// face looks into, as the mesher samples the world's faces.
pub fn light_wgsl(group: u32) -> String {
    include_str!("shaders/light_volume.wgsl").replace("GROUP", &group.to_string())
}

/// The uniform the shaders read (`VoxelLightFrame` in `light_volume.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct LightUniforms {
    /// The region's first block, camera-relative.
    pub origin: [f32; 3],
    /// 1 with a volume, else 0.
    pub on: u32,
    /// The eye's place in the textures (the eye modulo the region's blocks), in blocks.
    pub eye_texel: [f32; 3],
    pub brightness: f32,
    /// The region's blocks along x, y and z.
    pub size: [f32; 3],
    pub ambient: f32,
    /// Unit direction toward the sun.
    pub sun_dir: [f32; 3],
    pub _pad: f32,
}

/// The lighting the uniform carries besides the volume: sun direction, ambient share,
/// brightness.
pub(crate) struct Lighting {
    pub sun_dir: [f32; 3],
    pub ambient: f32,
    pub brightness: f32,
}

/// The light volume on the GPU and its bind group.
#[derive(Debug)]
pub(crate) struct LightVolume {
    /// Per block id: light enters it (every class but opaque).
    open: Vec<bool>,
    sky: wgpu::Texture,
    block: wgpu::Texture,
    uniform: wgpu::Buffer,
    sampler: wgpu::Sampler,
    pub(crate) layout: wgpu::BindGroupLayout,
    pub(crate) group: wgpu::BindGroup,
    region: Option<SunRegion>,
}

impl LightVolume {
    /// No volume yet (1-texel placeholders: the group is always there to bind) for a
    /// renderer of `registry`.
    pub(crate) fn new(device: &wgpu::Device, registry: &BlockRegistry) -> Self {
        let texture = wgpu::BindGroupLayoutEntry {
            binding: 1,
            visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: true },
                view_dimension: wgpu::TextureViewDimension::D3,
                multisampled: false,
            },
            count: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("voxel_light_layout"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    ..texture
                },
                texture,
                wgpu::BindGroupLayoutEntry {
                    binding: 2,
                    ..texture
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 3,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    ..texture
                },
            ],
        });
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("voxel_light_frame"),
            size: std::mem::size_of::<LightUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        // Repeat: the volume is a torus, a cell's neighbour across the textures' edge is
        // the texel at the other end.
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("voxel_light"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            address_mode_w: wgpu::AddressMode::Repeat,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        let sky = Self::texture(device, "voxel_sky_light", [1; 3]);
        let block = Self::texture(device, "voxel_block_light", [1; 3]);
        let group = Self::group(device, &layout, &uniform, &sky, &block, &sampler);
        Self {
            open: open_table(registry),
            sky,
            block,
            uniform,
            sampler,
            layout,
            group,
            region: None,
        }
    }

    fn texture(device: &wgpu::Device, label: &str, size: [u32; 3]) -> wgpu::Texture {
        device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width: size[0],
                height: size[1],
                depth_or_array_layers: size[2],
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D3,
            format: wgpu::TextureFormat::Rgba8Unorm,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        })
    }

    fn group(
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        uniform: &wgpu::Buffer,
        sky: &wgpu::Texture,
        block: &wgpu::Texture,
        sampler: &wgpu::Sampler,
    ) -> wgpu::BindGroup {
        let sky = sky.create_view(&wgpu::TextureViewDescriptor::default());
        let block = block.create_view(&wgpu::TextureViewDescriptor::default());
        crate::gpu::bind_group(
            device,
            "voxel_light",
            layout,
            &[
                uniform.as_entire_binding(),
                wgpu::BindingResource::TextureView(&sky),
                wgpu::BindingResource::TextureView(&block),
                wgpu::BindingResource::Sampler(sampler),
            ],
        )
    }

    /// The textures and group for `size` texels.
    fn make(&mut self, device: &wgpu::Device, size: [u32; 3]) {
        self.sky = Self::texture(device, "voxel_sky_light", size);
        self.block = Self::texture(device, "voxel_block_light", size);
        self.group = Self::group(
            device,
            &self.layout,
            &self.uniform,
            &self.sky,
            &self.block,
            &self.sampler,
        );
    }

    /// The region covered, if any.
    pub(crate) fn region(&self) -> Option<SunRegion> {
        self.region
    }

    /// Covers `region` with the light of `world`'s chunks (new textures and group).
    pub(crate) fn set(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        world: &World,
        light: ChunkLight<'_>,
        region: SunRegion,
    ) -> Result<()> {
        if open_table(world.registry()) != self.open {
            return Err(Error::InvalidSetting(format!(
                "light volume: the world's registry ({} blocks) is not the renderer's ({})",
                world.registry().len(),
                self.open.len()
            )));
        }
        let largest = device.limits().max_texture_dimension_3d;
        let blocks = region.chunks.map(|c| c * CHUNK_SIZE as u32);
        if region
            .chunks
            .iter()
            .any(|&c| c == 0 || c > MAX_LIGHT_CHUNKS)
            || blocks.iter().any(|&b| b > largest)
            || !region.is_valid()
        {
            return Err(Error::InvalidSetting(format!(
                "light volume over {region:?}: 1 to {MAX_LIGHT_CHUNKS} chunks an axis, at \
                 most {largest} blocks (the adapter's largest 3D texture)"
            )));
        }
        self.make(device, blocks);
        self.region = Some(region);
        let all: Vec<ChunkPos> = region.positions().collect();
        self.update(queue, world, light, &all);
        Ok(())
    }

    /// Moves the region so that its x and z centre on chunk `centre`, its size and heights
    /// kept, and reads the chunks that come into it (the volume is a torus: the chunks that
    /// stay are not touched). Returns how many chunks were read.
    pub(crate) fn follow(
        &mut self,
        queue: &wgpu::Queue,
        world: &World,
        light: ChunkLight<'_>,
        centre: ChunkPos,
    ) -> usize {
        let Some(old) = self.region else { return 0 };
        let Some(new) = old.centred_on(centre) else {
            return 0;
        };
        self.region = Some(new);
        let entering: Vec<ChunkPos> = new.positions().filter(|&p| !old.contains(p)).collect();
        self.update(queue, world, light, &entering);
        entering.len()
    }

    /// Writes chunks `chunks` again (those the region holds): a chunk without blocks or
    /// without light is written closed (the shaders fall back to the unlit light there).
    pub(crate) fn update(
        &mut self,
        queue: &wgpu::Queue,
        world: &World,
        light: ChunkLight<'_>,
        chunks: &[ChunkPos],
    ) {
        let Some(region) = self.region else { return };
        let closed = Chunk::default();
        for &pos in chunks.iter().filter(|&&p| region.contains(p)) {
            let lit = light(pos);
            let (blocks, lit) = match (world.chunk(pos), lit.as_deref()) {
                (Some(chunk), Some(lit)) => (chunk, Some(lit)),
                _ => (&closed, None),
            };
            let [sky, block] = texels(blocks, lit, &self.open);
            let [sx, sy, sz] = region.slot(pos);
            for (texture, data) in [(&self.sky, &sky), (&self.block, &block)] {
                write_chunk(queue, texture, [sx, sy, sz], data);
            }
        }
    }

    /// Drops the volume.
    pub(crate) fn clear(&mut self, device: &wgpu::Device) {
        self.make(device, [1; 3]);
        self.region = None;
    }

    /// The uniform for an eye at `eye_int + eye_frac` under `lighting`: off without a
    /// volume or for an eye so far from it that its blocks are not exact in `f32`.
    pub(crate) fn uniforms(
        &self,
        eye_int: [i64; 3],
        eye_frac: [f32; 3],
        lighting: Lighting,
    ) -> LightUniforms {
        let mut u = LightUniforms {
            brightness: lighting.brightness,
            ambient: lighting.ambient,
            sun_dir: lighting.sun_dir,
            ..LightUniforms::default()
        };
        let Some(region) = self.region else { return u };
        let first = region.first_block();
        let size = region.chunks.map(|c| i64::from(c) * CHUNK_SIZE as i64);
        let origin: [i64; 3] = std::array::from_fn(|a| first[a] - eye_int[a]);
        if origin.iter().any(|o| o.abs() > 1 << 24) {
            return u;
        }
        u.on = 1;
        u.origin = std::array::from_fn(|a| origin[a] as f32 - eye_frac[a]);
        u.eye_texel = std::array::from_fn(|a| eye_int[a].rem_euclid(size[a]) as f32 + eye_frac[a]);
        u.size = size.map(|s| s as f32);
        u
    }

    /// The uniform buffer, written each frame.
    pub(crate) fn uniform(&self) -> &wgpu::Buffer {
        &self.uniform
    }
}

/// Per block id of `registry`: light enters it.
fn open_table(registry: &BlockRegistry) -> Vec<bool> {
    registry
        .iter()
        .map(|(_, def)| def.class != voxel_core::RenderClass::Opaque)
        .collect()
}

/// A chunk's sky and block texels, x fastest, then y, then z: RGBA, the light times the
/// openness, the openness in alpha (`lit` `None`: all closed).
fn texels(blocks: &Chunk, lit: Option<&LightChunk>, open: &[bool]) -> [Vec<u8>; 2] {
    let n = CHUNK_SIZE;
    let mut sky = vec![0u8; n * n * n * 4];
    let mut block = vec![0u8; n * n * n * 4];
    let Some(lit) = lit else {
        return [sky, block];
    };
    let dense = blocks.to_dense();
    for y in 0..n {
        let layer = lit.layer(y);
        for z in 0..n {
            for x in 0..n {
                let id = dense[Chunk::dense_index(x, y, z)];
                if !open.get(usize::from(id.0)).copied().unwrap_or(false) {
                    continue;
                }
                let l = match layer {
                    LightLayer::Uniform(l) => l,
                    LightLayer::Dense(cells) => cells[(x << 5) | z],
                };
                let t = 4 * (x + n * (y + n * z));
                sky[t..t + 4].copy_from_slice(&[l[0], l[1], l[2], 255]);
                block[t..t + 4].copy_from_slice(&[l[3], l[4], l[5], 255]);
            }
        }
    }
    [sky, block]
}

/// Writes one chunk's texels at chunk slot `slot` of `texture`.
fn write_chunk(queue: &wgpu::Queue, texture: &wgpu::Texture, slot: [u32; 3], data: &[u8]) {
    let s = CHUNK_SIZE as u32;
    queue.write_texture(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: wgpu::Origin3d {
                x: slot[0] * s,
                y: slot[1] * s,
                z: slot[2] * s,
            },
            aspect: wgpu::TextureAspect::All,
        },
        data,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(4 * s),
            rows_per_image: Some(s),
        },
        wgpu::Extent3d {
            width: s,
            height: s,
            depth_or_array_layers: s,
        },
    );
}

#[cfg(test)]
mod tests {
    use voxel_core::LightField;
    use voxel_core::blocks::STONE;
    use voxel_core::light_blocks::TORCH;

    use super::*;

    #[test]
    fn texels_hold_the_light_of_open_cells_and_close_opaque_ones() {
        let registry = Arc::new(BlockRegistry::with_lights());
        let mut world = World::new(registry.clone());
        let pos = ChunkPos::new(0, 0, 0);
        let mut chunk = Chunk::default();
        chunk.fill_box([0, 0, 0], [31, 3, 31], STONE).unwrap();
        chunk.set(3, 10, 5, TORCH).unwrap();
        world.insert_chunk(pos, chunk).unwrap();
        let field = LightField::new(&world);
        let open = open_table(&registry);
        let [sky, block] = texels(world.chunk(pos).unwrap(), field.chunk(pos), &open);
        let texel = |t: &[u8], x: usize, y: usize, z: usize| {
            let i = 4 * (x + 32 * (y + 32 * z));
            [t[i], t[i + 1], t[i + 2], t[i + 3]]
        };
        for (x, y, z) in [(3, 11, 5), (4, 10, 5), (20, 30, 7), (0, 4, 0)] {
            let l = field.chunk(pos).unwrap().get(x, y, z).unwrap();
            let [r, g, b] = l.sky;
            assert_eq!(texel(&sky, x, y, z), [r, g, b, 255], "sky at {x} {y} {z}");
            let [r, g, b] = l.block;
            assert_eq!(
                texel(&block, x, y, z),
                [r, g, b, 255],
                "block at {x} {y} {z}"
            );
        }
        // Next to the torch: its light, warm.
        let near = texel(&block, 4, 10, 5);
        assert!(near[0] > 150 && near[0] >= near[2], "{near:?}");
        // Stone is closed.
        assert_eq!(texel(&sky, 7, 2, 7), [0; 4]);
        assert_eq!(texel(&block, 7, 2, 7), [0; 4]);
        // No light: all closed.
        let [sky, _] = texels(world.chunk(pos).unwrap(), None, &open);
        assert!(sky.iter().all(|&b| b == 0));
    }
}
