//! Issue 52's G1 cases: a game's flat things lying on glass under another glass layer (one
//! across chunk borders, cut there), and particles between two glass layers
//! (`scenes/regressions/foam_on_glass_under_glass.toml`, `particles_between_glass.toml`,
//! exact before and after the fix), and two scenes the search below found
//! (`foam_on_glass_big_side.toml`, `foam_on_glass_big_chunks.toml`: big things, the layers'
//! sides in view, 71/255 and 24/255 off on 28 % and 1.6 % of the picture before the fix):
//! `sorted-quads` within 1/255 of the A-buffer reference off quad edges (where the
//! rasteriser decides, not the order) and object overlaps, as `depth-peeling` is. And issue
//! 54's beam through seven panes and a water surface (`beam_through_seven_panes.toml`,
//! fifteen planes), held to that target. On lavapipe, as CI runs it.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use voxel_lab::edges::{self, Edges};
use voxel_lab::headless::{Offscreen, render_image, renderer_for};
use voxel_lab::overlaps::object_mask;
use voxel_lab::scene::Scene;
use voxel_render::{GpuContext, Image, Technique};

const SIZE: (u32, u32) = (320, 180);

fn scene(name: &str) -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../scenes/regressions")
        .join(name);
    Scene::load(&path).unwrap()
}

/// Each technique's picture of `scene` against the reference's: the largest channel error
/// off quad edges and off pixels of objects that meet, and the pixels off by more than
/// 1/255 there.
fn off_edges(
    ctx: &GpuContext,
    scene: &Scene,
    name: &str,
    camera: usize,
    techniques: &[Technique],
) -> Vec<(Technique, u32, usize)> {
    let camera = scene.cameras[camera];
    let picture = |technique: Technique| {
        let config = tests::technique_config(technique, SIZE.0, SIZE.1);
        let mut r = renderer_for(ctx, scene, config).unwrap();
        let target = Offscreen::new(ctx, SIZE.0, SIZE.1);
        let image = render_image(ctx, &mut r, &target, &camera).unwrap();
        (image, r.renderer.drawn_camera(&camera))
    };
    let (reference, drawn) = picture(Technique::Reference);
    let quad_edges = Edges::new(&scene.world, &drawn, SIZE);
    let objects = object_mask(&scene.content, &drawn, SIZE);
    let out = tests::out_dir("cut_on_glass");
    let _ = reference.save_png(&out.join(format!("{name}_reference.png")));
    techniques
        .iter()
        .map(|&t| {
            let (image, _): (Image, _) = picture(t);
            let _ = image.save_png(&out.join(format!("{name}_{}.png", t.name())));
            let _ = tests::diff_image(&reference, &image)
                .save_png(&out.join(format!("{name}_{}_diff.png", t.name())));
            let off = edges::error_off_edges(&quad_edges, &objects, &reference, &image);
            let d = tests::diff(&reference, &image);
            eprintln!(
                "{name} {}: max {} ({} px over 1/255), off edges and overlaps max {} ({} px over 8/255)",
                t.name(),
                d.max,
                d.over_one,
                off.max,
                off.over_8
            );
            (t, off.max, d.over_one)
        })
        .collect()
}

fn assert_exact(name: &str) {
    assert_each_camera(
        name,
        &[Technique::SortedQuads, Technique::DepthPeeling],
        |max, _| max <= 1,
    );
}

/// Each of `techniques` on every camera of the scene `name`: `ok(the largest error off quad
/// edges and overlaps, the pixels over 1/255)` must hold.
fn assert_each_camera(name: &str, techniques: &[Technique], ok: impl Fn(u32, usize) -> bool) {
    let Some(ctx) = tests::gpu() else { return };
    let scene = scene(name);
    let mut failed = Vec::new();
    for camera in 0..scene.cameras.len() {
        let tag = format!("{}_{camera}", name.trim_end_matches(".toml"));
        for (t, max, over_one) in off_edges(&ctx, &scene, &tag, camera, techniques) {
            if !ok(max, over_one) {
                failed.push(format!(
                    "camera {camera}: {} {max}/255 off edges, {over_one} px over 1/255",
                    t.name()
                ));
            }
        }
    }
    assert!(
        failed.is_empty(),
        "{name}: off the reference off quad edges: {failed:?}"
    );
}

#[test]
fn flat_things_lying_on_glass_under_glass_are_exact_in_sorted_quads() {
    assert_exact("foam_on_glass_under_glass.toml");
}

#[test]
fn particles_between_glass_layers_are_exact_in_sorted_quads() {
    assert_exact("particles_between_glass.toml");
}

/// Found by [`search_flat_things_on_glass_under_glass`]: a big flat thing on a water floor
/// under green glass, the layers' sides (one plane) in view. Before each run of a plane's
/// quads had its own box, the floor's side (drawn before the floor's top, and never
/// overlapping the thing on screen) shared the box of the upper layer's side (which does)
/// and kept the thing before the floor's top: 71/255 off on 16 061 pixels (28 %).
#[test]
fn a_big_flat_thing_on_glass_under_glass_seen_past_the_side_is_exact() {
    assert_exact("foam_on_glass_big_side.toml");
}

/// Issue 54: a 16-block beam through seven glass panes standing in a pool, its far half
/// under the surface: fifteen planes (fourteen pane faces and the surface). Cut at the four
/// planes nearest its centre, its spans behind the far panes were drawn at one place: 43/255
/// and 32/255 off (22 and 129 pixels over 8/255) at the two cameras. Held to issue 54's
/// target: no pixel over 8/255 off quad edges and overlaps, at most 0.1 % of the picture
/// over 1/255 (sixteen layers blended along a ray round to 2/255 on a few pixels).
/// `depth-peeling` is not held to it: the ray crosses more layers than it peels (18/255).
#[test]
fn a_beam_through_seven_panes_and_a_surface_is_cut_at_every_plane() {
    let pixels = f64::from(SIZE.0 * SIZE.1);
    assert_each_camera(
        "beam_through_seven_panes.toml",
        &[Technique::SortedQuads],
        |max, over_one| max <= 8 && over_one as f64 / pixels <= 0.001,
    );
}

/// Found by the search likewise: big flat things on a thick floor across a vertical chunk
/// border under glass: 24/255 off on 916 pixels before (1.6 %).
#[test]
fn big_flat_things_on_a_thick_floor_across_chunks_are_exact() {
    assert_exact("foam_on_glass_big_chunks.toml");
}

/// A small deterministic generator for the search (splitmix64).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    /// Uniform in `[a, b)`.
    fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn int(&mut self, a: i32, b: i32) -> i32 {
        a + (self.next() % (b - a + 1) as u64) as i32
    }
    fn pick<'a, T>(&mut self, v: &'a [T]) -> &'a T {
        &v[(self.next() % v.len() as u64) as usize]
    }
    fn chance(&mut self, p: f64) -> bool {
        self.range(0.0, 1.0) < p
    }
}

/// One random scene of issue 52's G1 space: a glass floor (1 to 3 blocks thick, any of the
/// registry's translucent blocks or a tinted volume) with a second layer 1 to 4 blocks
/// above, big flat things lying on the floor (4 to 40 blocks, 0.02 to 0.5 thick, turned,
/// some glowing), particles between the layers or on the floor, and cameras above both
/// layers (steep and grazing) and between them.
fn random_case(rng: &mut Rng, i: usize) -> String {
    use std::fmt::Write;
    let blocks = [
        "glass",
        "ice",
        "red_glass",
        "green_glass",
        "blue_glass",
        "water",
        "smoky",
    ];
    let (b1, b2) = (*rng.pick(&blocks), *rng.pick(&blocks));
    let oy = *rng.pick(&[0, 0, 0, 28, 29, 30, 31, -3]);
    let (t1, t2, gap) = (rng.int(1, 3), rng.int(1, 3), rng.int(1, 4));
    let l = *rng.pick(&[20, 40]);
    let (ox, oz) = (rng.int(-16, 16), rng.int(-16, 16));
    let top = oy + t1;
    let upper = top + gap;
    let upper_top = upper + t2;
    let mut s = format!(
        "name = \"g1 search {i}\"\n\
         [[blocks]]\nname = \"smoky\"\ncolor = [90, 90, 110]\nopacity = 0.4\nabsorption = 0.2\n\
         [[boxes]]\nblock = \"stone\"\nmin = [{}, {}, {}]\nmax = [{}, {}, {}]\n\
         [[boxes]]\nblock = \"{b1}\"\nmin = [{}, {oy}, {}]\nmax = [{}, {}, {}]\n\
         [[boxes]]\nblock = \"{b2}\"\nmin = [{}, {upper}, {}]\nmax = [{}, {}, {}]\n",
        ox - l - 4,
        oy - 1,
        oz - l - 4,
        ox + l + 4,
        oy - 1,
        oz + l + 4,
        ox - l,
        oz - l,
        ox + l,
        top - 1,
        oz + l,
        ox - l,
        oz - l,
        ox + l,
        upper_top - 1,
        oz + l,
    );
    let colours = [
        [245, 250, 255],
        [240, 120, 90],
        [90, 200, 120],
        [120, 140, 250],
        [250, 220, 90],
    ];
    let (mut cx, mut cz) = (f64::from(ox), f64::from(oz));
    let things = rng.int(1, 3);
    for k in 0..things {
        let (sx, sz) = (rng.range(4.0, 40.0), rng.range(4.0, 40.0));
        let th = *rng.pick(&[0.02, 0.02, 0.05, 0.1, 0.2, 0.5]);
        let lift = *rng.pick(&[0.0, 0.0, 0.01]);
        let room = (f64::from(l) - sx.max(sz) * 0.35).max(0.0);
        let (x, z) = (
            f64::from(ox) + rng.range(-room, room),
            f64::from(oz) + rng.range(-room, room),
        );
        if k == 0 {
            (cx, cz) = (x, z);
        }
        let yaw = rng.range(-45.0, 45.0);
        let (pitch, roll) = if rng.chance(0.15) {
            (rng.range(-2.0, 2.0), rng.range(-2.0, 2.0))
        } else {
            (0.0, 0.0)
        };
        let emissive = if rng.chance(0.25) {
            rng.range(1.0, 4.0)
        } else {
            0.0
        };
        let c = rng.pick(&colours);
        let _ = write!(
            s,
            "[[entities]]\ncenter = [{x:.3}, {:.4}, {z:.3}]\nsize = [{sx:.2}, {th}, {sz:.2}]\n\
             rotation = [{yaw:.1}, {pitch:.1}, {roll:.1}]\ncolor = [{}, {}, {}]\n\
             opacity = {:.2}\nemissive = {emissive:.1}\n",
            f64::from(top) + th / 2.0 + lift,
            c[0],
            c[1],
            c[2],
            rng.range(0.3, 0.9),
        );
    }
    if rng.chance(0.5) {
        let size = rng.range(0.1, 0.3);
        let _ = write!(
            s,
            "[[particles]]\nmin = [{}, {}, {}]\nmax = [{}, {}, {}]\ncount = 400\nseed = {}\n\
             size = {size:.2}\ncolor = [250, 120, 80]\nopacity = {:.2}\n",
            cx - 12.0,
            f64::from(top) + 0.05 + size,
            cz - 12.0,
            cx + 12.0,
            f64::from(upper) - 0.05 - size,
            cz + 12.0,
            i + 1,
            rng.range(0.3, 0.9),
        );
    }
    if rng.chance(0.3) {
        let _ = write!(
            s,
            "[[particles]]\nmin = [{}, {}, {}]\nmax = [{}, {}, {}]\ncount = 300\nseed = {}\n\
             size = 0.12\ncolor = [225, 240, 255]\nopacity = 0.5\n",
            cx - 10.0,
            f64::from(top) + 0.13,
            cz - 10.0,
            cx + 10.0,
            f64::from(top) + 0.13,
            cz + 10.0,
            i + 7,
        );
    }
    let angle = rng.range(0.0, std::f64::consts::TAU);
    let (dx, dz) = (angle.cos(), angle.sin());
    let (d1, d2) = (rng.range(2.0, 10.0), rng.range(15.0, 35.0));
    let cams = [
        // Above both layers, steep.
        [
            cx + dx * d1,
            f64::from(upper_top) + rng.range(6.0, 20.0),
            cz + dz * d1,
        ],
        // Above both, grazing.
        [
            cx + dx * d2,
            f64::from(upper_top) + rng.range(1.5, 4.0),
            cz + dz * d2,
        ],
        // Between the layers.
        [
            cx + dx * d2 * 0.5,
            f64::from(top) + rng.range(0.3, f64::from(gap) - 0.3),
            cz + dz * d2 * 0.5,
        ],
    ];
    for e in cams {
        let _ = write!(
            s,
            "[[cameras]]\neye = [{:.3}, {:.3}, {:.3}]\ntarget = [{cx:.3}, {top}, {cz:.3}]\n",
            e[0], e[1], e[2]
        );
    }
    s
}

/// Issue 52's G1 searched: random scenes of [`random_case`] (`G1_CASES`, default 40, from
/// `G1_SEED`, default 1), `sorted-quads` against the reference off quad edges and object
/// overlaps, the worst printed and their scene files kept in the test's output folder.
/// `cargo test --release --workspace --test cut_on_glass -- --ignored --nocapture search`
#[test]
#[ignore = "a search (minutes): run by hand"]
fn search_flat_things_on_glass_under_glass() {
    let Some(ctx) = tests::gpu() else { return };
    let env = |k: &str, d: u64| {
        std::env::var(k)
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(d)
    };
    let (cases, seed) = (env("G1_CASES", 40) as usize, env("G1_SEED", 1));
    let mut rng = Rng(seed);
    let out = tests::out_dir("cut_on_glass_search");
    let target = Offscreen::new(&ctx, SIZE.0, SIZE.1);
    let mut found = Vec::new();
    for i in 0..cases {
        let text = random_case(&mut rng, i);
        let scene = voxel_lab::scene::parse(&text).unwrap();
        let config = |t| tests::technique_config(t, SIZE.0, SIZE.1);
        let mut reference = renderer_for(&ctx, &scene, config(Technique::Reference)).unwrap();
        let mut sorted = renderer_for(&ctx, &scene, config(Technique::SortedQuads)).unwrap();
        for (c, camera) in scene.cameras.iter().enumerate() {
            let want = render_image(&ctx, &mut reference, &target, camera).unwrap();
            let got = render_image(&ctx, &mut sorted, &target, camera).unwrap();
            let drawn = reference.renderer.drawn_camera(camera);
            let quad_edges = Edges::new(&scene.world, &drawn, SIZE);
            let objects = object_mask(&scene.content, &drawn, SIZE);
            let off = edges::error_off_edges(&quad_edges, &objects, &want, &got);
            let peeled = if off.over_8 > 0 {
                let mut p = renderer_for(&ctx, &scene, config(Technique::DepthPeeling)).unwrap();
                let image = render_image(&ctx, &mut p, &target, camera).unwrap();
                edges::error_off_edges(&quad_edges, &objects, &want, &image).max
            } else {
                0
            };
            eprintln!("case {i} camera {c}: {off:?}, depth-peeling max {peeled}");
            if off.max > 1 {
                let name = format!("case{i}_{c}");
                let _ = want.save_png(&out.join(format!("{name}_reference.png")));
                let _ = got.save_png(&out.join(format!("{name}_sorted.png")));
                let _ =
                    tests::diff_image(&want, &got).save_png(&out.join(format!("{name}_diff.png")));
                std::fs::write(out.join(format!("case{i}.toml")), &text).unwrap();
            }
            found.push((off.over_8, off.max, i, c));
        }
    }
    found.sort_unstable_by(|a, b| b.cmp(a));
    for (over_8, max, i, c) in found.iter().take(12) {
        eprintln!("worst: case {i} camera {c}: {over_8} px over 8/255, max {max}/255");
    }
}
