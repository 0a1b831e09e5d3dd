//! Bevy's meshes and the world occlude each other both ways, and a game's translucent
//! entity between two panes is ordered exactly, checked against renders made without Bevy:
//!
//! - occlusion: Bevy draws unlit cubes (a cube half inside a hill, a character standing in
//!   water, a cube behind a glass pane); the reference draws the same boxes in the crate's
//!   own opaque frame stage (`FlatBoxes` below), so water, glass and the hill compose with
//!   them as the crate composes a game's opaque geometry;
//! - a translucent box and a particle as Bevy entities (`VoxelTranslucent`) between two
//!   glass panes, drawn with `sorted-quads`, against the crate's A-buffer reference of the
//!   same content.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

mod common;

use std::sync::Arc;

use bevy::asset::Assets;
use bevy::color::{Color, LinearRgba};
use bevy::mesh::{Mesh, Mesh3d};
use bevy::pbr::{MeshMaterial3d, StandardMaterial};
use bevy::shape::Cuboid;
use bevy::transform::components::Transform;
use common::{Harness, have_gpu, save, share_over_one};
use glam::DVec3;
use voxel_bevy::{VoxelShape, VoxelTechnique, VoxelTranslucent, VoxelWorld};
use voxel_core::{BlockRegistry, World, blocks};
use voxel_lab::scene::Scene;
use voxel_render::content::{Content, Entity as ContentEntity, Particle};
use voxel_render::{GameFrame, GameStages, GpuContext, Image, Renderer, Stages, Technique};

fn world(boxes: &[([i32; 3], [i32; 3], voxel_core::BlockId)]) -> World {
    let mut world = World::new(Arc::new(BlockRegistry::default()));
    for &(min, max, id) in boxes {
        voxel_lab::scene::fill_box(&mut world, min, max, id).unwrap();
    }
    world
}

/// An opaque box of one linear colour, unlit.
#[derive(Clone, Copy, Debug)]
struct FlatBox {
    center: DVec3,
    half: DVec3,
    color: [f32; 3],
}

/// The boxes drawn in the crate's opaque frame stage: what Bevy's unlit cubes are, without
/// Bevy.
struct FlatBoxes {
    boxes: Vec<FlatBox>,
    buffer: wgpu::Buffer,
    group: wgpu::BindGroup,
    pipeline: wgpu::RenderPipeline,
}

const FLAT_WGSL: &str = r"
struct Box3 { min: vec4<f32>, max: vec4<f32>, color: vec4<f32> }
struct U { view_proj: mat4x4<f32>, boxes: array<Box3, 4> }
@group(0) @binding(0) var<uniform> u: U;
struct VOut { @builtin(position) pos: vec4<f32>, @location(0) color: vec3<f32> }
@vertex
fn vs(@builtin(vertex_index) vi: u32, @builtin(instance_index) ii: u32) -> VOut {
    var idx = array<u32, 36>(0u, 2u, 6u, 0u, 6u, 4u, 1u, 3u, 7u, 1u, 7u, 5u, 0u, 1u, 5u, 0u, 5u, 4u,
        2u, 3u, 7u, 2u, 7u, 6u, 0u, 1u, 3u, 0u, 3u, 2u, 4u, 5u, 7u, 4u, 7u, 6u);
    let c = idx[vi];
    let b = u.boxes[ii];
    let p = vec3<f32>(
        select(b.min.x, b.max.x, (c & 1u) != 0u),
        select(b.min.y, b.max.y, (c & 2u) != 0u),
        select(b.min.z, b.max.z, (c & 4u) != 0u));
    var out: VOut;
    out.pos = u.view_proj * vec4<f32>(p, 1.0);
    out.color = b.color.rgb;
    return out;
}
@fragment
fn fs(in: VOut) -> @location(0) vec4<f32> { return vec4<f32>(in.color, 1.0); }
";

impl FlatBoxes {
    fn new(ctx: &GpuContext, boxes: Vec<FlatBox>) -> Self {
        assert!(boxes.len() <= 4);
        let device = &ctx.device;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("flat boxes"),
            source: wgpu::ShaderSource::Wgsl(FLAT_WGSL.into()),
        });
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("flat boxes"),
            size: 64 + 4 * 48,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: None,
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
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: buffer.as_entire_binding(),
            }],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: None,
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("flat boxes"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: Some(wgpu::DepthStencilState {
                format: voxel_render::DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(voxel_render::stages::DEPTH_COMPARE),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs"),
                compilation_options: Default::default(),
                targets: &[Some(voxel_render::SCENE_FORMAT.into())],
            }),
            multiview_mask: None,
            cache: None,
        });
        Self {
            boxes,
            buffer,
            group,
            pipeline,
        }
    }
}

impl GameStages for FlatBoxes {
    fn stages(&self) -> Stages {
        Stages {
            opaque: true,
            ..Default::default()
        }
    }

    fn prepare(&mut self, _ctx: &GpuContext, frame: &GameFrame<'_>) {
        let mut data: Vec<f32> = frame.view_proj.to_cols_array().to_vec();
        for b in &self.boxes {
            let min = frame.relative(b.center - b.half);
            let max = frame.relative(b.center + b.half);
            data.extend([min.x, min.y, min.z, 0.0, max.x, max.y, max.z, 0.0]);
            data.extend([b.color[0], b.color[1], b.color[2], 1.0]);
        }
        frame
            .write_buffer(&self.buffer, 0, bytemuck::cast_slice(&data))
            .unwrap();
    }

    fn opaque(&self, pass: &mut wgpu::RenderPass<'_>, _frame: &GameFrame<'_>) {
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.group, &[]);
        pass.draw(0..36, 0..self.boxes.len() as u32);
    }
}

/// The crate's own render of `world` with `boxes` in its opaque stage.
fn without_bevy(
    ctx: &GpuContext,
    world: &World,
    boxes: &[FlatBox],
    camera: &voxel_render::Camera,
    technique: Technique,
    size: (u32, u32),
) -> Image {
    let config = tests::technique_config(technique, size.0, size.1);
    let mut renderer = Renderer::new(ctx, world.registry(), config).unwrap();
    let positions: Vec<_> = world.iter().map(|(p, _)| p).collect();
    for (pos, meshes) in voxel_mesh::mesh_chunks(world, &positions).unwrap() {
        renderer.upload_chunk(pos, &meshes).unwrap();
    }
    let mut game = FlatBoxes::new(ctx, boxes.to_vec());
    let target = tests::Offscreen::new(ctx, size.0, size.1);
    renderer
        .render_and_submit(&target.view, camera, &mut game)
        .unwrap();
    target.read(ctx).unwrap()
}

#[test]
fn bevy_meshes_and_the_world_occlude_each_other_through_water_and_glass() {
    occlusion(wgpu::Backends::VULKAN);
}

/// The same on wgpu's GL backend (GLES through EGL: llvmpipe here), the path of Bevy's
/// WebGL2 builds natively.
#[test]
fn bevy_meshes_and_the_world_occlude_each_other_on_gl() {
    occlusion(wgpu::Backends::GL);
}

fn occlusion(backends: wgpu::Backends) {
    if !have_gpu() {
        return;
    }
    let w = world(&[
        // ground
        ([-24, -8, -16], [24, -1, 8], blocks::STONE),
        // a hill the first cube stands half inside (x from -14 to -8)
        ([-14, -1, -4], [-9, 3, 2], blocks::DIRT),
        // a pool: water to y = 0, with the character standing in it
        ([-4, -6, -4], [4, -1, 3], blocks::WATER),
        // a glass pane in front of the third cube
        ([8, 0, 2], [14, 5, 2], blocks::GLASS),
    ]);
    let boxes = [
        FlatBox {
            center: DVec3::new(-8.0, 1.0, -1.0),
            half: DVec3::splat(1.5),
            color: [0.7, 0.1, 0.1],
        },
        FlatBox {
            center: DVec3::new(0.5, -2.0, -0.5),
            half: DVec3::new(0.5, 2.5, 0.5),
            color: [0.1, 0.6, 0.2],
        },
        FlatBox {
            center: DVec3::new(11.0, 2.0, -1.0),
            half: DVec3::new(1.5, 1.5, 1.0),
            color: [0.15, 0.2, 0.75],
        },
    ];
    let eye = DVec3::new(0.0, 9.0, 22.0);
    let forward = DVec3::new(0.0, -6.5, -22.0);
    let size = (240, 135);
    let mut h = Harness::with_plugin(
        VoxelWorld::from_world(w.clone()),
        eye,
        forward,
        60.0,
        0.1,
        500.0,
        size,
        false,
        true,
        backends,
    );
    {
        let world = h.app.world_mut();
        let meshes: Vec<_> = boxes
            .iter()
            .map(|b| {
                let h = b.half.as_vec3();
                world.resource_mut::<Assets<Mesh>>().add(Cuboid::new(
                    2.0 * h.x,
                    2.0 * h.y,
                    2.0 * h.z,
                ))
            })
            .collect();
        for (b, mesh) in boxes.iter().zip(meshes) {
            let material = world
                .resource_mut::<Assets<StandardMaterial>>()
                .add(StandardMaterial {
                    base_color: Color::LinearRgba(LinearRgba::rgb(
                        b.color[0], b.color[1], b.color[2],
                    )),
                    unlit: true,
                    ..Default::default()
                });
            let c = b.center.as_vec3();
            world.spawn((
                Mesh3d(mesh),
                MeshMaterial3d(material),
                Transform::from_xyz(c.x, c.y, c.z),
            ));
        }
    }
    h.frames(2);
    let ctx = h.ctx();
    assert!(
        backends.contains(ctx.caps.backend.into()),
        "Bevy drew on {:?}, not {backends:?}",
        ctx.caps.backend
    );
    let camera = h.camera();
    let plain = without_bevy(&ctx, &w, &[], &camera, Technique::SortedQuads, size);
    for t in [
        Technique::SortedQuads,
        Technique::WboitMrt,
        Technique::DepthPeeling,
    ] {
        h.app.insert_resource(VoxelTechnique::Use(t));
        let bevy = h.frames(3);
        let reference = without_bevy(&ctx, &w, &boxes, &camera, t, size);
        let tag = format!("occlusion-{backends:?}-{}", t.name());
        save(&tag, &bevy, &reference);
        let share = share_over_one(&bevy, &reference);
        eprintln!("{tag}: {:.4} % of pixels over 1/255", share * 100.0);
        assert!(
            share <= 0.001,
            "{tag}: {:?}",
            tests::diff(&bevy, &reference)
        );
        // The cubes are there: the picture differs from the world alone (the three cubes
        // cover about 400 pixels here).
        let cubes = tests::diff(&bevy, &plain).over_one;
        eprintln!("{tag}: {cubes} pixels show the cubes");
        assert!(cubes > 250, "{tag}: the cubes are missing ({cubes} pixels)");
    }
}

#[test]
fn a_translucent_entity_between_two_panes_is_exact_against_the_reference() {
    if !have_gpu() {
        return;
    }
    let w = world(&[
        ([-10, -4, -14], [10, -1, 6], blocks::STONE),
        ([-4, 0, 0], [4, 5, 0], blocks::GLASS),
        ([-4, 0, -6], [4, 5, -6], blocks::WATER),
    ]);
    let eye = DVec3::new(1.5, 3.0, 9.0);
    let forward = DVec3::new(-0.5, -0.5, -9.0);
    let size = (200, 120);
    let mut h = Harness::new(
        VoxelWorld::from_world(w.clone()),
        eye,
        forward,
        60.0,
        0.1,
        500.0,
        size,
        false,
    );
    h.app
        .insert_resource(VoxelTechnique::Use(Technique::SortedQuads));
    let red = [220u8, 40, 40];
    let yellow = [250u8, 220, 60];
    h.app.world_mut().spawn((
        VoxelTranslucent {
            shape: VoxelShape::Box {
                half_extents: [1.5, 1.0, 1.0],
            },
            color: Color::srgb_u8(red[0], red[1], red[2]),
            opacity: 0.6,
            emissive: 0.0,
        },
        Transform::from_xyz(0.5, 2.5, -3.0),
    ));
    h.app.world_mut().spawn((
        VoxelTranslucent {
            shape: VoxelShape::Particle { half_size: 0.5 },
            color: Color::srgb_u8(yellow[0], yellow[1], yellow[2]),
            opacity: 0.8,
            emissive: 2.0,
        },
        Transform::from_xyz(3.0, 1.5, -2.5),
    ));
    let bevy = h.frames(3);
    let ctx = h.ctx();
    let mut scene = Scene::new("panes", w.clone(), h.camera());
    scene.content = Content {
        particles: vec![Particle {
            center: DVec3::new(3.0, 1.5, -2.5),
            half_size: 0.5,
            color: yellow,
            opacity: 0.8,
            emissive: 2.0,
        }],
        entities: vec![ContentEntity {
            center: DVec3::new(0.5, 2.5, -3.0),
            half_extents: [1.5, 1.0, 1.0],
            rotation: glam::DQuat::IDENTITY,
            color: red,
            opacity: 0.6,
            emissive: 0.0,
        }],
    };
    let reference = tests::render(&ctx, &scene, Technique::Reference, size.0, size.1);
    save("between-panes", &bevy, &reference);
    let d = tests::diff(&bevy, &reference);
    eprintln!("between panes: {d:?}");
    assert!(d.over_one == 0, "not exact against the A-buffer: {d:?}");
    let without = tests::render(
        &ctx,
        &Scene::new("panes", w, h.camera()),
        Technique::Reference,
        size.0,
        size.1,
    );
    assert!(
        tests::diff(&bevy, &without).over_one > 500,
        "the entities are missing"
    );
}
