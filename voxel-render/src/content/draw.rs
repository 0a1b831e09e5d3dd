//! [`ContentStages`]: a [`Content`] drawn through a renderer's stages.

use std::collections::HashMap;
use std::ops::Range;

use glam::DVec3;

use super::{Content, Entity, Particle};
use crate::stages::{
    DEPTH_COMPARE, GameFrame, GameStages, OIT_GROUP, Stages, TranslucentContract, TranslucentObject,
};
use crate::textures::srgb_to_linear;
use crate::{DEPTH_FORMAT, GpuContext, Renderer, Result, SCENE_FORMAT, Technique};

/// One primitive of the instance buffer (`Prim` in `content.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct Prim {
    /// Camera-relative centre.
    center: [f32; 3],
    /// 0: box, 1: particle.
    kind: u32,
    /// Box axes scaled by the half extents; a particle's half size in `axis_x[0]`.
    axis_x: [f32; 4],
    axis_y: [f32; 4],
    axis_z: [f32; 4],
    /// Linear colour (lit per face in the shader) and opacity.
    color: [f32; 4],
}

/// The content shader's uniform (`View` in `content.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct View {
    view_proj: [[f32; 4]; 4],
    right: [f32; 4],
    up: [f32; 4],
    sun: [f32; 3],
    ambient: f32,
    brightness: f32,
    _pad: [f32; 3],
}

/// Draws a [`Content`] through a renderer's stages: pass it to `Renderer::render`
/// each frame. Its pipelines are built when a frame first needs them (the translucent ones
/// per technique contract, kept by its id; the opaque one per sample count), or ahead with
/// [`ContentStages::prebuild`].
#[derive(Debug)]
pub struct ContentStages {
    /// The renderer's context its resources are made on.
    ctx: GpuContext,
    content: Content,
    module_src: String,
    view: wgpu::Buffer,
    view_layout: wgpu::BindGroupLayout,
    prims_layout: wgpu::BindGroupLayout,
    view_group: wgpu::BindGroup,
    /// Opaque boxes, and the translucent things in draw order.
    opaque: Buffer,
    translucent: Buffer,
    opaque_pipeline: Option<(u32, wgpu::RenderPipeline)>,
    /// One translucent pipeline per variant of each contract built for (by its id), and
    /// the contract in force.
    translucent_pipelines: HashMap<u64, Vec<wgpu::RenderPipeline>>,
    contract: Option<u64>,
    /// Whether a frame's contract it has no pipelines for is followed (built, or taken from
    /// those kept) rather than refused.
    follow: bool,
    /// Render pipelines built so far.
    built: usize,
    /// The translucent objects (particles, then translucent entities), for ordering.
    objects: Vec<TranslucentObject>,
}

/// An instance buffer with its group.
#[derive(Debug)]
struct Buffer {
    buffer: wgpu::Buffer,
    group: wgpu::BindGroup,
    count: u32,
}

impl Buffer {
    /// A storage buffer of room for `prims` primitives (at least one), bound alone in a
    /// group of `layout`.
    fn new(
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        label: &str,
        prims: usize,
    ) -> Self {
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: (prims.max(1) * std::mem::size_of::<Prim>()) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let group = crate::gpu::bind_group(device, label, layout, &[buffer.as_entire_binding()]);
        Self {
            buffer,
            group,
            count: 0,
        }
    }
}

const CONTENT_WGSL: &str = include_str!("content.wgsl");

/// Vertices drawn per primitive: a box's 36 (a particle uses the first 6, the rest
/// collapse to nothing).
const VERTICES: u32 = 36;

impl ContentStages {
    /// Resources for `content` on `renderer`'s device, lit like `renderer`'s world.
    pub fn new(renderer: &Renderer, content: Content) -> Self {
        let ctx = renderer.context();
        let device = &ctx.device;
        let uniform = wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::VERTEX,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let storage = wgpu::BindGroupLayoutEntry {
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: true },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            ..uniform
        };
        let layout = |label, entry| {
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(label),
                entries: &[entry],
            })
        };
        let view_layout = layout("content_view_layout", uniform);
        let prims_layout = layout("content_prims_layout", storage);
        let view = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("content_view"),
            size: std::mem::size_of::<View>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let view_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("content_view"),
            layout: &view_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: view.as_entire_binding(),
            }],
        });
        let buffer = |label, n: usize| Buffer::new(device, &prims_layout, label, n);
        let opaque_count = content.entities.iter().filter(|e| e.is_opaque()).count();
        let translucent_count = content.particles.len() + content.entities.len() - opaque_count;
        let objects = Self::objects(&content);
        Self {
            ctx: ctx.clone(),
            module_src: CONTENT_WGSL.to_owned(),
            opaque: buffer("content_opaque", opaque_count),
            translucent: buffer("content_translucent", translucent_count),
            view,
            view_layout,
            prims_layout,
            view_group,
            opaque_pipeline: None,
            translucent_pipelines: HashMap::new(),
            contract: None,
            follow: true,
            built: 0,
            objects,
            content,
        }
    }

    /// Replaces what it draws (moving particles, a turning cube); the instance buffers grow
    /// when needed.
    pub fn set_content(&mut self, ctx: &GpuContext, content: Content) {
        let opaque = content.entities.iter().filter(|e| e.is_opaque()).count();
        let translucent = content.particles.len() + content.entities.len() - opaque;
        let fits =
            |b: &Buffer, n: usize| b.buffer.size() >= (n * std::mem::size_of::<Prim>()) as u64;
        if !fits(&self.opaque, opaque) || !fits(&self.translucent, translucent) {
            // Twice what is needed, so that content growing a little rebuilds nothing.
            let make =
                |label, n: usize| Buffer::new(&ctx.device, &self.prims_layout, label, 2 * n.max(1));
            let rebuilt = (
                make("content_opaque", opaque),
                make("content_translucent", translucent),
            );
            (self.opaque, self.translucent) = rebuilt;
        }
        self.objects = Self::objects(&content);
        self.content = content;
    }

    /// The translucent objects in instance order before sorting: particles, then the
    /// translucent entities.
    fn objects(content: &Content) -> Vec<TranslucentObject> {
        content
            .particles
            .iter()
            // A square facing the camera: its corners, whichever way it turns.
            .map(|p| {
                TranslucentObject::ball(p.center, f64::from(p.half_size) * std::f64::consts::SQRT_2)
            })
            .chain(
                content
                    .entities
                    .iter()
                    .filter(|e| !e.is_opaque())
                    .map(|e| TranslucentObject::aabb(e.center, e.world_half_extents())),
            )
            .collect()
    }

    /// Builds now the pipelines for `renderer`'s configuration and contract, which the
    /// next frame would otherwise build (cheap when nothing changed): at loading time, or
    /// after a switch when it does not follow the contract ([`Self::set_follow_contract`]).
    pub fn update_pipelines(&mut self, renderer: &mut Renderer) -> Result<()> {
        self.check_renderer(renderer)?;
        let contract = renderer.translucent_contract()?;
        self.build_for(renderer, &contract);
        self.contract = Some(contract.id);
        Ok(())
    }

    /// Whether a frame whose technique's contract its translucent pipelines were not built
    /// for builds them first (`true`, the default: a technique switch needs nothing of
    /// the game) or is refused with `Error::StaleContract` (`false`: a game that builds
    /// them only when it chooses, with [`Self::update_pipelines`] and [`Self::prebuild`],
    /// and would rather see an error than a frame that compiles).
    pub fn set_follow_contract(&mut self, follow: bool) {
        self.follow = follow;
    }

    /// The opaque pipeline for `renderer`'s sample count and the translucent ones for
    /// `contract`, each built if it has none.
    fn build_for(&mut self, renderer: &Renderer, contract: &TranslucentContract) {
        let device = &renderer.context().device;
        self.opaque_pipeline_for(device, if renderer.config().msaa { 4 } else { 1 });
        self.translucent_pipelines_for(device, contract);
    }

    /// The translucent pipelines for `contract`, built if it has none.
    fn translucent_pipelines_for(&mut self, device: &wgpu::Device, contract: &TranslucentContract) {
        if !self.translucent_pipelines.contains_key(&contract.id) {
            let pipelines = self.translucent_for(device, contract);
            self.built += pipelines.len();
            self.translucent_pipelines.insert(contract.id, pipelines);
        }
    }

    /// The opaque pipeline for `samples`, built if it has none.
    fn opaque_pipeline_for(&mut self, device: &wgpu::Device, samples: u32) {
        if self.opaque_pipeline.as_ref().map(|(s, _)| *s) != Some(samples) {
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("content_opaque"),
                source: wgpu::ShaderSource::Wgsl(self.module_src.as_str().into()),
            });
            let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("content_opaque"),
                bind_group_layouts: &[Some(&self.view_layout), Some(&self.prims_layout)],
                immediate_size: 0,
            });
            let pipeline = self.pipeline(
                device,
                &module,
                &layout,
                "fs_opaque",
                &[Some(wgpu::ColorTargetState {
                    format: SCENE_FORMAT,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
                wgpu::DepthStencilState {
                    format: DEPTH_FORMAT,
                    depth_write_enabled: Some(true),
                    depth_compare: Some(DEPTH_COMPARE),
                    stencil: wgpu::StencilState::default(),
                    bias: wgpu::DepthBiasState::default(),
                },
                samples,
            );
            self.opaque_pipeline = Some((samples, pipeline));
            self.built += 1;
        }
    }

    /// How many render pipelines it has built (opaque and translucent).
    pub fn pipelines_built(&self) -> usize {
        self.built
    }

    /// Builds the translucent pipelines for `technique`'s contract ahead
    /// (`Renderer::translucent_contract_for`, which builds the technique too), as a game
    /// does at loading time for every technique its settings offer: a switch to it then
    /// compiles nothing (its opaque pipeline is built too). Pipelines are kept by contract
    /// id.
    pub fn prebuild(&mut self, renderer: &mut Renderer, technique: Technique) -> Result<()> {
        self.check_renderer(renderer)?;
        let contract = renderer.translucent_contract_for(technique)?;
        self.build_for(renderer, &contract);
        Ok(())
    }

    /// A renderer of another device is an error: the resources are this one's.
    fn check_renderer(&self, renderer: &Renderer) -> Result<()> {
        if renderer.context().same_device(&self.ctx) {
            Ok(())
        } else {
            Err(crate::Error::OtherDevice(
                "content stages made for a renderer of another device".into(),
            ))
        }
    }

    fn translucent_for(
        &self,
        device: &wgpu::Device,
        contract: &TranslucentContract,
    ) -> Vec<wgpu::RenderPipeline> {
        contract
            .variants
            .iter()
            .map(|v| {
                let source = v.wgsl.clone() + &self.module_src + TRANSLUCENT_ENTRY;
                let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some(v.name),
                    source: wgpu::ShaderSource::Wgsl(source.into()),
                });
                let mut groups = vec![Some(&self.view_layout), Some(&self.prims_layout)];
                while groups.len() < OIT_GROUP as usize {
                    groups.push(None);
                }
                groups.push(Some(&v.layout));
                let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some(v.name),
                    bind_group_layouts: &groups,
                    immediate_size: 0,
                });
                self.pipeline(
                    device,
                    &module,
                    &layout,
                    "fs_translucent",
                    &v.targets,
                    v.depth_stencil.clone(),
                    1,
                )
            })
            .collect()
    }

    #[allow(clippy::too_many_arguments)]
    fn pipeline(
        &self,
        device: &wgpu::Device,
        module: &wgpu::ShaderModule,
        layout: &wgpu::PipelineLayout,
        fragment: &str,
        targets: &[Option<wgpu::ColorTargetState>],
        depth: wgpu::DepthStencilState,
        samples: u32,
    ) -> wgpu::RenderPipeline {
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(fragment),
            layout: Some(layout),
            vertex: wgpu::VertexState {
                module,
                entry_point: Some("vs_content"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState {
                cull_mode: Some(wgpu::Face::Back),
                ..Default::default()
            },
            depth_stencil: Some(depth),
            multisample: wgpu::MultisampleState {
                count: samples,
                ..Default::default()
            },
            fragment: Some(wgpu::FragmentState {
                module,
                entry_point: Some(fragment),
                compilation_options: Default::default(),
                targets,
            }),
            multiview_mask: None,
            cache: None,
        })
    }

    fn prim_of_entity(&self, e: &Entity, frame: &GameFrame<'_>) -> Prim {
        let mut axes = e.axes();
        // Seen from inside, a translucent box is a volume the eye is in: its far faces
        // are drawn (one axis mirrored turns every face's winding inward), and tint
        // what lies beyond as its near faces do from outside.
        if !e.is_opaque() && e.contains(frame.camera.eye) {
            axes[0] = -axes[0];
        }
        let a = |v: DVec3| [v.x as f32, v.y as f32, v.z as f32, 0.0];
        Prim {
            center: frame.relative(e.center).to_array(),
            kind: 0,
            axis_x: a(axes[0]),
            axis_y: a(axes[1]),
            axis_z: a(axes[2]),
            color: linear(e.color, e.opacity),
        }
    }

    fn prim_of_particle(p: &Particle, frame: &GameFrame<'_>) -> Prim {
        Prim {
            center: frame.relative(p.center).to_array(),
            kind: 1,
            axis_x: [p.half_size, 0.0, 0.0, 0.0],
            color: linear(p.color, p.opacity),
            ..Prim::default()
        }
    }
}

fn linear(c: [u8; 3], opacity: f32) -> [f32; 4] {
    let [r, g, b] = c.map(srgb_to_linear);
    [r, g, b, opacity.clamp(0.0, 1.0)]
}

/// The translucent fragment entry, after a technique's prelude and the content shader.
const TRANSLUCENT_ENTRY: &str = "
@fragment
fn fs_translucent(in: ContentOut) -> OitOutput {
    return oit_output(in.position, in.color);
}
";

impl GameStages for ContentStages {
    fn stages(&self) -> Stages {
        Stages {
            opaque: self.content.entities.iter().any(Entity::is_opaque),
            translucent: !self.objects.is_empty(),
            ..Stages::default()
        }
    }

    fn translucent_objects(&self) -> &[TranslucentObject] {
        &self.objects
    }

    fn context(&self) -> Option<&GpuContext> {
        Some(&self.ctx)
    }

    fn translucent_contract_id(&self) -> Option<u64> {
        self.contract
    }

    fn follow_contract(&mut self, ctx: &GpuContext, contract: &TranslucentContract) {
        if self.follow {
            self.translucent_pipelines_for(&ctx.device, contract);
            self.contract = Some(contract.id);
        }
    }

    fn prepare(&mut self, ctx: &GpuContext, frame: &GameFrame<'_>) {
        if self.stages().opaque {
            self.opaque_pipeline_for(&ctx.device, frame.opaque_samples);
        }
        // The camera's right and up, for particles: the basis of `Camera::view_proj`.
        let (right, true_up) = frame.camera.right_up();
        let v = |d: DVec3| [d.x as f32, d.y as f32, d.z as f32, 0.0];
        let view = View {
            view_proj: frame.view_proj.to_cols_array_2d(),
            right: v(right),
            up: v(true_up),
            sun: frame.sun_dir.to_array(),
            ambient: frame.ambient,
            brightness: frame.brightness,
            _pad: [0.0; 3],
        };
        // In the frame's encoder: a frame recorded before this one keeps its own view.
        let mut written = frame.write_buffer(&self.view, 0, bytemuck::bytes_of(&view));
        let opaque: Vec<Prim> = self
            .content
            .entities
            .iter()
            .filter(|e| e.is_opaque())
            .map(|e| self.prim_of_entity(e, frame))
            .collect();
        let mut translucent: Vec<Prim> = self
            .content
            .particles
            .iter()
            .map(|p| Self::prim_of_particle(p, frame))
            .chain(
                self.content
                    .entities
                    .iter()
                    .filter(|e| !e.is_opaque())
                    .map(|e| self.prim_of_entity(e, frame)),
            )
            .collect();
        if let Some(order) = frame.order {
            // An object cut at a plane it reaches through is in the order once per part.
            translucent = order
                .iter()
                .filter_map(|&i| translucent.get(i as usize).copied())
                .collect();
            let need = (translucent.len() * std::mem::size_of::<Prim>()) as u64;
            if self.translucent.buffer.size() < need {
                self.translucent = Buffer::new(
                    &ctx.device,
                    &self.prims_layout,
                    "content_translucent",
                    2 * translucent.len(),
                );
            }
        }
        for (buffer, prims) in [
            (&mut self.opaque, opaque),
            (&mut self.translucent, translucent),
        ] {
            buffer.count = prims.len() as u32;
            written =
                written.and(frame.write_buffer(&buffer.buffer, 0, bytemuck::cast_slice(&prims)));
        }
        // The buffers are made for these writes (`set_content` grows them).
        if let Err(e) = written {
            log::error!("content: {e}");
        }
    }

    fn opaque(&self, pass: &mut wgpu::RenderPass<'_>, _frame: &GameFrame<'_>) {
        let Some((_, pipeline)) = &self.opaque_pipeline else {
            return;
        };
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &self.view_group, &[]);
        pass.set_bind_group(1, &self.opaque.group, &[]);
        pass.draw(0..VERTICES, 0..self.opaque.count);
    }

    fn translucent(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        _frame: &GameFrame<'_>,
        variant: usize,
        objects: Range<usize>,
    ) {
        let Some(pipeline) = self
            .contract
            .and_then(|id| self.translucent_pipelines.get(&id))
            .and_then(|p| p.get(variant))
        else {
            return;
        };
        let end = (objects.end as u32).min(self.translucent.count);
        let start = (objects.start as u32).min(end);
        if start == end {
            return;
        }
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &self.view_group, &[]);
        pass.set_bind_group(1, &self.translucent.group, &[]);
        pass.draw(0..VERTICES, start..end);
    }
}
