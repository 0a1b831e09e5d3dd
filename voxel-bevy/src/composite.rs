//! Bevy's opaque pass and the voxel frame composed both ways (`composite.wgsl`).
//!
//! - Into the world: a frame stage ([`BevyOpaque`]) draws Bevy's opaque colour and depth into
//!   the crate's scene where they are nearer than the world's, before the technique's passes,
//!   so water, glass and fog lie over Bevy's meshes as over the world's blocks.
//! - Into Bevy: after the frame, the world's opaque depth is written into Bevy's depth
//!   buffer ([`Composite::depth_into_bevy`]) for Bevy's passes that come after.

use voxel_render::{DEPTH_FORMAT, GameFrame, GameStages, GpuContext, SCENE_FORMAT, Stages};
use wgpu::util::DeviceExt;

/// The pipelines and layout of both directions, made once per device.
#[derive(Debug)]
pub(crate) struct Composite {
    layout: wgpu::BindGroupLayout,
    module: wgpu::ShaderModule,
    pipeline_layout: wgpu::PipelineLayout,
    /// Into the crate's scene, by sample count.
    into_world: Vec<(u32, wgpu::RenderPipeline)>,
    into_bevy: wgpu::RenderPipeline,
    /// Nearest, for depth (composite.wgsl: a depth texture read without a sampler reads 0
    /// on WebGL2).
    nearest: wgpu::Sampler,
}

/// The depth mapping between Bevy's infinite reverse-Z projection and the crate's, with the
/// same near plane and the crate's far plane `far`: crate = a * bevy + b.
pub(crate) fn depth_mapping(near: f64, far: f64) -> [f32; 2] {
    let a = far / (far - near);
    let b = -near / (far - near);
    [a as f32, b as f32]
}

impl Composite {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("voxel-bevy composite"),
            source: wgpu::ShaderSource::Wgsl(include_str!("composite.wgsl").into()),
        });
        let texture = |binding, sample_type| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Texture {
                sample_type,
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("voxel-bevy composite"),
            entries: &[
                texture(0, wgpu::TextureSampleType::Float { filterable: false }),
                // Depth as unfilterable float: see composite.wgsl (WebGL2).
                texture(1, wgpu::TextureSampleType::Float { filterable: false }),
                wgpu::BindGroupLayoutEntry {
                    binding: 2,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 3,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::NonFiltering),
                    count: None,
                },
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("voxel-bevy composite"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let into_bevy = Self::pipeline(device, &pipeline_layout, &module, 1, false);
        Self {
            layout,
            module,
            pipeline_layout,
            into_world: Vec::new(),
            into_bevy,
            nearest: device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("voxel-bevy composite depth"),
                ..Default::default()
            }),
        }
    }

    fn pipeline(
        device: &wgpu::Device,
        layout: &wgpu::PipelineLayout,
        module: &wgpu::ShaderModule,
        samples: u32,
        into_world: bool,
    ) -> wgpu::RenderPipeline {
        let targets = [Some(wgpu::ColorTargetState {
            format: SCENE_FORMAT,
            blend: None,
            write_mask: wgpu::ColorWrites::ALL,
        })];
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(if into_world {
                "voxel-bevy: Bevy's opaque pixels into the world"
            } else {
                "voxel-bevy: the world's depth into Bevy's"
            }),
            layout: Some(layout),
            vertex: wgpu::VertexState {
                module,
                entry_point: Some("vs_fullscreen"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: Some(wgpu::DepthStencilState {
                // Bevy's 3D depth format is the crate's: Depth32Float.
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(voxel_render::stages::DEPTH_COMPARE),
                stencil: wgpu::StencilState::default(),
                bias: wgpu::DepthBiasState::default(),
            }),
            multisample: wgpu::MultisampleState {
                count: samples,
                ..Default::default()
            },
            fragment: Some(wgpu::FragmentState {
                module,
                entry_point: Some(if into_world {
                    "fs_into_world"
                } else {
                    "fs_into_bevy"
                }),
                compilation_options: Default::default(),
                targets: if into_world { &targets } else { &[] },
            }),
            multiview_mask: None,
            cache: None,
        })
    }

    /// The pipeline into the crate's scene for `samples` samples, made the first time.
    fn world_pipeline(&mut self, device: &wgpu::Device, samples: u32) -> wgpu::RenderPipeline {
        if let Some((_, p)) = self.into_world.iter().find(|(s, _)| *s == samples) {
            return p.clone();
        }
        let p = Self::pipeline(device, &self.pipeline_layout, &self.module, samples, true);
        self.into_world.push((samples, p.clone()));
        p
    }

    /// The bind groups of one camera's frame (both directions) for what they read: Bevy's
    /// colour view, Bevy's depth texture, the crate's scene depth, the depth mapping and
    /// whether Bevy's colour is tonemapped (LDR). Made when one of those changes (a resize,
    /// another target, another near plane), not every frame: [`Binding::reads`].
    pub(crate) fn binding(&self, device: &wgpu::Device, reads: BindingReads) -> Binding {
        let params: [u32; 4] = [
            reads.mapping[0].to_bits(),
            reads.mapping[1].to_bits(),
            u32::from(reads.ldr),
            0,
        ];
        let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("voxel-bevy composite params"),
            contents: bytemuck::cast_slice(&params),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let bevy_depth = reads
            .bevy_depth
            .create_view(&wgpu::TextureViewDescriptor::default());
        let group = |depth: &wgpu::TextureView| {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("voxel-bevy composite"),
                layout: &self.layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::TextureView(&reads.bevy_color),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(depth),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: buffer.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 3,
                        resource: wgpu::BindingResource::Sampler(&self.nearest),
                    },
                ],
            })
        };
        let into_world = group(&bevy_depth);
        let into_bevy = group(&reads.scene_depth);
        Binding {
            reads,
            bevy_depth,
            into_world,
            into_bevy,
        }
    }

    /// Writes the world's opaque depth (`group` reads the crate's scene depth) into Bevy's
    /// depth buffer where it is nearer.
    pub(crate) fn depth_into_bevy(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        bevy_depth: &wgpu::TextureView,
        group: &wgpu::BindGroup,
    ) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("voxel-bevy: the world's depth into Bevy's"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: bevy_depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.into_bevy);
        pass.set_bind_group(0, group, &[]);
        pass.draw(0..3, 0..1);
    }
}

/// What a camera's composite bind groups read. The views and textures compare by identity
/// (wgpu's handles), and a [`Binding`] holds them, so an equal one is the same object.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct BindingReads {
    /// Bevy's main texture (the view Bevy's opaque pass drew into).
    pub(crate) bevy_color: wgpu::TextureView,
    /// Bevy's depth texture.
    pub(crate) bevy_depth: wgpu::Texture,
    /// The crate's scene depth (`Renderer::scene_depth_view`, made again on resize).
    pub(crate) scene_depth: wgpu::TextureView,
    /// Crate depth = `mapping[0]` · Bevy depth + `mapping[1]` ([`depth_mapping`]).
    pub(crate) mapping: [f32; 2],
    /// Bevy's colour is tonemapped (an LDR target).
    pub(crate) ldr: bool,
}

/// One camera's composite bind groups ([`Composite::binding`]), kept across frames.
#[derive(Debug)]
pub(crate) struct Binding {
    /// What they read: a frame that reads anything else makes a new binding.
    pub(crate) reads: BindingReads,
    /// The view of Bevy's depth texture (read into the world, written into Bevy).
    pub(crate) bevy_depth: wgpu::TextureView,
    /// Bevy's colour and depth, read into the crate's scene.
    pub(crate) into_world: wgpu::BindGroup,
    /// The crate's scene depth, written into Bevy's depth.
    pub(crate) into_bevy: wgpu::BindGroup,
}

/// The frame stage that draws Bevy's opaque pixels into the crate's scene.
#[derive(Debug)]
pub(crate) struct BevyOpaque<'a, 'g> {
    pub(crate) composite: &'a mut Composite,
    pub(crate) group: &'g wgpu::BindGroup,
    pipeline: Option<wgpu::RenderPipeline>,
}

impl<'a, 'g> BevyOpaque<'a, 'g> {
    pub(crate) fn new(composite: &'a mut Composite, group: &'g wgpu::BindGroup) -> Self {
        Self {
            composite,
            group,
            pipeline: None,
        }
    }
}

impl GameStages for BevyOpaque<'_, '_> {
    fn stages(&self) -> Stages {
        Stages {
            opaque: true,
            ..Default::default()
        }
    }

    fn prepare(&mut self, ctx: &GpuContext, frame: &GameFrame<'_>) {
        self.pipeline = Some(
            self.composite
                .world_pipeline(&ctx.device, frame.opaque_samples),
        );
    }

    fn opaque(&self, pass: &mut wgpu::RenderPass<'_>, _frame: &GameFrame<'_>) {
        if let Some(p) = &self.pipeline {
            pass.set_pipeline(p);
            pass.set_bind_group(0, self.group, &[]);
            pass.draw(0..3, 0..1);
        }
    }
}
