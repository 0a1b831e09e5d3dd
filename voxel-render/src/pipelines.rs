//! Pass plumbing every technique shares: the scene bind group layout (group 0), shader
//! assembly, and builders for chunk pipelines (vertex pulling) and fullscreen pipelines.

use crate::{DEPTH_FORMAT, SCENE_FORMAT};

/// WGSL shared by every chunk pipeline.
pub const COMMON_WGSL: &str = include_str!("shaders/common.wgsl");
/// WGSL shared by every fullscreen pipeline.
pub const FULLSCREEN_WGSL: &str = include_str!("shaders/fullscreen.wgsl");

/// Layouts every chunk pipeline is built against.
#[derive(Debug, Clone)]
pub struct SharedLayouts {
    /// Group 0: frame uniforms, block textures, sampler, Bayer levels.
    pub scene: wgpu::BindGroupLayout,
    /// Group 1: a chunk mesh's quads and the chunk uniform.
    pub chunk: wgpu::BindGroupLayout,
}

impl SharedLayouts {
    /// Creates both layouts.
    pub fn new(device: &wgpu::Device) -> Self {
        let scene = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("scene_layout"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: true },
                        view_dimension: wgpu::TextureViewDimension::D2Array,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 2,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 3,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Storage { read_only: true },
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
            ],
        });

        Self {
            scene,
            chunk: crate::chunks::chunk_layout(device),
        }
    }
}

/// A shader module made of `parts` concatenated (shared code first).
pub fn shader(device: &wgpu::Device, label: &str, parts: &[&str]) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(parts.concat().into()),
    })
}

/// How a chunk pipeline tests and writes depth.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DepthMode {
    /// Reverse-Z test (nearer passes) and write: opaque, cutout, stipple.
    Write,
    /// Reverse-Z test, no write: blended translucent passes.
    ReadOnly,
    /// Reverse-Z test, nearer or equal, no write: the sorted baseline (seed 003's LessEqual
    /// in a standard depth range).
    ReadOnlyOrEqual,
    /// Keep the farthest fragment and write it: back-layer peeling.
    WriteFarthest,
}

/// A pipeline drawing chunk quads from `module` (which includes `common.wgsl`'s `vs_main`).
#[allow(clippy::too_many_arguments)]
pub fn chunk_pipeline(
    device: &wgpu::Device,
    label: &str,
    module: &wgpu::ShaderModule,
    fragment_entry: &str,
    bind_group_layouts: &[Option<&wgpu::BindGroupLayout>],
    targets: &[Option<wgpu::ColorTargetState>],
    depth: DepthMode,
    samples: u32,
) -> wgpu::RenderPipeline {
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts,
        immediate_size: 0,
    });
    let (write, compare) = match depth {
        DepthMode::Write => (true, wgpu::CompareFunction::Greater),
        DepthMode::ReadOnly => (false, wgpu::CompareFunction::Greater),
        DepthMode::ReadOnlyOrEqual => (false, wgpu::CompareFunction::GreaterEqual),
        DepthMode::WriteFarthest => (true, wgpu::CompareFunction::Less),
    };
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState {
            topology: wgpu::PrimitiveTopology::TriangleList,
            front_face: wgpu::FrontFace::Ccw,
            // Every face is an entry surface seen from its front: the mesher emits the face
            // of each side of a boundary, and back faces are culled everywhere.
            cull_mode: Some(wgpu::Face::Back),
            ..Default::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(write),
            depth_compare: Some(compare),
            stencil: wgpu::StencilState::default(),
            bias: wgpu::DepthBiasState::default(),
        }),
        multisample: wgpu::MultisampleState {
            count: samples,
            ..Default::default()
        },
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some(fragment_entry),
            compilation_options: Default::default(),
            targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// A fullscreen-triangle pipeline: `source` (a technique's fragment shader) after
/// `fullscreen.wgsl`, whose `vs_fullscreen` it uses. No depth unless `depth_write` asks for a
/// depth target that always passes and writes.
#[allow(clippy::too_many_arguments)]
pub fn fullscreen_pipeline(
    device: &wgpu::Device,
    label: &str,
    source: &str,
    fragment_entry: &str,
    bind_group_layouts: &[Option<&wgpu::BindGroupLayout>],
    targets: &[Option<wgpu::ColorTargetState>],
    depth_write: bool,
    constants: &[(&str, f64)],
) -> wgpu::RenderPipeline {
    let module = &shader(device, label, &[FULLSCREEN_WGSL, source]);
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts,
        immediate_size: 0,
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("vs_fullscreen"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: depth_write.then(|| wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Always),
            stencil: wgpu::StencilState::default(),
            bias: wgpu::DepthBiasState::default(),
        }),
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some(fragment_entry),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants,
                ..Default::default()
            },
            targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// A colour target of the HDR scene format with `blend`.
pub fn scene_target(blend: Option<wgpu::BlendState>) -> Option<wgpu::ColorTargetState> {
    Some(wgpu::ColorTargetState {
        format: SCENE_FORMAT,
        blend,
        write_mask: wgpu::ColorWrites::ALL,
    })
}

/// A layout entry for a non-filterable 2D texture read with `textureLoad` in fragments.
pub fn texture_entry(
    binding: u32,
    sample_type: wgpu::TextureSampleType,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type,
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

/// A colour attachment that loads what is there and stores the result.
pub fn load_attachment(view: &wgpu::TextureView) -> Option<wgpu::RenderPassColorAttachment<'_>> {
    Some(wgpu::RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: None,
        ops: wgpu::Operations {
            load: wgpu::LoadOp::Load,
            store: wgpu::StoreOp::Store,
        },
    })
}

/// A colour attachment cleared to `color`.
pub fn clear_attachment(
    view: &wgpu::TextureView,
    color: wgpu::Color,
) -> Option<wgpu::RenderPassColorAttachment<'_>> {
    Some(wgpu::RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: None,
        ops: wgpu::Operations {
            load: wgpu::LoadOp::Clear(color),
            store: wgpu::StoreOp::Store,
        },
    })
}

/// The opaque depth as a read-only attachment (translucent passes test, never write).
pub fn read_only_depth(
    view: &wgpu::TextureView,
) -> Option<wgpu::RenderPassDepthStencilAttachment<'_>> {
    Some(wgpu::RenderPassDepthStencilAttachment {
        view,
        depth_ops: None,
        stencil_ops: None,
    })
}

/// A colour attachment cleared to transparent black.
pub fn clear_transparent(view: &wgpu::TextureView) -> Option<wgpu::RenderPassColorAttachment<'_>> {
    clear_attachment(view, wgpu::Color::TRANSPARENT)
}

/// A 2D texture of `format` and `usage` at `width` × `height`, with its default view.
pub fn target(
    device: &wgpu::Device,
    label: &str,
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
    width: u32,
    height: u32,
) -> (wgpu::Texture, wgpu::TextureView) {
    multisampled_target(device, label, format, usage, width, height, 1)
}

/// [`target`] with `samples` samples per pixel.
pub fn multisampled_target(
    device: &wgpu::Device,
    label: &str,
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
    width: u32,
    height: u32,
    samples: u32,
) -> (wgpu::Texture, wgpu::TextureView) {
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: samples,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    });
    let view = texture.create_view(&Default::default());
    (texture, view)
}

/// A bind group of texture views at bindings 0, 1, ...
pub fn texture_group(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    views: &[&wgpu::TextureView],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry<'_>> = views
        .iter()
        .enumerate()
        .map(|(i, v)| wgpu::BindGroupEntry {
            binding: i as u32,
            resource: wgpu::BindingResource::TextureView(v),
        })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &entries,
    })
}

/// A layout of `count` fragment textures at bindings 0, 1, ... of `sample_type`.
pub fn textures_layout(
    device: &wgpu::Device,
    label: &str,
    sample_type: wgpu::TextureSampleType,
    count: u32,
) -> wgpu::BindGroupLayout {
    let entries: Vec<wgpu::BindGroupLayoutEntry> =
        (0..count).map(|i| texture_entry(i, sample_type)).collect();
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &entries,
    })
}

/// Submits what `encoder` holds and replaces it with a fresh one, so that a technique can
/// wait for GPU results in the middle of a frame (the exact methods do; real-time ones
/// never do). Commands keep their order: the rest of the frame follows in the new encoder.
pub fn flush(ctx: &crate::GpuContext, encoder: &mut wgpu::CommandEncoder) {
    let fresh = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("frame_continued"),
        });
    let done = std::mem::replace(encoder, fresh);
    ctx.queue.submit([done.finish()]);
}
