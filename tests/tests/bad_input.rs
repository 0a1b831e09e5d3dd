//! Bad input and stress: every case gets a clear error (kind and message checked) or a
//! documented fallback, never a panic, a hang or a silently wrong picture. GPU cases run
//! under wgpu's default uncaptured-error handler, which panics: a validation error the
//! renderer lets through fails the test.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

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
    let other = voxel_render::gpu::target(
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
    c.peeling.layers = voxel_render::oit::peeling::MAX_PEEL_LAYERS;
    r.set_oit_config(c).unwrap();
    frame(&ctx, &mut r, &scene.cameras[0]);
}

#[test]
fn config_tells_the_truth_after_every_setter() {
    let Some(ctx) = gpu() else { return };
    let scene = dense_sheets(2, 0.5);
    let mut r = renderer_for(&ctx, &scene, technique_config(Technique::WboitMrt, 64, 48)).unwrap();
    r.set_technique(Technique::Stipple);
    assert_eq!(r.config().oit.technique, Technique::Stipple);
    r.set_weight(voxel_render::WeightFunction::McGuire8);
    assert_eq!(
        r.config().oit.wboit.weight,
        voxel_render::WeightFunction::McGuire8
    );
    assert_eq!(r.oit().config(), &r.config().oit);
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
    for near in [0.1, voxel_render::MIN_NEAR] {
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
        // No leaves and no medium in this scene: no cutout and no medium pass.
        if !matches!(pass, GpuPass::Cutout | GpuPass::Medium) {
            assert!(times.get(pass).is_some(), "{pass} untimed: {times:?}");
        }
    }
}

#[test]
fn unknown_names_list_the_known_ones() {
    let e = Technique::from_name("wboit").unwrap_err();
    assert!(matches!(e, voxel_render::Error::UnknownName { .. }));
    assert!(e.to_string().contains("wboit-mrt") && e.to_string().contains("peel-reference"));
    let e = voxel_render::WeightFunction::from_name("x").unwrap_err();
    assert!(e.to_string().contains("fitted"), "{e}");
    let e = voxel_render::BayerSize::from_side(3).unwrap_err();
    assert!(e.to_string().contains("16"), "{e}");
}
