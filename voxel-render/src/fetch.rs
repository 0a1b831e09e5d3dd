//! How the chunk pipelines' vertex shader gets the quads and their lookup tables (each
//! chunk's record, each block's texture layers): pulled from storage buffers by vertex
//! index, or, on devices whose vertex stage has no storage buffers (WebGL2, many GLES 3.1
//! phones), each quad an instance's vertex attribute (the same 8 bytes), the chunk's record
//! a uniform bound for its draw and the block layers an integer texture read with
//! `textureLoad`, which every device allows in vertex shaders. `shaders/common.wgsl` has
//! both kinds of entry point; [`QuadFetch`] picks one.

use crate::context::Capabilities;
use crate::ladder::{self, Limit, Need};
use crate::submission::Upload;
use crate::{Error, Result};

/// How quads reach the vertex shader.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum QuadFetch {
    /// Vertex pulling: a draw's vertices are its quads' corners (6 a quad), the quad read
    /// from the arena's page (a storage buffer) at `vertex_index / 6`, the chunk record
    /// from a storage buffer at the instance index (the chunk's slot), the block's layers
    /// from a storage buffer.
    #[default]
    Storage,
    /// Instancing: a draw's instances are its quads, read as a vertex attribute from the
    /// page (a vertex buffer), 6 vertices each; the chunk's record a uniform bound for the
    /// draw (one draw per mesh), the block's layers from a texture.
    Instanced,
}

/// Entries of a lookup table per texture row ([`TableTexture`]): 256, so that 65 536
/// blocks' three layers fit in 768 rows, within WebGL2's 2 048.
pub(crate) const TABLE_WIDTH: u32 = 256;

/// Storage buffers the vertex stage binds with [`QuadFetch::Storage`]: the page, the chunk
/// records, the block layers, the page's light and the light palettes.
const VERTEX_STORAGE_BUFFERS: u64 = 5;

/// Textures the vertex stage binds with [`QuadFetch::Instanced`]: the block layers and the
/// light palettes.
const VERTEX_TEXTURES: u64 = 2;

impl QuadFetch {
    /// Both, the faster first (on lavapipe, `cargo bench -p voxel-lab --bench quad_fetch`):
    /// the order [`QuadFetch::choose`] tries them in.
    pub const ALL: [QuadFetch; 2] = [QuadFetch::Storage, QuadFetch::Instanced];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            QuadFetch::Storage => "storage",
            QuadFetch::Instanced => "instanced",
        }
    }

    /// What the world's chunk pipelines need of the device when they fetch quads this way.
    pub(crate) fn needs(self) -> Vec<Need> {
        match self {
            QuadFetch::Storage => vec![
                Need::Downlevel(wgpu::DownlevelFlags::VERTEX_STORAGE),
                Need::Limit(Limit::StorageBuffersPerStage, VERTEX_STORAGE_BUFFERS),
                // A page holds a quad; a mesh larger than a page is refused at its upload
                // (`Error::TooLarge`), not the whole world.
                Need::Limit(Limit::StorageBufferBindingSize, QUAD_BYTES),
            ],
            QuadFetch::Instanced => vec![
                // The page's quads and their light (`chunks/light.rs`).
                Need::Limit(Limit::VertexBuffers, 2),
                Need::Limit(Limit::VertexAttributes, 2),
                Need::Limit(Limit::VertexBufferArrayStride, QUAD_BYTES),
                Need::Limit(Limit::SampledTexturesPerStage, VERTEX_TEXTURES),
                Need::Limit(Limit::DynamicUniformBuffers, 1),
            ],
        }
    }

    /// The way to fetch quads on the device of `caps`: `wanted` when given (an error
    /// naming what the device lacks for it if it cannot), else the first of
    /// [`QuadFetch::ALL`] it can.
    pub fn choose(caps: &Capabilities, wanted: Option<QuadFetch>) -> Result<QuadFetch> {
        if let Some(fetch) = wanted {
            ladder::check(
                &format!("drawing the world with {} quad fetch", fetch.name()),
                &fetch.needs(),
                caps,
            )?;
            return Ok(fetch);
        }
        if let Some(fetch) = Self::ALL
            .into_iter()
            .find(|f| ladder::missing(&f.needs(), caps).is_none())
        {
            return Ok(fetch);
        }
        let why: Vec<String> = Self::ALL
            .into_iter()
            .filter_map(|f| {
                Some(format!(
                    "{}: {}",
                    f.name(),
                    ladder::missing(&f.needs(), caps)?
                ))
            })
            .collect();
        Err(Error::Unsupported(format!(
            "drawing the world: {} lacks what every way of fetching quads needs ({})",
            caps.adapter_name,
            why.join("; ")
        )))
    }

    /// The vertex entry point of chunk pipelines: `vs_main` (translucent and cutout quads)
    /// or, `solid`, `vs_solid` (opaque quads, grown against cracks), of this fetch.
    pub(crate) fn vertex_entry(self, solid: bool) -> &'static str {
        match (self, solid) {
            (QuadFetch::Storage, false) => "vs_main",
            (QuadFetch::Storage, true) => "vs_solid",
            (QuadFetch::Instanced, false) => "vs_main_instanced",
            (QuadFetch::Instanced, true) => "vs_solid_instanced",
        }
    }

    /// The vertex buffers of chunk pipelines: none, or the page as one 8-byte attribute
    /// per instance and its light page as another.
    pub(crate) fn vertex_buffers(self) -> &'static [Option<wgpu::VertexBufferLayout<'static>>] {
        match self {
            QuadFetch::Storage => &[],
            QuadFetch::Instanced => &[Some(QUAD_INSTANCES), Some(LIGHT_INSTANCES)],
        }
    }

    /// The usages of the arena's pages.
    pub(crate) fn page_usage(self) -> wgpu::BufferUsages {
        let copies = wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC;
        match self {
            QuadFetch::Storage => wgpu::BufferUsages::STORAGE | copies,
            QuadFetch::Instanced => wgpu::BufferUsages::VERTEX | copies,
        }
    }

    /// The largest page in bytes on a device of `limits`: a storage binding, or any
    /// buffer.
    pub(crate) fn max_page_bytes(self, limits: &wgpu::Limits) -> u64 {
        match self {
            QuadFetch::Storage => limits
                .max_storage_buffer_binding_size
                .min(limits.max_buffer_size),
            QuadFetch::Instanced => limits.max_buffer_size,
        }
    }

    /// The draw of quads `quads` (first and count, in the page) of the chunk in `slot`:
    /// vertices and instances (with [`QuadFetch::Instanced`], the record is bound for
    /// the draw instead).
    pub(crate) fn draw_ranges(
        self,
        slot: u32,
        first: u32,
        count: u32,
    ) -> (std::ops::Range<u32>, std::ops::Range<u32>) {
        match self {
            QuadFetch::Storage => (6 * first..6 * (first + count), slot..slot + 1),
            QuadFetch::Instanced => (0..6, first..first + count),
        }
    }

    /// Whether chunks can be drawn with `multi_draw_indirect`: not with
    /// [`QuadFetch::Instanced`], whose draws each bind their chunk's record.
    pub(crate) fn indirect(self) -> bool {
        self == QuadFetch::Storage
    }
}

/// Bytes of one quad.
const QUAD_BYTES: u64 = std::mem::size_of::<voxel_mesh::PackedQuad>() as u64;

/// One `vec2<u32>` per instance at location 0: a page read as instanced quads.
const QUAD_INSTANCES: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: QUAD_BYTES,
    step_mode: wgpu::VertexStepMode::Instance,
    attributes: &[wgpu::VertexAttribute {
        format: wgpu::VertexFormat::Uint32x2,
        offset: 0,
        shader_location: 0,
    }],
};

/// One `vec2<u32>` per instance at location 1: the light page beside the page, each quad's
/// corner light (`voxel_mesh::QuadLight`).
const LIGHT_INSTANCES: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: QUAD_BYTES,
    step_mode: wgpu::VertexStepMode::Instance,
    attributes: &[wgpu::VertexAttribute {
        format: wgpu::VertexFormat::Uint32x2,
        offset: 0,
        shader_location: 1,
    }],
};

/// An array of texels in a 2D texture [`TABLE_WIDTH`] wide, entry `i` at
/// `(i % TABLE_WIDTH, i / TABLE_WIDTH)` (`table_texel` in `common.wgsl`): a lookup table
/// the vertex stage reads where it has no storage buffers (the block layers: a game's
/// registry may hold more blocks than a uniform buffer).
#[derive(Debug)]
pub(crate) struct TableTexture {
    texture: wgpu::Texture,
    /// Its view.
    pub view: wgpu::TextureView,
    /// Bytes per entry.
    texel_bytes: u32,
}

impl TableTexture {
    /// A table of at least `entries` entries of `format` (an integer format).
    pub(crate) fn new(
        device: &wgpu::Device,
        label: &str,
        format: wgpu::TextureFormat,
        entries: usize,
    ) -> Self {
        let rows = entries.div_ceil(TABLE_WIDTH as usize).max(1) as u32;
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width: TABLE_WIDTH,
                height: rows,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        let view = texture.create_view(&Default::default());
        Self {
            texture,
            view,
            texel_bytes: format.block_copy_size(None).unwrap_or(4),
        }
    }

    /// Entries it holds.
    pub(crate) fn capacity(&self) -> usize {
        (TABLE_WIDTH * self.texture.height()) as usize
    }

    /// Writes `data` (whole entries) from entry `first` on; entries past the capacity are
    /// dropped.
    pub(crate) fn write(&self, queue: &wgpu::Queue, first: usize, data: &[u8]) {
        let texel = self.texel_bytes as usize;
        let width = TABLE_WIDTH as usize;
        let end = (first + data.len() / texel).min(self.capacity());
        let mut i = first;
        // Row by row: a copy is a rectangle.
        while i < end {
            let (x, y) = (i % width, i / width);
            let n = (width - x).min(end - i);
            let bytes = &data[(i - first) * texel..(i - first + n) * texel];
            queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: &self.texture,
                    mip_level: 0,
                    origin: wgpu::Origin3d {
                        x: x as u32,
                        y: y as u32,
                        z: 0,
                    },
                    aspect: wgpu::TextureAspect::All,
                },
                bytes,
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some((n * texel) as u32),
                    rows_per_image: None,
                },
                wgpu::Extent3d {
                    width: n as u32,
                    height: 1,
                    depth_or_array_layers: 1,
                },
            );
            i += n;
        }
    }
}

/// The chunk records by slot: an array in a storage buffer ([`QuadFetch::Storage`]), or
/// one record every `stride` bytes of a uniform buffer, bound at the drawn chunk's record
/// with a dynamic offset ([`QuadFetch::Instanced`]; `stride` the device's uniform offset
/// alignment): a uniform is a constant for the whole draw on every device, where a table
/// texture (as the block layers need: a game's registry can outgrow a uniform buffer)
/// would be fetched by every vertex.
#[derive(Debug)]
pub(crate) struct Records {
    buffer: wgpu::Buffer,
    /// Bytes from one record to the next.
    stride: u64,
    /// Whether a draw binds one record at a dynamic offset ([`QuadFetch::Instanced`]), not
    /// the whole array: not told by the stride, which is a record's size where the
    /// device's uniform offset alignment is (32 on some GL drivers).
    one_record: bool,
}

/// Bytes of a chunk record (`ChunkUniforms`, checked by a test).
pub(crate) const RECORD_BYTES: usize = 32;

impl Records {
    /// Room for `slots` records on a device of `limits`.
    pub(crate) fn new(
        device: &wgpu::Device,
        fetch: QuadFetch,
        limits: &wgpu::Limits,
        slots: usize,
    ) -> Self {
        let (stride, usage) = match fetch {
            QuadFetch::Storage => (RECORD_BYTES as u64, wgpu::BufferUsages::STORAGE),
            QuadFetch::Instanced => (
                u64::from(limits.min_uniform_buffer_offset_alignment).max(RECORD_BYTES as u64),
                wgpu::BufferUsages::UNIFORM,
            ),
        };
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("chunk_records"),
            size: slots.max(1) as u64 * stride,
            usage: usage | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Self {
            buffer,
            stride,
            one_record: fetch == QuadFetch::Instanced,
        }
    }

    /// Records it holds.
    pub(crate) fn capacity(&self) -> usize {
        (self.buffer.size() / self.stride) as usize
    }

    /// Bytes it takes.
    pub(crate) fn bytes(&self) -> u64 {
        self.buffer.size()
    }

    /// Writes `records` ([`RECORD_BYTES`] each) from slot `first` on.
    pub(crate) fn write(&self, to: &mut Upload<'_>, first: usize, records: &[u8]) {
        let at = first as u64 * self.stride;
        if self.stride == RECORD_BYTES as u64 {
            to.write(&self.buffer, at, records);
            return;
        }
        let mut spread = vec![0; records.len() / RECORD_BYTES * self.stride as usize];
        for (to, from) in spread
            .chunks_exact_mut(self.stride as usize)
            .zip(records.chunks_exact(RECORD_BYTES))
        {
            to[..RECORD_BYTES].copy_from_slice(from);
        }
        to.write(&self.buffer, at, &spread);
    }

    /// Its bind group resource: the whole array, or one record (the dynamic offset picks
    /// which).
    pub(crate) fn binding(&self) -> wgpu::BindingResource<'_> {
        if !self.one_record {
            return self.buffer.as_entire_binding();
        }
        wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &self.buffer,
            offset: 0,
            size: wgpu::BufferSize::new(RECORD_BYTES as u64),
        })
    }

    /// The dynamic offset of slot `slot`'s record.
    pub(crate) fn offset(&self, slot: u32) -> u32 {
        (u64::from(slot) * self.stride) as u32
    }
}

/// The layout entry of one chunk record, a uniform at a dynamic offset
/// ([`QuadFetch::Instanced`]).
pub(crate) fn record_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::VERTEX,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: true,
            min_binding_size: wgpu::BufferSize::new(RECORD_BYTES as u64),
        },
        count: None,
    }
}

/// A layout entry for an unsigned integer table texture read in the vertex stage.
pub(crate) fn table_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::VERTEX,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Uint,
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

/// Parses a command-line name (what `name` gives); the error lists the known names.
impl std::str::FromStr for QuadFetch {
    type Err = Error;

    fn from_str(name: &str) -> Result<Self> {
        crate::error::parse_name("quad fetch", name, &Self::ALL, Self::name)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_cover_the_same_quads_either_way() {
        for (slot, first, count) in [(0, 0, 1), (7, 100, 33), (1023, 5, 0)] {
            let (v, i) = QuadFetch::Storage.draw_ranges(slot, first, count);
            assert_eq!((v.start / 6, v.end / 6), (first, first + count));
            assert_eq!(i, slot..slot + 1);
            let (v, i) = QuadFetch::Instanced.draw_ranges(slot, first, count);
            assert_eq!(v, 0..6, "one quad's corners");
            assert_eq!(i, first..first + count, "one instance per quad");
        }
    }

    #[test]
    fn names_round_trip() {
        for f in QuadFetch::ALL {
            assert_eq!(f.name().parse::<QuadFetch>().unwrap(), f);
        }
        assert!("texture".parse::<QuadFetch>().is_err());
    }
}
