//! [`ContentStages`]: a [`Content`] drawn through a renderer's stages.

use std::collections::HashMap;
use std::ops::Range;

use glam::DVec3;

use super::{Content, Entity, Particle};
use crate::error::scoped;
use crate::ladder::{self, Limit, Need};
use crate::light_volume::light_wgsl;
use crate::stages::{
    DEPTH_COMPARE, GameFrame, GameStages, OIT_GROUP, Stages, TranslucentContract, TranslucentObject,
};
use crate::textures::srgb_to_linear;
use crate::{DEPTH_FORMAT, GpuContext, QuadFetch, Renderer, Result, SCENE_FORMAT, Technique};

/// One primitive of the instances (`Prim` in `content.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct Prim {
    /// Camera-relative centre.
    center: [f32; 3],
    /// 0: box, 1: particle.
    kind: u32,
    /// Box axes scaled by the half extents; a particle's half size in `axis_x[0]`.
    axis_x: [f32; 3],
    /// The light it gives off, in multiples of its linear colour.
    emissive: f32,
    axis_y: [f32; 4],
    axis_z: [f32; 4],
    /// Linear colour (lit per face in the shader) and opacity.
    color: [f32; 4],
}

/// Bytes of one primitive.
const PRIM_BYTES: u64 = std::mem::size_of::<Prim>() as u64;

/// The content shader's uniform (`View` in `content.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct View {
    view_proj: [[f32; 4]; 4],
    right: [f32; 4],
    up: [f32; 4],
}

/// The fields of [`Prim`] as per-instance vertex attributes (`content_instanced.wgsl`).
const PRIM_ATTRIBUTES: [wgpu::VertexAttribute; 7] = [
    attribute(
        0,
        wgpu::VertexFormat::Float32x3,
        std::mem::offset_of!(Prim, center),
    ),
    attribute(
        1,
        wgpu::VertexFormat::Uint32,
        std::mem::offset_of!(Prim, kind),
    ),
    attribute(
        2,
        wgpu::VertexFormat::Float32x3,
        std::mem::offset_of!(Prim, axis_x),
    ),
    attribute(
        3,
        wgpu::VertexFormat::Float32,
        std::mem::offset_of!(Prim, emissive),
    ),
    attribute(
        4,
        wgpu::VertexFormat::Float32x4,
        std::mem::offset_of!(Prim, axis_y),
    ),
    attribute(
        5,
        wgpu::VertexFormat::Float32x4,
        std::mem::offset_of!(Prim, axis_z),
    ),
    attribute(
        6,
        wgpu::VertexFormat::Float32x4,
        std::mem::offset_of!(Prim, color),
    ),
];

const fn attribute(
    location: u32,
    format: wgpu::VertexFormat,
    offset: usize,
) -> wgpu::VertexAttribute {
    wgpu::VertexAttribute {
        format,
        offset: offset as u64,
        shader_location: location,
    }
}

/// One [`Prim`] per instance.
const PRIM_INSTANCES: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: PRIM_BYTES,
    step_mode: wgpu::VertexStepMode::Instance,
    attributes: &PRIM_ATTRIBUTES,
};

/// What the content needs of a device to fetch its instances the way `fetch` says.
fn needs(fetch: QuadFetch) -> Vec<Need> {
    match fetch {
        QuadFetch::Storage => vec![
            Need::Downlevel(wgpu::DownlevelFlags::VERTEX_STORAGE),
            Need::Limit(Limit::StorageBuffersPerStage, 1),
            Need::Limit(Limit::StorageBufferBindingSize, PRIM_BYTES),
        ],
        QuadFetch::Instanced => vec![
            Need::Limit(Limit::VertexBuffers, 1),
            Need::Limit(Limit::VertexAttributes, PRIM_ATTRIBUTES.len() as u64),
            Need::Limit(Limit::VertexBufferArrayStride, PRIM_BYTES),
        ],
    }
}

/// Draws a [`Content`] through a renderer's stages: pass it to `Renderer::render`
/// each frame. Its pipelines are built when a frame first needs them (the translucent ones
/// per technique contract, kept by its id; the opaque one per sample count), or ahead with
/// [`ContentStages::prebuild`]. Its instances reach the shader the way the renderer's
/// world gets its quads (`RendererConfig::quad_fetch`): from storage buffers, or as
/// instanced vertex attributes where the vertex stage has no storage buffers.
#[derive(Debug)]
pub struct ContentStages {
    /// The renderer's context its resources are made on.
    ctx: GpuContext,
    content: Content,
    fetch: QuadFetch,
    module_src: String,
    view: wgpu::Buffer,
    view_layout: wgpu::BindGroupLayout,
    /// The instances' group (storage fetch).
    prims_layout: wgpu::BindGroupLayout,
    /// The renderer's light volume group (`Renderer::light_layout`), after the instances'.
    light_layout: wgpu::BindGroupLayout,
    view_group: wgpu::BindGroup,
    /// Instances a buffer holds at most: a storage binding's or a buffer's size.
    per_page: usize,
    /// Opaque boxes, and the translucent things in draw order.
    opaque: Instances,
    translucent: Instances,
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

/// Instances in buffers of at most `per_page` each (pages), for as many as the content
/// holds: a storage binding (128 MiB by default, 1.68 million primitives) or a buffer
/// cannot hold every count a game may draw.
#[derive(Debug, Default)]
struct Instances {
    pages: Vec<Page>,
    /// Instances it has room for.
    capacity: usize,
    /// Instances written this frame.
    count: usize,
    /// Per instance in draw order: whether it is a particle (6 vertices, else a box's 36),
    /// and where the run of its kind it lies in ends.
    particle: Vec<bool>,
    run_end: Vec<u32>,
}

/// One buffer of instances, with its group for the storage fetch.
#[derive(Debug)]
struct Page {
    buffer: wgpu::Buffer,
    group: Option<wgpu::BindGroup>,
}

impl Instances {
    /// Room for `capacity` instances (at least one) in pages of at most `per_page`.
    fn new(
        device: &wgpu::Device,
        fetch: QuadFetch,
        layout: &wgpu::BindGroupLayout,
        label: &str,
        capacity: usize,
        per_page: usize,
    ) -> Self {
        let capacity = capacity.max(1);
        let pages = (0..capacity.div_ceil(per_page))
            .map(|p| {
                let n = per_page.min(capacity - p * per_page);
                let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size: n as u64 * PRIM_BYTES,
                    usage: match fetch {
                        QuadFetch::Storage => wgpu::BufferUsages::STORAGE,
                        QuadFetch::Instanced => wgpu::BufferUsages::VERTEX,
                    } | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                let group = (fetch == QuadFetch::Storage).then(|| {
                    crate::gpu::bind_group(device, label, layout, &[buffer.as_entire_binding()])
                });
                Page { buffer, group }
            })
            .collect();
        Self {
            pages,
            capacity,
            ..Self::default()
        }
    }

    /// Writes `prims` (at most its capacity) page by page in `frame`'s encoder (a frame
    /// recorded before this one keeps its own), and notes their kinds.
    fn write(&mut self, frame: &GameFrame<'_>, prims: &[Prim], per_page: usize) -> Result<()> {
        self.count = prims.len().min(self.capacity);
        let mut written = Ok(());
        for (page, chunk) in self.pages.iter().zip(prims[..self.count].chunks(per_page)) {
            written = written.and(frame.write_buffer(&page.buffer, 0, bytemuck::cast_slice(chunk)));
        }
        self.note_kinds(&prims[..self.count]);
        written
    }

    /// Notes the kind of each of `prims` and where its run of one kind ends.
    fn note_kinds(&mut self, prims: &[Prim]) {
        self.count = prims.len();
        self.particle.clear();
        self.particle
            .extend(prims.iter().map(|p| p.kind == PARTICLE));
        self.run_end.clear();
        self.run_end.resize(self.count, 0);
        for i in (0..self.count).rev() {
            let same = i + 1 < self.count && self.particle[i + 1] == self.particle[i];
            self.run_end[i] = if same {
                self.run_end[i + 1]
            } else {
                (i + 1) as u32
            };
        }
    }

    /// Draws instances `range` (clamped to those written): page by page, each run of one
    /// kind in one draw.
    fn draw(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        fetch: QuadFetch,
        range: Range<usize>,
        per_page: usize,
    ) {
        let end = range.end.min(self.count);
        let mut i = range.start.min(end);
        let mut bound = None;
        while i < end {
            let page = i / per_page;
            let Some(p) = self.pages.get(page) else {
                return;
            };
            if bound != Some(page) {
                match (&p.group, fetch) {
                    (Some(group), QuadFetch::Storage) => {
                        crate::cost::set_bind_group(1, Some(group), &[]);
                        pass.set_bind_group(1, group, &[]);
                    }
                    _ => {
                        crate::cost::set_vertex_buffer();
                        pass.set_vertex_buffer(0, p.buffer.slice(..));
                    }
                }
                bound = Some(page);
            }
            let base = page * per_page;
            let j = (self.run_end[i] as usize).min(end).min(base + per_page);
            let vertices = if self.particle[i] {
                PARTICLE_VERTICES
            } else {
                BOX_VERTICES
            };
            crate::cost::draw(1, 1);
            pass.draw(0..vertices, (i - base) as u32..(j - base) as u32);
            i = j;
        }
    }
}

const CONTENT_WGSL: &str = include_str!("content.wgsl");
const STORAGE_WGSL: &str = include_str!("content_storage.wgsl");
const INSTANCED_WGSL: &str = include_str!("content_instanced.wgsl");

/// `Prim::kind` of a particle.
const PARTICLE: u32 = 1;
/// Vertices drawn per box (its 6 faces) and per particle (one square).
const BOX_VERTICES: u32 = 36;
const PARTICLE_VERTICES: u32 = 6;

impl ContentStages {
    /// Resources for `content` on `renderer`'s device, lit like `renderer`'s world, its
    /// instances fetched the way the renderer fetches the world's quads
    /// (`RendererConfig::quad_fetch`: from storage buffers, or as instanced vertex
    /// attributes on a device without storage buffers in the vertex stage, such as
    /// WebGL2's). Fails on a value outside its range ([`Content::validate`]:
    /// `Error::InvalidContent`), on a device that lacks what that fetch needs
    /// (`Error::Unsupported` naming it), or when the device cannot hold the instances
    /// (`Error::Gpu`).
    pub fn new(renderer: &Renderer, content: Content) -> Result<Self> {
        content.validate()?;
        let ctx = renderer.context();
        let fetch = renderer.config().quad_fetch.unwrap_or_default();
        ladder::check("drawing game content", &needs(fetch), &ctx.caps)?;
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
        let layout = |label, entries: &[wgpu::BindGroupLayoutEntry]| {
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(label),
                entries,
            })
        };
        let view_layout = layout("content_view_layout", &[uniform]);
        // No storage binding at all where the fetch takes none (WebGL2 has none to give).
        let prims_layout = match fetch {
            QuadFetch::Storage => layout("content_prims_layout", &[storage]),
            QuadFetch::Instanced => layout("content_prims_layout", &[]),
        };
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
        let limits = &ctx.caps.limits;
        let page_bytes = match fetch {
            QuadFetch::Storage => limits
                .max_storage_buffer_binding_size
                .min(limits.max_buffer_size),
            QuadFetch::Instanced => limits.max_buffer_size,
        };
        let per_page = usize::try_from(page_bytes / PRIM_BYTES)
            .unwrap_or(usize::MAX)
            .max(1);
        let module_src = CONTENT_WGSL.to_owned()
            + &light_wgsl(light_group(fetch))
            + match fetch {
                QuadFetch::Storage => STORAGE_WGSL,
                QuadFetch::Instanced => INSTANCED_WGSL,
            };
        let mut stages = Self {
            ctx: ctx.clone(),
            content: Content::default(),
            fetch,
            module_src,
            view,
            view_layout,
            prims_layout,
            light_layout: renderer.light_layout().clone(),
            view_group,
            per_page,
            opaque: Instances::default(),
            translucent: Instances::default(),
            opaque_pipeline: None,
            translucent_pipelines: HashMap::new(),
            contract: None,
            follow: true,
            built: 0,
            objects: Vec::new(),
        };
        let (opaque, translucent) = counts(&content);
        stages.allocate(ctx, opaque, translucent)?;
        Self::objects_into(&content, &mut stages.objects);
        stages.content = content;
        Ok(stages)
    }

    /// How its instances reach the shader: the renderer's quad fetch when it was made.
    pub fn fetch(&self) -> QuadFetch {
        self.fetch
    }

    /// Replaces what it draws (moving particles, a turning cube). The instance buffers grow
    /// when needed (to twice what is needed, at most a buffer more, so that content growing
    /// a little rebuilds nothing), over as many buffers as the device's binding size
    /// needs. Fails, keeping what it drew, on a `ctx` of another device than the one it
    /// was made on (`Error::OtherDevice`, before anything is made: its buffers live on its
    /// own device), on a value outside its range (`Error::InvalidContent`) or when the
    /// device cannot hold the instances (`Error::Gpu`).
    pub fn set_content(&mut self, ctx: &GpuContext, content: Content) -> Result<()> {
        if !ctx.same_device(&self.ctx) {
            return Err(crate::Error::OtherDevice(format!(
                "ContentStages::set_content was given a context of {}, the content was made \
                 on {} (pass the renderer's context, Renderer::context, or a clone of it)",
                ctx.caps.adapter_name, self.ctx.caps.adapter_name
            )));
        }
        content.validate()?;
        let (opaque, translucent) = counts(&content);
        if opaque > self.opaque.capacity || translucent > self.translucent.capacity {
            let room = |n: usize| n + n.min(self.per_page);
            self.allocate(ctx, room(opaque), room(translucent))?;
        }
        Self::objects_into(&content, &mut self.objects);
        self.content = content;
        Ok(())
    }

    /// New instance buffers with room for `opaque` and `translucent` instances; on failure
    /// (out of memory) the old ones stay.
    fn allocate(&mut self, ctx: &GpuContext, opaque: usize, translucent: usize) -> Result<()> {
        let device = &ctx.device;
        let (fetch, per_page, layout) = (self.fetch, self.per_page, &self.prims_layout);
        let make = |label, n| Instances::new(device, fetch, layout, label, n, per_page);
        let (o, t) = scoped(device, "allocating the game content's instances", || {
            (
                make("content_opaque", opaque),
                make("content_translucent", translucent),
            )
        })?;
        (self.opaque, self.translucent) = (o, t);
        Ok(())
    }

    /// The translucent objects in instance order before sorting: particles, then the
    /// translucent entities, into `objects` (its room kept from call to call).
    fn objects_into(content: &Content, objects: &mut Vec<TranslucentObject>) {
        objects.clear();
        objects.extend(
            content
                .particles
                .iter()
                // A square facing the camera: its corners, whichever way it turns.
                .map(|p| {
                    TranslucentObject::ball(
                        p.center,
                        f64::from(p.half_size) * std::f64::consts::SQRT_2,
                    )
                })
                .chain(
                    content
                        .entities
                        .iter()
                        .filter(|e| !e.is_opaque())
                        .map(|e| TranslucentObject::aabb(e.center, e.world_half_extents())),
                ),
        );
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

    /// The groups of its pipelines before [`OIT_GROUP`]: the view, the instances' group
    /// where they come from storage buffers, the light volume's.
    fn groups(&self) -> Vec<Option<&wgpu::BindGroupLayout>> {
        match self.fetch {
            QuadFetch::Storage => vec![
                Some(&self.view_layout),
                Some(&self.prims_layout),
                Some(&self.light_layout),
            ],
            QuadFetch::Instanced => vec![Some(&self.view_layout), Some(&self.light_layout)],
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
                bind_group_layouts: &self.groups(),
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
                let mut groups = self.groups();
                groups.resize(OIT_GROUP as usize, None);
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
        let buffers: &[Option<wgpu::VertexBufferLayout<'_>>] = match self.fetch {
            QuadFetch::Storage => &[],
            QuadFetch::Instanced => &[Some(PRIM_INSTANCES)],
        };
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(fragment),
            layout: Some(layout),
            vertex: wgpu::VertexState {
                module,
                entry_point: Some("vs_content"),
                compilation_options: Default::default(),
                buffers,
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
        let a3 = |v: DVec3| [v.x as f32, v.y as f32, v.z as f32];
        let a4 = |v: DVec3| [v.x as f32, v.y as f32, v.z as f32, 0.0];
        Prim {
            center: frame.relative(e.center).to_array(),
            kind: 0,
            axis_x: a3(axes[0]),
            emissive: e.emissive,
            axis_y: a4(axes[1]),
            axis_z: a4(axes[2]),
            color: linear(e.color, e.opacity),
        }
    }

    fn prim_of_particle(p: &Particle, frame: &GameFrame<'_>) -> Prim {
        Prim {
            center: frame.relative(p.center).to_array(),
            kind: PARTICLE,
            axis_x: [p.half_size, 0.0, 0.0],
            emissive: p.emissive,
            color: linear(p.color, p.opacity),
            ..Prim::default()
        }
    }

    /// Binds what every draw of its pipelines reads besides the instances: the view and
    /// the frame's light volume.
    fn bind_view(&self, pass: &mut wgpu::RenderPass<'_>, frame: &GameFrame<'_>) {
        crate::cost::set_bind_group(0, Some(&self.view_group), &[]);
        pass.set_bind_group(0, &self.view_group, &[]);
        let light = light_group(self.fetch);
        crate::cost::set_bind_group(light, Some(frame.light), &[]);
        pass.set_bind_group(light, frame.light, &[]);
    }
}

/// The group the light volume is bound at: after the instances' where they have one.
fn light_group(fetch: QuadFetch) -> u32 {
    match fetch {
        QuadFetch::Storage => 2,
        QuadFetch::Instanced => 1,
    }
}

/// Opaque and translucent instances of `content`.
fn counts(content: &Content) -> (usize, usize) {
    let opaque = content.entities.iter().filter(|e| e.is_opaque()).count();
    (
        opaque,
        content.particles.len() + content.entities.len() - opaque,
    )
}

/// An sRGB colour and an opacity as the shader takes them: linear, the opacity as it is
/// (checked to lie in 0 to 1).
fn linear(c: [u8; 3], opacity: f32) -> [f32; 4] {
    let [r, g, b] = c.map(srgb_to_linear);
    [r, g, b, opacity]
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
            translucent = order
                .iter()
                .filter_map(|&i| translucent.get(i as usize).copied())
                .collect();
        }
        let per_page = self.per_page;
        let device = &ctx.device;
        for (instances, prims, label) in [
            (&mut self.opaque, opaque, "content_opaque"),
            (&mut self.translucent, translucent, "content_translucent"),
        ] {
            // An object cut at a plane it reaches through is in the order once per part:
            // the instances may outgrow what `set_content` made room for.
            if prims.len() > instances.capacity {
                *instances = Instances::new(
                    device,
                    self.fetch,
                    &self.prims_layout,
                    label,
                    2 * prims.len(),
                    per_page,
                );
            }
            written = written.and(instances.write(frame, &prims, per_page));
        }
        if let Err(e) = written {
            log::error!("content: {e}");
        }
    }

    fn opaque(&self, pass: &mut wgpu::RenderPass<'_>, frame: &GameFrame<'_>) {
        let Some((_, pipeline)) = &self.opaque_pipeline else {
            return;
        };
        crate::cost::set_pipeline(pipeline);
        pass.set_pipeline(pipeline);
        self.bind_view(pass, frame);
        self.opaque
            .draw(pass, self.fetch, 0..self.opaque.count, self.per_page);
    }

    fn translucent(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        frame: &GameFrame<'_>,
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
        if objects.start >= objects.end.min(self.translucent.count) {
            return;
        }
        crate::cost::set_pipeline(pipeline);
        pass.set_pipeline(pipeline);
        self.bind_view(pass, frame);
        self.translucent
            .draw(pass, self.fetch, objects, self.per_page);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wgsl_layout::{assert_layout, field, parse};

    #[test]
    fn prim_and_view_match_the_wgsl() {
        let module = parse(&(CONTENT_WGSL.to_owned() + &light_wgsl(2) + STORAGE_WGSL));
        assert_layout::<Prim>(
            &module,
            "Prim",
            &[
                field!(Prim, center),
                field!(Prim, kind),
                field!(Prim, axis_x),
                field!(Prim, emissive),
                field!(Prim, axis_y),
                field!(Prim, axis_z),
                field!(Prim, color),
            ],
        );
        assert_layout::<View>(
            &module,
            "View",
            &[
                field!(View, view_proj),
                field!(View, right),
                field!(View, up),
            ],
        );
        // The instanced entry point parses too, its attributes at the fields' offsets.
        let _ = parse(&(CONTENT_WGSL.to_owned() + &light_wgsl(1) + INSTANCED_WGSL));
        assert_eq!(PRIM_ATTRIBUTES[3].offset, 28);
        assert_eq!(PRIM_BYTES, 80);
    }

    /// Runs of one kind end where the kind changes.
    #[test]
    fn runs_end_where_the_kind_changes() {
        let prims: Vec<Prim> = [1, 1, 0, 0, 0, 1, 0]
            .iter()
            .map(|&kind| Prim {
                kind,
                ..Prim::default()
            })
            .collect();
        let mut inst = Instances::default();
        inst.note_kinds(&prims);
        assert_eq!(inst.run_end, vec![2, 2, 5, 5, 5, 6, 7]);
        assert_eq!(inst.particle[..3], [true, true, false]);
        inst.note_kinds(&[]);
        assert!(inst.run_end.is_empty());
    }
}
