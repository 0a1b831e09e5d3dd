//! Plumbing every pass shares: shader assembly (with constants generated from Rust),
//! pipeline builders for chunk quads and fullscreen triangles, render targets, and one
//! helper that records a render pass with its attachments and timing.

use crate::cost;
use crate::fetch::QuadFetch;
use crate::timing::{GpuPass, Timer};
use crate::{DEPTH_FORMAT, GpuContext, SCENE_FORMAT};

/// How shaders read a depth texture: as an unfilterable float texture (`texture_2d<f32>`,
/// the depth in `.x`, which WebGPU allows for depth formats), sampled at a texel's centre
/// with a nearest, non-filtering sampler ([`depth_sampler`], [`DEPTH_UV_WGSL`]). GLSL has
/// no load from depth textures (naga refuses `textureLoad` of a `texture_depth_2d` for GL
/// and GLES). A `texelFetch` of it as a float texture would read through no sampler
/// object on wgpu's GL backend, so with the texture's own filter, linear by default; GLES
/// 3.0 counts a depth texture filtered linearly and not compared as incomplete (and a read
/// of an incomplete texture as 0), which ANGLE, WebGL2 in Chrome, enforces. Mesa's
/// llvmpipe returns the texel either way, so the tests here cannot tell: the nearest
/// sampler keeps the read valid under the rule.
pub(crate) const DEPTH_READ: wgpu::TextureSampleType =
    wgpu::TextureSampleType::Float { filterable: false };

/// WGSL: `depth_uv(xy, size)`, the coordinates of the centre of the texel under pixel `xy`
/// of a texture of `size`, where a nearest sampler returns exactly that texel.
pub(crate) const DEPTH_UV_WGSL: &str = "
// The centre of the texel under pixel `xy` of a depth texture of `size` (`gpu.rs`,
// DEPTH_READ): sampled there with a nearest sampler, the texel's exact depth.
fn depth_uv(xy: vec2<f32>, size: vec2<u32>) -> vec2<f32> {
    return (floor(xy) + 0.5) / vec2<f32>(size);
}
";

/// The sampler depth textures are read with ([`DEPTH_READ`]): nearest, no mipmaps,
/// clamped.
pub(crate) fn depth_sampler(device: &wgpu::Device) -> wgpu::Sampler {
    device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("depth_sampler"),
        ..Default::default()
    })
}

/// A layout entry for [`depth_sampler`] in the fragment stage.
pub(crate) fn depth_sampler_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::NonFiltering),
        count: None,
    }
}

/// WGSL shared by every fullscreen pipeline.
pub(crate) const FULLSCREEN_WGSL: &str = include_str!("shaders/fullscreen.wgsl");

/// A shader module made of `parts` concatenated (shared code first).
pub fn shader(device: &wgpu::Device, label: &str, parts: &[&str]) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(parts.concat().into()),
    })
}

/// WGSL `const` declarations made from Rust values, so that a constant the CPU and GPU
/// share has one source: prepend [`WgslConsts::finish`] to the shader.
#[derive(Debug, Default)]
pub(crate) struct WgslConsts(String);

impl WgslConsts {
    /// A `u32` constant.
    pub(crate) fn u32(mut self, name: &str, value: u32) -> Self {
        self.0 += &format!("const {name}: u32 = {value}u;\n");
        self
    }

    /// An `i32` constant.
    pub(crate) fn i32(mut self, name: &str, value: i32) -> Self {
        self.0 += &format!("const {name}: i32 = {value}i;\n");
        self
    }

    /// An `f32` constant.
    pub(crate) fn f32(mut self, name: &str, value: f32) -> Self {
        self.0 += &format!("const {name}: f32 = {value:?};\n");
        self
    }

    /// A `u32` array constant.
    pub(crate) fn u32_array(mut self, name: &str, values: &[u32]) -> Self {
        let items: Vec<String> = values.iter().map(|v| format!("{v}u")).collect();
        self.0 += &format!(
            "const {name} = array<u32, {}>({});\n",
            values.len(),
            items.join(", ")
        );
        self
    }

    /// The declarations.
    pub(crate) fn finish(self) -> String {
        self.0
    }
}

/// How a chunk pipeline tests and writes depth.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum DepthMode {
    /// Reverse-Z test (nearer passes) and write: opaque, cutout, stipple.
    Write,
    /// Reverse-Z test, no write: blended translucent passes.
    ReadOnly,
    /// Keep the farthest fragment and write it: back-layer peeling.
    WriteFarthest,
}

/// The depth state of `mode` (format [`DEPTH_FORMAT`], reverse-Z).
pub(crate) fn depth_state(mode: DepthMode) -> wgpu::DepthStencilState {
    let (write, compare) = match mode {
        DepthMode::Write => (true, wgpu::CompareFunction::Greater),
        DepthMode::ReadOnly => (false, wgpu::CompareFunction::Greater),
        DepthMode::WriteFarthest => (true, wgpu::CompareFunction::Less),
    };
    wgpu::DepthStencilState {
        format: DEPTH_FORMAT,
        depth_write_enabled: Some(write),
        depth_compare: Some(compare),
        stencil: wgpu::StencilState::default(),
        bias: wgpu::DepthBiasState::default(),
    }
}

/// A pipeline that draws chunk quads with `common.wgsl`'s vertex entry points (`vs_main`,
/// or `vs_solid` for opaque quads, of the groups' [`crate::QuadFetch`]).
#[derive(Debug)]
pub(crate) struct ChunkPipeline<'a> {
    /// Debug label.
    pub label: &'a str,
    /// The module holding `common.wgsl`'s vertex entries and the fragment entry.
    pub module: &'a wgpu::ShaderModule,
    /// The fragment entry point.
    pub fragment_entry: &'a str,
    /// Bind group layouts: group 0 the scene, group 1 the chunk, then the technique's
    /// (`SharedLayouts::with`), and how quads are fetched.
    pub groups: &'a ChunkGroups<'a>,
    /// Colour targets.
    pub targets: &'a [Option<wgpu::ColorTargetState>],
    /// Depth test and write.
    pub depth: DepthMode,
    /// Samples per pixel (1 or 4).
    pub samples: u32,
}

/// The bind group layouts of a chunk pipeline, and how it fetches quads
/// (`SharedLayouts::with`).
#[derive(Debug, Clone)]
pub(crate) struct ChunkGroups<'a> {
    /// Groups 0, 1, then the technique's.
    pub layouts: Vec<Option<&'a wgpu::BindGroupLayout>>,
    /// How the pipeline fetches quads: its vertex entry point and buffers.
    pub fetch: QuadFetch,
}

/// A translucent chunk pipeline in its two variants: culling back faces (the eye in air),
/// and drawing both sides (the eye inside a translucent volume, whose surfaces it sees from
/// behind; see `medium.rs`).
#[derive(Debug)]
pub(crate) struct SidedPipeline {
    culled: wgpu::RenderPipeline,
    two_sided: wgpu::RenderPipeline,
}

impl SidedPipeline {
    /// The variant for a frame.
    pub(crate) fn get(&self, two_sided: bool) -> &wgpu::RenderPipeline {
        if two_sided {
            &self.two_sided
        } else {
            &self.culled
        }
    }
}

impl ChunkPipeline<'_> {
    /// Creates the pipeline (back faces culled).
    pub(crate) fn build(&self, device: &wgpu::Device) -> wgpu::RenderPipeline {
        self.build_with(device, false, Some(wgpu::Face::Back))
    }

    /// Creates an opaque pipeline: back faces culled, quads grown against T-junction
    /// cracks (`vs_solid`; see `OPAQUE_EXPANSION_PX` in `bindings.rs`).
    pub(crate) fn build_solid(&self, device: &wgpu::Device) -> wgpu::RenderPipeline {
        self.build_with(device, true, Some(wgpu::Face::Back))
    }

    /// Creates the pipeline drawing both sides of every face.
    pub(crate) fn build_two_sided(&self, device: &wgpu::Device) -> wgpu::RenderPipeline {
        self.build_with(device, false, None)
    }

    /// Creates the pipeline drawing both sides of every face, the quads grown against
    /// T-junction cracks: a depth pass of where paths end, which a sliver between two
    /// merged quads must not leave open.
    pub(crate) fn build_two_sided_solid(&self, device: &wgpu::Device) -> wgpu::RenderPipeline {
        self.build_with(device, true, None)
    }

    /// Creates both variants of a translucent pipeline (see [`SidedPipeline`]).
    pub(crate) fn build_sided(&self, device: &wgpu::Device) -> SidedPipeline {
        SidedPipeline {
            culled: self.build_with(device, false, Some(wgpu::Face::Back)),
            two_sided: self.build_with(device, false, None),
        }
    }

    fn build_with(
        &self,
        device: &wgpu::Device,
        solid: bool,
        cull_mode: Option<wgpu::Face>,
    ) -> wgpu::RenderPipeline {
        count_pipeline();
        let fetch = self.groups.fetch;
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(self.label),
            bind_group_layouts: &self.groups.layouts,
            immediate_size: 0,
        });
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(self.label),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: self.module,
                entry_point: Some(fetch.vertex_entry(solid)),
                compilation_options: Default::default(),
                buffers: fetch.vertex_buffers(),
            },
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleList,
                front_face: wgpu::FrontFace::Ccw,
                // Faces are entry surfaces seen from their front (the mesher emits the face
                // of each side of a boundary); back faces only count from inside a volume.
                cull_mode,
                ..Default::default()
            },
            depth_stencil: Some(depth_state(self.depth)),
            multisample: wgpu::MultisampleState {
                count: self.samples,
                ..Default::default()
            },
            fragment: Some(wgpu::FragmentState {
                module: self.module,
                entry_point: Some(self.fragment_entry),
                compilation_options: Default::default(),
                targets: self.targets,
            }),
            multiview_mask: None,
            cache: None,
        })
    }
}

thread_local! {
    /// Render pipelines the renderer built on this thread (see [`pipelines_built`]).
    static PIPELINES_BUILT: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
}

fn count_pipeline() {
    PIPELINES_BUILT.with(|n| n.set(n.get() + 1));
}

/// How many render pipelines the renderer's own passes have built on the calling thread
/// (a renderer builds them on the thread that calls it): what a frame or a call cost in
/// pipeline compilation, the usual cause of a hitch. A game's own pipelines are not
/// counted.
pub fn pipelines_built() -> u64 {
    PIPELINES_BUILT.with(std::cell::Cell::get)
}

/// A fullscreen-triangle pipeline: `source` (a fragment shader, after `fullscreen.wgsl`,
/// whose `vs_fullscreen` it uses).
#[derive(Debug)]
pub(crate) struct FullscreenPipeline<'a> {
    /// Debug label.
    pub label: &'a str,
    /// WGSL of the fragment shader and what it needs.
    pub source: &'a str,
    /// The fragment entry point.
    pub fragment_entry: &'a str,
    /// Bind group layouts.
    pub groups: &'a [Option<&'a wgpu::BindGroupLayout>],
    /// Colour targets.
    pub targets: &'a [Option<wgpu::ColorTargetState>],
    /// A depth target that always passes and is written (a depth copy).
    pub writes_depth: bool,
    /// Values of the shader's pipeline-overridable constants.
    pub constants: &'a [(&'a str, f64)],
}

impl FullscreenPipeline<'_> {
    /// Creates the pipeline.
    pub(crate) fn build(&self, device: &wgpu::Device) -> wgpu::RenderPipeline {
        count_pipeline();
        let module = &shader(device, self.label, &[FULLSCREEN_WGSL, self.source]);
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(self.label),
            bind_group_layouts: self.groups,
            immediate_size: 0,
        });
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(self.label),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module,
                entry_point: Some("vs_fullscreen"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: self.writes_depth.then(|| wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Always),
                stencil: wgpu::StencilState::default(),
                bias: wgpu::DepthBiasState::default(),
            }),
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module,
                entry_point: Some(self.fragment_entry),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants: self.constants,
                    ..Default::default()
                },
                targets: self.targets,
            }),
            multiview_mask: None,
            cache: None,
        })
    }
}

/// A colour target of the HDR scene format with `blend`.
pub(crate) fn scene_target(blend: Option<wgpu::BlendState>) -> Option<wgpu::ColorTargetState> {
    Some(wgpu::ColorTargetState {
        format: SCENE_FORMAT,
        blend,
        write_mask: wgpu::ColorWrites::ALL,
    })
}

/// A layout entry for a non-filterable 2D texture read with `textureLoad` in fragments
/// (a depth texture: [`DEPTH_READ`]).
pub(crate) fn texture_entry(
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

/// A layout entry for a buffer seen by `visibility`.
pub(crate) fn buffer_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
    ty: wgpu::BufferBindingType,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// A bind group layout of `entries`.
pub(crate) fn layout(
    device: &wgpu::Device,
    label: &str,
    entries: &[wgpu::BindGroupLayoutEntry],
) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries,
    })
}

/// A full-screen pass running `source`'s `fs_composite` over the scene colour with
/// `ALPHA_BLENDING`, reading two unfilterable float textures: how the weighted (WBOIT) and
/// moment-based (MBOIT) techniques lay their sums over the opaque image. Returns the
/// textures' layout and the pipeline.
pub(crate) fn composite_pipeline(
    device: &wgpu::Device,
    label: &str,
    source: &str,
) -> (wgpu::BindGroupLayout, wgpu::RenderPipeline) {
    let float = wgpu::TextureSampleType::Float { filterable: false };
    let layout = textures_layout(device, &format!("{label}_layout"), float, 2);
    let pipeline = FullscreenPipeline {
        label,
        source,
        fragment_entry: "fs_composite",
        groups: &[Some(&layout)],
        targets: &[scene_target(Some(wgpu::BlendState::ALPHA_BLENDING))],
        writes_depth: false,
        constants: &[],
    }
    .build(device);
    (layout, pipeline)
}

/// A layout of `count` fragment textures at bindings 0, 1, ... of `sample_type`.
pub(crate) fn textures_layout(
    device: &wgpu::Device,
    label: &str,
    sample_type: wgpu::TextureSampleType,
    count: u32,
) -> wgpu::BindGroupLayout {
    let entries: Vec<wgpu::BindGroupLayoutEntry> =
        (0..count).map(|i| texture_entry(i, sample_type)).collect();
    layout(device, label, &entries)
}

/// A bind group of `resources` at bindings 0, 1, ...
pub fn bind_group(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    resources: &[wgpu::BindingResource<'_>],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry<'_>> = resources
        .iter()
        .enumerate()
        .map(|(i, r)| wgpu::BindGroupEntry {
            binding: i as u32,
            resource: r.clone(),
        })
        .collect();
    cost::created_bind_group();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &entries,
    })
}

/// A uniform buffer holding a zeroed `T` (written before each use) and a bind group of it
/// alone, at binding 0 of `layout`.
pub(crate) fn zeroed_uniform<T: bytemuck::Pod>(
    device: &wgpu::Device,
    (buffer_label, group_label): (&str, &str),
    layout: &wgpu::BindGroupLayout,
) -> (wgpu::Buffer, wgpu::BindGroup) {
    use wgpu::util::DeviceExt;
    let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(buffer_label),
        contents: bytemuck::bytes_of(&T::zeroed()),
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
    });
    let group = bind_group(device, group_label, layout, &[buffer.as_entire_binding()]);
    (buffer, group)
}

/// A bind group of texture views at bindings 0, 1, ...
pub(crate) fn texture_group(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    views: &[&wgpu::TextureView],
) -> wgpu::BindGroup {
    let resources: Vec<wgpu::BindingResource<'_>> = views
        .iter()
        .map(|v| wgpu::BindingResource::TextureView(v))
        .collect();
    bind_group(device, label, layout, &resources)
}

/// A 2D render target and its default view.
#[derive(Debug)]
pub struct Target {
    /// The texture.
    pub texture: wgpu::Texture,
    /// Its default view.
    pub view: wgpu::TextureView,
}

/// What a [`Target`] is.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TargetDesc<'a> {
    /// Debug label.
    pub label: &'a str,
    /// Texel format.
    pub format: wgpu::TextureFormat,
    /// Usages.
    pub usage: wgpu::TextureUsages,
    /// Width and height in pixels.
    pub size: (u32, u32),
    /// Samples per pixel.
    pub samples: u32,
}

impl TargetDesc<'_> {
    /// Creates the texture and its view.
    pub(crate) fn create(&self, device: &wgpu::Device) -> Target {
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some(self.label),
            size: wgpu::Extent3d {
                width: self.size.0,
                height: self.size.1,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: self.samples,
            dimension: wgpu::TextureDimension::D2,
            format: self.format,
            usage: self.usage,
            view_formats: &[],
        });
        let view = texture.create_view(&Default::default());
        Target { texture, view }
    }
}

/// A single-sample 2D texture of `format` and `usage` at `size`, with its default view.
pub fn target(
    device: &wgpu::Device,
    label: &str,
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
    size: (u32, u32),
) -> Target {
    TargetDesc {
        label,
        format,
        usage,
        size,
        samples: 1,
    }
    .create(device)
}

/// A colour attachment that loads what is there and stores the result.
pub fn load(view: &wgpu::TextureView) -> Option<wgpu::RenderPassColorAttachment<'_>> {
    attachment(view, wgpu::LoadOp::Load, None)
}

/// A colour attachment cleared to `color`.
pub(crate) fn clear(
    view: &wgpu::TextureView,
    color: wgpu::Color,
) -> Option<wgpu::RenderPassColorAttachment<'_>> {
    attachment(view, wgpu::LoadOp::Clear(color), None)
}

/// A colour attachment with `load`, resolved into `resolve` when given (MSAA).
pub(crate) fn attachment<'a>(
    view: &'a wgpu::TextureView,
    load: wgpu::LoadOp<wgpu::Color>,
    resolve: Option<&'a wgpu::TextureView>,
) -> Option<wgpu::RenderPassColorAttachment<'a>> {
    Some(wgpu::RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: resolve,
        ops: wgpu::Operations {
            load,
            store: wgpu::StoreOp::Store,
        },
    })
}

/// The depth attachment of a pass.
#[derive(Clone, Copy, Debug, Default)]
pub enum Depth<'a> {
    /// No depth attachment.
    #[default]
    None,
    /// Tested, never written (translucent passes against the opaque depth).
    ReadOnly(&'a wgpu::TextureView),
    /// Tested and written, starting from what is there.
    Load(&'a wgpu::TextureView),
    /// Cleared to the value, then tested and written.
    Clear(&'a wgpu::TextureView, f32),
}

impl<'a> Depth<'a> {
    /// The pass attachment (`None` for [`Depth::None`]).
    pub fn attachment(self) -> Option<wgpu::RenderPassDepthStencilAttachment<'a>> {
        let ops = |load| {
            Some(wgpu::Operations {
                load,
                store: wgpu::StoreOp::Store,
            })
        };
        let (view, depth_ops) = match self {
            Depth::None => return None,
            Depth::ReadOnly(view) => (view, None),
            Depth::Load(view) => (view, ops(wgpu::LoadOp::Load)),
            Depth::Clear(view, v) => (view, ops(wgpu::LoadOp::Clear(v))),
        };
        Some(wgpu::RenderPassDepthStencilAttachment {
            view,
            depth_ops,
            stencil_ops: None,
        })
    }
}

/// One render pass: what it draws into and how it is timed.
#[derive(Debug)]
pub(crate) struct Pass<'a> {
    /// Debug label.
    pub label: &'a str,
    /// Colour attachments ([`load`], [`clear`], `attachment`).
    pub colors: &'a [Option<wgpu::RenderPassColorAttachment<'a>>],
    /// Depth attachment.
    pub depth: Depth<'a>,
    /// Which kind of GPU work its time counts as (`None`: untimed).
    pub timing: Option<GpuPass>,
    /// Occlusion queries the pass writes to.
    pub occlusion: Option<&'a wgpu::QuerySet>,
    /// Whether its pipelines blend into the colour attachments (each written sample then
    /// reads the texel too): what a counted frame's bytes assume (`cost`).
    pub blends: bool,
    /// Textures each fragment reads once (a composite's sums, a copy's source), for a
    /// counted frame's bytes.
    pub reads: &'a [&'a wgpu::TextureView],
}

impl<'a> Pass<'a> {
    /// A timed pass into `colors` without depth, blending.
    pub(crate) fn new(
        label: &'a str,
        timing: GpuPass,
        colors: &'a [Option<wgpu::RenderPassColorAttachment<'a>>],
    ) -> Self {
        Self {
            label,
            colors,
            depth: Depth::None,
            timing: Some(timing),
            occlusion: None,
            blends: true,
            reads: &[],
        }
    }

    /// The same pass with `depth`.
    pub(crate) fn depth(self, depth: Depth<'a>) -> Self {
        Self { depth, ..self }
    }

    /// The same pass writing its colour attachments without blending.
    pub(crate) fn opaque(self) -> Self {
        Self {
            blends: false,
            ..self
        }
    }

    /// The same pass with each fragment reading `textures` once.
    pub(crate) fn reads(self, textures: &'a [&'a wgpu::TextureView]) -> Self {
        Self {
            reads: textures,
            ..self
        }
    }

    /// What the pass's attachments cost per sample, and its clears ([`crate::cost`]).
    fn shape(&self) -> cost::PassShape {
        let mut shape = cost::PassShape::default();
        for c in self.colors.iter().flatten() {
            let t = c.view.texture();
            shape.size = (t.width(), t.height());
            let bytes = cost::texel_bytes(t.format());
            shape.write_bytes += bytes;
            if self.blends {
                shape.read_bytes += bytes;
            }
            if matches!(c.ops.load, wgpu::LoadOp::Clear(_)) {
                shape.clear_bytes += cost::texture_bytes(t);
            }
        }
        let depth = match self.depth {
            Depth::None => None,
            Depth::ReadOnly(v) => Some((v, false, false)),
            Depth::Load(v) => Some((v, true, false)),
            Depth::Clear(v, _) => Some((v, true, true)),
        };
        if let Some((view, writes, clears)) = depth {
            let t = view.texture();
            shape.size = (t.width(), t.height());
            let bytes = cost::texel_bytes(t.format());
            shape.read_bytes += bytes;
            if writes {
                shape.write_bytes += bytes;
            }
            if clears {
                shape.clear_bytes += cost::texture_bytes(t);
            }
        }
        shape.texture_bytes = self
            .reads
            .iter()
            .map(|v| cost::texel_bytes(v.texture().format()))
            .sum();
        shape
    }

    /// Records the pass into `encoder` (timed by `timer` when given): `body` sets
    /// pipelines and draws. In a counted frame (`cost`) what `body` records is
    /// counted, and the pass's fragments and samples are measured where the device can.
    pub(crate) fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        timer: Option<&Timer>,
        body: impl FnOnce(&mut CountedPass<'_, '_>),
    ) {
        let query = self
            .timing
            .zip(timer)
            .map(|(pass, t)| t.begin(pass, encoder));
        let counted = cost::counting().then(|| self.shape());
        let slots = counted.and_then(|shape| {
            cost::begin_pass(self.label, self.timing, shape, self.occlusion.is_some())
        });
        let own_occlusion = slots.as_ref().and_then(|s| s.occlusion.as_ref());
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some(self.label),
                color_attachments: self.colors,
                depth_stencil_attachment: self.depth.attachment(),
                timestamp_writes: query
                    .as_ref()
                    .and_then(|q| q.render_pass_timestamp_writes()),
                occlusion_query_set: self.occlusion.or(own_occlusion),
                multiview_mask: None,
            });
            if let Some(s) = &slots {
                if let Some(stats) = &s.statistics {
                    pass.begin_pipeline_statistics_query(stats, s.index);
                }
                if own_occlusion.is_some() {
                    pass.begin_occlusion_query(s.index);
                }
            }
            body(&mut CountedPass { raw: &mut pass });
            if let Some(s) = &slots {
                if own_occlusion.is_some() {
                    pass.end_occlusion_query();
                }
                if s.statistics.is_some() {
                    pass.end_pipeline_statistics_query();
                }
            }
        }
        if counted.is_some() {
            cost::end_pass();
        }
        if let (Some(q), Some(t)) = (query, timer) {
            t.end(encoder, q);
        }
    }
}

/// A render pass being recorded by [`Pass::record`]: the commands the renderer records
/// go through it, so that a counted frame counts them (`cost`); it derefs to the
/// `wgpu::RenderPass` for everything else.
#[derive(Debug)]
pub(crate) struct CountedPass<'p, 'e> {
    raw: &'p mut wgpu::RenderPass<'e>,
}

impl<'e> CountedPass<'_, 'e> {
    /// `RenderPass::set_pipeline`.
    pub(crate) fn set_pipeline(&mut self, pipeline: &wgpu::RenderPipeline) {
        cost::set_pipeline(pipeline);
        self.raw.set_pipeline(pipeline);
    }

    /// `RenderPass::set_bind_group`.
    pub(crate) fn set_bind_group(&mut self, index: u32, group: &wgpu::BindGroup, offsets: &[u32]) {
        cost::set_bind_group(index, Some(group), offsets);
        self.raw.set_bind_group(index, group, offsets);
    }

    /// `RenderPass::set_vertex_buffer`.
    pub(crate) fn set_vertex_buffer(&mut self, slot: u32, slice: wgpu::BufferSlice<'_>) {
        cost::set_vertex_buffer();
        self.raw.set_vertex_buffer(slot, slice);
    }

    /// `RenderPass::set_scissor_rect`.
    pub(crate) fn set_scissor_rect(&mut self, x: u32, y: u32, width: u32, height: u32) {
        cost::scissor(u64::from(width) * u64::from(height));
        self.raw.set_scissor_rect(x, y, width, height);
    }

    /// `RenderPass::draw`.
    pub(crate) fn draw(&mut self, vertices: std::ops::Range<u32>, instances: std::ops::Range<u32>) {
        cost::draw(1, 1);
        self.raw.draw(vertices, instances);
    }

    /// Draws the full-screen triangle of `fullscreen.wgsl` (three vertices, one instance).
    pub(crate) fn draw_full_screen(&mut self) {
        cost::full_screen();
        self.raw.draw(0..3, 0..1);
    }

    /// `RenderPass::multi_draw_indirect`: one call, `count` draws.
    pub(crate) fn multi_draw_indirect(&mut self, buffer: &wgpu::Buffer, offset: u64, count: u32) {
        cost::draw(1, count);
        self.raw.multi_draw_indirect(buffer, offset, count);
    }

    /// Hands the raw pass to a game's own drawing (`stages::GameStages`): counted
    /// as one call into the game; what it sets is unknown afterwards.
    pub(crate) fn game<R>(&mut self, f: impl FnOnce(&mut wgpu::RenderPass<'e>) -> R) -> R {
        cost::game_call();
        let r = f(self.raw);
        cost::game_call_done();
        r
    }
}

impl<'e> std::ops::Deref for CountedPass<'_, 'e> {
    type Target = wgpu::RenderPass<'e>;
    fn deref(&self) -> &Self::Target {
        self.raw
    }
}

impl std::ops::DerefMut for CountedPass<'_, '_> {
    fn deref_mut(&mut self) -> &mut Self::Target {
        self.raw
    }
}

/// The depth state of a pipeline a game draws over a finished frame, tested against the
/// frame's depth (`Renderer::scene_depth`, attached read-only): reverse-Z, so nearer is
/// greater, and positions camera-relative (`Camera::view_proj` of `Renderer::drawn_camera`).
pub fn overlay_depth() -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format: crate::DEPTH_FORMAT,
        depth_write_enabled: Some(false),
        depth_compare: Some(wgpu::CompareFunction::GreaterEqual),
        stencil: wgpu::StencilState::default(),
        bias: wgpu::DepthBiasState::default(),
    }
}

/// A pipeline a game draws over a finished frame into `format` (the renderer's output):
/// its vertex shader makes positions from vertex indices (no vertex buffers), its bind
/// groups are laid out from the shader, and with `depth_tested` it is tested against the
/// frame's depth ([`overlay_depth`]). What the window example's selection box and HUD use.
pub fn overlay_pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    entry_points: (&str, &str),
    format: wgpu::TextureFormat,
    topology: wgpu::PrimitiveTopology,
    depth_tested: bool,
) -> wgpu::RenderPipeline {
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(entry_points.1),
        layout: None,
        vertex: wgpu::VertexState {
            module,
            entry_point: Some(entry_points.0),
            compilation_options: Default::default(),
            buffers: &[],
        },
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some(entry_points.1),
            compilation_options: Default::default(),
            targets: &[Some(format.into())],
        }),
        primitive: wgpu::PrimitiveState {
            topology,
            ..Default::default()
        },
        depth_stencil: depth_tested.then(overlay_depth),
        multisample: wgpu::MultisampleState::default(),
        multiview_mask: None,
        cache: None,
    })
}

/// Submits what `encoder` holds and replaces it with a fresh one, so that a technique can
/// wait for GPU results in the middle of a frame (the exact methods do; real-time ones
/// never do). Commands keep their order: the rest of the frame follows in the new encoder.
/// On a device lost meanwhile (a game's draw can land anywhere) nothing is submitted and
/// the error says so: what was recorded after the loss may refer to resources the lost
/// device never made.
pub(crate) fn flush(ctx: &GpuContext, encoder: &mut wgpu::CommandEncoder) -> crate::Result<()> {
    ctx.check_device()?;
    let fresh = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("frame_continued"),
        });
    let done = std::mem::replace(encoder, fresh);
    ctx.queue.submit([done.finish()]);
    Ok(())
}

/// Copies one depth target into another of the same size: a texture copy where the device
/// copies depth textures, else a full-screen pass that writes each texel's depth. wgpu's GL
/// backend copies textures through a colour framebuffer, so a depth texture copy does
/// nothing there (no error either); those are the backends without
/// `DownlevelFlags::DEPTH_TEXTURE_AND_BUFFER_COPIES` ("GLES/WebGL don't support this"), and
/// the flag decides.
#[derive(Debug)]
pub(crate) struct DepthCopy {
    /// The pass, where texture copies cannot.
    pass: Option<CopyPass>,
}

/// What [`DepthCopy`]'s pass is made of.
#[derive(Debug)]
struct CopyPass {
    device: wgpu::Device,
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    sampler: wgpu::Sampler,
}

impl DepthCopy {
    /// The copy for the device of `ctx`.
    pub(crate) fn new(ctx: &GpuContext) -> Self {
        let copies = ctx
            .caps
            .downlevel
            .contains(wgpu::DownlevelFlags::DEPTH_TEXTURE_AND_BUFFER_COPIES);
        let pass = (!copies).then(|| {
            let device = &ctx.device;
            let layout = layout(
                device,
                "depth_copy_layout",
                &[texture_entry(0, DEPTH_READ), depth_sampler_entry(1)],
            );
            let source = DEPTH_UV_WGSL.to_owned() + include_str!("shaders/depth_copy.wgsl");
            let pipeline = FullscreenPipeline {
                label: "depth_copy",
                source: &source,
                fragment_entry: "fs_copy_depth",
                groups: &[Some(&layout)],
                targets: &[],
                writes_depth: true,
                constants: &[],
            }
            .build(device);
            CopyPass {
                device: device.clone(),
                pipeline,
                layout,
                sampler: depth_sampler(device),
            }
        });
        Self { pass }
    }

    /// Records the copy of `src` into `dst` (timed as `timing`, when a pass).
    pub(crate) fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        src: &Target,
        dst: &Target,
        timing: GpuPass,
        timer: Option<&Timer>,
    ) {
        let Some(CopyPass {
            device,
            pipeline,
            layout,
            sampler,
        }) = &self.pass
        else {
            encoder.copy_texture_to_texture(
                src.texture.as_image_copy(),
                dst.texture.as_image_copy(),
                src.texture.size(),
            );
            cost::copied(
                "depth_copy",
                Some(timing),
                cost::texture_bytes(&src.texture),
            );
            return;
        };
        let group = bind_group(
            device,
            "depth_copy",
            layout,
            &[
                wgpu::BindingResource::TextureView(&src.view),
                wgpu::BindingResource::Sampler(sampler),
            ],
        );
        Pass::new("depth_copy", timing, &[])
            .depth(Depth::Clear(&dst.view, 0.0))
            .reads(&[&src.view])
            .record(encoder, timer, |pass| {
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, &group, &[]);
                pass.draw_full_screen();
            });
    }
}
