//! The demo's own passes: the blit of a finished frame to the surface and the error map
//! against the reference, and the targets of one window size.

use voxel_render::stages::{self, Target};

/// The format frames are drawn in before they reach the surface.
pub const FRAME_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;

fn target(device: &wgpu::Device, label: &str, w: u32, h: u32) -> Target {
    use wgpu::TextureUsages as U;
    let usage = U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC | U::COPY_DST;
    stages::target(device, label, FRAME_FORMAT, usage, (w, h))
}

/// Fullscreen passes of the demo: the blit to the surface and the error map.
pub struct Post {
    layout: wgpu::BindGroupLayout,
    pub blit: wgpu::RenderPipeline,
    pub diff: wgpu::RenderPipeline,
    sampler: wgpu::Sampler,
}

const POST_WGSL: &str = r#"
struct Out { @builtin(position) clip: vec4<f32>, @location(0) uv: vec2<f32> };

@vertex
fn vs(@builtin(vertex_index) vi: u32) -> Out {
    let uv = vec2<f32>(f32((vi << 1u) & 2u), f32(vi & 2u));
    var out: Out;
    out.clip = vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
    out.uv = vec2<f32>(uv.x, 1.0 - uv.y);
    return out;
}

@group(0) @binding(0) var a: texture_2d<f32>;
@group(0) @binding(1) var b: texture_2d<f32>;
@group(0) @binding(2) var s: sampler;

override SRGB_ENCODE: bool = false;

fn encode(c: f32) -> f32 {
    if c <= 0.0031308 { return c * 12.92; }
    return 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}

@fragment
fn fs_blit(in: Out) -> @location(0) vec4<f32> {
    let c = textureSample(a, s, in.uv).rgb;
    if SRGB_ENCODE {
        return vec4<f32>(encode(c.r), encode(c.g), encode(c.b), 1.0);
    }
    return vec4<f32>(c, 1.0);
}

// Error map: the largest channel difference (in sRGB steps) between the technique's
// picture and the reference's, from black through red and yellow to white at 32/255,
// over a dim grey copy of the picture so that the scene stays readable. A difference of
// one step is rounding (the two exact methods differ by that much) and is not shown.
@fragment
fn fs_diff(in: Out) -> @location(0) vec4<f32> {
    let p = vec2<i32>(in.clip.xy);
    let x = textureLoad(a, p, 0).rgb;
    let y = textureLoad(b, p, 0).rgb;
    let d = abs(vec3<f32>(encode(x.r), encode(x.g), encode(x.b)) - vec3<f32>(encode(y.r), encode(y.g), encode(y.b)));
    let e = clamp(max(d.r, max(d.g, d.b)) * 255.0 / 32.0, 0.0, 1.0);
    let heat = clamp(vec3<f32>(e * 3.0, e * 3.0 - 1.0, e * 3.0 - 2.0), vec3<f32>(0.0), vec3<f32>(1.0));
    let grey = dot(x, vec3<f32>(0.3, 0.59, 0.11)) * 0.25;
    return vec4<f32>(select(vec3<f32>(grey), heat, e > 1.5 / 32.0), 1.0);
}
"#;

impl Post {
    pub fn new(device: &wgpu::Device, surface_format: wgpu::TextureFormat) -> Self {
        let tex = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: true },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("demo_post_layout"),
            entries: &[
                tex(0),
                tex(1),
                wgpu::BindGroupLayoutEntry {
                    binding: 2,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
            ],
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("demo_post"),
            source: wgpu::ShaderSource::Wgsl(POST_WGSL.into()),
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("demo_post"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let make = |label, entry, format: wgpu::TextureFormat| {
            let encode = if format.is_srgb() { 0.0 } else { 1.0 };
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(&pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: wgpu::PrimitiveState::default(),
                depth_stencil: None,
                multisample: wgpu::MultisampleState::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(entry),
                    compilation_options: wgpu::PipelineCompilationOptions {
                        constants: &[("SRGB_ENCODE", encode)],
                        ..Default::default()
                    },
                    targets: &[Some(wgpu::ColorTargetState {
                        format,
                        blend: None,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        Self {
            blit: make("demo_blit", "fs_blit", surface_format),
            diff: make("demo_error_map", "fs_diff", FRAME_FORMAT),
            sampler: device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("demo_blit"),
                ..Default::default()
            }),
            layout,
        }
    }

    fn group(
        &self,
        device: &wgpu::Device,
        a: &wgpu::TextureView,
        b: &wgpu::TextureView,
    ) -> wgpu::BindGroup {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("demo_post"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(a),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(b),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::Sampler(&self.sampler),
                },
            ],
        })
    }

    /// Draws `pipeline` over the whole of `target` with `group`.
    pub fn draw(
        encoder: &mut wgpu::CommandEncoder,
        pipeline: &wgpu::RenderPipeline,
        group: &wgpu::BindGroup,
        target: &wgpu::TextureView,
    ) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("demo_post"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            ..Default::default()
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, group, &[]);
        pass.draw(0..3, 0..1);
    }
}

/// Targets of one window size: the whole frame (panel included, what the surface and
/// screenshots get), and the 3D view right of the panel, with the technique's and the
/// reference's pictures for the error map.
pub struct Frames {
    pub frame: Target,
    pub view: Target,
    /// Left edge of the 3D view in the frame, pixels.
    pub view_x: u32,
    pub technique: Target,
    pub reference: Target,
    pub blit_group: wgpu::BindGroup,
    pub diff_group: wgpu::BindGroup,
}

impl Frames {
    pub fn new(device: &wgpu::Device, post: &Post, w: u32, h: u32, view_x: u32) -> Self {
        let view_w = w.saturating_sub(view_x).max(1);
        let frame = target(device, "demo_frame", w, h);
        let view = target(device, "demo_view", view_w, h);
        let technique = target(device, "demo_technique", view_w, h);
        let reference = target(device, "demo_reference", view_w, h);
        Self {
            blit_group: post.group(device, &frame.view, &frame.view),
            diff_group: post.group(device, &technique.view, &reference.view),
            frame,
            view,
            view_x,
            technique,
            reference,
        }
    }

    /// Size of the 3D view.
    pub fn view_size(&self) -> (u32, u32) {
        (self.view.texture.width(), self.view.texture.height())
    }
}
