//! Frames recorded before one submit: two frames of different cameras in one encoder, and
//! in two encoders submitted together, each draw what the frame drawn alone draws, with
//! every technique, the ready-made content (`ContentStages`) and a game's own stage that
//! writes its uniform with `GameFrame::write_buffer`. A write made with
//! `Queue::write_buffer` lands at the next submit, before every command of it, so both
//! frames used to draw with the second's camera.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use glam::{DQuat, DVec3};
use tests::{Offscreen, Scene, diff, gpu, out_dir, renderer_for, technique_config};
use voxel_core::blocks::{GLASS, RED_GLASS, SAND, STONE, WATER};
use voxel_render::content::{Content, ContentStages, Entity};
use voxel_render::stages::{self, GameFrame, GameStages, Stages};
use voxel_render::{Camera, Error, GpuContext, Image, Renderer, Technique};

const W: u32 = 160;
const H: u32 = 90;

/// Water (a volume) over sand with glass and a stone pillar, and the content: particles,
/// a translucent cube and an opaque crate. Two cameras that see it from opposite sides.
fn scene() -> (Scene, [Camera; 2]) {
    let world = tests::box_world(&[
        ([-10, -6, -10], [10, -6, 10], SAND),
        ([-10, -5, -10], [10, -1, 10], WATER),
        ([-3, 0, 2], [3, 3, 2], GLASS),
        ([4, 0, -4], [5, 4, -3], STONE),
        ([-6, 0, -5], [-4, 2, -5], RED_GLASS),
    ]);
    let mut scene = tests::scene("frames", world, [0.5, 7.0, 16.0], [0.5, -1.0, 0.0]);
    scene.content = Content {
        particles: Content::scatter(
            DVec3::new(-6.0, -4.0, -6.0),
            DVec3::new(6.0, 4.0, 6.0),
            40,
            7,
            0.3,
            [250, 240, 120],
            0.6,
        ),
        entities: vec![
            Entity {
                center: DVec3::new(-1.5, 1.5, -1.0),
                half_extents: [1.2, 1.2, 1.2],
                rotation: DQuat::from_rotation_y(0.5),
                color: [60, 200, 90],
                opacity: 0.5,
                emissive: 0.0,
            },
            Entity {
                center: DVec3::new(2.0, -0.5, 5.0),
                half_extents: [0.8, 0.8, 0.8],
                rotation: DQuat::from_rotation_z(0.3),
                color: [150, 90, 40],
                opacity: 1.0,
                emissive: 0.0,
            },
        ],
    };
    let a = scene.cameras[0];
    let b = Camera::look_at(
        DVec3::new(-12.0, 4.0, -9.0),
        DVec3::new(0.5, -1.0, 0.0),
        75.0,
        0.1,
        500.0,
    )
    .unwrap();
    (scene, [a, b])
}

/// The content stages of `renderer`.
fn content(renderer: &Renderer, content: &Content) -> ContentStages {
    ContentStages::new(renderer, content.clone()).expect("content that validates")
}

/// Saves the pictures side by side when they differ, and fails naming the case.
fn same(name: &str, got: &Image, alone: &Image) {
    let d = diff(got, alone);
    if d.max > 0 {
        let dir = out_dir("frames_before_submit");
        got.save_png(&dir.join(format!("{name}_got.png"))).unwrap();
        alone
            .save_png(&dir.join(format!("{name}_alone.png")))
            .unwrap();
    }
    assert_eq!(
        d.max, 0,
        "{name}: differs from the frame drawn alone: {d:?}"
    );
}

/// Each camera's frame drawn and submitted alone into its target: the pictures.
fn drawn_alone(
    ctx: &GpuContext,
    renderer: &mut Renderer,
    game: &mut dyn GameStages,
    cameras: &[Camera; 2],
    targets: &[Offscreen; 2],
) -> Vec<Image> {
    let mut alone = Vec::new();
    for (camera, target) in cameras.iter().zip(targets) {
        renderer
            .render_and_submit(&target.view, camera, game)
            .unwrap();
        alone.push(target.read(ctx).unwrap());
    }
    alone
}

/// Both cameras' frames recorded into one encoder and submitted once: each target holds
/// what its frame drew alone (`name_<i>` when not).
fn one_encoder_draws_as_alone(
    ctx: &GpuContext,
    renderer: &mut Renderer,
    game: &mut dyn GameStages,
    (cameras, targets): (&[Camera; 2], &[Offscreen; 2]),
    alone: &[Image],
    name: &str,
) {
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    for (camera, target) in cameras.iter().zip(targets) {
        renderer
            .render(&mut encoder, &target.view, camera, game)
            .unwrap();
    }
    ctx.queue.submit([encoder.finish()]);
    for (i, target) in targets.iter().enumerate() {
        same(
            &format!("{name}_{i}"),
            &target.read(ctx).unwrap(),
            &alone[i],
        );
    }
}

/// Each technique: both cameras alone, then both in one encoder, then in two encoders
/// submitted together; the pictures must be the frames drawn alone, exactly. The exact
/// techniques submit inside their frame: the second frame in another encoder is refused
/// until the first is submitted (`Error::FrameOrder`), then drawn.
#[test]
fn two_frames_before_a_submit_each_draw_with_their_own_camera() {
    let Some(ctx) = gpu() else { return };
    let (scene, cameras) = scene();
    for technique in Technique::ALL {
        let name = technique.name();
        let mut r = renderer_for(&ctx, &scene, technique_config(technique, W, H)).unwrap();
        let mut game = content(&r, &scene.content);
        let targets = [Offscreen::new(&ctx, W, H), Offscreen::new(&ctx, W, H)];
        // Twice alone first: adaptive state (peeling's layer count) settles.
        drawn_alone(&ctx, &mut r.renderer, &mut game, &cameras, &targets);
        let alone = drawn_alone(&ctx, &mut r.renderer, &mut game, &cameras, &targets);
        assert_ne!(
            diff(&alone[0], &alone[1]).max,
            0,
            "{name}: the cameras see the same"
        );

        one_encoder_draws_as_alone(
            &ctx,
            &mut r.renderer,
            &mut game,
            (&cameras, &targets),
            &alone,
            &format!("{name}_one_encoder"),
        );

        let mut encoders = Vec::new();
        for (camera, target) in cameras.iter().zip(&targets) {
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            let drawn = r
                .renderer
                .render(&mut encoder, &target.view, camera, &mut game);
            if technique.stalls() && !encoders.is_empty() {
                // It submits inside its frame: the frame before, in another encoder not
                // yet submitted, would run after its first half. Refused; submitted
                // first, it draws.
                let e = drawn.unwrap_err();
                assert!(matches!(e, Error::FrameOrder(_)), "{name}: {e:?}");
                ctx.queue.submit(encoders.drain(..));
                r.renderer
                    .render(&mut encoder, &target.view, camera, &mut game)
                    .unwrap();
            } else {
                drawn.unwrap();
            }
            encoders.push(encoder.finish());
        }
        ctx.queue.submit(encoders);
        for (i, target) in targets.iter().enumerate() {
            same(
                &format!("{name}_two_encoders_{i}"),
                &target.read(&ctx).unwrap(),
                &alone[i],
            );
        }
    }
}

/// A game's HDR overlay: a yellow square at a world point, placed by a uniform the game
/// writes in `prepare` with `GameFrame::write_buffer` (the point's clip position).
struct Marker {
    uniform: wgpu::Buffer,
    group: wgpu::BindGroup,
    pipeline: wgpu::RenderPipeline,
    point: DVec3,
}

const MARKER_WGSL: &str = "
@group(0) @binding(0) var<uniform> clip: vec4<f32>;

@vertex
fn vs_marker(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let corner = vec2<f32>(f32(i & 1u), f32((i >> 1u) & 1u)) * 2.0 - 1.0;
    let c = clip / clip.w;
    // Nearest (reverse-Z): in front of everything the frame drew.
    return vec4<f32>(c.xy + corner * 0.08, 1.0, 1.0);
}

@fragment
fn fs_marker() -> @location(0) vec4<f32> {
    return vec4<f32>(4.0, 3.0, 0.0, 1.0);
}
";

impl Marker {
    fn new(ctx: &GpuContext, point: DVec3) -> Self {
        let d = &ctx.device;
        let module = stages::shader(d, "marker", &[MARKER_WGSL]);
        let pipeline = stages::overlay_pipeline(
            d,
            &module,
            ("vs_marker", "fs_marker"),
            voxel_render::SCENE_FORMAT,
            wgpu::PrimitiveTopology::TriangleStrip,
            true,
        );
        let uniform = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("marker"),
            size: 16,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let group = stages::bind_group(
            d,
            "marker",
            &pipeline.get_bind_group_layout(0),
            &[uniform.as_entire_binding()],
        );
        Self {
            uniform,
            group,
            pipeline,
            point,
        }
    }
}

impl GameStages for Marker {
    fn stages(&self) -> Stages {
        Stages {
            hdr_overlay: true,
            ..Stages::default()
        }
    }

    fn prepare(&mut self, _ctx: &GpuContext, frame: &GameFrame<'_>) {
        let clip = frame.view_proj * frame.relative(self.point).extend(1.0);
        let bytes: Vec<u8> = clip
            .to_array()
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        frame.write_buffer(&self.uniform, 0, &bytes).unwrap();
    }

    fn hdr_overlay(&self, pass: &mut wgpu::RenderPass<'_>, _frame: &GameFrame<'_>) {
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.group, &[]);
        pass.draw(0..4, 0..1);
    }
}

/// A game's own uniform written with `GameFrame::write_buffer` lands in its frame: two
/// frames in one encoder each put the marker where their camera sees the point. Writes
/// `wgpu` would refuse, and writes after `prepare`, are errors.
#[test]
fn a_games_own_writes_land_in_its_frame() {
    let Some(ctx) = gpu() else { return };
    let (scene, cameras) = scene();
    let mut r = renderer_for(&ctx, &scene, technique_config(Technique::WboitMrt, W, H)).unwrap();
    let mut game = Marker::new(&ctx, DVec3::new(0.5, 2.0, 0.0));
    let targets = [Offscreen::new(&ctx, W, H), Offscreen::new(&ctx, W, H)];
    let alone = drawn_alone(&ctx, &mut r.renderer, &mut game, &cameras, &targets);
    one_encoder_draws_as_alone(
        &ctx,
        &mut r.renderer,
        &mut game,
        (&cameras, &targets),
        &alone,
        "marker",
    );

    /// A game that writes what wgpu would refuse, and checks each is an error.
    struct BadWrites {
        buffer: wgpu::Buffer,
        no_copy: wgpu::Buffer,
        checked: bool,
    }
    impl GameStages for BadWrites {
        fn stages(&self) -> Stages {
            Stages {
                opaque: true,
                ..Stages::default()
            }
        }
        fn prepare(&mut self, _ctx: &GpuContext, frame: &GameFrame<'_>) {
            use voxel_render::Error::BufferWrite;
            let cases: [(&wgpu::Buffer, u64, &[u8]); 4] = [
                (&self.buffer, 2, &[0; 4]),
                (&self.buffer, 0, &[0; 6]),
                (&self.buffer, 12, &[0; 8]),
                (&self.no_copy, 0, &[0; 4]),
            ];
            for (buffer, offset, data) in cases {
                let e = frame.write_buffer(buffer, offset, data).unwrap_err();
                assert!(matches!(e, BufferWrite(_)), "{e:?}");
            }
            frame.write_buffer(&self.buffer, 12, &[1; 4]).unwrap();
            self.checked = true;
        }
        fn opaque(&self, _pass: &mut wgpu::RenderPass<'_>, frame: &GameFrame<'_>) {
            // Too late: the frame's writes are recorded by now.
            let e = frame.write_buffer(&self.buffer, 0, &[0; 4]).unwrap_err();
            assert!(e.to_string().contains("prepare"), "{e}");
        }
    }
    let buffer = |usage| {
        ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size: 16,
            usage,
            mapped_at_creation: false,
        })
    };
    let mut bad = BadWrites {
        buffer: buffer(wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST),
        no_copy: buffer(wgpu::BufferUsages::UNIFORM),
        checked: false,
    };
    r.renderer
        .render_and_submit(&targets[0].view, &cameras[0], &mut bad)
        .unwrap();
    assert!(bad.checked);
}
