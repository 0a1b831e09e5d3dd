//! What every chunk pipeline binds: group 0 (the frame: camera, light, sky, viewport, the
//! block textures with their table of layers, and what volumes read) and group 1 (a chunk mesh's quads and its uniform), with the
//! structs shared with WGSL (`shaders/common.wgsl`) byte for byte. Techniques add their own
//! groups from 2 on; nothing here belongs to one technique.

use bytemuck::{Pod, Zeroable};

use crate::fetch::{self, QuadFetch};
use crate::gpu::{self, ChunkGroups, buffer_entry};

/// WGSL shared by every chunk pipeline: the structs below, vertex pulling and shading,
/// after the constants it shares with this module.
pub(crate) fn common_wgsl() -> String {
    gpu::WgslConsts::default()
        .u32("NO_MEDIUM", NO_MEDIUM)
        .u32("FLAG_INTERFACE", FLAG_INTERFACE)
        .u32("FLAG_LIT", FLAG_LIT)
        .u32("SUN_STOP", u32::from(crate::sun::SUN_STOP))
        .u32("MAX_SUN_STEPS", crate::sun::MAX_SUN_STEPS)
        .i32("SUN_TILE", crate::sun::SUN_TILE as i32)
        .f32("SUN_NUDGE", crate::sun::SUN_NUDGE)
        .f32("AO_DEPTH", AO_DEPTH)
        .f32("OPAQUE_EXPANSION_PX", OPAQUE_EXPANSION_PX)
        .f32("MAX_GROWTH", MAX_GROWTH)
        .u32("TABLE_WIDTH", crate::fetch::TABLE_WIDTH)
        .finish()
        + &frame_wgsl()
        + gpu::DEPTH_UV_WGSL
        + include_str!("shaders/common.wgsl")
        + VOLUME_WGSL
        + PATH_WGSL
}

/// The media between the eye and a fragment for the real-time techniques
/// (`shaders/path.wgsl`).
pub(crate) const PATH_WGSL: &str = include_str!("shaders/path.wgsl");

/// The volume functions (`shaders/volume.wgsl`): they read `frame`, `block_media` and
/// `TABLE_WIDTH`, `FLAG_INTERFACE`, which the including shader declares.
pub(crate) const VOLUME_WGSL: &str = include_str!("shaders/volume.wgsl");

/// WGSL of a full-screen pass that binds the chunk passes' group 0 (the renderer's scene
/// group, [`SharedLayouts::scene`]) as group `group`: the frame, the depth sampler, the
/// volume depth and each block's look as a medium (`medium_look`), with the volume
/// functions.
pub(crate) fn scene_volume_wgsl(group: u32) -> String {
    gpu::WgslConsts::default()
        .u32("NO_MEDIUM", NO_MEDIUM)
        .u32("FLAG_INTERFACE", FLAG_INTERFACE)
        .u32("TABLE_WIDTH", crate::fetch::TABLE_WIDTH)
        .finish()
        + &frame_wgsl()
        + gpu::DEPTH_UV_WGSL
        + &format!(
            "@group({group}) @binding(0) var<uniform> frame: Frame;\n\
             @group({group}) @binding(6) var depth_sampler: sampler;\n\
             @group({group}) @binding(7) var volume_depth: texture_2d<f32>;\n\
             @group({group}) @binding(8) var block_media: texture_2d<f32>;\n\n\
             // A block's look as a medium (`medium_look` of `common.wgsl`).\n\
             fn medium_look(block: u32) -> vec4<f32> {{\n    \
             if block == OBJECT_BLOCK {{\n        return vec4<f32>(0.0);\n    }}\n    \
             return textureLoad(block_media, vec2<i32>(i32(block % TABLE_WIDTH), i32(block / TABLE_WIDTH)), 0);\n}}\n\n\
             // The opaque depth at pixel `xy` (the exact references' volume depth).\n\
             fn opaque_depth_at(xy: vec2<f32>) -> f32 {{\n    \
             let uv = depth_uv(xy, textureDimensions(volume_depth));\n    \
             return textureSampleLevel(volume_depth, depth_sampler, uv, 0.0).x;\n}}\n\n\
             @group({group}) @binding(12) var volume_far: texture_2d<f32>;\n\n\
             // Where a medium still open after the last fragment (at window depth `last`)\n\
             // ends at pixel `xy`: the nearest back face of a volume behind it (the exact\n\
             // references' exit pass, its quads grown: a sliver between two merged quads\n\
             // leaves no way out open), or the opaque surface.\n\
             fn walk_end(xy: vec2<f32>, last: f32) -> f32 {{\n    \
             let opaque = opaque_depth_at(xy);\n    \
             let uv = depth_uv(xy, textureDimensions(volume_far));\n    \
             let exit = textureSampleLevel(volume_far, depth_sampler, uv, 0.0).x;\n    \
             return select(opaque, exit, exit < last && exit > opaque);\n}}\n\n"
        )
        + VOLUME_WGSL
}

/// The `Frame` struct (what [`FrameUniforms`] is in WGSL), after the values of its
/// `volumes` field.
pub(crate) fn frame_wgsl() -> String {
    gpu::WgslConsts::default()
        .u32("MEDIA_NONE", MEDIA_NONE)
        .u32("MEDIA_EYE", MEDIA_EYE)
        .u32("MEDIA_VOLUMES", MEDIA_VOLUMES)
        .u32("MEDIA_WALK", MEDIA_WALK)
        .finish()
        + include_str!("shaders/frame.wgsl")
}

/// How much ambient occlusion darkens at full strength: a vertex of AO value `v` (0 to 3,
/// `voxel_mesh::ao`) gets brightness `1 − strength · AO_DEPTH · (3 − v) / 3`, so an inner
/// corner (value 0) keeps 45 % of its light, about Minecraft's smooth lighting.
pub const AO_DEPTH: f32 = 0.55;

/// Opaque quads grow by this many pixels at each vertex (along the quad's own plane, as far
/// as it takes to move the vertex that far on screen along each of the quad's axes), so that the T-junctions of greedy-merged
/// quads leave no crack: the rasteriser snaps the vertex in the middle of another quad's
/// edge to its sub-pixel grid independently of that edge, which can leave a sliver no
/// quad covers. An eighth of a pixel is several times the snapping error (1/256 px with 8
/// sub-pixel bits) and changes only pixels on an edge: an opaque block hides its neighbours'
/// faces, so what pokes out of a convex edge is a sliver beyond the silhouette and what
/// pokes into a concave one is hidden. Translucent quads do not grow (an overlap would blend
/// twice), nor cutout ones (leaves keep their inner faces, which would poke out along the
/// seams of the faces in front).
pub const OPAQUE_EXPANSION_PX: f32 = 1.0 / 64.0;

/// The most an opaque quad grows along an axis, in blocks: a quad seen edge-on would need to
/// grow without bound to move a vertex by [`OPAQUE_EXPANSION_PX`] on screen.
pub(crate) const MAX_GROWTH: f32 = 1.0 / 16.0;

/// The tonemap's shoulder (`shaders/tonemap.wgsl`): values up to it pass unchanged.
pub const TONEMAP_SHOULDER: f32 = 0.8;

/// Per-frame uniforms every pass uses (`Frame` in WGSL).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub(crate) struct FrameUniforms {
    /// Camera-relative view × reverse-Z projection.
    pub view_proj: [[f32; 4]; 4],
    /// Integer part of the eye, clamped to the i32 world.
    pub eye_int: [i32; 3],
    /// Near plane distance.
    pub near: f32,
    /// Fractional part of the eye, in [0, 1).
    pub eye_frac: [f32; 3],
    /// Far plane distance.
    pub far: f32,
    /// Unit vector towards the sun.
    pub sun_dir: [f32; 3],
    /// Ambient light in [0, 1]: the share of light that does not depend on the normal.
    pub ambient: f32,
    /// Sky colour, linear.
    pub sky: [f32; 3],
    /// How much darker chunks of odd levels of detail are drawn (0: not at all;
    /// `Renderer::set_level_bands`).
    pub level_bands: f32,
    /// Render target size in pixels.
    pub viewport: [f32; 2],
    /// Block id of the translucent type the eye is inside, or `NO_MEDIUM` (`u32::MAX`).
    pub medium: u32,
    /// Ambient-occlusion strength, 0 (off) to 1.
    pub ao_strength: f32,
    /// `tan` of half the horizontal and vertical field of view: a pixel's ray length per
    /// unit of view depth.
    pub tan_half: [f32; 2],
    /// Which media the frame's fragments are seen through ([`MEDIA_NONE`],
    /// [`MEDIA_EYE`], [`MEDIA_VOLUMES`], [`MEDIA_WALK`]).
    pub volumes: u32,
    /// How bright the light of the sun (or moon) and the ambient light are: 1 by day,
    /// `Lighting::MOONLIGHT` at night. Scales every lit
    /// colour; the sky is cleared to its own colour.
    pub brightness: f32,
    /// The look of the medium the eye is in: linear colour and absorption, zero for none.
    pub medium_look: [f32; 4],
    /// Sun shadows (`crate::sun`): the eye's integer part minus the shadow volume's first
    /// block, so that a fragment's block in the volume is `pos + eye_frac + sun_offset`.
    pub sun_offset: [i32; 3],
    /// 1 while the renderer has sun shadows, else 0.
    pub sun_on: u32,
    /// The volume's size in blocks.
    pub sun_size: [u32; 3],
    /// Where the sun filters of class 1 start in the media table (`block_media`): two
    /// entries a class, the filter of a cell entered from another kind, then from its own.
    pub sun_table: u32,
    /// Where the volume's first block lies in its texture (a torus: a block at its world
    /// position modulo the size).
    pub sun_wrap: [u32; 3],
    pub sun_pad: u32,
    /// Per tile of the volume (8 × 8 columns of blocks; x + 32 z): the highest cell
    /// (volume y) holding anything but air, -1 for none.
    pub sun_tops: crate::sun::SunTops,
}

// A record is one texel of the records' table texture (`fetch.rs`).
const _: () = assert!(std::mem::size_of::<ChunkUniforms>() == crate::fetch::RECORD_BYTES);

/// [`FrameUniforms::volumes`]: no volume in view and the eye in no absorbing medium.
pub(crate) const MEDIA_NONE: u32 = 0;
/// [`FrameUniforms::volumes`], real-time techniques: the eye in an absorbing medium, no
/// volume to compose besides (or a technique that draws no translucency): fragments are
/// seen through the eye's medium up to its boundary (`path.wgsl`).
pub(crate) const MEDIA_EYE: u32 = 1;
/// [`FrameUniforms::volumes`], real-time techniques: a volume in view too; `volume_depth`
/// holds where volumes end, `volume_entry` and `entry_look` the nearest entry into one,
/// `volume_entry2` and `entry2_look` the nearest entry beyond where that one ends,
/// `volume_far` the farthest back face of one beyond that, `opaque_copy` the opaque depth.
/// (With [`MEDIA_WALK`], `volume_far` holds the nearest back face of a volume, its quads
/// grown, where an open medium ends: `walk_end`.)
pub(crate) const MEDIA_VOLUMES: u32 = 2;
/// [`FrameUniforms::volumes`], exact references: they walk the media from the eye along
/// their sorted fragments; `volume_depth` holds the opaque depth.
pub(crate) const MEDIA_WALK: u32 = 3;

/// [`FrameUniforms::medium`] when the eye is in no translucent volume.
pub(crate) const NO_MEDIUM: u32 = u32::MAX;

/// Quad flag (bit 16 of word 1 of a [`voxel_mesh::PackedQuad`]): a translucent face toward
/// another translucent type (`FLAG_INTERFACE` in WGSL).
pub(crate) const FLAG_INTERFACE: u32 = 1;
/// `VsOut::flags` bit set by the vertex stage for a quad of a lit chunk (above the 16 bits
/// the quad's word 1 gives it).
pub(crate) const FLAG_LIT: u32 = 1 << 16;

/// A chunk's record in the records array, by slot (`ChunkInfo` in WGSL).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub(crate) struct ChunkUniforms {
    /// World coordinates of the chunk's block (0, 0, 0).
    pub origin: [i32; 3],
    /// Whole-chunk opacity multiplier (fade-in), 1 when settled.
    pub alpha: f32,
    /// Blocks per cell along x and z: 1 for a chunk, `2^level` for a chunk of a level of
    /// detail ([`voxel_core::level_scale`]; its cells are one block high).
    pub scale: u32,
    /// Where the chunk's light palette starts in the palettes buffer (`chunks/light.rs`).
    pub light_base: u32,
    /// 1 for a lit chunk (its quads' light in the arena's light page), 0 for one drawn
    /// unlit (full sky light, no block light: as before light existed).
    pub lit: u32,
    pub pad0: u32,
}

/// Layouts every chunk pipeline is built against.
#[derive(Debug, Clone)]
pub(crate) struct SharedLayouts {
    /// Group 0: frame uniforms, block textures, sampler, the medium's boundary depth, and
    /// the layer of each block's face groups in the block textures.
    pub scene: wgpu::BindGroupLayout,
    /// Group 1: a page of the quad arena and the chunk records (with
    /// [`QuadFetch::Instanced`], the records only: the page is a vertex buffer).
    pub chunk: wgpu::BindGroupLayout,
    /// How the chunk pipelines fetch quads.
    pub fetch: QuadFetch,
}

impl SharedLayouts {
    /// Creates both layouts for `fetch`.
    pub(crate) fn new(device: &wgpu::Device, fetch: QuadFetch) -> Self {
        use wgpu::BufferBindingType as B;
        use wgpu::ShaderStages as S;
        let mut scene_entries = vec![
            buffer_entry(0, S::VERTEX_FRAGMENT, B::Uniform),
            wgpu::BindGroupLayoutEntry {
                binding: 1,
                visibility: S::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: true },
                    view_dimension: wgpu::TextureViewDimension::D2Array,
                    multisampled: false,
                },
                count: None,
            },
            wgpu::BindGroupLayoutEntry {
                binding: 2,
                visibility: S::FRAGMENT,
                ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                count: None,
            },
            gpu::texture_entry(3, gpu::DEPTH_READ),
            gpu::depth_sampler_entry(6),
            // The opaque depth as volumes read it, and each block's look as a medium.
            gpu::texture_entry(7, gpu::DEPTH_READ),
            gpu::texture_entry(8, wgpu::TextureSampleType::Float { filterable: false }),
            // The nearest entry into a volume and its medium's look, and a copy of the
            // opaque depth.
            gpu::texture_entry(9, gpu::DEPTH_READ),
            gpu::texture_entry(10, wgpu::TextureSampleType::Float { filterable: false }),
            gpu::texture_entry(11, gpu::DEPTH_READ),
            // The farthest back face of a volume, and the nearest entry beyond where the
            // nearest volume ends with its look.
            gpu::texture_entry(12, gpu::DEPTH_READ),
            gpu::texture_entry(13, gpu::DEPTH_READ),
            gpu::texture_entry(14, wgpu::TextureSampleType::Float { filterable: false }),
            // What the sun's ray crosses in each cell of the shadow volume (`sun.rs`).
            wgpu::BindGroupLayoutEntry {
                binding: 15,
                visibility: S::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Uint,
                    view_dimension: wgpu::TextureViewDimension::D3,
                    multisampled: false,
                },
                count: None,
            },
        ];
        // Group 0's block layers (read where the quad is expanded) and group 1, as
        // `common.wgsl` declares them for each way of fetching quads.
        let chunk_entries = match fetch {
            QuadFetch::Storage => {
                scene_entries.push(buffer_entry(4, S::VERTEX, B::Storage { read_only: true }));
                vec![
                    buffer_entry(0, S::VERTEX, B::Storage { read_only: true }),
                    buffer_entry(1, S::VERTEX, B::Storage { read_only: true }),
                    // The page's light and the light palettes (`chunks/light.rs`).
                    buffer_entry(3, S::VERTEX, B::Storage { read_only: true }),
                    buffer_entry(4, S::VERTEX, B::Storage { read_only: true }),
                ]
            }
            QuadFetch::Instanced => {
                scene_entries.push(fetch::table_entry(5));
                // The record, and the light palettes as a table texture.
                vec![fetch::record_entry(2), fetch::table_entry(5)]
            }
        };
        Self {
            scene: gpu::layout(device, "scene_layout", &scene_entries),
            chunk: gpu::layout(device, "chunk_layout", &chunk_entries),
            fetch,
        }
    }

    /// Groups 0 and 1, then `extra` (a technique's own groups from 2 on), with the way
    /// quads are fetched: what a [`gpu::ChunkPipeline`] is built against.
    pub(crate) fn with<'a>(&'a self, extra: &[&'a wgpu::BindGroupLayout]) -> ChunkGroups<'a> {
        ChunkGroups {
            layouts: [&self.scene, &self.chunk]
                .into_iter()
                .chain(extra.iter().copied())
                .map(Some)
                .collect(),
            fetch: self.fetch,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wgsl_layout::{assert_layout, field};

    /// The Rust structs are laid out exactly as naga lays out the WGSL ones.
    #[test]
    fn structs_match_their_wgsl() {
        let module = crate::wgsl_layout::parse(&common_wgsl());
        assert_layout::<FrameUniforms>(
            &module,
            "Frame",
            &[
                field!(FrameUniforms, view_proj),
                field!(FrameUniforms, eye_int),
                field!(FrameUniforms, near),
                field!(FrameUniforms, eye_frac),
                field!(FrameUniforms, far),
                field!(FrameUniforms, sun_dir),
                field!(FrameUniforms, ambient),
                field!(FrameUniforms, sky),
                field!(FrameUniforms, level_bands),
                field!(FrameUniforms, viewport),
                field!(FrameUniforms, medium),
                field!(FrameUniforms, ao_strength),
                field!(FrameUniforms, tan_half),
                field!(FrameUniforms, volumes),
                field!(FrameUniforms, brightness),
                field!(FrameUniforms, medium_look),
                field!(FrameUniforms, sun_offset),
                field!(FrameUniforms, sun_on),
                field!(FrameUniforms, sun_size),
                field!(FrameUniforms, sun_table),
                field!(FrameUniforms, sun_wrap),
                field!(FrameUniforms, sun_pad),
                field!(FrameUniforms, sun_tops),
            ],
        );
        let tonemap = include_str!("shaders/tonemap.wgsl");
        assert!(
            tonemap.contains(&format!("const SHOULDER: f32 = {TONEMAP_SHOULDER:?};")),
            "TONEMAP_SHOULDER is the shader's"
        );
        assert_layout::<ChunkUniforms>(
            &module,
            "ChunkInfo",
            &[
                field!(ChunkUniforms, origin),
                field!(ChunkUniforms, alpha),
                field!(ChunkUniforms, scale),
                field!(ChunkUniforms, light_base),
                field!(ChunkUniforms, lit),
                field!(ChunkUniforms, pad0),
            ],
        );
    }
}
