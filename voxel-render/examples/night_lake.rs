//! A game at night on a lake: the ready-made content (fireflies that glow by their own
//! light, over the water and under it, a lantern glowing on a boat) beside the game's own
//! stages (a sheet of mist over the water, drawn by the game's WGSL in every pass of the
//! transparency technique, and a HUD drawn over the finished picture), in one frame:
//! `stages::Both` draws the two as one game, their translucent things ordered together,
//! with no stage method forwarded by hand. It runs wherever the world runs, WebGL2's
//! limits included: the content then reads its instances from vertex buffers, the mist
//! needs only a uniform.
//!
//! Headless: `cargo run --release -p voxel-render --example night_lake -- --frames 30 --out
//! night_lake.png [--technique sorted-quads] [--limits webgl2]`; `WGPU_BACKEND=gl` draws on
//! wgpu's GL backend.

use std::collections::HashMap;
use std::ops::Range;
use std::sync::Arc;

use glam::{DQuat, DVec3};
use voxel_core::{BlockRegistry, World, WorldPos, blocks};
use voxel_render::content::{Content, ContentStages, Entity, Particle};
use voxel_render::stages::{
    self, Both, GameFrame, GameStages, OIT_GROUP, Stages, TranslucentContract, TranslucentObject,
};
use voxel_render::{
    Camera, GpuContext, Lighting, LimitsPreset, Renderer, RendererConfig, Technique,
};

const SHADER: &str = include_str!("night_lake.wgsl");
const MIST_ENTRY: &str = "
@fragment
fn fs_mist(in: MistOut) -> OitOutput {
    return oit_output(in.position, mist_color(in.uv));
}
";

/// The mist's uniform (`Mist` in `night_lake.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct MistUniform {
    view_proj: [[f32; 4]; 4],
    center: [f32; 4],
    color: [f32; 4],
    size: [f32; 4],
}

/// The game's own stages: a sheet of mist (translucent) and a HUD (overlay).
struct Mist {
    center: DVec3,
    half: f64,
    uniform: wgpu::Buffer,
    layout: wgpu::BindGroupLayout,
    group: wgpu::BindGroup,
    /// Its translucent pipelines, one per pass of each contract it met, by contract id.
    pipelines: HashMap<u64, Vec<wgpu::RenderPipeline>>,
    contract: Option<u64>,
    objects: [TranslucentObject; 1],
    /// The HUD's pipeline and group for the output format it was built for.
    hud: Option<(wgpu::TextureFormat, wgpu::RenderPipeline, wgpu::BindGroup)>,
}

impl Mist {
    fn new(device: &wgpu::Device, center: DVec3, half: f64) -> Self {
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("mist"),
            size: std::mem::size_of::<MistUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("mist"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        let group = stages::bind_group(device, "mist", &layout, &[uniform.as_entire_binding()]);
        let objects = [TranslucentObject::aabb(center, DVec3::new(half, 0.0, half))];
        Self {
            center,
            half,
            uniform,
            layout,
            group,
            pipelines: HashMap::new(),
            contract: None,
            objects,
            hud: None,
        }
    }

    /// One pipeline per pass of `contract`: the technique's prelude, then the mist.
    fn build(
        &self,
        device: &wgpu::Device,
        contract: &TranslucentContract,
    ) -> Vec<wgpu::RenderPipeline> {
        contract
            .variants
            .iter()
            .map(|v| {
                let module = stages::shader(device, v.name, &[&v.wgsl, SHADER, MIST_ENTRY]);
                let mut groups = vec![Some(&self.layout)];
                groups.resize(OIT_GROUP as usize, None);
                groups.push(Some(&v.layout));
                let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some("mist"),
                    bind_group_layouts: &groups,
                    immediate_size: 0,
                });
                device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some("mist"),
                    layout: Some(&layout),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some("vs_mist"),
                        compilation_options: Default::default(),
                        buffers: &[],
                    },
                    // Seen from above and from below.
                    primitive: wgpu::PrimitiveState::default(),
                    depth_stencil: Some(v.depth_stencil.clone()),
                    multisample: Default::default(),
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some("fs_mist"),
                        compilation_options: Default::default(),
                        targets: &v.targets,
                    }),
                    multiview_mask: None,
                    cache: None,
                })
            })
            .collect()
    }
}

impl GameStages for Mist {
    fn stages(&self) -> Stages {
        Stages {
            translucent: true,
            overlay: true,
            ..Stages::default()
        }
    }

    fn translucent_objects(&self) -> &[TranslucentObject] {
        &self.objects
    }

    fn translucent_contract_id(&self) -> Option<u64> {
        self.contract
    }

    fn follow_contract(&mut self, ctx: &GpuContext, contract: &TranslucentContract) {
        if !self.pipelines.contains_key(&contract.id) {
            let built = self.build(&ctx.device, contract);
            self.pipelines.insert(contract.id, built);
        }
        self.contract = Some(contract.id);
    }

    fn prepare(&mut self, ctx: &GpuContext, frame: &GameFrame<'_>) {
        let c = frame.relative(self.center);
        // A pale blue-grey lit by the frame's light (moonlight at night), as a face turned
        // to the sky is.
        let light =
            frame.brightness * (frame.ambient + (1.0 - frame.ambient) * frame.sun_dir.y.max(0.0));
        let u = MistUniform {
            view_proj: frame.view_proj.to_cols_array_2d(),
            center: [c.x, c.y, c.z, self.half as f32],
            color: [0.8 * light, 0.9 * light, light, 0.45],
            size: [frame.size.0 as f32, frame.size.1 as f32, 0.0, 0.0],
        };
        ctx.queue
            .write_buffer(&self.uniform, 0, bytemuck::bytes_of(&u));
        // The HUD is drawn into the output: built for its format.
        if self.hud.as_ref().map(|h| h.0) != Some(frame.output_format) {
            let module = stages::shader(&ctx.device, "hud", &[SHADER]);
            let pipeline = stages::overlay_pipeline(
                &ctx.device,
                &module,
                ("vs_hud", "fs_hud"),
                frame.output_format,
                wgpu::PrimitiveTopology::TriangleList,
                false,
            );
            let group = stages::bind_group(
                &ctx.device,
                "hud",
                &pipeline.get_bind_group_layout(0),
                &[self.uniform.as_entire_binding()],
            );
            self.hud = Some((frame.output_format, pipeline, group));
        }
    }

    fn translucent(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        _frame: &GameFrame<'_>,
        variant: usize,
        objects: Range<usize>,
    ) {
        // Its one object, drawn in the run that holds it.
        if !objects.contains(&0) {
            return;
        }
        let Some(pipeline) = self
            .contract
            .and_then(|id| self.pipelines.get(&id))
            .and_then(|p| p.get(variant))
        else {
            return;
        };
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &self.group, &[]);
        pass.draw(0..6, 0..1);
    }

    fn overlay(&self, pass: &mut wgpu::RenderPass<'_>, _frame: &GameFrame<'_>) {
        if let Some((_, pipeline, group)) = &self.hud {
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, group, &[]);
            pass.draw(0..24, 0..1);
        }
    }
}

/// The ready-made things at `t` seconds: fireflies drifting over and under the water, a
/// boat rocking, a lantern glowing on it.
fn things(t: f64) -> Content {
    let hash = |x: u64| {
        let mut z = x.wrapping_mul(0x9e37_79b9_7f4a_7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        (z ^ (z >> 31)) as f64 / u64::MAX as f64
    };
    let fireflies = (0..300u64).map(|i| {
        let h = |k: u64| hash(i << 8 | k);
        let phase = h(1) * 6.3 + t * (0.5 + h(2));
        Particle {
            center: DVec3::new(
                h(3) * 16.0 - 8.0 + 0.3 * phase.sin(),
                h(4) * 5.0 - 3.0 + 0.2 * (phase * 1.3).cos(),
                h(5) * 12.0 - 8.0,
            ),
            half_size: 0.07,
            color: [255, 214, 90],
            opacity: 0.85,
            // Their own light: bright at night, dimmed by the water like anything in it.
            emissive: 5.0,
        }
    });
    let rock = 0.05 * (t * 1.1).sin();
    let boat = Entity {
        center: DVec3::new(-2.0, 0.25, 1.0),
        half_extents: [2.2, 0.35, 1.0],
        rotation: DQuat::from_euler(glam::EulerRot::YXZ, 0.4, 0.0, rock),
        color: [110, 75, 45],
        opacity: 1.0,
        emissive: 0.0,
    };
    let lantern = Entity {
        center: boat.center + DVec3::new(0.0, 0.75, 0.0),
        half_extents: [0.25, 0.35, 0.25],
        rotation: boat.rotation,
        color: [255, 180, 80],
        opacity: 0.6,
        emissive: 3.0,
    };
    Content {
        particles: fireflies.collect(),
        entities: vec![boat, lantern],
    }
}

/// A lake of water on sand, walled with stone, a glass wall across its far end.
fn lake_world() -> Result<World, voxel_core::Error> {
    let mut world = World::new(Arc::new(BlockRegistry::default()));
    let fill = |w: &mut World, a: [i32; 3], b: [i32; 3], id| {
        w.fill_box(
            WorldPos::new(a[0], a[1], a[2]),
            WorldPos::new(b[0], b[1], b[2]),
            id,
        )
    };
    fill(&mut world, [-12, -8, -12], [12, -8, 12], blocks::SAND)?;
    fill(&mut world, [-13, -8, -13], [13, 0, -13], blocks::STONE)?;
    fill(&mut world, [-13, -8, -13], [-13, 0, 12], blocks::STONE)?;
    fill(&mut world, [13, -8, -13], [13, 0, 12], blocks::STONE)?;
    fill(&mut world, [-12, -7, -12], [12, -1, 12], blocks::WATER)?;
    fill(&mut world, [-12, 0, -12], [12, 3, -12], blocks::GLASS)?;
    Ok(world)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let arg = |name: &str| {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1).cloned())
    };
    let frames: u32 = arg("--frames").map_or(Ok(30), |v| v.parse())?;
    let out = arg("--out").unwrap_or_else(|| "night_lake.png".into());
    let technique = match arg("--technique") {
        Some(name) => name.parse::<Technique>()?,
        None => Technique::SortedQuads,
    };
    let limits = match arg("--limits").as_deref() {
        None | Some("adapter") => LimitsPreset::Adapter,
        Some("webgl2") => LimitsPreset::WebGl2,
        Some(other) => return Err(format!("--limits {other}: adapter or webgl2").into()),
    };
    // WGPU_BACKEND picks the backend (gl, vulkan, ...); by default the primary ones.
    let backends = wgpu::Backends::from_env().unwrap_or(wgpu::Backends::PRIMARY);
    let ctx = GpuContext::headless_with(backends, limits)?;

    let mut world = lake_world()?;
    let (width, height) = (640, 360);
    let mut config = RendererConfig {
        width,
        height,
        ..RendererConfig::default()
    };
    config.oit.technique = technique;
    let mut renderer = Renderer::new(&ctx, world.registry(), config)?;
    renderer.set_lighting(Lighting::daytime(23.0))?;
    for (pos, meshes) in voxel_mesh::mesh_dirty(&mut world)? {
        renderer.upload_chunk(pos, &meshes)?;
    }
    let output = stages::target(
        &ctx.device,
        "game_output",
        wgpu::TextureFormat::Rgba8UnormSrgb,
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        (width, height),
    );
    let camera = Camera::look_at(
        DVec3::new(0.5, 5.0, 16.0),
        DVec3::new(0.0, -1.0, -4.0),
        70.0,
        0.1,
        300.0,
    )?;
    // The content and the game's own stages, drawn as one game.
    let content = ContentStages::new(&renderer, things(0.0))?;
    let mist = Mist::new(&ctx.device, DVec3::new(0.0, 1.5, -2.0), 9.0);
    let mut game = Both::new(content, mist);
    for frame in 0..frames.max(1) {
        game.first
            .set_content(&ctx, things(f64::from(frame) / 30.0))?;
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        renderer.render(&mut encoder, &output.view, &camera, &mut game)?;
        ctx.queue.submit([encoder.finish()]);
    }
    let rgba = voxel_render::readback::read_texture(&ctx, &output.texture, 4)?;
    voxel_render::Image {
        width,
        height,
        rgba,
    }
    .save_png(std::path::Path::new(&out))?;
    println!(
        "wrote {out}: {frames} frames of {} on {} with 300 fireflies, a boat, a lantern, mist and a HUD",
        renderer.config().oit.technique.name(),
        ctx.caps.adapter_name
    );
    Ok(())
}
