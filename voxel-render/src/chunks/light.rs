//! The light of lit chunks on the GPU (issue 51): each quad's [`QuadLight`] in the arena's
//! light page at the quad's own index ([`crate::arena::QuadArena::enable_light`]; a storage
//! buffer, or with [`QuadFetch::Instanced`] a second instance attribute), and each chunk's
//! palette of corner lights here, at a base its record holds (`ChunkInfo::light_base` in
//! `common.wgsl`): one storage buffer, or with [`QuadFetch::Instanced`] a table texture
//! (WebGL2's vertex stage reads no storage buffer).

use std::collections::HashMap;

use voxel_mesh::{PackedLight, PackedQuad, QuadLight};

use crate::arena::{Allocator, QUAD_BYTES};
use crate::error::scoped;
use crate::fetch::{TABLE_WIDTH, TableTexture};
use crate::{Error, GpuContext, QuadFetch, Result};

/// Entries of the palette buffer at first (32 KiB): some 30 a chunk on open terrain.
const FIRST_ENTRIES: u32 = 4096;

/// Every lit chunk's palette (8 bytes an entry, `vec2<u32>` in WGSL), with a copy on the
/// CPU that a larger buffer or table is filled from.
#[derive(Debug)]
pub(crate) struct Palettes {
    store: Store,
    alloc: Allocator,
    data: Vec<PackedLight>,
    /// The most entries the device binds, and the limit that sets it.
    max_entries: u32,
    limit_name: &'static str,
}

/// Where the palettes lie on the GPU.
#[derive(Debug)]
pub(crate) enum Store {
    /// A storage buffer ([`QuadFetch::Storage`]).
    Buffer(wgpu::Buffer),
    /// A table texture of `Rg32Uint` texels ([`QuadFetch::Instanced`]).
    Table(TableTexture),
}

impl Palettes {
    /// Room for [`FIRST_ENTRIES`], as `fetch` reads them.
    pub(crate) fn new(ctx: &GpuContext, fetch: QuadFetch) -> Self {
        let l = &ctx.caps.limits;
        let (max, limit_name) = match fetch {
            QuadFetch::Storage => (
                l.max_storage_buffer_binding_size / QUAD_BYTES,
                "max_storage_buffer_binding_size (in 8-byte entries)",
            ),
            QuadFetch::Instanced => (
                u64::from(TABLE_WIDTH) * u64::from(l.max_texture_dimension_2d),
                "256 × max_texture_dimension_2d (entries of the palette table)",
            ),
        };
        let max_entries = max.min(u64::from(u32::MAX)) as u32;
        let first = FIRST_ENTRIES.min(max_entries.max(1));
        Self {
            store: Self::make(&ctx.device, fetch, first),
            alloc: Allocator::new(first),
            data: vec![PackedLight::default(); first as usize],
            max_entries,
            limit_name,
        }
    }

    fn make(device: &wgpu::Device, fetch: QuadFetch, entries: u32) -> Store {
        match fetch {
            QuadFetch::Storage => Store::Buffer(device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("light_palettes"),
                size: u64::from(entries.max(1)) * QUAD_BYTES,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })),
            QuadFetch::Instanced => Store::Table(TableTexture::new(
                device,
                "light_palettes",
                wgpu::TextureFormat::Rg32Uint,
                entries as usize,
            )),
        }
    }

    fn fetch(&self) -> QuadFetch {
        match self.store {
            Store::Buffer(_) => QuadFetch::Storage,
            Store::Table(_) => QuadFetch::Instanced,
        }
    }

    /// Where they lie (bound in group 1).
    pub(crate) fn store(&self) -> &Store {
        &self.store
    }

    /// Bytes held.
    pub(crate) fn bytes(&self) -> u64 {
        self.alloc.capacity() as u64 * QUAD_BYTES
    }

    /// Writes entries `first..` from the CPU copy, `n` of them.
    fn upload(&self, queue: &wgpu::Queue, first: usize, n: usize) {
        let bytes = bytemuck::cast_slice(&self.data[first..first + n]);
        match &self.store {
            Store::Buffer(b) => queue.write_buffer(b, first as u64 * QUAD_BYTES, bytes),
            Store::Table(t) => t.write(queue, first, bytes),
        }
    }

    /// Places `palette` and writes it (at the next submit); returns where it lies (base and
    /// entries, what [`Palettes::free`] takes) and whether the store was replaced by a
    /// larger one (bind groups over it must be remade). An error when the device's binding
    /// cannot hold it or the device cannot make the store; nothing changed then.
    pub(crate) fn alloc(
        &mut self,
        ctx: &GpuContext,
        palette: &[PackedLight],
    ) -> Result<((u32, u32), bool)> {
        let n = u32::try_from(palette.len().max(1)).unwrap_or(u32::MAX);
        let mut grew = false;
        let base = match self.alloc.alloc(n) {
            Some(b) => b,
            None => {
                let cap = self.alloc.capacity();
                let want = cap.saturating_mul(2).max(cap.saturating_add(n));
                if u64::from(self.alloc.used()) + u64::from(n) > u64::from(self.max_entries) {
                    return Err(Error::TooLarge {
                        what: "the light palettes of the chunks, in 8-byte entries,".into(),
                        value: u64::from(self.alloc.used()) + u64::from(n),
                        limit_name: self.limit_name,
                        limit: u64::from(self.max_entries),
                    });
                }
                let size = want.min(self.max_entries);
                let store = scoped(&ctx.device, "growing the light palettes", || {
                    Self::make(&ctx.device, self.fetch(), size)
                })?;
                self.alloc.grow(size);
                self.data.resize(size as usize, PackedLight::default());
                self.store = store;
                grew = true;
                self.alloc
                    .alloc(n)
                    .ok_or_else(|| Error::Unsupported("the light palettes found no room".into()))?
            }
        };
        let b = base as usize;
        self.data[b..b + palette.len()].copy_from_slice(palette);
        if grew {
            // A new buffer: all of it, from the CPU copy.
            self.upload(&ctx.queue, 0, self.data.len());
        } else {
            self.upload(&ctx.queue, b, palette.len());
        }
        Ok(((base, n), grew))
    }

    /// Gives back a palette placed at `base` of `len` entries.
    pub(crate) fn free(&mut self, base: u32, len: u32) {
        self.alloc.free(base, len);
    }
}

/// Where a lit chunk's palette lies, and the light of its translucent quads by quad, which a
/// new order of those quads takes its light stream from.
#[derive(Debug, Default)]
pub(crate) struct ChunkLight {
    /// Base and length in [`Palettes`].
    pub palette: (u32, u32),
    /// The light of each translucent quad.
    pub translucent: HashMap<PackedQuad, QuadLight>,
}

impl ChunkLight {
    /// The light stream of translucent quads `quads` (a permutation of the chunk's).
    pub(crate) fn translucent_stream(&self, quads: &[PackedQuad]) -> Vec<QuadLight> {
        quads
            .iter()
            .map(|q| self.translucent.get(q).copied().unwrap_or_default())
            .collect()
    }
}
