//! What a game or tool can get wrong, answered with an `Error` (never a panic under
//! wgpu's default error handler, nor a wrong picture): textures read back that cannot be
//! copied (a depth texture on GL, which the lab's ray-march check reads through a pass
//! instead), a renderer's contract or content stages shared with another renderer, the
//! renderer's own scene colour or another device's view as the output, and lighting too
//! bright for half-float targets.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use glam::DVec3;
use tests::{Offscreen, Scene, diff, gl, gpu, renderer_for, technique_config};
use voxel_core::blocks::{GLASS, RED_GLASS, STONE, WATER};
use voxel_render::content::{Content, ContentStages, Particle};
use voxel_render::readback::{read_depth, read_texture};
use voxel_render::{Error, GpuContext, Lighting, NoGame, Renderer, RendererConfig, Technique};

const W: u32 = 96;
const H: u32 = 64;

/// A stone floor, a glass wall and a red glass block, seen from above and in front.
fn scene() -> Scene {
    let world = tests::box_world(&[
        ([0, 0, 0], [11, 0, 11], STONE),
        ([2, 1, 6], [9, 4, 6], GLASS),
        ([4, 1, 2], [6, 3, 4], RED_GLASS),
    ]);
    tests::scene("misuse", world, [5.5, 7.0, 15.0], [5.5, 1.0, 3.0])
}

fn config() -> RendererConfig {
    technique_config(Technique::WboitMrt, W, H)
}

/// A depth texture filled with `depth` by a pass that clears it, with `usage` besides.
fn cleared_depth(ctx: &GpuContext, depth: f32, usage: wgpu::TextureUsages) -> wgpu::Texture {
    let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("test_depth"),
        size: wgpu::Extent3d {
            width: 37,
            height: 11,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Depth32Float,
        usage: usage | wgpu::TextureUsages::RENDER_ATTACHMENT,
        view_formats: &[],
    });
    let view = texture.create_view(&Default::default());
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        depth_stencil_attachment: voxel_render::stages::Depth::Clear(&view, depth).attachment(),
        ..Default::default()
    });
    ctx.queue.submit([encoder.finish()]);
    texture
}

/// `read_depth` copies where it can (`COPY_SRC`, a device that copies depth) and reads
/// through a pass otherwise (no `COPY_SRC` here): the same values either way.
#[test]
fn depth_is_read_by_copy_or_through_a_pass() {
    let Some(ctx) = gpu() else { return };
    use wgpu::TextureUsages as U;
    let copied = cleared_depth(&ctx, 0.25, U::COPY_SRC | U::TEXTURE_BINDING);
    let sampled = cleared_depth(&ctx, 0.75, U::TEXTURE_BINDING);
    assert!(
        read_depth(&ctx, &copied)
            .unwrap()
            .iter()
            .all(|&d| d == 0.25)
    );
    let through = read_depth(&ctx, &sampled).unwrap();
    assert_eq!(through.len(), 37 * 11);
    assert!(through.iter().all(|&d| d == 0.75), "{:?}", &through[..4]);
    // Neither copyable nor sampled: an error naming what it lacks.
    let neither = cleared_depth(&ctx, 0.5, U::empty());
    let e = read_depth(&ctx, &neither).unwrap_err();
    assert!(matches!(e, Error::Unreadable(_)), "{e:?}");
    assert!(e.to_string().contains("TEXTURE_BINDING"), "{e}");
}

/// What `read_texture` cannot copy is an `Error::Unreadable` before anything is
/// recorded: no `COPY_SRC`, a texel size that is not the format's, several samples, a
/// colour texture given to `read_depth`.
#[test]
fn textures_that_cannot_be_copied_are_refused() {
    let Some(ctx) = gpu() else { return };
    let texture = |usage, samples, format| {
        ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: None,
            size: wgpu::Extent3d {
                width: 8,
                height: 8,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: samples,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
    };
    use wgpu::TextureFormat::{Rgba8Unorm, Rgba16Float};
    use wgpu::TextureUsages as U;
    let cases = [
        (texture(U::TEXTURE_BINDING, 1, Rgba8Unorm), 4, "COPY_SRC"),
        (texture(U::COPY_SRC, 1, Rgba16Float), 4, "bytes"),
        (
            texture(U::COPY_SRC | U::RENDER_ATTACHMENT, 4, Rgba8Unorm),
            4,
            "samples",
        ),
    ];
    for (t, bytes, what) in cases {
        let e = read_texture(&ctx, &t, bytes).unwrap_err();
        assert!(matches!(e, Error::Unreadable(_)), "{e:?}");
        assert!(e.to_string().contains(what), "{what}: {e}");
    }
    assert_eq!(
        read_texture(&ctx, &texture(U::COPY_SRC, 1, Rgba16Float), 8)
            .unwrap()
            .len(),
        8 * 8 * 8
    );
    let e = read_depth(&ctx, &texture(U::COPY_SRC, 1, Rgba8Unorm)).unwrap_err();
    assert!(matches!(e, Error::Unreadable(_)), "{e:?}");
}

/// wgpu's GL backend copies no depth texture to a buffer: `read_texture` says so (an
/// error, not wgpu's validation panic), `read_depth` reads it through a pass, and its
/// depths are the Vulkan renderer's.
#[test]
fn a_depth_texture_on_gl_is_read_through_a_pass() {
    let (Some(gl), Some(vk)) = (gl(), gpu()) else {
        return;
    };
    let scene = scene();
    let depth = |ctx: &GpuContext| {
        let mut r = renderer_for(ctx, &scene, config()).unwrap();
        let target = Offscreen::new(ctx, W, H);
        r.render_and_submit(&target.view, &scene.cameras[0])
            .unwrap();
        if ctx.caps.backend == wgpu::Backend::Gl {
            let e = read_texture(ctx, r.scene_depth(), 4).unwrap_err();
            assert!(matches!(e, Error::Unreadable(_)), "{e:?}");
            assert!(e.to_string().contains("read_depth"), "{e}");
        }
        read_depth(ctx, r.scene_depth()).unwrap()
    };
    let (on_gl, on_vk) = (depth(&gl), depth(&vk));
    assert_eq!(on_gl.len(), (W * H) as usize);
    // The sky is cleared to 0 (reverse-Z far), the floor and walls nearer.
    assert!(on_gl.contains(&0.0) && on_gl.iter().any(|&d| d > 0.0));
    let same = on_gl
        .iter()
        .zip(&on_vk)
        .filter(|(a, b)| (*a - *b).abs() <= 1e-6)
        .count();
    // Two rasterisers may split an edge pixel differently; nothing else may differ.
    eprintln!(
        "GL depth equal to Vulkan's on {same} of {} pixels",
        on_gl.len()
    );
    assert!(same * 100 >= on_gl.len() * 98, "{same} of {}", on_gl.len());
}

/// The lab's check of a scene against its CPU ray march reads the frame's depth: on GL it
/// runs (it panicked in wgpu's validation before) and agrees off edges as on Vulkan.
#[test]
fn the_lab_ray_march_check_runs_on_gl() {
    let Some(gl) = gl() else { return };
    let scene = scene();
    let check = voxel_lab::eval::raymarch_check(&gl, &scene, &scene.cameras[0], (W, H)).unwrap();
    let c = &check.comparison;
    assert_eq!(c.pixels, (W * H) as usize);
    assert_eq!((c.differing, c.cracks), (0, 0), "{c:?}");
}

/// Contract ids are unique in the process: pipelines built for one renderer's contract
/// are refused by another renderer with `StaleContract` (each renderer's group layouts
/// are its own), never drawn with.
#[test]
fn contract_ids_differ_between_renderers() {
    let Some(ctx) = gpu() else { return };
    let scene = scene();
    let mut a = renderer_for(&ctx, &scene, config()).unwrap();
    let mut b = renderer_for(&ctx, &scene, config()).unwrap();
    let (ia, ib) = (
        a.translucent_contract().unwrap().id,
        b.translucent_contract().unwrap().id,
    );
    assert_ne!(ia, ib, "two renderers gave out contract {ia}");
    // Stable on one renderer.
    assert_eq!(a.translucent_contract().unwrap().id, ia);
    let content = Content {
        particles: vec![particle()],
        entities: vec![],
    };
    let mut game = ContentStages::new(&a.renderer, content).expect("content that validates");
    game.set_follow_contract(false);
    game.update_pipelines(&mut a.renderer).unwrap();
    let target = Offscreen::new(&ctx, W, H);
    let camera = scene.cameras[0];
    a.renderer
        .render_and_submit(&target.view, &camera, &mut game)
        .unwrap();
    let e = b
        .renderer
        .render_and_submit(&target.view, &camera, &mut game)
        .unwrap_err();
    assert!(matches!(e, Error::StaleContract { .. }), "{e:?}");
}

fn particle() -> Particle {
    Particle {
        center: DVec3::new(5.5, 3.0, 8.0),
        half_size: 1.5,
        color: [230, 40, 40],
        opacity: 0.6,
        emissive: 0.0,
    }
}

/// One `ContentStages` drawn by two renderers of one device with different techniques,
/// frames alternating: each picture is what that renderer draws with content stages of
/// its own.
#[test]
fn content_stages_shared_by_two_renderers_draw_right_for_both() {
    let Some(ctx) = gpu() else { return };
    let mut scene = scene();
    scene.content = Content {
        particles: vec![particle()],
        entities: vec![],
    };
    let camera = scene.cameras[0];
    let mut renderers = [Technique::WboitMrt, Technique::SortedQuads].map(|t| {
        let r = renderer_for(&ctx, &scene, technique_config(t, W, H)).unwrap();
        r.renderer
    });
    let own: Vec<_> = renderers
        .iter_mut()
        .map(|r| {
            let mut game =
                ContentStages::new(r, scene.content.clone()).expect("content that validates");
            let target = Offscreen::new(&ctx, W, H);
            r.render_and_submit(&target.view, &camera, &mut game)
                .unwrap();
            target.read(&ctx).unwrap()
        })
        .collect();
    let mut shared =
        ContentStages::new(&renderers[0], scene.content.clone()).expect("content that validates");
    for _ in 0..2 {
        for (r, expected) in renderers.iter_mut().zip(&own) {
            let target = Offscreen::new(&ctx, W, H);
            r.render_and_submit(&target.view, &camera, &mut shared)
                .unwrap();
            let d = diff(&target.read(&ctx).unwrap(), expected);
            assert_eq!(d.max, 0, "{}: {d:?}", r.config().oit.technique);
        }
    }
}

/// Content stages made for a renderer of another device: every call that could use them
/// there is an `Error::OtherDevice`, before anything is recorded.
#[test]
fn content_stages_of_another_device_are_refused() {
    let (Some(ctx), Some(other)) = (gpu(), gpu()) else {
        return;
    };
    assert!(!ctx.same_device(&other) && ctx.same_device(&ctx.clone()));
    let mut scene = scene();
    scene.content = Content {
        particles: vec![particle()],
        entities: vec![],
    };
    let a = renderer_for(&ctx, &scene, config()).unwrap();
    let mut b = renderer_for(&other, &scene, config()).unwrap();
    let mut game =
        ContentStages::new(&a.renderer, scene.content.clone()).expect("content that validates");
    let target = Offscreen::new(&other, W, H);
    let e = b
        .renderer
        .render_and_submit(&target.view, &scene.cameras[0], &mut game)
        .unwrap_err();
    assert!(matches!(e, Error::OtherDevice(_)), "{e:?}");
    let e = game.update_pipelines(&mut b.renderer).unwrap_err();
    assert!(matches!(e, Error::OtherDevice(_)), "{e:?}");
    let e = game
        .prebuild(&mut b.renderer, Technique::Stipple)
        .unwrap_err();
    assert!(matches!(e, Error::OtherDevice(_)), "{e:?}");
    // New content through the other device's context (more things than it has room for,
    // so that it would make buffers there): refused before wgpu is called, where it
    // panicked ("Cannot get non-existent resource BindGroupLayoutId"); what it drew stays.
    let more = Content {
        particles: vec![particle(); 64],
        entities: vec![],
    };
    let e = game.set_content(&other, more.clone()).unwrap_err();
    assert!(matches!(e, Error::OtherDevice(_)), "{e:?}");
    assert!(e.to_string().contains("set_content"), "{e}");
    game.set_content(&ctx, more).unwrap();
    // The renderer still draws.
    b.renderer
        .render_and_submit(&target.view, &scene.cameras[0], &mut NoGame)
        .unwrap();
}

/// The renderer's own scene colour as the output (the tonemap reads it) is an
/// `Error::Output`, not a usage conflict in wgpu's validation; the renderer still draws.
#[test]
fn the_scene_colour_is_refused_as_the_output() {
    let Some(ctx) = gpu() else { return };
    let scene = scene();
    let mut c = config();
    c.output_format = voxel_render::SCENE_FORMAT;
    let mut r = renderer_for(&ctx, &scene, c).unwrap();
    let own = r.scene_color().create_view(&Default::default());
    let e = r
        .renderer
        .render_and_submit(&own, &scene.cameras[0], &mut NoGame)
        .unwrap_err();
    assert!(matches!(e, Error::Output(_)), "{e:?}");
    assert!(e.to_string().contains("scene colour"), "{e}");
    let target = Offscreen::new(&ctx, W, H);
    r.render_and_submit(&target.view, &scene.cameras[0])
        .unwrap();
}

/// Two devices of one adapter: a view of the other device's texture as the output is an
/// `Error::OtherDevice` from the output check (wgpu's device mismatch caught in an error
/// scope), not a panic. (Objects of another wgpu instance cannot be told apart by any
/// public means: docs/limits-and-errors.md says what that does.)
#[test]
fn an_output_view_of_another_device_is_refused() {
    let Some(_) = gpu() else { return };
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = wgpu::Backends::VULKAN;
    let instance = wgpu::Instance::new(desc);
    let adapter = pollster::block_on(instance.request_adapter(&Default::default())).unwrap();
    let device = || {
        let (device, queue) = pollster::block_on(voxel_render::request_device(&adapter)).unwrap();
        GpuContext::from_device(&adapter, device, queue)
    };
    let (ctx, other) = (device(), device());
    let scene = scene();
    let mut r = renderer_for(&ctx, &scene, config()).unwrap();
    let theirs = Offscreen::new(&other, W, H);
    let e = r
        .renderer
        .render_and_submit(&theirs.view, &scene.cameras[0], &mut NoGame)
        .unwrap_err();
    assert!(matches!(e, Error::OtherDevice(_)), "{e:?}");
    let target = Offscreen::new(&ctx, W, H);
    r.render_and_submit(&target.view, &scene.cameras[0])
        .unwrap();
}

/// A game that makes two wgpu instances (a window's and a headless one) and hands the
/// renderer an output view or an encoder of the other: `Error::OtherDevice` naming the
/// instance, found before the frame is recorded, where wgpu-core panicked looking the
/// object's id up in the renderer's instance ("Cannot get non-existent resource"); the
/// renderer draws on afterwards.
#[test]
fn an_output_view_or_encoder_of_another_instance_is_refused() {
    let (Some(ctx), Some(other)) = (gpu(), gpu()) else {
        return;
    };
    let scene = scene();
    let mut r = renderer_for(&ctx, &scene, config()).unwrap();
    let target = Offscreen::new(&ctx, W, H);
    r.render_and_submit(&target.view, &scene.cameras[0])
        .unwrap();
    let expected = target.read(&ctx).unwrap();
    let instance_error = |e: Error| {
        assert!(matches!(e, Error::OtherDevice(_)), "{e:?}");
        assert!(e.to_string().contains("wgpu::Instance"), "{e}");
    };

    // Their view as the output, in the renderer's own encoder.
    let theirs = Offscreen::new(&other, W, H);
    let e = r
        .renderer
        .render_and_submit(&theirs.view, &scene.cameras[0], &mut NoGame)
        .unwrap_err();
    instance_error(e);

    // Their encoder, the renderer's own output.
    let mut encoder = other.device.create_command_encoder(&Default::default());
    let e = r
        .renderer
        .render(&mut encoder, &target.view, &scene.cameras[0], &mut NoGame)
        .unwrap_err();
    instance_error(e);
    // Nothing was recorded into it: it finishes and submits on its own device.
    other.queue.submit([encoder.finish()]);
    other
        .device
        .poll(wgpu::PollType::wait_indefinitely())
        .unwrap();

    // The renderer draws on, the same picture.
    r.render_and_submit(&target.view, &scene.cameras[0])
        .unwrap();
    let d = diff(&target.read(&ctx).unwrap(), &expected);
    assert_eq!(d.max, 0, "{d:?}");
}

/// Brightness and sky channels above `Lighting::MAX_BRIGHTNESS` (up to `f32::MAX`) are
/// refused, at creation and by `set_lighting` (which then changes nothing).
#[test]
fn lighting_too_bright_for_half_floats_is_refused() {
    let Some(ctx) = gpu() else { return };
    let registry = voxel_core::BlockRegistry::default();
    let max = Lighting::MAX_BRIGHTNESS;
    for bright in [max * 1.001, 1e6, 1e30, f32::MAX] {
        let e = Renderer::new(
            &ctx,
            &registry,
            RendererConfig {
                brightness: bright,
                ..config()
            },
        )
        .unwrap_err();
        assert!(matches!(e, Error::InvalidSetting(_)), "{bright}: {e:?}");
        assert!(e.to_string().contains("brightness"), "{e}");
        let e = Renderer::new(
            &ctx,
            &registry,
            RendererConfig {
                sky: [0.5, bright, 0.5],
                ..config()
            },
        )
        .unwrap_err();
        assert!(matches!(e, Error::InvalidSetting(_)), "{bright}: {e:?}");
    }
    let mut r = Renderer::new(&ctx, &registry, config()).unwrap();
    let before = r.lighting();
    for bright in [1e6, f32::MAX] {
        let too = Lighting {
            brightness: bright,
            ..before
        };
        assert!(matches!(r.set_lighting(too), Err(Error::InvalidSetting(_))));
        assert_eq!(r.lighting(), before);
    }
    r.set_lighting(Lighting {
        brightness: max,
        sky: [max; 3],
        ..before
    })
    .unwrap();
}

/// At the brightest light and sky allowed, every technique's scene colour (half floats)
/// holds finite values below 65 504, the largest half float: where lavapipe saturates a
/// larger value there, a GPU makes it infinite (the tonemap's magenta). Several layers of
/// glass and water add up in the weighted sums.
#[test]
fn the_brightest_light_stays_finite_in_half_floats() {
    let Some(ctx) = gpu() else { return };
    let mut boxes = vec![
        ([0, 0, 0], [11, 0, 11], STONE),
        ([0, 1, 0], [11, 2, 11], WATER),
    ];
    for z in 0..6 {
        boxes.push(([2, 3, 2 * z], [9, 6, 2 * z], GLASS));
    }
    let world = tests::box_world(&boxes);
    let scene = tests::scene("bright", world, [5.5, 8.0, 16.0], [5.5, 2.0, 3.0]);
    let max = Lighting::MAX_BRIGHTNESS;
    for technique in Technique::ALL {
        let mut c = technique_config(technique, W, H);
        c.brightness = max;
        c.sky = [max; 3];
        let mut r = renderer_for(&ctx, &scene, c).unwrap();
        let target = Offscreen::new(&ctx, W, H);
        r.render_and_submit(&target.view, &scene.cameras[0])
            .unwrap();
        let hdr = tests::read_hdr(&ctx, r.scene_color());
        let worst = hdr.iter().flatten().fold(0f32, |m, v| {
            if v.is_finite() {
                m.max(v.abs())
            } else {
                f32::INFINITY
            }
        });
        assert!(worst < 65_504.0, "{}: {worst}", technique.name());
        // Lit surfaces reach the light's scale: the cap is not met by clamping colours.
        assert!(worst > max * 0.5, "{}: {worst}", technique.name());
        let img = target.read(&ctx).unwrap();
        let magenta = img
            .rgba
            .chunks_exact(4)
            .filter(|p| p[0] == 255 && p[1] == 0 && p[2] == 255)
            .count();
        assert_eq!(magenta, 0, "{}", technique.name());
    }
}

/// A game asks whether the device is lost with the public `GpuContext::check_device`
/// (docs/limits-and-errors.md tells it to).
#[test]
fn a_game_checks_the_device_itself() {
    let Some(ctx) = gpu() else { return };
    ctx.check_device().unwrap();
    ctx.device.destroy();
    let e = ctx.check_device().unwrap_err();
    assert!(matches!(e, Error::DeviceLost { .. }), "{e:?}");
}
