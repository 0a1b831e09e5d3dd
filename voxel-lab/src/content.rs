//! A game's own things in the world, as the lab, the demo and the tests draw them through the
//! renderer's stages (`voxel_render::stages`): camera-facing translucent particles
//! (bubbles, snow, smoke) and box entities turned any way (an opaque boat or mob, a glass
//! or slime cube), lit like the world's faces.
//!
//! [`Content`] is the description (scene files' `[[particles]]` and `[[entities]]`, the
//! random generator, the demo's toggles); [`ContentStages`] draws it. Every translucent
//! particle and box is one object the sorted techniques order with the chunks; the instance
//! buffer is written in that order each frame. The CPU ray march (the `raymarch` module) draws
//! the same things from the same description.

use std::collections::HashMap;
use std::ops::Range;

use glam::{DQuat, DVec3, Mat3};
use voxel_render::stages::{
    GameFrame, GameStages, OIT_GROUP, Stages, TranslucentContract, TranslucentObject,
};
use voxel_render::{DEPTH_FORMAT, GpuContext, Renderer, SCENE_FORMAT};

/// A camera-facing square of translucent colour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Particle {
    /// Centre, world blocks.
    pub center: DVec3,
    /// Half the side of the square, blocks.
    pub half_size: f32,
    /// sRGB colour.
    pub color: [u8; 3],
    /// Opacity, 0 to 1.
    pub opacity: f32,
}

/// A box turned any way: opaque (opacity 1) or translucent (its faces toward the eye drawn
/// as one layer).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Entity {
    /// Centre, world blocks.
    pub center: DVec3,
    /// Half extents along its own axes, blocks.
    pub half_extents: [f32; 3],
    /// Its orientation.
    pub rotation: DQuat,
    /// sRGB colour.
    pub color: [u8; 3],
    /// Opacity: 1 is opaque.
    pub opacity: f32,
}

impl Entity {
    /// Whether it is drawn with the opaque geometry.
    pub fn is_opaque(&self) -> bool {
        self.opacity >= 1.0
    }

    /// Whether point `p` lies inside it (strictly).
    pub fn contains(&self, p: DVec3) -> bool {
        let o = p - self.center;
        self.axes().iter().all(|a| {
            let len2 = a.length_squared();
            len2 > 0.0 && o.dot(*a).abs() < len2
        })
    }

    /// Half the sides of the axis-aligned box around it, world blocks.
    pub fn world_half_extents(&self) -> DVec3 {
        self.axes().iter().map(|a| a.abs()).sum()
    }

    /// Its axes scaled by the half extents (columns), world directions.
    pub fn axes(&self) -> [DVec3; 3] {
        let h = self.half_extents.map(f64::from);
        [
            self.rotation * DVec3::X * h[0],
            self.rotation * DVec3::Y * h[1],
            self.rotation * DVec3::Z * h[2],
        ]
    }
}

/// Particles and entities.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Content {
    /// Translucent particles.
    pub particles: Vec<Particle>,
    /// Entities, opaque or translucent.
    pub entities: Vec<Entity>,
}

impl Content {
    /// Whether there is nothing.
    pub fn is_empty(&self) -> bool {
        self.particles.is_empty() && self.entities.is_empty()
    }

    /// `count` particles spread over the box `min..max` by a deterministic sequence from
    /// `seed`.
    pub fn scatter(
        min: DVec3,
        max: DVec3,
        count: usize,
        seed: u64,
        half_size: f32,
        color: [u8; 3],
        opacity: f32,
    ) -> Vec<Particle> {
        let mut s = seed ^ 0x9e37_79b9_7f4a_7c15;
        let mut next = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..count)
            .map(|_| Particle {
                center: min + (max - min) * DVec3::new(next(), next(), next()),
                half_size,
                color,
                opacity,
            })
            .collect()
    }
}

/// sRGB to linear, the same conversion textures get.
pub fn srgb_to_linear(c: u8) -> f32 {
    let c = f32::from(c) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The lit colour of an entity face with world normal `normal`: Lambert with the sun plus
/// ambient, as the world's faces (without ambient occlusion).
pub fn face_light(normal: DVec3, sun: DVec3, ambient: f64) -> f64 {
    ambient + (1.0 - ambient) * normal.dot(sun).max(0.0)
}

/// The light of a particle: a face turned to the sky.
pub fn particle_light(sun: DVec3, ambient: f64) -> f64 {
    ambient + (1.0 - ambient) * sun.y.max(0.0)
}

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
}

/// Draws a [`Content`] through a renderer's stages.
#[derive(Debug)]
pub struct ContentStages {
    content: Content,
    sun: DVec3,
    ambient: f64,
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
        let group =
            voxel_render::stages::bind_group(device, label, layout, &[buffer.as_entire_binding()]);
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
        let config = renderer.config();
        let buffer = |label, n: usize| Buffer::new(device, &prims_layout, label, n);
        let opaque_count = content.entities.iter().filter(|e| e.is_opaque()).count();
        let translucent_count = content.particles.len() + content.entities.len() - opaque_count;
        let objects = Self::objects(&content);
        Self {
            sun: DVec3::from(config.sun_dir.map(f64::from))
                .try_normalize()
                .unwrap_or(DVec3::Y),
            ambient: f64::from(config.ambient),
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
            built: 0,
            objects,
            content,
        }
    }

    /// What it draws.
    pub fn content(&self) -> &Content {
        &self.content
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

    /// Builds (or rebuilds, after a technique switch) the pipelines for `renderer`'s
    /// configuration and contract. Call before drawing a frame (cheap when nothing
    /// changed).
    pub fn update_pipelines(&mut self, renderer: &mut Renderer) -> voxel_render::Result<()> {
        self.opaque_pipeline_for(renderer);
        let contract = renderer.translucent_contract()?;
        if !self.translucent_pipelines.contains_key(&contract.id) {
            let device = renderer.context().device.clone();
            let pipelines = self.translucent_for(&device, &contract);
            self.built += pipelines.len();
            self.translucent_pipelines.insert(contract.id, pipelines);
        }
        self.contract = Some(contract.id);
        Ok(())
    }

    /// The opaque pipeline for `renderer`'s sample count, built if it has none.
    fn opaque_pipeline_for(&mut self, renderer: &Renderer) {
        let samples = if renderer.config().msaa { 4 } else { 1 };
        let ctx = renderer.context().clone();
        let device = &ctx.device;
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
                    depth_compare: Some(voxel_render::stages::DEPTH_COMPARE),
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
    pub fn prebuild(
        &mut self,
        renderer: &mut Renderer,
        technique: voxel_render::Technique,
    ) -> voxel_render::Result<()> {
        self.opaque_pipeline_for(renderer);
        let contract = renderer.translucent_contract_for(technique)?;
        if !self.translucent_pipelines.contains_key(&contract.id) {
            let device = renderer.context().device.clone();
            let pipelines = self.translucent_for(&device, &contract);
            self.built += pipelines.len();
            self.translucent_pipelines.insert(contract.id, pipelines);
        }
        Ok(())
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

    fn translucent_contract_id(&self) -> Option<u64> {
        self.contract
    }

    fn prepare(&mut self, ctx: &GpuContext, frame: &GameFrame<'_>) {
        // The camera's right and up, for particles: the basis of `Camera::view_proj`.
        let f = frame.camera.unit_forward();
        let up = if f.y.abs() > 0.999 {
            DVec3::Z
        } else {
            DVec3::Y
        };
        let right = f.cross(up).normalize();
        let true_up = right.cross(f);
        let v = |d: DVec3| [d.x as f32, d.y as f32, d.z as f32, 0.0];
        let view = View {
            view_proj: frame.view_proj.to_cols_array_2d(),
            right: v(right),
            up: v(true_up),
            sun: [self.sun.x as f32, self.sun.y as f32, self.sun.z as f32],
            ambient: self.ambient as f32,
        };
        ctx.queue
            .write_buffer(&self.view, 0, bytemuck::bytes_of(&view));
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
        for (buffer, prims) in [
            (&mut self.opaque, opaque),
            (&mut self.translucent, translucent),
        ] {
            buffer.count = prims.len() as u32;
            if !prims.is_empty() {
                ctx.queue
                    .write_buffer(&buffer.buffer, 0, bytemuck::cast_slice(&prims));
            }
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

/// The unit vectors of a rotation given as yaw (about y), pitch (about x) and roll (about
/// z), degrees, applied in that order.
pub fn rotation(yaw_pitch_roll_deg: [f64; 3]) -> DQuat {
    let [y, p, r] = yaw_pitch_roll_deg.map(f64::to_radians);
    DQuat::from_rotation_y(y) * DQuat::from_rotation_x(p) * DQuat::from_rotation_z(r)
}

/// A box's world normal of face `axis` (0 x, 1 y, 2 z) on side `sign` (±1).
pub fn box_normal(rotation: DQuat, axis: usize, sign: f64) -> DVec3 {
    let mut n = DVec3::ZERO;
    n[axis] = sign;
    rotation * n
}

/// For tests: an entity's faces in world space as matrices (unused by the renderer).
pub fn entity_matrix(e: &Entity) -> Mat3 {
    let axes = e.axes().map(|a| a.as_vec3());
    Mat3::from_cols(axes[0], axes[1], axes[2])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scatter_is_deterministic_and_inside() {
        let a = Content::scatter(DVec3::ZERO, DVec3::splat(4.0), 50, 7, 0.1, [1, 2, 3], 0.5);
        let b = Content::scatter(DVec3::ZERO, DVec3::splat(4.0), 50, 7, 0.1, [1, 2, 3], 0.5);
        assert_eq!(a, b);
        assert!(
            a.iter()
                .all(|p| p.center.cmpge(DVec3::ZERO).all()
                    && p.center.cmple(DVec3::splat(4.0)).all())
        );
        assert_ne!(a[0].center, a[1].center);
    }

    #[test]
    fn rotation_turns_axes() {
        let q = rotation([90.0, 0.0, 0.0]);
        let x = q * DVec3::X;
        assert!((x - DVec3::new(0.0, 0.0, -1.0)).length() < 1e-9);
        assert!((box_normal(q, 1, 1.0) - DVec3::Y).length() < 1e-9);
        let e = Entity {
            center: DVec3::ZERO,
            half_extents: [1.0, 2.0, 3.0],
            rotation: DQuat::IDENTITY,
            color: [0; 3],
            opacity: 1.0,
        };
        assert_eq!(entity_matrix(&e).y_axis, glam::Vec3::new(0.0, 2.0, 0.0));
    }
}
