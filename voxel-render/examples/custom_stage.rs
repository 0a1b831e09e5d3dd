//! A game loop with its own shaders for its own things in the world, composed with the
//! crate's water and glass by whatever transparency technique is in force: an opaque crate
//! floating half in a pool, a translucent cube turning through the water surface, and
//! bubbles rising to it. `examples/entities.rs` draws the same with the ready-made helper
//! (`voxel_render::content`) in a few lines; this is the path for a game that needs its own
//! shader (here: instances in a vertex buffer, which WebGL2 runs). The game writes its
//! shaders (`custom_stage.wgsl`) and joins the frame's stages (`voxel_render::stages`): its
//! opaque pipeline draws after the world's opaque passes, and one translucent pipeline per
//! pass of the technique ends in `oit_output`, rebuilt when the technique's contract changes.
//!
//! Headless: `cargo run --release -p voxel-render --example custom_stage -- --frames 60 --out
//! custom_stage.png [--technique sorted-quads]`.

use std::ops::Range;

use glam::{DQuat, DVec3};
use voxel_render::stages::{
    DEPTH_COMPARE, GameFrame, GameStages, OIT_GROUP, Stages, TranslucentContract, TranslucentObject,
};
use voxel_render::{DEPTH_FORMAT, GpuContext, Renderer, SCENE_FORMAT};

mod common;

const SHADER: &str = include_str!("custom_stage.wgsl");
const TRANSLUCENT_ENTRY: &str = "
@fragment
fn fs_translucent(in: GameOut) -> OitOutput {
    return oit_output(in.position, in.color);
}
";

/// One box or particle, as the vertex shader reads it (per instance).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Instance {
    center: [f32; 4],
    axes: [[f32; 4]; 3],
    color: [f32; 4],
}

/// A thing of the game: a box (`half` extents, turned by `rotation`) or a particle.
#[derive(Clone, Copy)]
struct Thing {
    center: DVec3,
    half: DVec3,
    rotation: DQuat,
    particle: bool,
    /// Linear colour and opacity.
    color: [f32; 4],
}

impl Thing {
    /// Half the sides of the axis-aligned box around the turned box.
    fn world_half(&self) -> DVec3 {
        [DVec3::X, DVec3::Y, DVec3::Z]
            .into_iter()
            .zip(self.half.to_array())
            .map(|(axis, h)| (self.rotation * axis * h).abs())
            .sum()
    }
}

/// The game's stages: its pipelines, buffers and this frame's things.
struct Game {
    view: wgpu::Buffer,
    view_group: wgpu::BindGroup,
    view_layout: wgpu::BindGroupLayout,
    module: String,
    opaque_pipeline: wgpu::RenderPipeline,
    /// The technique's passes the pipelines were built for, and one pipeline per pass.
    translucent: Option<(u64, Vec<wgpu::RenderPipeline>)>,
    opaque_things: Vec<Thing>,
    things: Vec<Thing>,
    objects: Vec<TranslucentObject>,
    opaque_buffer: wgpu::Buffer,
    buffer: wgpu::Buffer,
}

const MAX_THINGS: u64 = 4096;

impl Game {
    fn new(device: &wgpu::Device) -> Self {
        let view_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("game_view"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        let view = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("game_view"),
            size: 128,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let view_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("game_view"),
            layout: &view_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: view.as_entire_binding(),
            }],
        });
        let instances = |label| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: MAX_THINGS * std::mem::size_of::<Instance>() as u64,
                usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        // Opaque: the scene colour and depth, reverse-Z, tested and written like terrain.
        let depth = wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(true),
            depth_compare: Some(DEPTH_COMPARE),
            stencil: Default::default(),
            bias: Default::default(),
        };
        let target = wgpu::ColorTargetState::from(SCENE_FORMAT);
        let opaque_pipeline = pipeline(
            device,
            &view_layout,
            None,
            SHADER,
            "fs_opaque",
            &[Some(target)],
            depth,
        );
        Self {
            view,
            view_group,
            view_layout,
            module: SHADER.to_owned(),
            opaque_pipeline,
            translucent: None,
            opaque_things: Vec::new(),
            things: Vec::new(),
            objects: Vec::new(),
            opaque_buffer: instances("game_opaque"),
            buffer: instances("game_translucent"),
        }
    }

    /// The world at `t` seconds: the crate bobbing, the cube turning, the bubbles rising.
    fn update(&mut self, t: f64) {
        let crate_box = Thing {
            center: common::crate_center(t),
            half: DVec3::new(1.0, 0.6, 1.0),
            rotation: DQuat::from_rotation_y(0.3),
            particle: false,
            color: [0.35, 0.18, 0.07, 1.0],
        };
        let (center, rotation) = common::cube_pose(t);
        let cube = Thing {
            center,
            half: DVec3::splat(1.2),
            rotation,
            particle: false,
            color: [0.1, 0.7, 0.25, 0.5],
        };
        let bubbles = (0..1000u64).map(|i| {
            let (center, half) = common::bubble(i, t);
            Thing {
                center,
                half: DVec3::splat(half),
                rotation: DQuat::IDENTITY,
                particle: true,
                color: [0.85, 0.92, 1.0, 0.45],
            }
        });
        self.opaque_things = vec![crate_box];
        self.things = std::iter::once(cube).chain(bubbles).collect();
        // What the sorted techniques order: a ball around each bubble (a square facing
        // the camera), the box around the turning cube.
        self.objects = self
            .things
            .iter()
            .map(|th| {
                if th.particle {
                    TranslucentObject::ball(th.center, th.half.x * std::f64::consts::SQRT_2)
                } else {
                    TranslucentObject::aabb(th.center, th.world_half())
                }
            })
            .collect();
    }

    /// One pipeline per pass of the technique in force, rebuilt when its contract changes.
    fn update_pipelines(&mut self, renderer: &mut Renderer) -> voxel_render::Result<()> {
        let contract = renderer.translucent_contract()?;
        if self.translucent.as_ref().map(|(id, _)| *id) != Some(contract.id) {
            let device = &renderer.context().device;
            let pipelines = self.translucent_pipelines(device, &contract);
            self.translucent = Some((contract.id, pipelines));
        }
        Ok(())
    }

    fn translucent_pipelines(
        &self,
        device: &wgpu::Device,
        contract: &TranslucentContract,
    ) -> Vec<wgpu::RenderPipeline> {
        contract
            .variants
            .iter()
            .map(|v| {
                // The technique's prelude declares `oit_output` for this pass.
                let source = v.wgsl.clone() + &self.module + TRANSLUCENT_ENTRY;
                pipeline(
                    device,
                    &self.view_layout,
                    Some(&v.layout),
                    &source,
                    "fs_translucent",
                    &v.targets,
                    v.depth_stencil.clone(),
                )
            })
            .collect()
    }
}

fn instance(th: &Thing, frame: &GameFrame<'_>) -> Instance {
    let axis = |a: DVec3| {
        let v = th.rotation * a;
        [v.x as f32, v.y as f32, v.z as f32, 0.0]
    };
    let c = frame.relative(th.center);
    Instance {
        center: [c.x, c.y, c.z, if th.particle { 1.0 } else { 0.0 }],
        axes: [
            axis(DVec3::X * th.half.x),
            axis(DVec3::Y * th.half.y),
            axis(DVec3::Z * th.half.z),
        ],
        color: th.color,
    }
}

impl GameStages for Game {
    fn stages(&self) -> Stages {
        Stages {
            opaque: true,
            translucent: true,
            ..Stages::default()
        }
    }

    fn translucent_objects(&self) -> &[TranslucentObject] {
        &self.objects
    }

    fn translucent_contract_id(&self) -> Option<u64> {
        self.translucent.as_ref().map(|(id, _)| *id)
    }

    fn prepare(&mut self, ctx: &GpuContext, frame: &GameFrame<'_>) {
        // The camera's basis (particles face it) and the frame's lighting.
        let f = frame.camera.forward.normalize();
        let right = f.cross(DVec3::Y).normalize();
        let up = right.cross(f);
        let v = |d: DVec3, w: f32| [d.x as f32, d.y as f32, d.z as f32, w];
        let sun = frame.sun_dir.as_dvec3();
        let light = [frame.brightness, 0.0, 0.0, 0.0];
        let mut bytes = Vec::with_capacity(128);
        bytes.extend_from_slice(bytemuck::bytes_of(&frame.view_proj.to_cols_array()));
        for row in [v(right, 0.0), v(up, 0.0), v(sun, frame.ambient), light] {
            bytes.extend_from_slice(bytemuck::bytes_of(&row));
        }
        ctx.queue.write_buffer(&self.view, 0, &bytes);
        // Sorted techniques draw the objects in `frame.order`: upload them in that order.
        let translucent: Vec<Instance> = match frame.order {
            Some(order) => order
                .iter()
                .map(|&i| instance(&self.things[i as usize], frame))
                .collect(),
            None => self.things.iter().map(|th| instance(th, frame)).collect(),
        };
        let opaque: Vec<Instance> = self
            .opaque_things
            .iter()
            .map(|th| instance(th, frame))
            .collect();
        ctx.queue
            .write_buffer(&self.buffer, 0, bytemuck::cast_slice(&translucent));
        ctx.queue
            .write_buffer(&self.opaque_buffer, 0, bytemuck::cast_slice(&opaque));
    }

    fn opaque(&self, pass: &mut wgpu::RenderPass<'_>, _frame: &GameFrame<'_>) {
        pass.set_pipeline(&self.opaque_pipeline);
        pass.set_bind_group(0, &self.view_group, &[]);
        pass.set_vertex_buffer(0, self.opaque_buffer.slice(..));
        pass.draw(0..36, 0..self.opaque_things.len() as u32);
    }

    fn translucent(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        _frame: &GameFrame<'_>,
        variant: usize,
        objects: Range<usize>,
    ) {
        let Some(pipeline) = self.translucent.as_ref().and_then(|(_, p)| p.get(variant)) else {
            return;
        };
        // The renderer has bound its group at OIT_GROUP; the game binds its own.
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &self.view_group, &[]);
        pass.set_vertex_buffer(0, self.buffer.slice(..));
        pass.draw(0..36, objects.start as u32..objects.end as u32);
    }
}

/// A pipeline of the game's shader: group 0 its view, group [`OIT_GROUP`] the technique's
/// when translucent; instances in one vertex buffer.
fn pipeline(
    device: &wgpu::Device,
    view_layout: &wgpu::BindGroupLayout,
    oit_layout: Option<&wgpu::BindGroupLayout>,
    source: &str,
    fragment: &str,
    targets: &[Option<wgpu::ColorTargetState>],
    depth: wgpu::DepthStencilState,
) -> wgpu::RenderPipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(fragment),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let mut groups = vec![Some(view_layout)];
    if let Some(oit) = oit_layout {
        groups.resize(OIT_GROUP as usize, None);
        groups.push(Some(oit));
    }
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(fragment),
        bind_group_layouts: &groups,
        immediate_size: 0,
    });
    let attributes = wgpu::vertex_attr_array![
        0 => Float32x4, 1 => Float32x4, 2 => Float32x4, 3 => Float32x4, 4 => Float32x4
    ];
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(fragment),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs_game"),
            compilation_options: Default::default(),
            buffers: &[Some(wgpu::VertexBufferLayout {
                array_stride: std::mem::size_of::<Instance>() as u64,
                step_mode: wgpu::VertexStepMode::Instance,
                attributes: &attributes,
            })],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: Some(depth),
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some(fragment),
            compilation_options: Default::default(),
            targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = common::Args::parse("custom_stage.png")?;
    let ctx = common::game_device()?;
    let (mut renderer, output, camera) = common::pool(&ctx, args.technique)?;
    let mut game = Game::new(&ctx.device);
    for frame in 0..args.frames {
        game.update(f64::from(frame) / 30.0);
        // After a technique switch (or a setting its pipelines depend on) the contract's
        // id changes and the game builds new translucent pipelines.
        game.update_pipelines(&mut renderer)?;
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        renderer.render(&mut encoder, &output.view, &camera, &mut game)?;
        ctx.queue.submit([encoder.finish()]);
    }
    common::save(&ctx, &output, &args, "with the game's own shaders")?;
    Ok(())
}
