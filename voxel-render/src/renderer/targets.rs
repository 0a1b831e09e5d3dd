//! The per-size scene targets (HDR colour and depth, the medium boundary, the volume
//! depths) with the bind groups that read them, and the passes after the technique's.

use std::collections::HashMap;

use super::Renderer;
#[cfg(doc)]
use crate::QuadFetch;
use crate::bindings::SharedLayouts;
use crate::fetch::TableTexture;
use crate::gpu::{self, FullscreenPipeline, Target};
use crate::light_volume::LightVolume;
use crate::medium;
use crate::sun::SunVolume;
use crate::textures::BlockTextures;
use crate::{DEPTH_FORMAT, GpuContext, SCENE_FORMAT};

/// What group 0 binds, apart from the per-size medium boundary.
#[derive(Debug)]
pub(super) struct SceneResources {
    pub(super) frame_buffer: wgpu::Buffer,
    pub(super) textures: BlockTextures,
    /// The block layers as a texture ([`QuadFetch::Instanced`]).
    pub(super) layer_table: Option<TableTexture>,
    /// Per block id, its look as a medium (`block_media` in `common.wgsl`): linear colour
    /// and absorption.
    pub(super) media: TableTexture,
    /// Where the sun filters start in `media`.
    pub(super) sun_table: u32,
    /// The sun shadows' volume (`sun_cells` in `common.wgsl`).
    pub(super) sun: SunVolume,
    /// The light field around the eye for a game's shaders (`light_volume.rs`).
    pub(super) light: LightVolume,
    /// The nearest sampler every depth texture is read with (`gpu::DEPTH_READ`).
    pub(super) depth_sampler: wgpu::Sampler,
}

/// The HDR scene colour and depth, the medium boundary, and what reads them.
#[derive(Debug)]
pub(super) struct SceneTargets {
    pub(super) size: (u32, u32),
    pub(super) color: Target,
    pub(super) depth: Target,
    /// Inside a medium: the depth of its first surface per pixel ([`crate::medium`]).
    pub(super) boundary: Target,
    /// With a volume in view: a copy of the opaque depth, which the translucent passes
    /// read (their depth attachment is that depth, read-only).
    pub(super) volume_depth: Target,
    /// Whether `volume_depth` is at full size (1×1 until a volume is in view).
    pub(super) volumes: bool,
    /// Group 0 of the chunk passes (the boundary readable).
    pub(super) scene_group: wgpu::BindGroup,
    /// Group 0 of the pass that writes the boundary.
    pub(super) boundary_scene_group: wgpu::BindGroup,
    /// The scene group of the pass writing `volume_depth` (the opaque depth in its place).
    pub(super) exit_scene_group: wgpu::BindGroup,
    /// The scene group of the pass writing `volume_entry` and `entry_look`.
    pub(super) entry_scene_group: wgpu::BindGroup,
    /// The nearest front face of a volume (`shaders/path.wgsl`).
    pub(super) volume_entry: Target,
    /// Its medium's look.
    pub(super) entry_look: Target,
    /// A copy of the opaque depth the chunk passes read (`opaque_copy` in `common.wgsl`).
    pub(super) opaque_copy: Target,
    /// The farthest back face of a volume (`volume_far` in `common.wgsl`).
    pub(super) volume_far: Target,
    /// The nearest entry into a volume beyond where the nearest volume ends, and its look.
    pub(super) volume_entry2: Target,
    pub(super) entry2_look: Target,
    /// The scene group of the pass writing `volume_entry2` and `entry2_look`.
    pub(super) entry2_scene_group: wgpu::BindGroup,
    /// The scene group of the pass writing `volume_far` (the opaque depth in its place).
    pub(super) far_scene_group: wgpu::BindGroup,
    /// MSAA colour and depth, resolved into `color` and `depth`.
    pub(super) msaa: Option<(Target, Target)>,
    pub(super) tonemap_group: wgpu::BindGroup,
    pub(super) depth_resolve_group: Option<wgpu::BindGroup>,
}

/// The passes after the technique's: tonemap (per output format) and the MSAA depth
/// resolve.
#[derive(Debug)]
pub(super) struct Post {
    tonemap_layout: wgpu::BindGroupLayout,
    /// Per output format: the tonemap, and the same with a depth target, which
    /// [`Renderer::check_output`] sets in a pass beside the scene depth.
    pub(super) tonemap: HashMap<wgpu::TextureFormat, (wgpu::RenderPipeline, wgpu::RenderPipeline)>,
    depth_resolve_layout: wgpu::BindGroupLayout,
    /// `None` on a device without 4× MSAA ([`crate::Capabilities::msaa4`]), whose shading
    /// language may have no multisampled textures (GLSL ES 3.00: WebGL2).
    pub(super) depth_resolve: Option<wgpu::RenderPipeline>,
}

pub(super) const MSAA_SAMPLES: u32 = 4;

impl Renderer {
    /// The scene targets for `size`, with or without MSAA, and the volume depth at full
    /// size once a volume has been in view.
    pub(super) fn targets_for(&self, size: (u32, u32), msaa: bool, volumes: bool) -> SceneTargets {
        SceneTargets::new(
            &self.ctx,
            &self.post,
            &self.layouts,
            &self.scene,
            size,
            (msaa, volumes),
        )
    }
}

impl Post {
    /// The passes of a device where 4× MSAA works when `msaa`.
    pub(super) fn new(device: &wgpu::Device, msaa: bool) -> Self {
        let float = wgpu::TextureSampleType::Float { filterable: false };
        let tonemap_layout = gpu::layout(device, "tonemap_layout", &[gpu::texture_entry(0, float)]);
        let depth_resolve_layout = gpu::layout(
            device,
            "depth_resolve_layout",
            &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: gpu::DEPTH_READ,
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: true,
                },
                count: None,
            }],
        );
        let depth_resolve = msaa.then(|| {
            FullscreenPipeline {
                label: "depth_resolve",
                source: include_str!("../shaders/depth_resolve.wgsl"),
                fragment_entry: "fs_depth_resolve",
                groups: &[Some(&depth_resolve_layout)],
                targets: &[],
                writes_depth: true,
                constants: &[],
            }
            .build(device)
        });
        Self {
            tonemap_layout,
            tonemap: HashMap::new(),
            depth_resolve_layout,
            depth_resolve,
        }
    }

    /// Creates the tonemap pipeline for `format` if it does not exist yet.
    pub(super) fn make_tonemap(&mut self, ctx: &GpuContext, format: wgpu::TextureFormat) {
        let layout = &self.tonemap_layout;
        self.tonemap.entry(format).or_insert_with(|| {
            // sRGB formats are encoded by the GPU, a float one is written linear.
            let encode = !(format.is_srgb() || format == wgpu::TextureFormat::Rgba16Float);
            let make = |label, writes_depth| {
                FullscreenPipeline {
                    label,
                    source: include_str!("../shaders/tonemap.wgsl"),
                    fragment_entry: "fs_tonemap",
                    groups: &[Some(layout)],
                    targets: &[Some(wgpu::ColorTargetState {
                        format,
                        blend: None,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                    writes_depth,
                    constants: &[("SRGB_ENCODE", if encode { 1.0 } else { 0.0 })],
                }
                .build(&ctx.device)
            };
            (make("tonemap", false), make("tonemap_output_check", true))
        });
    }
}

impl SceneTargets {
    /// The targets for `size`; `(msaa, volumes)`: with MSAA targets, and with the volume
    /// depth at full size (else 1×1: no volume has been in view).
    pub(super) fn new(
        ctx: &GpuContext,
        post: &Post,
        layouts: &SharedLayouts,
        scene: &SceneResources,
        size: (u32, u32),
        (msaa, volumes): (bool, bool),
    ) -> Self {
        use wgpu::TextureUsages as U;
        let device = &ctx.device;
        let target = |label, format, samples, usage| {
            gpu::TargetDesc {
                label,
                format,
                usage,
                size,
                samples,
            }
            .create(device)
        };
        let color = target(
            "scene_color",
            SCENE_FORMAT,
            1,
            U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC | U::COPY_DST,
        );
        let depth = target(
            "scene_depth",
            DEPTH_FORMAT,
            1,
            U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC,
        );
        let msaa = msaa.then(|| {
            (
                target(
                    "scene_color_msaa",
                    SCENE_FORMAT,
                    MSAA_SAMPLES,
                    U::RENDER_ATTACHMENT,
                ),
                target(
                    "scene_depth_msaa",
                    DEPTH_FORMAT,
                    MSAA_SAMPLES,
                    U::RENDER_ATTACHMENT | U::TEXTURE_BINDING,
                ),
            )
        });
        let boundary = target(
            "medium_boundary",
            DEPTH_FORMAT,
            1,
            U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_DST,
        );
        // The volumes' depths and the nearest entry's look: 1×1 until a volume is in view.
        let volume_target = |label, format| {
            gpu::TargetDesc {
                label,
                format,
                usage: U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_DST,
                size: if volumes { size } else { (1, 1) },
                samples: 1,
            }
            .create(device)
        };
        let volume_depth = volume_target("volume_depth", DEPTH_FORMAT);
        let volume_entry = volume_target("volume_entry", DEPTH_FORMAT);
        let entry_look = volume_target("entry_look", medium::ENTRY_LOOK_FORMAT);
        let opaque_copy = volume_target("opaque_copy", DEPTH_FORMAT);
        let volume_far = volume_target("volume_far", DEPTH_FORMAT);
        let volume_entry2 = volume_target("volume_entry2", DEPTH_FORMAT);
        let entry2_look = volume_target("entry2_look", medium::ENTRY_LOOK_FORMAT);
        // The block layers: binding 4 (a storage buffer) or 5 (a table texture),
        // `shaders/common.wgsl`.
        let layers = match &scene.layer_table {
            Some(table) => (5, wgpu::BindingResource::TextureView(&table.view)),
            None => (4, scene.textures.layers.as_entire_binding()),
        };
        let group = |label,
                     boundary: &Target,
                     volume_depth: &Target,
                     entry: (&Target, &wgpu::TextureView),
                     far: &Target,
                     entry2: (&Target, &wgpu::TextureView)| {
            let resources = [
                (0, scene.frame_buffer.as_entire_binding()),
                (1, wgpu::BindingResource::TextureView(&scene.textures.view)),
                (2, wgpu::BindingResource::Sampler(&scene.textures.sampler)),
                (3, wgpu::BindingResource::TextureView(&boundary.view)),
                layers.clone(),
                (6, wgpu::BindingResource::Sampler(&scene.depth_sampler)),
                (7, wgpu::BindingResource::TextureView(&volume_depth.view)),
                (8, wgpu::BindingResource::TextureView(&scene.media.view)),
                (9, wgpu::BindingResource::TextureView(&entry.0.view)),
                (10, wgpu::BindingResource::TextureView(entry.1)),
                (11, wgpu::BindingResource::TextureView(&opaque_copy.view)),
                (12, wgpu::BindingResource::TextureView(&far.view)),
                (13, wgpu::BindingResource::TextureView(&entry2.0.view)),
                (14, wgpu::BindingResource::TextureView(entry2.1)),
                (15, wgpu::BindingResource::TextureView(&scene.sun.view)),
            ];
            let entries =
                resources.map(|(binding, resource)| wgpu::BindGroupEntry { binding, resource });
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(label),
                layout: &layouts.scene,
                entries: &entries,
            })
        };
        let entry = (&volume_entry, &entry_look.view);
        let entry2 = (&volume_entry2, &entry2_look.view);
        let scene_group = group(
            "scene",
            &boundary,
            &volume_depth,
            entry,
            &volume_far,
            entry2,
        );
        // The pass writing the boundary reads the opaque depth in its place (ties with
        // cutout faces, `shaders/medium_boundary.wgsl`), and so do the passes writing the
        // volume depth and the volume entry (which reads the media table for the look).
        let boundary_scene_group = group(
            "scene_writing_boundary",
            &depth,
            &volume_depth,
            entry,
            &volume_far,
            entry2,
        );
        let exit_scene_group = group(
            "scene_writing_volume_depth",
            &boundary,
            &depth,
            entry,
            &volume_far,
            entry2,
        );
        let entry_scene_group = group(
            "scene_writing_volume_entry",
            &boundary,
            &volume_depth,
            (&depth, &scene.media.view),
            &volume_far,
            entry2,
        );
        let entry2_scene_group = group(
            "scene_writing_volume_entry2",
            &boundary,
            &volume_depth,
            entry,
            &volume_far,
            (&depth, &scene.media.view),
        );
        let far_scene_group = group(
            "scene_writing_volume_far",
            &boundary,
            &volume_depth,
            entry,
            &depth,
            entry2,
        );
        let tonemap_group =
            gpu::texture_group(device, "tonemap", &post.tonemap_layout, &[&color.view]);
        let depth_resolve_group = msaa.as_ref().map(|(_, d)| {
            gpu::texture_group(
                device,
                "depth_resolve",
                &post.depth_resolve_layout,
                &[&d.view],
            )
        });
        Self {
            size,
            color,
            depth,
            boundary,
            volume_depth,
            volumes,
            scene_group,
            boundary_scene_group,
            exit_scene_group,
            entry_scene_group,
            volume_entry,
            entry_look,
            opaque_copy,
            volume_far,
            far_scene_group,
            volume_entry2,
            entry2_look,
            entry2_scene_group,
            msaa,
            tonemap_group,
            depth_resolve_group,
        }
    }
}
