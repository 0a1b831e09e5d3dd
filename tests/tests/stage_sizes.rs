//! Issue 52: a game's own stages never have to know how many parts `sorted-quads` cuts its
//! objects into. The order a sorted technique gives (`GameFrame::order`) holds each object
//! once, and the ranges the game is asked to draw lie within it: an instance buffer sized
//! for the game's objects holds every frame, however many parts are drawn (a part is its
//! object's position drawn again, with its own clip). Before, the order held an object once
//! per part, and a game whose buffers were sized for its objects met a validation error.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use std::cell::{Cell, RefCell};
use std::ops::Range;

use glam::DVec3;
use voxel_core::blocks::{GLASS, GRASS};
use voxel_lab::headless::{Offscreen, renderer_for};
use voxel_render::stages::{GameFrame, Stages};
use voxel_render::{GameStages, GpuContext, Technique, TranslucentObject};

/// A game whose instance buffers hold its objects and no more: it records every order and
/// every range it is given (drawing nothing, so that a range past its objects is reported
/// here rather than as wgpu's validation error).
struct Sized {
    objects: Vec<TranslucentObject>,
    contract: Option<u64>,
    order_len: Cell<usize>,
    ranges: RefCell<Vec<Range<usize>>>,
}

impl GameStages for Sized {
    fn stages(&self) -> Stages {
        Stages {
            translucent: true,
            ..Stages::default()
        }
    }

    fn translucent_objects(&self) -> &[TranslucentObject] {
        &self.objects
    }

    fn translucent_contract_id(&self) -> Option<u64> {
        self.contract
    }

    fn prepare(&mut self, _: &GpuContext, frame: &GameFrame<'_>) {
        let order = frame.order.unwrap();
        self.order_len.set(order.len());
        // A permutation of the objects: each once.
        let mut seen = vec![false; self.objects.len()];
        for &i in order {
            assert!(
                !std::mem::replace(&mut seen[i as usize], true),
                "object {i} twice"
            );
        }
        self.ranges.borrow_mut().clear();
    }

    fn translucent(
        &self,
        _: &mut wgpu::RenderPass<'_>,
        _: &GameFrame<'_>,
        _: usize,
        objects: Range<usize>,
    ) {
        self.ranges.borrow_mut().push(objects);
    }
}

#[test]
fn a_games_buffers_sized_for_its_objects_hold_the_parts_sorted_quads_cuts() {
    let Some(ctx) = tests::gpu() else { return };
    // A glass floor (its top face at y = 1) and a glass layer above (y = 4 to 5) over four
    // chunks: cubes through the floor's top face are cut there (the layer above keeps the
    // chunk undecided), those across a chunk border at the border too.
    let world = tests::box_world(&[
        ([-24, -1, -24], [24, -1, 24], GRASS),
        ([-20, 0, -20], [20, 0, 20], GLASS),
        ([-20, 4, -20], [20, 4, 20], GLASS),
    ]);
    let scene = tests::scene("stage_sizes", world, [1.5, 11.0, 13.0], [0.0, 0.0, -1.0]);
    let objects: Vec<TranslucentObject> = (0..40)
        .map(|i| {
            let (x, z) = (f64::from(i % 8) * 2.5 - 9.0, f64::from(i / 8) * 2.5 - 6.0);
            TranslucentObject::aabb(DVec3::new(x, 1.0, z), DVec3::splat(0.6))
        })
        .collect();
    let n = objects.len();
    let mut game = Sized {
        objects,
        contract: None,
        order_len: Cell::new(0),
        ranges: RefCell::new(Vec::new()),
    };
    let (w, h) = (160, 90);
    let mut r = renderer_for(
        &ctx,
        &scene,
        tests::technique_config(Technique::SortedQuads, w, h),
    )
    .unwrap();
    let renderer = &mut r.renderer;
    game.contract = Some(renderer.translucent_contract().unwrap().id);
    let target = Offscreen::new(&ctx, w, h);
    let camera = scene.cameras[0];
    for _ in 0..2 {
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        renderer
            .render(&mut encoder, &target.view, &camera, &mut game)
            .unwrap();
        ctx.queue.submit([encoder.finish()]);
    }
    let ranges = game.ranges.borrow();
    let drawn: usize = ranges.iter().map(|r| r.len()).sum();
    // Cut: more positions drawn than objects (each part a run of its own).
    assert!(
        drawn > n,
        "{drawn} positions drawn for {n} objects: nothing was cut"
    );
    assert_eq!(game.order_len.get(), n, "the order holds each object once");
    for r in ranges.iter() {
        assert!(
            r.start < r.end && r.end <= n,
            "a range {r:?} past the {n} objects the game sized its buffers for"
        );
    }
    // Every object drawn at least once.
    let mut covered = vec![false; n];
    for r in ranges.iter() {
        covered[r.clone()].fill(true);
    }
    assert!(covered.iter().all(|&c| c));
}
