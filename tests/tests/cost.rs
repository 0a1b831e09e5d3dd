//! What each technique's frame asks of the GPU, counted (`voxel_render::low_level::FrameCost`)
//! on suite scenes at a small size, bounded per technique: what decides a GPU's cost, which
//! a CPU rasteriser's milliseconds hide (a regression like a sorted order that draws every
//! quad on its own shows here first).

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use std::collections::HashMap;
use std::path::Path;

use voxel_render::low_level::{self, CostTotals, FrameCost};
use voxel_render::{GpuContext, GpuPass, OitConfig, RendererConfig, Technique};

use tests::*;

const W: u32 = 160;
const H: u32 = 90;

const TECHNIQUES: [Technique; 6] = [
    Technique::Sorted,
    Technique::SortedQuads,
    Technique::WboitMrt,
    Technique::WboitTwoPass,
    Technique::Mboit,
    Technique::Stipple,
];

/// A renderer of suite scene `scene` at W×H with the default settings, its target and its
/// first camera.
fn suite_renderer(
    ctx: &GpuContext,
    scene: &str,
) -> (
    voxel_lab::headless::SceneRenderer,
    Offscreen,
    voxel_render::Camera,
) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../scenes")
        .join(format!("{scene}.toml"));
    let scene = Scene::load(&path).unwrap();
    let config = RendererConfig {
        width: W,
        height: H,
        ..RendererConfig::default()
    };
    let renderer = renderer_for(ctx, &scene, config).unwrap();
    (renderer, Offscreen::new(ctx, W, H), scene.cameras[0])
}

/// Every technique of [`TECHNIQUES`] on one renderer of `scene`, each counted in its third
/// frame (the first builds, the second settles a switch).
fn costs(ctx: &GpuContext, scene: &str) -> HashMap<Technique, FrameCost> {
    let (mut renderer, target, camera) = suite_renderer(ctx, scene);
    let mut out = HashMap::new();
    for t in TECHNIQUES {
        renderer.set_oit_config(OitConfig::with(t)).unwrap();
        for _ in 0..2 {
            renderer.render_and_submit(&target.view, &camera).unwrap();
        }
        low_level::count_next_frame(&mut renderer);
        renderer.render_and_submit(&target.view, &camera).unwrap();
        let cost = low_level::frame_cost(&mut renderer).unwrap().unwrap();
        assert!(
            cost.measured,
            "{t}: lavapipe has occlusion and pipeline-statistics queries"
        );
        // Nothing after a counted frame is counted.
        renderer.render_and_submit(&target.view, &camera).unwrap();
        assert!(low_level::frame_cost(&mut renderer).unwrap().is_none());
        out.insert(t, cost);
    }
    out
}

fn fragments(t: &CostTotals) -> u64 {
    t.fragments.unwrap()
}

fn bytes(t: &CostTotals) -> u64 {
    t.bytes().unwrap()
}

#[test]
fn counted_frames_bound_each_techniques_work_on_suite_scenes() {
    let Some(ctx) = gpu() else { return };
    for scene in ["deep_stack", "game_sea", "lake_depths"] {
        let c = costs(&ctx, scene);
        let tr = |t: Technique| c[&t].translucent();
        let (sorted, quads) = (tr(Technique::Sorted), tr(Technique::SortedQuads));
        let (mrt, two) = (tr(Technique::WboitMrt), tr(Technique::WboitTwoPass));
        let mboit = tr(Technique::Mboit);
        eprintln!(
            "{scene}: sorted {sorted:?}\n  sorted-quads {quads:?}\n  wboit-mrt {mrt:?}\n  \
             wboit-two-pass {two:?}\n  mboit {mboit:?}"
        );

        // Sorting quads changes the order, not what is drawn: the same fragments, and at
        // most twice the draws and state changes (the game's objects among the quads).
        assert_eq!(quads.passes, 1, "{scene}");
        assert_eq!(quads.full_screen_passes, 0, "{scene}");
        assert!(
            fragments(&quads) * 100 <= fragments(&sorted) * 102,
            "{scene}: sorted-quads shades {} fragments, sorted {}",
            fragments(&quads),
            fragments(&sorted)
        );
        assert!(
            quads.draws <= 2 * sorted.draws && quads.pipelines <= 2 * sorted.pipelines + 2,
            "{scene}: sorted-quads {quads:?} against sorted {sorted:?}"
        );
        // A still camera sorts nothing again: a frame uploads what sorted's uploads.
        assert!(
            c[&Technique::SortedQuads].upload_bytes <= c[&Technique::Sorted].upload_bytes + 64,
            "{scene}: sorted-quads uploads {} bytes a still frame, sorted {}",
            c[&Technique::SortedQuads].upload_bytes,
            c[&Technique::Sorted].upload_bytes
        );

        // WBOIT: one pass of the geometry (two in two-pass form), one composite at most,
        // and the one-pass form never more work than the two-pass one.
        assert!(
            mrt.passes <= 2 && mrt.full_screen_passes <= 1,
            "{scene}: {mrt:?}"
        );
        assert!(
            two.passes <= 3 && two.full_screen_passes <= 1,
            "{scene}: {two:?}"
        );
        assert!(mrt.draws <= two.draws && fragments(&mrt) <= fragments(&two));
        assert!(
            bytes(&mrt) <= bytes(&two),
            "{scene}: wboit-mrt moves {} bytes, wboit-two-pass {}",
            bytes(&mrt),
            bytes(&two)
        );
        // MBOIT draws the geometry twice: at most twice WBOIT's fragments, one composite.
        assert!(
            fragments(&mboit) <= 2 * fragments(&mrt) && mboit.full_screen_passes <= 1,
            "{scene}: mboit {mboit:?} against wboit-mrt {mrt:?}"
        );

        // What a real-time frame creates: the frame's staging buffer, and the game's group
        // and clip buffer where a game draws; never per chunk or per object.
        for t in TECHNIQUES {
            let f = &c[&t];
            assert!(
                f.buffers_created <= 2 && f.bind_groups_created <= 2,
                "{scene}, {t}: {} buffers and {} bind groups made in a frame",
                f.buffers_created,
                f.bind_groups_created
            );
        }
    }
}

#[test]
fn media_passes_run_only_with_a_volume_or_the_eyes_medium_in_view() {
    let Some(ctx) = gpu() else { return };
    // Sheets of ice and glass, the eye in air: no medium anywhere.
    for (t, f) in costs(&ctx, "deep_stack") {
        let media = f.of_kind(GpuPass::Medium);
        assert_eq!(
            (media.passes, media.copies),
            (0, 0),
            "deep_stack, {t}: media passes without a volume in view"
        );
    }
    // A lake: water is a volume in view; its depth passes (drawing the translucent chunks)
    // and the full-screen media pass run, the same for every real-time technique.
    let lake = costs(&ctx, "lake_depths");
    let sorted = lake[&Technique::Sorted].of_kind(GpuPass::Medium);
    assert!(
        sorted.passes >= 4 && sorted.full_screen_passes == 1,
        "{sorted:?}"
    );
    for (t, f) in &lake {
        assert_eq!(f.of_kind(GpuPass::Medium), sorted, "lake_depths, {t}");
    }
}

#[test]
fn the_game_objects_of_the_sorted_order_cost_few_runs() {
    let Some(ctx) = gpu() else { return };
    // 2 000 bubbles in a pool behind glass: sorted-quads places them among the water's and
    // the pane's quads, in as few runs as their places allow (each run a draw of the game's
    // and a switch of pipeline); parts of bubbles cut at the surface join one run per
    // clip where they overlap nothing they pass.
    let c = costs(&ctx, "particles_over_water");
    let (sorted, quads) = (
        c[&Technique::Sorted].translucent(),
        c[&Technique::SortedQuads].translucent(),
    );
    eprintln!("sorted {sorted:?}\nsorted-quads {quads:?}");
    // Before runs were gathered: 416 draws, 807 pipeline changes and 403 calls into the
    // game at 320x180. Now about a quarter of that; the bound leaves room for the view.
    assert!(
        quads.game_calls <= 150 && quads.pipelines <= 2 * quads.game_calls + 2,
        "{quads:?}"
    );
    assert!(
        quads.draws <= 8 * sorted.draws,
        "{quads:?} against {sorted:?}"
    );
}

/// A counted frame whose encoder is not submitted yet has no cost to give: `frame_cost`
/// is an `Error::FrameOrder` until the submit (the counted frame is kept), then the cost;
/// one whose encoder is dropped unsubmitted ran nothing: `None`. (Before, both gave a
/// cost read from query results the GPU never wrote.)
#[test]
fn an_unsubmitted_frame_has_no_cost() {
    let Some(ctx) = gpu() else { return };
    let (mut r, target, camera) = suite_renderer(&ctx, "deep_stack");
    r.render_and_submit(&target.view, &camera).unwrap();
    // A counted frame recorded into an encoder of its own, not submitted.
    let record_counted = |renderer: &mut voxel_render::Renderer| {
        low_level::count_next_frame(renderer);
        let mut e = ctx.device.create_command_encoder(&Default::default());
        renderer
            .render(&mut e, &target.view, &camera, &mut voxel_render::NoGame)
            .unwrap();
        e
    };

    // Recorded, not submitted: an error naming the submit, the frame kept.
    let e = record_counted(&mut r.renderer);
    let err = low_level::frame_cost(&mut r.renderer).unwrap_err();
    assert!(
        matches!(err, voxel_render::Error::FrameOrder(_)) && err.to_string().contains("submit"),
        "{err:?}"
    );
    ctx.queue.submit([e.finish()]);
    let cost = low_level::frame_cost(&mut r.renderer).unwrap().unwrap();
    assert!(cost.measured && fragments(&cost.all()) > 0, "{cost:?}");
    assert!(low_level::frame_cost(&mut r.renderer).unwrap().is_none());

    // Dropped unsubmitted: nothing ran, no cost; then the next counted frame has one.
    drop(record_counted(&mut r.renderer));
    assert!(low_level::frame_cost(&mut r.renderer).unwrap().is_none());
    // Also once a later frame has learnt of the drop.
    drop(record_counted(&mut r.renderer));
    r.render_and_submit(&target.view, &camera).unwrap();
    assert!(low_level::frame_cost(&mut r.renderer).unwrap().is_none());
    low_level::count_next_frame(&mut r.renderer);
    r.render_and_submit(&target.view, &camera).unwrap();
    let cost = low_level::frame_cost(&mut r.renderer).unwrap().unwrap();
    assert!(cost.measured && fragments(&cost.all()) > 0, "{cost:?}");
}

/// wgpu's GL backend answers occlusion queries with GL's `ANY_SAMPLES_PASSED_CONSERVATIVE`
/// (1 where any sample passed) and has no pipeline statistics: a counted frame there is
/// not measured, its fragments, samples and bytes `None` (they read 4 fragments for a
/// frame of millions before), its commands still counted.
#[test]
fn gl_frames_are_counted_but_not_measured() {
    let Some(ctx) = tests::gl() else { return };
    let (mut r, target, camera) = suite_renderer(&ctx, "deep_stack");
    for t in [Technique::WboitMrt, Technique::SortedQuads] {
        r.renderer.set_oit_config(OitConfig::with(t)).unwrap();
        r.render_and_submit(&target.view, &camera).unwrap();
        low_level::count_next_frame(&mut r.renderer);
        r.render_and_submit(&target.view, &camera).unwrap();
        let cost = low_level::frame_cost(&mut r.renderer).unwrap().unwrap();
        let all = cost.all();
        assert!(!cost.measured, "{t} on GL: {cost:?}");
        assert_eq!(
            (all.fragments, all.samples, all.bytes()),
            (None, None, None),
            "{t} on GL"
        );
        assert!(
            cost.passes
                .iter()
                .all(|p| p.samples.is_none() && p.fragments.is_none()),
            "{t} on GL: {cost:?}"
        );
        assert!(all.passes >= 2 && all.draw_calls > 0, "{t} on GL: {all:?}");
    }
}
