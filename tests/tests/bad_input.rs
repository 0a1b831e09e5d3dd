//! Bad input and stress: every case gets a clear error (kind and message checked) or a
//! documented fallback, never a panic, a hang or a silently wrong picture. GPU cases run
//! under wgpu's default uncaptured-error handler, which panics: a validation error the
//! renderer lets through fails the test.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use voxel_render::NoGame;
use voxel_render::Technique;

use tests::*;

#[test]
fn the_exact_methods_agree_on_200_dense_sheets() {
    let Some(ctx) = gpu() else { return };
    for n in [64, 200] {
        let scene = dense_sheets(n, 0.99);
        let mut r =
            renderer_for(&ctx, &scene, technique_config(Technique::Reference, 96, 64)).unwrap();
        let target = Offscreen::new(&ctx, 96, 64);
        let stats = r
            .render_and_submit(&target.view, &scene.cameras[0])
            .unwrap();
        let a = target.read(&ctx).unwrap();
        let p = render_with(
            &ctx,
            &scene,
            technique_config(Technique::PeelReference, 96, 64),
        );
        eprintln!(
            "{n}: {:?} diff {:?}",
            stats.technique.reference,
            diff(&a, &p)
        );
        assert_close(&format!("dense_sheets_{n}"), &p, &a, 2);
        // The CPU ray march settles it: the A-buffer agrees with it off edges.
        let check =
            voxel_lab::eval::raymarch_check(&ctx, &scene, &scene.cameras[0], (96, 64)).unwrap();
        let c = &check.comparison;
        assert_eq!(
            (c.differing, c.cracks),
            (0, 0),
            "{n} sheets: the ray march differs from the A-buffer: {:?}",
            c.worst
        );
    }
}

#[test]
fn a_render_size_above_the_adapter_limit_is_an_error() {
    let Some(ctx) = gpu() else { return };
    let limit = ctx.caps.limits.max_texture_dimension_2d;
    let scene = dense_sheets(2, 0.5);
    let e = voxel_render::Renderer::new(
        &ctx,
        scene.world.registry(),
        technique_config(Technique::WboitMrt, limit + 1, 64),
    )
    .unwrap_err();
    assert!(matches!(e, voxel_render::Error::TooLarge { .. }), "{e:?}");
    let msg = e.to_string();
    assert!(
        msg.contains("render width") && msg.contains(&limit.to_string()),
        "{msg}"
    );

    let mut r = renderer_for(&ctx, &scene, technique_config(Technique::WboitMrt, 64, 48)).unwrap();
    let e = r.resize(64, limit + 1).unwrap_err();
    assert!(e.to_string().contains("render height"), "{e}");
    assert_eq!(r.size(), (64, 48), "a failed resize changes nothing");
    // Zero sizes are the documented fallback: ignored until a real size comes.
    r.resize(0, 48).unwrap();
    assert_eq!(r.size(), (64, 48));
    frame(&ctx, &mut r, &scene.cameras[0]);
}

#[test]
fn an_output_of_another_size_or_format_is_an_error() {
    let Some(ctx) = gpu() else { return };
    let scene = dense_sheets(2, 0.5);
    let mut r = renderer_for(&ctx, &scene, technique_config(Technique::WboitMrt, 64, 48)).unwrap();
    let cam = scene.cameras[0];
    let small = Offscreen::new(&ctx, 32, 48);
    let e = r.render_and_submit(&small.view, &cam).unwrap_err();
    assert!(matches!(e, voxel_render::Error::Output(_)), "{e:?}");
    assert!(
        e.to_string().contains("32x48") && e.to_string().contains("64x48"),
        "{e}"
    );
    // Every format a surface offers is drawn (tests/tests/embed.rs); others are errors.
    let usage = wgpu::TextureUsages::RENDER_ATTACHMENT;
    let other = voxel_render::stages::target(
        &ctx.device,
        "rgba32",
        wgpu::TextureFormat::Rgba32Float,
        usage,
        (64, 48),
    );
    let e = r.render_and_submit(&other.view, &cam).unwrap_err();
    assert!(e.to_string().contains("Rgba32Float"), "{e}");
    // The right one still works afterwards.
    frame(&ctx, &mut r, &cam);
}

#[test]
fn peel_layers_beyond_the_limit_are_an_error_not_a_hang() {
    let Some(ctx) = gpu() else { return };
    let scene = dense_sheets(2, 0.5);
    let mut r = renderer_for(
        &ctx,
        &scene,
        technique_config(Technique::DepthPeeling, 64, 48),
    )
    .unwrap();
    for layers in [u32::MAX, 8194, 513 * 2, 3, 0] {
        let mut c = r.config().oit.clone();
        c.peeling.layers = layers;
        let e = r.set_oit_config(c).unwrap_err();
        assert!(matches!(e, voxel_render::Error::InvalidSetting(_)), "{e:?}");
        assert!(
            e.to_string().contains(&layers.to_string()) && e.to_string().contains("512"),
            "{e}"
        );
    }
    assert_eq!(r.config().oit.peeling.layers, 8, "nothing changed");
    let mut c = r.config().oit.clone();
    c.peeling.layers = voxel_render::low_level::MAX_PEEL_LAYERS;
    r.set_oit_config(c).unwrap();
    frame(&ctx, &mut r, &scene.cameras[0]);
}

#[test]
fn config_tells_the_truth_after_every_setter() {
    let Some(ctx) = gpu() else { return };
    let scene = dense_sheets(2, 0.5);
    let mut r = renderer_for(&ctx, &scene, technique_config(Technique::WboitMrt, 64, 48)).unwrap();
    assert_eq!(
        r.set_technique(Technique::Stipple).unwrap(),
        Technique::Stipple
    );
    assert_eq!(r.config().oit.technique, Technique::Stipple);
    let mut oit = r.config().oit.clone();
    oit.wboit.weight = voxel_render::WeightFunction::McGuire8;
    r.set_oit_config(oit).unwrap();
    assert_eq!(
        r.config().oit.wboit.weight,
        voxel_render::WeightFunction::McGuire8
    );
    assert_eq!(voxel_render::low_level::oit(&r).config(), &r.config().oit);
}

#[test]
fn the_a_buffer_tiles_its_head_pointers_when_they_exceed_a_storage_binding() {
    // A device whose storage bindings hold 64 KiB: the head pointers of 160x120 pixels
    // (75 KiB) do not fit one, so they are tiled; the picture stays exact.
    let Some(ctx) = gpu_with_limits(|l| l.max_storage_buffer_binding_size = 64 << 10) else {
        return;
    };
    let scene = dense_sheets(6, 0.4);
    let mut r = renderer_for(
        &ctx,
        &scene,
        technique_config(Technique::Reference, 160, 120),
    )
    .unwrap();
    let target = Offscreen::new(&ctx, 160, 120);
    let stats = r
        .render_and_submit(&target.view, &scene.cameras[0])
        .unwrap();
    let report = stats.technique.reference.unwrap();
    assert!(report.tiles >= 2, "{report:?}");
    assert!(report.exact(), "{report:?}");
    let a = target.read(&ctx).unwrap();
    let p = render_with(
        &ctx,
        &scene,
        technique_config(Technique::PeelReference, 160, 120),
    );
    assert_close("abuffer_tiled_heads", &a, &p, 2);
}

#[test]
fn chunks_and_eyes_outside_the_i32_world_are_errors() {
    let Some(ctx) = gpu() else { return };
    let scene = dense_sheets(2, 0.5);
    let mut r = renderer_for(&ctx, &scene, technique_config(Technique::WboitMrt, 64, 48)).unwrap();
    let meshes = voxel_mesh::ChunkMeshes {
        opaque: vec![voxel_mesh::PackedQuad::new(
            [0, 0, 0],
            1,
            1,
            voxel_core::Face::PosY,
            voxel_core::blocks::STONE,
        )],
        ..Default::default()
    };
    let e = r
        .upload_chunk(voxel_core::ChunkPos::new(1 << 26, 0, 0), &meshes)
        .unwrap_err();
    assert!(e.to_string().contains("outside the i32 world"), "{e}");
    let d = glam::DVec3::new(0.0, 0.0, -1.0);
    for (eye, fov, near, what) in [
        (
            glam::DVec3::new(3e9, 0.0, 0.0),
            60.0,
            0.1,
            "outside the i32 world",
        ),
        (glam::DVec3::ZERO, 60.0, 1e-50, "near"),
        (glam::DVec3::ZERO, 1e-40, 0.1, "field of view"),
        (glam::DVec3::new(f64::NAN, 0.0, 0.0), 60.0, 0.1, "finite"),
    ] {
        let e = voxel_render::Camera::look_at(eye, eye + d, fov, near, 100.0).unwrap_err();
        assert!(matches!(e, voxel_render::Error::InvalidCamera(_)), "{e:?}");
        assert!(e.to_string().contains(what), "{what}: {e}");
    }
}

#[test]
fn the_nearest_near_plane_still_shows_the_floor() {
    let Some(ctx) = gpu() else { return };
    let world = box_world(&[([-50, -1, -50], [50, -1, 50], voxel_core::blocks::STONE)]);
    let make = |near| {
        let cam = voxel_render::Camera::look_at(
            glam::DVec3::new(0.5, 1.5, 0.5),
            glam::DVec3::new(0.5, 0.0, -10.0),
            60.0,
            near,
            500.0,
        )
        .unwrap();
        Scene::new("floor", world.clone(), cam)
    };
    let sky = render_with(
        &ctx,
        &make(0.1),
        technique_config(Technique::WboitMrt, 64, 48),
    )
    .pixel(32, 2);
    for near in [0.1, voxel_render::low_level::MIN_NEAR] {
        let img = render_with(
            &ctx,
            &make(near),
            technique_config(Technique::WboitMrt, 64, 48),
        );
        let floor = img.pixel(32, 46);
        assert_ne!(floor, sky, "near {near}: the floor vanished");
    }
}

#[test]
fn hundreds_of_timed_passes_keep_every_pass_timed() {
    let Some(ctx) = gpu() else { return };
    if !ctx.caps.timestamps() {
        return;
    }
    // Peeling 100 layers to convergence records 200+ timed passes in one frame.
    let scene = dense_sheets(100, 0.3);
    let mut r = renderer_for(
        &ctx,
        &scene,
        technique_config(Technique::PeelReference, 48, 32),
    )
    .unwrap();
    frame(&ctx, &mut r, &scene.cameras[0]);
    let times = r.gpu_times_blocking();
    use voxel_render::GpuPass;
    for pass in GpuPass::ALL {
        // No leaves, no medium and no game in this scene: no cutout, medium or game pass.
        if !matches!(pass, GpuPass::Cutout | GpuPass::Medium | GpuPass::Game) {
            assert!(times.get(pass).is_some(), "{pass} untimed: {times:?}");
        }
    }
}

#[test]
fn unknown_names_list_the_known_ones() {
    let e = "wboit".parse::<Technique>().unwrap_err();
    assert!(matches!(e, voxel_render::Error::UnknownName { .. }));
    assert!(e.to_string().contains("wboit-mrt") && e.to_string().contains("peel-reference"));
    let e = "x".parse::<voxel_render::WeightFunction>().unwrap_err();
    assert!(e.to_string().contains("fitted"), "{e}");
    let e = voxel_render::BayerSize::from_side(3).unwrap_err();
    assert!(e.to_string().contains("16"), "{e}");
}

/// A texture of `size` with `mips` levels and `layers` layers, usable as a render target,
/// with `view_formats`.
fn texture(
    ctx: &voxel_render::GpuContext,
    size: (u32, u32),
    mips: u32,
    layers: u32,
    format: wgpu::TextureFormat,
    view_formats: &[wgpu::TextureFormat],
) -> wgpu::Texture {
    ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("test_output"),
        size: wgpu::Extent3d {
            width: size.0,
            height: size.1,
            depth_or_array_layers: layers,
        },
        mip_level_count: mips,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats,
    })
}

/// The output must be a whole level-0 2D view of the renderer's size, viewed
/// as a format the tonemap pipeline writes. A view of mip level 1 (the right size for a
/// level but not the renderer), the sRGB twin viewed as the linear format, a 2D-array
/// view or a layer of an array texture are errors before anything is recorded (under
/// the panicking error handler, a validation error let through fails the test); the
/// allowed twin (a linear texture viewed as the sRGB format asked for) draws the same
/// picture as the plain target.
#[test]
fn output_views_other_than_a_whole_level_0_2d_view_are_errors() {
    use wgpu::TextureFormat as F;
    let Some(ctx) = gpu() else { return };
    let scene = dense_sheets(2, 0.5);
    let cam = scene.cameras[0];
    let (w, h) = (160, 90);
    let mut r = renderer_for(&ctx, &scene, technique_config(Technique::WboitMrt, w, h)).unwrap();
    let plain = frame(&ctx, &mut r, &cam);
    assert!(distinct_colours(&plain) > 8);

    let expect_output_error =
        |r: &mut voxel_render::Renderer, view: &wgpu::TextureView, what| match r.render_and_submit(
            view,
            &cam,
            &mut NoGame,
        ) {
            Err(e @ voxel_render::Error::Output(_)) => e.to_string(),
            Err(e) => panic!("{what}: {e:?}"),
            Ok(_) => panic!("{what}: accepted"),
        };
    let mipped = texture(&ctx, (w, h), 2, 1, F::Rgba8UnormSrgb, &[]);
    let level1 = mipped.create_view(&wgpu::TextureViewDescriptor {
        base_mip_level: 1,
        mip_level_count: Some(1),
        ..Default::default()
    });
    let msg = expect_output_error(&mut r, &level1, "mip level 1");
    assert!(
        msg.contains("mip level 0") && msg.contains("160x90"),
        "{msg}"
    );
    // Level 0 of the same texture is fine.
    let level0 = mipped.create_view(&wgpu::TextureViewDescriptor {
        mip_level_count: Some(1),
        ..Default::default()
    });
    r.render_and_submit(&level0, &cam).unwrap();

    let twin = texture(&ctx, (w, h), 1, 1, F::Rgba8UnormSrgb, &[F::Rgba8Unorm]);
    let linear = twin.create_view(&wgpu::TextureViewDescriptor {
        format: Some(F::Rgba8Unorm),
        ..Default::default()
    });
    let msg = expect_output_error(&mut r, &linear, "sRGB texture viewed linear");
    assert!(msg.contains("Rgba8UnormSrgb"), "{msg}");

    let layered = texture(&ctx, (w, h), 1, 2, F::Rgba8UnormSrgb, &[]);
    let array_view = layered.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    });
    let msg = expect_output_error(&mut r, &array_view, "2D-array view of 2 layers");
    assert!(msg.contains("2 layers"), "{msg}");
    let layer = layered.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2),
        base_array_layer: 1,
        array_layer_count: Some(1),
        ..Default::default()
    });
    let msg = expect_output_error(&mut r, &layer, "a layer of an array texture");
    assert!(msg.contains("2 layers"), "{msg}");
    // A 2D-array view of a single-layer texture is the whole texture: wgpu draws into it
    // like a 2D view (the same picture), so it is accepted.
    let single = texture(&ctx, (w, h), 1, 1, F::Rgba8UnormSrgb, &[]);
    let single_array = single.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    });
    r.render_and_submit(&single_array, &cam).unwrap();
    let rgba = voxel_render::readback::read_texture(&ctx, &single, 4).unwrap();
    let image = voxel_render::Image {
        width: w,
        height: h,
        rgba,
    };
    assert_close("output_single_layer_array_view", &image, &plain, 0);

    // The allowed twin: a linear texture viewed as the sRGB format, declared in
    // `output_view_format` (wgpu hides a view's format); undeclared, it is an error.
    let unorm = texture(&ctx, (w, h), 1, 1, F::Rgba8Unorm, &[F::Rgba8UnormSrgb]);
    let srgb = unorm.create_view(&wgpu::TextureViewDescriptor {
        format: Some(F::Rgba8UnormSrgb),
        ..Default::default()
    });
    let msg = expect_output_error(&mut r, &srgb, "an undeclared twin view");
    assert!(msg.contains("Rgba8Unorm"), "{msg}");
    let mut config = technique_config(Technique::WboitMrt, w, h);
    config.output_view_format = Some(F::Rgba8UnormSrgb);
    let mut declared = renderer_for(&ctx, &scene, config).unwrap();
    declared.render_and_submit(&srgb, &cam).unwrap();
    let bytes = voxel_render::readback::read_texture(&ctx, &unorm, 4).unwrap();
    let twin_image = voxel_render::Image {
        width: w,
        height: h,
        rgba: bytes,
    };
    assert_close("output_twin_view", &twin_image, &plain, 0);
    // And the plain target still works after every refusal.
    assert_close(
        "output_after_refusals",
        &frame(&ctx, &mut r, &cam),
        &plain,
        0,
    );
}

/// An `output_format` the tonemap cannot write (integer, depth, not
/// renderable) is an error at `new`, naming it; NaN, infinite or out-of-range lighting
/// values are errors at `new`, naming the field.
#[test]
fn bad_output_formats_and_lighting_are_errors_at_new() {
    use wgpu::TextureFormat as F;
    let Some(ctx) = gpu() else { return };
    let registry = voxel_core::BlockRegistry::default();
    let config = technique_config(Technique::WboitMrt, 64, 48);
    for format in [F::Rgba8Uint, F::Depth32Float, F::R32Sint, F::Rgb9e5Ufloat] {
        let c = voxel_render::RendererConfig {
            output_format: format,
            ..config.clone()
        };
        let e = voxel_render::Renderer::new(&ctx, &registry, c).unwrap_err();
        assert!(matches!(e, voxel_render::Error::InvalidSetting(_)), "{e:?}");
        assert!(e.to_string().contains(&format!("{format:?}")), "{e}");
    }
    for format in [F::Rgba16Float, F::Bgra8UnormSrgb, F::Rgba8Unorm] {
        let c = voxel_render::RendererConfig {
            output_format: format,
            ..config.clone()
        };
        voxel_render::Renderer::new(&ctx, &registry, c).unwrap();
    }
    const NAN: f32 = f32::NAN;
    const INF: f32 = f32::INFINITY;
    type Change = Box<dyn Fn(&mut voxel_render::RendererConfig)>;
    let cases: [(&str, Change); 7] = [
        ("ambient", Box::new(|c| c.ambient = NAN)),
        ("ambient", Box::new(|c| c.ambient = INF)),
        ("ambient", Box::new(|c| c.ambient = -0.5)),
        ("sky", Box::new(|c| c.sky = [0.1, NAN, 0.2])),
        ("sky", Box::new(|c| c.sky = [INF, 0.1, 0.2])),
        ("sky", Box::new(|c| c.sky = [0.1, -1.0, 0.2])),
        ("sun_dir", Box::new(|c| c.sun_dir = [0.0, INF, 0.0])),
    ];
    for (field, change) in cases {
        let mut c = config.clone();
        change(&mut c);
        let e = voxel_render::Renderer::new(&ctx, &registry, c).unwrap_err();
        assert!(matches!(e, voxel_render::Error::InvalidSetting(_)), "{e:?}");
        assert!(e.to_string().contains(field), "{field}: {e}");
    }
    // The edges of the ranges are fine: all ambient light, a black sky, a zero sun
    // direction (straight up).
    let mut c = config.clone();
    c.ambient = 1.0;
    c.sky = [0.0; 3];
    c.sun_dir = [0.0; 3];
    let scene = dense_sheets(2, 0.5);
    let mut r = renderer_for(&ctx, &scene, c).unwrap();
    let img = frame(&ctx, &mut r, &scene.cameras[0]);
    assert!(distinct_colours(&img) > 4);
}

/// Finite directions of any length are directions: a sun of `[1e38; 3]` or `[f32::MAX, 0,
/// 0]` lights as the same direction of length 1, a camera looking along a direction of
/// length 1e160 (or 1e-300) draws what the unit direction draws; zero and non-finite ones
/// are errors that say which.
#[test]
fn huge_and_tiny_directions_draw_as_their_unit_direction() {
    let Some(ctx) = gpu() else { return };
    let mut world = box_world(&[
        ([-12, -2, -12], [12, -1, 12], voxel_core::blocks::STONE),
        ([-4, 0, -4], [4, 3, -2], voxel_core::blocks::STONE),
        ([-2, 0, 0], [2, 2, 2], voxel_core::blocks::WATER),
    ]);
    voxel_lab::scene::fill_box(&mut world, [5, 0, 3], [6, 4, 4], voxel_core::blocks::GRASS)
        .unwrap();
    let scene = scene("directions", world, [9.5, 7.5, 11.0], [0.0, 0.0, -2.0]);
    let cam = scene.cameras[0];
    let config = technique_config(Technique::SortedQuads, 96, 64);
    let mut r = renderer_for(&ctx, &scene, config).unwrap();
    let base = r.lighting();
    for (huge, unit) in [
        ([1e38f32; 3], [1.0f32; 3]),
        ([f32::MAX, 0.0, 0.0], [1.0, 0.0, 0.0]),
        ([f32::MAX, f32::MAX, -f32::MAX], [1.0, 1.0, -1.0]),
        ([0.0, 1e-44, 1e-44], [0.0, 1.0, 1.0]),
    ] {
        r.set_lighting(voxel_render::Lighting {
            sun_dir: unit,
            ..base
        })
        .unwrap();
        let expected = frame(&ctx, &mut r, &cam);
        r.set_lighting(voxel_render::Lighting {
            sun_dir: huge,
            ..base
        })
        .unwrap();
        let got = frame(&ctx, &mut r, &cam);
        assert!(distinct_colours(&got) > 8);
        assert_close(&format!("sun_{huge:?}"), &got, &expected, 0);
    }
    for bad in [[0.0f32; 3], [f32::NAN, 1.0, 0.0], [f32::INFINITY, 0.0, 0.0]] {
        let e = r
            .set_lighting(voxel_render::Lighting {
                sun_dir: bad,
                ..base
            })
            .unwrap_err()
            .to_string();
        let why = if bad[0] == 0.0 { "zero" } else { "finite" };
        assert!(e.contains(why), "{bad:?}: {e}");
    }
    r.set_lighting(base).unwrap();
    let expected = frame(&ctx, &mut r, &cam);
    for scale in [1e160, 1e300, 1e-300, f64::MAX] {
        let stretched = voxel_render::Camera {
            forward: cam.forward * scale,
            ..cam
        };
        let got = frame(&ctx, &mut r, &stretched);
        assert_close(&format!("camera_x{scale:e}"), &got, &expected, 0);
    }
    for (forward, why) in [
        (glam::DVec3::ZERO, "zero"),
        (glam::DVec3::new(f64::NAN, 0.0, 1.0), "finite"),
    ] {
        let bad = voxel_render::Camera { forward, ..cam };
        let target = Offscreen::new(&ctx, 96, 64);
        let e = r
            .render_and_submit(&target.view, &bad)
            .unwrap_err()
            .to_string();
        assert!(e.contains(why), "{forward}: {e}");
    }
}
