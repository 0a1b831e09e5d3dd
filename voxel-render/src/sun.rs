//! Sun shadows: the sun's light dimmed and tinted by the blocks along the ray toward the sun,
//! per fragment, by a voxel march in the shaders (`sun_transmittance` in `common.wgsl`)
//! through a volume of the world's cells around a point the game chooses
//! (`Renderer::set_sun_shadows`). Each cell of the volume is a byte: 0 air,
//! [`SUN_STOP`] a block that stops the sun (opaque and cutout blocks), else the class of a
//! translucent block, whose two filters (entered from another kind, from its own) are
//! [`voxel_core::SunFilters`]'s: the light field's filters, the colours that tint the view.
//! The CPU twin is [`voxel_core::SunMarch`].

use std::collections::HashMap;

use voxel_core::{BlockRegistry, CHUNK_SIZE, Chunk, ChunkPos, SunFilters, World, WorldPos};

use crate::error::{Error, Result};

/// The class of a cell that stops the sun.
pub(crate) const SUN_STOP: u8 = 255;
/// The most chunks the volume spans along an axis (256 blocks: WebGL2's largest 3D texture;
/// the frame's uniforms keep a top per tile, 32 × 32).
pub const MAX_SUN_CHUNKS: u32 = 8;
/// Steps a march takes at most (a ray crosses at most 3 × 256 cells of the volume).
pub(crate) const MAX_SUN_STEPS: u32 = 1024;
/// Columns of blocks a tile spans along x and z: per tile the volume keeps its highest cell
/// that is not air, and a ray above it crosses the rest of the tile in one step.
pub(crate) const SUN_TILE: u32 = 8;
/// Tiles a chunk spans along x and z.
const TILES: usize = CHUNK_SIZE / SUN_TILE as usize;
/// Tiles the volume spans along x and z at most.
const MAX_TILES: usize = MAX_SUN_CHUNKS as usize * TILES;
/// How far along its face's normal a fragment's march starts (blocks): inside the cell in
/// front of the face.
pub const SUN_NUDGE: f32 = 1e-3;

/// The chunks a renderer's sun shadows, or its light volume, cover: `chunks` along x, y
/// and z from `min`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SunRegion {
    /// The first chunk.
    pub min: ChunkPos,
    /// How many chunks along x, y and z (1 to [`MAX_SUN_CHUNKS`]).
    pub chunks: [u32; 3],
}

impl SunRegion {
    /// The loaded chunks of `world`, or the [`MAX_SUN_CHUNKS`] along each axis nearest
    /// `around` where they span more; `None` for a world with no chunk.
    pub fn around(world: &World, around: WorldPos) -> Option<Self> {
        Self::around_at_most(world, around, MAX_SUN_CHUNKS)
    }

    /// The loaded chunks of `world`, or the `max` along each axis nearest `around` where
    /// they span more (a light volume's: `MAX_LIGHT_CHUNKS`); `None` for a world with no
    /// chunk.
    pub fn around_at_most(world: &World, around: WorldPos, max: u32) -> Option<Self> {
        let (lo, hi) = world.chunk_bounds()?;
        let (lo, hi) = ([lo.x, lo.y, lo.z], [hi.x, hi.y, hi.z]);
        let (centre, _) = around.split();
        let centre = [centre.x, centre.y, centre.z];
        let max = max.clamp(1, 1 << 16) as i32;
        let mut min = [0; 3];
        let mut chunks = [0; 3];
        for a in 0..3 {
            let span = hi[a] - lo[a] + 1;
            if span <= max {
                min[a] = lo[a];
                chunks[a] = span as u32;
            } else {
                min[a] = (centre[a] - max / 2).clamp(lo[a], hi[a] - max + 1);
                chunks[a] = max as u32;
            }
        }
        Some(Self {
            min: ChunkPos::new(min[0], min[1], min[2]),
            chunks,
        })
    }

    /// Whether chunk `pos` lies in the region.
    pub fn contains(&self, pos: ChunkPos) -> bool {
        self.local(pos).is_some()
    }

    /// The region's first block.
    pub fn first_block(&self) -> [i64; 3] {
        self.min.origin()
    }

    /// `pos`'s chunk coordinates in the region.
    fn local(&self, pos: ChunkPos) -> Option<[u32; 3]> {
        let d = [
            i64::from(pos.x) - i64::from(self.min.x),
            i64::from(pos.y) - i64::from(self.min.y),
            i64::from(pos.z) - i64::from(self.min.z),
        ];
        (0..3)
            .all(|a| (0..i64::from(self.chunks[a])).contains(&d[a]))
            .then(|| d.map(|v| v as u32))
    }

    fn blocks(&self) -> [u32; 3] {
        self.chunks.map(|c| c * CHUNK_SIZE as u32)
    }

    /// The last chunk.
    fn max(&self) -> ChunkPos {
        let last = |m: i32, n: u32| m.saturating_add(n as i32 - 1);
        ChunkPos::new(
            last(self.min.x, self.chunks[0]),
            last(self.min.y, self.chunks[1]),
            last(self.min.z, self.chunks[2]),
        )
    }

    /// Every chunk of the region.
    pub fn positions(self) -> impl Iterator<Item = ChunkPos> {
        let [cx, cy, cz] = self.chunks.map(|c| c as i32);
        (0..cz).flat_map(move |z| {
            (0..cy).flat_map(move |y| {
                (0..cx).map(move |x| ChunkPos::new(self.min.x + x, self.min.y + y, self.min.z + z))
            })
        })
    }

    /// Whether its first and last chunks lie in the `i32` world.
    pub(crate) fn is_valid(&self) -> bool {
        self.min.is_valid() && self.max().is_valid()
    }

    /// The region moved so that its x and z centre on chunk `centre`, its size and heights
    /// kept; `None` where it does not move, or would leave the `i32` world.
    pub(crate) fn centred_on(&self, centre: ChunkPos) -> Option<Self> {
        let half = |n: u32| (n / 2) as i32;
        let min = ChunkPos::new(
            centre.x.saturating_sub(half(self.chunks[0])),
            self.min.y,
            centre.z.saturating_sub(half(self.chunks[2])),
        );
        let new = Self { min, ..*self };
        (new != *self && new.is_valid()).then_some(new)
    }

    /// Where chunk `pos`'s cells lie in the torus, in chunks.
    pub(crate) fn slot(&self, pos: ChunkPos) -> [u32; 3] {
        let p = [pos.x, pos.y, pos.z];
        std::array::from_fn(|a| p[a].rem_euclid(self.chunks[a] as i32) as u32)
    }
}

/// The shadow volume on the GPU and what the shaders need to read it.
#[derive(Debug)]
pub(crate) struct SunVolume {
    /// Per block id its class.
    classes: Vec<u8>,
    /// The filters of classes 1.. in order, two per class: what the media table appends.
    filters: Vec<[f32; 4]>,
    texture: wgpu::Texture,
    pub(crate) view: wgpu::TextureView,
    region: Option<SunRegion>,
    /// Per chunk of the region, per tile of it (x + 4 z): its highest cell holding anything
    /// but air (the chunk's y), -1 for none.
    tops: HashMap<ChunkPos, [i32; TILES * TILES]>,
    /// `tops` per tile of the region as the frame's uniforms hold them
    /// ([`SunVolume::gather_tops`], after each change: not every frame).
    tiles: SunTops,
}

impl SunVolume {
    /// No volume yet (a 1-block placeholder) for a renderer of `registry`.
    pub(crate) fn new(device: &wgpu::Device, registry: &BlockRegistry) -> Self {
        let (classes, filters) = classes(&SunFilters::new(registry));
        let texture = Self::texture(device, [1; 3]);
        Self {
            classes,
            filters,
            view: texture.create_view(&wgpu::TextureViewDescriptor::default()),
            texture,
            region: None,
            tops: HashMap::new(),
            tiles: NO_TOPS,
        }
    }

    fn texture(device: &wgpu::Device, size: [u32; 3]) -> wgpu::Texture {
        device.create_texture(&wgpu::TextureDescriptor {
            label: Some("sun_cells"),
            size: wgpu::Extent3d {
                width: size[0],
                height: size[1],
                depth_or_array_layers: size[2],
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D3,
            format: wgpu::TextureFormat::R8Uint,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        })
    }

    /// The filters the media table holds after the looks.
    pub(crate) fn filters(&self) -> &[[f32; 4]] {
        &self.filters
    }

    /// The region covered, if any.
    pub(crate) fn region(&self) -> Option<SunRegion> {
        self.region
    }

    /// Covers `region` with `world`'s cells (a new texture: the scene groups must be made
    /// again).
    pub(crate) fn set(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        world: &World,
        region: SunRegion,
    ) -> Result<()> {
        let (world_classes, world_filters) = classes(&SunFilters::new(world.registry()));
        if world_classes != self.classes || world_filters != self.filters {
            return Err(Error::InvalidSetting(format!(
                "sun shadows: the world's registry ({} blocks) is not the renderer's ({}): \
                 its blocks cross the sun otherwise",
                world.registry().len(),
                self.classes.len()
            )));
        }
        let largest = device.limits().max_texture_dimension_3d;
        if region.chunks.iter().any(|&c| c == 0 || c > MAX_SUN_CHUNKS)
            || region.blocks().iter().any(|&b| b > largest)
            || !region.is_valid()
        {
            return Err(Error::InvalidSetting(format!(
                "sun shadows over {region:?}: 1 to {MAX_SUN_CHUNKS} chunks an axis, at most \
                 {largest} blocks (the adapter's largest 3D texture)"
            )));
        }
        self.texture = Self::texture(device, region.blocks());
        self.view = self
            .texture
            .create_view(&wgpu::TextureViewDescriptor::default());
        self.region = Some(region);
        self.tops.clear();
        for pos in region.positions() {
            if let Some(chunk) = world.chunk(pos) {
                self.write(queue, pos, chunk);
            }
        }
        self.gather_tops();
        Ok(())
    }

    /// Moves the region so that its x and z centre on chunk `centre`, its size and heights
    /// kept, and reads the chunks that come into it from `world` (air where not loaded):
    /// the volume is a torus (a chunk's cells lie at its position modulo the size), so the
    /// chunks that stay are not touched. Returns how many chunks were read.
    pub(crate) fn follow(&mut self, queue: &wgpu::Queue, world: &World, centre: ChunkPos) -> usize {
        let Some(old) = self.region else { return 0 };
        let Some(new) = old.centred_on(centre) else {
            return 0;
        };
        self.region = Some(new);
        self.tops.retain(|&pos, _| new.contains(pos));
        let entering: Vec<ChunkPos> = new.positions().filter(|&p| !old.contains(p)).collect();
        self.update(queue, world, &entering);
        entering.len()
    }

    /// Writes chunks `chunks` again from `world` (air where not loaded), those the region
    /// holds.
    pub(crate) fn update(&mut self, queue: &wgpu::Queue, world: &World, chunks: &[ChunkPos]) {
        let Some(region) = self.region else { return };
        for &pos in chunks.iter().filter(|&&p| region.contains(p)) {
            match world.chunk(pos) {
                Some(chunk) => self.write(queue, pos, chunk),
                None => self.write(queue, pos, &Chunk::default()),
            }
        }
        self.gather_tops();
    }

    /// Drops the volume.
    pub(crate) fn clear(&mut self, device: &wgpu::Device) {
        self.texture = Self::texture(device, [1; 3]);
        self.view = self
            .texture
            .create_view(&wgpu::TextureViewDescriptor::default());
        self.region = None;
        self.tops.clear();
        self.tiles = NO_TOPS;
    }

    fn write(&mut self, queue: &wgpu::Queue, pos: ChunkPos, chunk: &Chunk) {
        let Some(region) = self.region else { return };
        if !region.contains(pos) {
            return;
        }
        let (cells, tops) = cells(chunk, &self.classes);
        self.tops
            .insert(pos, tops.map(|t| t.map_or(-1, |t| t as i32)));
        // The chunk's slot in the torus.
        let [sx, sy, sz] = region.slot(pos);
        let s = CHUNK_SIZE as u32;
        queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &self.texture,
                mip_level: 0,
                origin: wgpu::Origin3d {
                    x: sx * s,
                    y: sy * s,
                    z: sz * s,
                },
                aspect: wgpu::TextureAspect::All,
            },
            &cells,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(s),
                rows_per_image: Some(s),
            },
            wgpu::Extent3d {
                width: s,
                height: s,
                depth_or_array_layers: s,
            },
        );
    }

    /// `tiles` from `tops`: per tile of the region (x + 32 z from its first block) the
    /// highest top of its chunks' tiles, in volume y.
    fn gather_tops(&mut self) {
        self.tiles = NO_TOPS;
        let Some(region) = self.region else { return };
        for (&pos, chunk_tops) in &self.tops {
            let Some([x, y, z]) = region.local(pos) else {
                continue;
            };
            let [x, y, z] = [x, y, z].map(|v| v as usize);
            for (t, &top) in chunk_tops.iter().enumerate() {
                let i = x * TILES + t % TILES + MAX_TILES * (z * TILES + t / TILES);
                let top = if top < 0 {
                    -1
                } else {
                    (y * CHUNK_SIZE) as i32 + top
                };
                self.tiles[i / 4][i % 4] = self.tiles[i / 4][i % 4].max(top);
            }
        }
    }

    /// The frame uniforms' sun fields for an eye whose integer part is `eye_int`; all zero
    /// without a volume or for an eye so far from it that its blocks are not exact in
    /// `f32`.
    pub(crate) fn uniforms(&self, eye_int: [i64; 3]) -> SunUniforms {
        let none = SunUniforms {
            offset: [0; 3],
            on: 0,
            size: [0; 3],
            wrap: [0; 3],
            tops: NO_TOPS,
        };
        let Some(region) = self.region else {
            return none;
        };
        let first = region.first_block();
        let offset: [i64; 3] = std::array::from_fn(|a| eye_int[a] - first[a]);
        const EXACT: i64 = 1 << 24;
        if offset.iter().any(|o| o.abs() >= EXACT) {
            return none;
        }
        let size = region.blocks();
        SunUniforms {
            offset: offset.map(|o| o as i32),
            on: 1,
            size,
            wrap: std::array::from_fn(|a| first[a].rem_euclid(i64::from(size[a])) as u32),
            tops: self.tiles,
        }
    }
}

/// Per block id its class, and the filters of classes 1.. (two each).
fn classes(sun: &SunFilters) -> (Vec<u8>, Vec<[f32; 4]>) {
    let mut classes = Vec::with_capacity(sun.cells().len());
    let mut filters = Vec::new();
    let mut full = false;
    for cell in sun.cells() {
        classes.push(match cell {
            None => SUN_STOP,
            Some(c) if c.kind == 0 => 0,
            Some(c) => {
                let class = filters.len() / 2 + 1;
                if class >= usize::from(SUN_STOP) {
                    full = true;
                    SUN_STOP
                } else {
                    let [r, g, b] = c.enter;
                    filters.push([r, g, b, 0.0]);
                    let [r, g, b] = c.within;
                    filters.push([r, g, b, 0.0]);
                    class as u8
                }
            }
        });
    }
    if full {
        log::warn!(
            "sun shadows: more than {} translucent block types; the rest stop the sun",
            SUN_STOP - 1
        );
    }
    (classes, filters)
}

/// The tops of every tile of the volume, four to a vector (`sun_tops` in `frame.wgsl`).
pub(crate) type SunTops = [[i32; 4]; MAX_TILES * MAX_TILES / 4];

/// No tile holds anything.
const NO_TOPS: SunTops = [[-1; 4]; MAX_TILES * MAX_TILES / 4];

/// The frame uniforms' sun fields (`FrameUniforms` in `bindings.rs`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct SunUniforms {
    /// The eye's integer part minus the region's first block.
    pub(crate) offset: [i32; 3],
    /// 1 with a volume.
    pub(crate) on: u32,
    /// The region's size in blocks.
    pub(crate) size: [u32; 3],
    /// Where the region's first block lies in the torus.
    pub(crate) wrap: [u32; 3],
    /// Per tile of the region (x + 32 z, from its first block), its top.
    pub(crate) tops: SunTops,
}

/// A chunk's cells as the volume holds them (x fastest, then y, then z), and per tile of its
/// columns (x + 4 z) its highest cell holding anything but air (local y).
fn cells(chunk: &Chunk, classes: &[u8]) -> (Vec<u8>, [Option<usize>; TILES * TILES]) {
    let s = CHUNK_SIZE;
    let class =
        |id: voxel_core::BlockId| classes.get(usize::from(id.0)).copied().unwrap_or(SUN_STOP);
    if let Some(id) = chunk.as_uniform() {
        let c = class(id);
        return (
            vec![c; s * s * s],
            [(c != 0).then_some(s - 1); TILES * TILES],
        );
    }
    let dense = chunk.to_dense();
    let mut out = vec![0u8; s * s * s];
    let mut tops = [None; TILES * TILES];
    let tile = SUN_TILE as usize;
    for x in 0..s {
        for z in 0..s {
            for y in 0..s {
                let c = class(dense[Chunk::dense_index(x, y, z)]);
                if c != 0 {
                    out[x + s * (y + s * z)] = c;
                    let t = &mut tops[x / tile + TILES * (z / tile)];
                    *t = (*t).max(Some(y));
                }
            }
        }
    }
    (out, tops)
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use voxel_core::blocks;

    use super::*;

    #[test]
    fn a_region_covers_a_small_world_and_the_nearest_chunks_of_a_large_one() {
        let mut w = World::new(Arc::new(BlockRegistry::default()));
        assert_eq!(SunRegion::around(&w, WorldPos::new(0, 0, 0)), None);
        w.set_block(WorldPos::new(-40, 0, 5), blocks::STONE)
            .unwrap();
        w.set_block(WorldPos::new(40, 70, 5), blocks::STONE)
            .unwrap();
        let r = SunRegion::around(&w, WorldPos::new(0, 0, 0)).unwrap();
        assert_eq!(r.min, ChunkPos::new(-2, 0, 0));
        assert_eq!(r.chunks, [4, 3, 1]);
        w.set_block(WorldPos::new(32 * 20, 0, 5), blocks::STONE)
            .unwrap();
        let r = SunRegion::around(&w, WorldPos::new(32 * 19, 0, 0)).unwrap();
        assert_eq!((r.min.x, r.chunks[0]), (13, 8));
        let r = SunRegion::around(&w, WorldPos::new(-1000, 0, 0)).unwrap();
        assert_eq!((r.min.x, r.chunks[0]), (-2, 8));
        assert!(r.contains(ChunkPos::new(5, 1, 0)) && !r.contains(ChunkPos::new(6, 1, 0)));
    }

    #[test]
    fn cells_hold_the_classes_in_texture_order() {
        let r = BlockRegistry::default();
        let (classes, filters) = classes(&SunFilters::new(&r));
        let water_class = classes[usize::from(blocks::WATER.0)];
        let water = SunFilters::new(&r).get(blocks::WATER).unwrap();
        let at = 2 * (usize::from(water_class) - 1);
        assert_eq!(filters[at][..3], water.enter);
        assert_eq!(filters[at + 1][..3], water.within);
        let mut chunk = Chunk::default();
        chunk.set(3, 7, 9, blocks::STONE).unwrap();
        chunk.set(4, 8, 9, blocks::WATER).unwrap();
        let (cells, tops) = cells(&chunk, &classes);
        assert_eq!(cells[3 + 32 * (7 + 32 * 9)], SUN_STOP);
        let water = cells[4 + 32 * (8 + 32 * 9)];
        assert!(water != 0 && water != SUN_STOP);
        assert_eq!(cells.iter().filter(|&&c| c != 0).count(), 2);
        // Tile (0, 1) holds both blocks (x 3 and 4, z 9), the others nothing.
        assert_eq!(tops[TILES], Some(8));
        assert_eq!(tops.iter().flatten().count(), 1);
        // Leaves stop the sun as they stop the sky's beam.
        assert_eq!(classes[usize::from(blocks::LEAVES.0)], SUN_STOP);
        assert_eq!(classes[usize::from(blocks::AIR.0)], 0);
    }
}
