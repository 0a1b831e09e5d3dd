//! Light drawn (issue 51): chunks meshed with the light field's light (`Mesher::mesh_lit`)
//! are shaded by it in every technique: sky light through a red pane tints the floor below
//! by the pane's filter, a torch lights a closed cave by day and by night alike, an edit's
//! light shows in the next frame, open sky looks as an unlit world does, and the instanced
//! fetch (WebGL2) draws the same light.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use std::sync::Arc;

use glam::{DQuat, DVec3};
use voxel_core::blocks::{GLASS, RED_GLASS, STONE};
use voxel_core::light_blocks::TORCH;
use voxel_core::{BlockId, BlockRegistry, LightField, SunFilters, SunMarch, World, WorldPos};
use voxel_mesh::{mesh_dirty_lit, mesh_world};
use voxel_render::content::{Content, ContentStages, Entity};
use voxel_render::{
    Camera, ChunkStreamer, Error, GameStages, GpuContext, Image, Lighting, MAX_LIGHT_CHUNKS,
    MAX_SUN_CHUNKS, QuadFetch, Renderer, RendererConfig, StreamConfig, SunFeed, SunRegion,
    Technique,
};

use tests::*;

const W: u32 = 320;
const H: u32 = 200;

/// A closed stone room, x and z 0 to 10, floor y = 0, roof y = 7, with `roof` blocks in the
/// roof over x and z 4 to 6 (a 3 × 3 pane), over the registry with light sources.
fn room(roof: BlockId) -> World {
    let mut world = World::new(Arc::new(BlockRegistry::with_lights()));
    let fill = |w: &mut World, a: [i32; 3], b: [i32; 3], id| {
        voxel_lab::scene::fill_box(w, a, b, id).unwrap();
    };
    fill(&mut world, [0, 0, 0], [10, 7, 10], STONE);
    fill(&mut world, [1, 1, 1], [9, 6, 9], BlockId::AIR);
    fill(&mut world, [4, 7, 4], [6, 7, 6], roof);
    world
}

/// A renderer of `config` with every chunk of `world` uploaded, meshed with the light of a
/// field lit from scratch (`lit`) or without light.
fn renderer(ctx: &GpuContext, world: &World, config: RendererConfig, lit: bool) -> Renderer {
    let mut r = Renderer::new(ctx, world.registry(), config).unwrap();
    let field = lit.then(|| LightField::new(world));
    for (pos, m) in mesh_world(world, field.as_ref()).unwrap() {
        r.upload_chunk(pos, &m).unwrap();
    }
    r
}

fn config(technique: Technique) -> RendererConfig {
    technique_config(technique, W, H)
}

/// Looking down at the floor from under the roof.
fn floor_camera() -> Camera {
    Camera::look_at(
        DVec3::new(5.5, 5.5, 1.8),
        DVec3::new(5.5, 1.0, 5.5),
        60.0,
        0.1,
        100.0,
    )
    .unwrap()
}

/// The pixel a world point projects to.
fn pixel(camera: &Camera, p: DVec3) -> (u32, u32) {
    project(camera, (W, H), p)
}

fn to_linear(c: u8) -> f32 {
    let c = f32::from(c) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn to_srgb(l: f32) -> f32 {
    let l = l.clamp(0.0, 1.0);
    255.0
        * if l <= 0.003_130_8 {
            l * 12.92
        } else {
            1.055 * l.powf(1.0 / 2.4) - 0.055
        }
}

/// The pixel of `img` at the centre of the top face of floor block (x, 0, z).
fn floor_pixel(img: &Image, camera: &Camera, x: i32, z: i32) -> [u8; 4] {
    let (px, py) = pixel(
        camera,
        DVec3::new(f64::from(x) + 0.5, 1.0, f64::from(z) + 0.5),
    );
    img.pixel(px, py)
}

/// Under a red pane in the roof, the floor is lit by the sky light the pane lets through:
/// the unlit picture's colour times the field's level there (210, 130, 130 of 255: the
/// pane's filter 0.822, 0.511, 0.511 times full sky), per channel, in every technique; the
/// floor where no beam falls is darker still.
#[test]
fn sky_light_through_a_red_pane_tints_the_floor_by_its_filter() {
    let Some(ctx) = gpu() else { return };
    let world = room(RED_GLASS);
    let light = LightField::new(&world);
    let level = light.get(WorldPos::new(5, 1, 5)).unwrap().sky;
    assert_eq!(level, [210, 130, 130], "the pane's filter times full sky");
    let camera = floor_camera();
    let unlit = render_frame(&ctx, &world, config(Technique::SortedQuads), false, &camera);
    let dir = out_dir("light");
    unlit.save_png(&dir.join("red_pane_unlit.png")).unwrap();
    let u = floor_pixel(&unlit, &camera, 5, 5);
    assert!(u[0] > 40, "the unlit floor is lit by the sky: {u:?}");
    for technique in Technique::ALL {
        let lit = render_frame(&ctx, &world, config(technique), true, &camera);
        lit.save_png(&dir.join(format!("red_pane_{}.png", technique.name())))
            .unwrap();
        let l = floor_pixel(&lit, &camera, 5, 5);
        for ch in 0..3 {
            let want = to_srgb(to_linear(u[ch]) * f32::from(level[ch]) / 255.0);
            assert!(
                (f32::from(l[ch]) - want).abs() <= 2.0,
                "{}: channel {ch} of the floor under the pane is {} (unlit {}), want {want:.1}",
                technique.name(),
                l[ch],
                u[ch]
            );
        }
        // A floor block by the wall, away from the beam: lit only by what spreads from it
        // (16 levels less a block).
        let side = floor_pixel(&lit, &camera, 2, 5);
        let under = l[0];
        assert!(
            side[0] < under,
            "{}: the floor away from the pane ({side:?}) is darker than under it ({l:?})",
            technique.name()
        );
    }
}

fn render_frame(
    ctx: &GpuContext,
    world: &World,
    config: RendererConfig,
    lit: bool,
    camera: &Camera,
) -> Image {
    let mut r = renderer(ctx, world, config, lit);
    frame(ctx, &mut r, camera)
}

/// A torch in a closed room lights its floor with its own warm colour, the same by day and by
/// night (block light is not the sky's: night scales the sky light only), and where no
/// light reaches the room is black.
#[test]
fn a_torch_lights_a_closed_room_by_day_and_by_night() {
    let Some(ctx) = gpu() else { return };
    let mut world = room(STONE);
    voxel_lab::scene::fill_box(&mut world, [5, 1, 7], [5, 1, 7], TORCH).unwrap();
    let camera = floor_camera();
    let dark = room(STONE);
    let black = render_frame(&ctx, &dark, config(Technique::SortedQuads), true, &camera);
    let b = floor_pixel(&black, &camera, 5, 4);
    assert_eq!(&b[..3], &[0, 0, 0], "a closed room without light is black");
    let at = |hour: f32| {
        let l = Lighting::daytime(hour);
        RendererConfig {
            sun_dir: l.sun_dir,
            ambient: l.ambient,
            brightness: l.brightness,
            sky: l.sky,
            ..config(Technique::SortedQuads)
        }
    };
    let (day, night) = (at(12.0), at(0.0));
    assert!(night.brightness < 0.5 * day.brightness);
    let by_day = render_frame(&ctx, &world, day, true, &camera);
    let by_night = render_frame(&ctx, &world, night, true, &camera);
    let dir = out_dir("light");
    by_day.save_png(&dir.join("torch_day.png")).unwrap();
    by_night.save_png(&dir.join("torch_night.png")).unwrap();
    let d = floor_pixel(&by_day, &camera, 5, 6);
    assert!(
        d[0] > 60 && d[0] > d[1] && d[1] > d[2],
        "the floor by the torch is lit warm (255, 170, 90): {d:?}"
    );
    assert_eq!(
        diff(&by_day, &by_night).max,
        0,
        "no sky light in a closed room: night changes nothing"
    );
    // Two blocks farther from the torch, the light has fallen off by 16 levels a block in
    // every channel: the blue (90 at the torch) the most in proportion, the red the
    // least (the stone's texture varies from pixel to pixel: its colour is grey).
    let far = floor_pixel(&by_day, &camera, 5, 4);
    let blue_to_red = |p: [u8; 4]| to_linear(p[2]) / to_linear(p[0]);
    assert!(
        blue_to_red(far) < 0.8 * blue_to_red(d),
        "light falls off: {far:?} against {d:?}"
    );
}

/// Open sky over flat ground: every level is full sky light and no block light, which is
/// what an unlit chunk is drawn with, so the lit picture is the unlit one.
#[test]
fn open_sky_lit_is_the_unlit_picture() {
    let Some(ctx) = gpu() else { return };
    let mut world = World::new(Arc::new(BlockRegistry::with_lights()));
    voxel_lab::scene::fill_box(&mut world, [-20, -2, -20], [20, 0, 20], STONE).unwrap();
    voxel_lab::scene::fill_box(&mut world, [-3, 1, -3], [3, 1, 3], GLASS).unwrap();
    let camera = Camera::look_at(
        DVec3::new(0.5, 12.0, 14.0),
        DVec3::new(0.5, 0.0, 0.0),
        60.0,
        0.1,
        200.0,
    )
    .unwrap();
    let unlit = render_frame(&ctx, &world, config(Technique::SortedQuads), false, &camera);
    let lit = render_frame(&ctx, &world, config(Technique::SortedQuads), true, &camera);
    assert!(distinct_colours(&unlit) > 20, "a picture, not a blank");
    // The glass's own faces are lit by the cell in front (open air): full sky. The ground
    // beside and under the glass loses a little to the glass's filter and the falloff.
    let d = diff(&unlit, &lit);
    let far = floor_pixel_world(&lit, &camera, [-15, 0, 5]);
    assert_eq!(
        far,
        floor_pixel_world(&unlit, &camera, [-15, 0, 5]),
        "open ground is drawn as unlit"
    );
    assert!(
        d.differing < (W * H / 4) as usize,
        "only around the glass may the light differ: {d:?}"
    );
}

fn floor_pixel_world(img: &Image, camera: &Camera, b: [i32; 3]) -> [u8; 4] {
    let (px, py) = pixel(
        camera,
        DVec3::new(
            f64::from(b[0]) + 0.5,
            f64::from(b[1]) + 1.0,
            f64::from(b[2]) + 0.5,
        ),
    );
    img.pixel(px, py)
}

/// A torch placed in a dark room, then removed: the light field's edit and the chunks it
/// changed meshed again (`mesh_dirty_lit`) and uploaded show in the next frame.
#[test]
fn a_torch_placed_and_removed_shows_in_the_next_frame() {
    let Some(ctx) = gpu() else { return };
    let mut world = room(STONE);
    let mut light = LightField::new(&world);
    let camera = floor_camera();
    let mut r = renderer(&ctx, &world, config(Technique::SortedQuads), true);
    let before = frame(&ctx, &mut r, &camera);
    let spot = WorldPos::new(5, 1, 5);
    let mut step = |world: &mut World, light: &mut LightField, id| {
        world.set_block_lit(light, spot, id).unwrap();
        for (pos, m) in mesh_dirty_lit(world, light).unwrap() {
            r.upload_chunk(pos, &m).unwrap();
        }
        frame(&ctx, &mut r, &camera)
    };
    let placed = step(&mut world, &mut light, TORCH);
    let removed = step(&mut world, &mut light, BlockId::AIR);
    let b = floor_pixel(&before, &camera, 5, 4);
    let p = floor_pixel(&placed, &camera, 5, 4);
    assert_eq!(&b[..3], &[0, 0, 0]);
    assert!(p[0] > 60, "the torch's light shows at once: {p:?}");
    assert_eq!(
        diff(&before, &removed).max,
        0,
        "and is gone once it is removed"
    );
}

/// Panes of red and clear glass across a torch-lit room, each pane's faces lit by the cell
/// in front of it (light that differs pane by pane): every exact technique agrees with the
/// A-buffer reference, `sorted-quads` too, which re-sorts the quads (a translucent quad's
/// light follows it to its new place in the mesh).
#[test]
fn lit_panes_agree_with_the_reference_in_every_technique() {
    let Some(ctx) = gpu() else { return };
    let mut world = room(RED_GLASS);
    let fill = |w: &mut World, a: [i32; 3], b: [i32; 3], id| {
        voxel_lab::scene::fill_box(w, a, b, id).unwrap();
    };
    fill(&mut world, [8, 1, 8], [8, 1, 8], TORCH);
    fill(&mut world, [1, 1, 6], [9, 4, 6], RED_GLASS);
    fill(&mut world, [1, 1, 4], [9, 4, 4], GLASS);
    fill(&mut world, [3, 1, 2], [7, 3, 2], RED_GLASS);
    let camera = Camera::look_at(
        DVec3::new(5.2, 3.5, 1.3),
        DVec3::new(5.0, 1.5, 9.0),
        70.0,
        0.1,
        100.0,
    )
    .unwrap();
    let reference = render_frame(&ctx, &world, config(Technique::Reference), true, &camera);
    let unlit = render_frame(&ctx, &world, config(Technique::Reference), false, &camera);
    let dir = out_dir("light");
    reference
        .save_png(&dir.join("panes_reference.png"))
        .unwrap();
    unlit.save_png(&dir.join("panes_unlit.png")).unwrap();
    assert!(
        diff(&reference, &unlit).differing > (W * H / 4) as usize,
        "the light changes the picture"
    );
    let exact = Technique::ALL
        .into_iter()
        .filter(|t| t.is_exact() && *t != Technique::Reference);
    for technique in exact {
        let img = render_frame(&ctx, &world, config(technique), true, &camera);
        img.save_png(&dir.join(format!("panes_{}.png", technique.name())))
            .unwrap();
        let d = diff(&img, &reference);
        assert!(
            d.over_one * 200 < (W * H) as usize,
            "{}: {d:?} against the reference",
            technique.name()
        );
    }
}

/// With the instanced fetch (WebGL2 and GL 3.3 devices, whose vertex stage reads no storage
/// buffer: the quads' light a second instance attribute, the palettes a table texture), and
/// on a device with WebGL2's limits, lit chunks are drawn as the storage fetch draws them.
#[test]
fn the_instanced_fetch_and_webgl2_limits_draw_the_same_light() {
    let Some(ctx) = gpu() else { return };
    let world = room(RED_GLASS);
    let camera = floor_camera();
    let storage = render_frame(&ctx, &world, config(Technique::SortedQuads), true, &camera);
    let mut c = config(Technique::SortedQuads);
    c.quad_fetch = Some(QuadFetch::Instanced);
    let instanced = render_frame(&ctx, &world, c, true, &camera);
    let unlit = render_frame(&ctx, &world, config(Technique::SortedQuads), false, &camera);
    assert!(
        diff(&storage, &unlit).over_one > (W * H / 4) as usize,
        "lit"
    );
    let d = diff(&instanced, &storage);
    assert_eq!(d.over_one, 0, "instanced against storage: {d:?}");
    let Some(w2) = webgl2() else { return };
    let limited = render_frame(&w2, &world, config(Technique::SortedQuads), true, &camera);
    let d = diff(&limited, &storage);
    assert_eq!(d.over_one, 0, "WebGL2's limits against storage: {d:?}");
    // On wgpu's GL backend (llvmpipe's GLES 3.2), with its own limits and WebGL2's: the
    // floor under the pane as on Vulkan (GL rasterises edges a little differently).
    let want = floor_pixel(&storage, &camera, 5, 5);
    for (name, gl) in [("gl", gl()), ("gl with WebGL2's limits", gl_webgl2())] {
        let Some(gl) = gl else { return };
        let img = render_frame(&gl, &world, config(Technique::SortedQuads), true, &camera);
        img.save_png(&out_dir("light").join(format!("red_pane_{}.png", name.replace(' ', "_"))))
            .unwrap();
        let got = floor_pixel(&img, &camera, 5, 5);
        for ch in 0..3 {
            assert!(
                got[ch].abs_diff(want[ch]) <= 2,
                "{name}: the floor under the pane is {got:?}, on Vulkan {want:?}"
            );
        }
    }
}

/// The scenes of `scenes/light/` (drawn with their light field), by day and at night: the
/// A-buffer reference with flat textures against the lab's CPU ray march computing the
/// same light from the field by the documented rules (no mesh, no GPU), and every
/// technique's picture against the ray march's, mean error per scene in
/// `target/test-output/light/reference.md`.
#[test]
fn lit_scenes_agree_with_the_ray_march() {
    use voxel_lab::raymarch::{RayMarcher, Shading};
    let Some(ctx) = gpu() else { return };
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/light");
    let files = voxel_lab::scene::scene_files(&dir).unwrap();
    assert!(files.len() >= 3, "{files:?}");
    let size = (320, 180);
    let mut table = String::from(
        "| scene | hour | reference: pixels off edges beyond 1/255 (max) | technique: mean error against the ray march, 1/255 |\n|---|---|---|---|\n",
    );
    for file in files {
        let scene = voxel_lab::scene::Scene::load(&file).unwrap();
        assert!(scene.light, "{}: a light scene", scene.name);
        let field = Arc::new(LightField::new(&scene.world));
        let mut marcher = RayMarcher::with_content(&scene.world, &scene.content).with_light(field);
        if voxel_lab::headless::sun_region(&scene).is_some() {
            marcher = marcher.with_sun_shadows(scene.world.registry());
        }
        let camera = scene.cameras[0];
        for hour in [12.0, 0.0] {
            let l = Lighting::daytime(hour);
            let config = |t: Technique| RendererConfig {
                flat_textures: true,
                sun_dir: l.sun_dir,
                ambient: l.ambient,
                brightness: l.brightness,
                sky: l.sky,
                ..technique_config(t, size.0, size.1)
            };
            let reference = config(Technique::Reference);
            let shading = Shading::of(&reference);
            let mut r = voxel_lab::headless::renderer_for(&ctx, &scene, reference).unwrap();
            let gpu_image = frame(&ctx, &mut r, &camera);
            let drawn = r.drawn_camera(&camera);
            let ray = marcher.render(&drawn, size.0, size.1, &shading);
            let name = format!("{}_{hour}", file.file_stem().unwrap().to_string_lossy());
            ray.image
                .save_png(&out_dir("light").join(format!("{name}_raymarch.png")))
                .unwrap();
            let c = marcher.compare(&ray, &drawn, &shading, &gpu_image, None);
            assert!(
                distinct_colours(&ray.image) > 20,
                "{name}: the ray march drew a picture"
            );
            assert_eq!(
                (c.differing, c.cracks),
                (0, 0),
                "{name}: {} pixels off edges differ (max {}/255): {:?}",
                c.differing,
                c.max_abs_err_off_edges,
                c.worst
            );
            let mut errors = Vec::new();
            for t in Technique::ALL {
                let img = render_with(&ctx, &scene, config(t));
                let mean = mean_error(&img, &ray.image);
                if t.is_exact() {
                    assert!(mean <= 3.0, "{name}: {} {mean:.2}/255", t.name());
                }
                errors.push(format!("{} {mean:.2}", t.name()));
            }
            table += &format!(
                "| {} | {hour} | {} ({}) | {} |\n",
                scene.name,
                c.differing,
                c.max_abs_err_off_edges,
                errors.join(", ")
            );
        }
    }
    std::fs::write(out_dir("light").join("reference.md"), &table).unwrap();
    eprintln!("{table}");
}

/// The mean absolute channel difference (RGB) of two pictures, in 1/255 steps.
fn mean_error(a: &Image, b: &Image) -> f64 {
    let sum: u64 = a
        .rgba
        .chunks_exact(4)
        .zip(b.rgba.chunks_exact(4))
        .map(|(p, q)| (0..3).map(|i| u64::from(p[i].abs_diff(q[i]))).sum::<u64>())
        .sum();
    sum as f64 / (a.rgba.len() / 4 * 3) as f64
}

/// The sun in +x, rising two blocks a block: lit pictures with sun shadows.
const SUN: [f32; 3] = [1.0, 2.0, 0.0];

fn slanted_sun(technique: Technique) -> RendererConfig {
    RendererConfig {
        sun_dir: SUN,
        ..config(technique)
    }
}

/// `renderer` with sun shadows over all of `world`.
fn shadowed(ctx: &GpuContext, world: &World, config: RendererConfig) -> Renderer {
    let mut r = renderer(ctx, world, config, true);
    let region = SunRegion::around(world, WorldPos::new(0, 0, 0)).unwrap();
    r.set_sun_shadows(world, region).unwrap();
    assert_eq!(r.sun_region(), Some(region));
    r
}

/// What a floor pixel drawn without sun shadows (`off`, sRGB) becomes with them, the sun's
/// share of the light reaching it `t` (linear), its sky level `sky` (of 255): without, the
/// sky light scales the ambient and the sun's share alike; with, the sun's share is `t`.
fn with_sun(off: [u8; 4], sky: [u8; 3], t: [f32; 3], c: &RendererConfig) -> [f32; 3] {
    let n_dot_l = glam::Vec3::from(c.sun_dir).normalize().y;
    let a = c.ambient;
    std::array::from_fn(|ch| {
        let s = f32::from(sky[ch]) / 255.0;
        let was = s * (a + (1.0 - a) * n_dot_l);
        let now = a * s + (1.0 - a) * n_dot_l * t[ch];
        to_srgb(to_linear(off[ch]) * now / was)
    })
}

/// Sun shadows through a red pane in the roof. The sun slanted: its light falls through the
/// pane onto the floor along its ray, three blocks in -x of the pane's foot, tinted by the
/// pane's filter (the CPU twin `SunMarch` gives the filter there), and under the pane the
/// roof's stone now hides the sun. The sun straight up: the patch lies under the pane. In
/// every technique each floor pixel is what the same pixel drawn without shadows (the sky
/// light standing for the sun's) becomes with the sun's share replaced (`with_sun`), within
/// 2/255.
#[test]
fn the_sun_through_a_red_pane_throws_a_red_patch_along_its_ray() {
    let Some(ctx) = gpu() else { return };
    let world = room(RED_GLASS);
    let light = LightField::new(&world);
    let march = SunMarch::new(&world);
    let red = SunFilters::new(world.registry())
        .get(RED_GLASS)
        .unwrap()
        .enter;
    let camera = floor_camera();
    let dir_out = out_dir("light");
    // From the floor's top (y = 1) the slanted ray reaches the roof (y = 7) 3 blocks on in
    // +x: the pane over x 4 to 6 lights the floor over x 1 to 3.
    for (sun, patch, hidden) in [(SUN, (2, 5), (5, 5)), ([0.0, 1.0, 0.0], (5, 5), (2, 5))] {
        let t = |(x, z): (i32, i32)| {
            let from = [f64::from(x) + 0.5, 1.001, f64::from(z) + 0.5];
            march.transmittance(from, sun.map(f64::from))
        };
        assert_eq!(
            t(patch),
            red,
            "{sun:?}: the ray from the patch crosses the pane"
        );
        assert_eq!(
            t(hidden),
            [0.0; 3],
            "{sun:?}: the ray meets the roof's stone"
        );
        for technique in Technique::ALL {
            let c = RendererConfig {
                sun_dir: sun,
                ..config(technique)
            };
            let off = render_frame(&ctx, &world, c.clone(), true, &camera);
            let mut r = shadowed(&ctx, &world, c.clone());
            let on = frame(&ctx, &mut r, &camera);
            on.save_png(&dir_out.join(format!("sun_{}_{}.png", sun[0], technique.name())))
                .unwrap();
            for (x, z) in [patch, hidden] {
                let sky = light.get(WorldPos::new(x, 1, z)).unwrap().sky;
                let want = with_sun(floor_pixel(&off, &camera, x, z), sky, t((x, z)), &c);
                let got = floor_pixel(&on, &camera, x, z);
                for ch in 0..3 {
                    assert!(
                        (f32::from(got[ch]) - want[ch]).abs() <= 2.0,
                        "{} {sun:?}: floor ({x}, {z}) with sun shadows {got:?}, want {want:?}",
                        technique.name()
                    );
                }
            }
            let p = floor_pixel(&on, &camera, patch.0, patch.1);
            assert!(
                p[0] > p[1] + 15 && p[0] > p[2] + 15,
                "{} {sun:?}: the patch is red: {p:?}",
                technique.name()
            );
        }
    }
}

/// A stone pillar placed on open ground casts its shadow in the next frame once the edited
/// chunks are read again (`Renderer::update_sun_shadows`), and the shadow is gone once the
/// pillar is removed: the picture is the one before, bit for bit.
#[test]
fn an_edit_casts_its_shadow_in_the_next_frame() {
    let Some(ctx) = gpu() else { return };
    let mut world = World::new(Arc::new(BlockRegistry::with_lights()));
    voxel_lab::scene::fill_box(&mut world, [-20, -2, -20], [20, 0, 20], STONE).unwrap();
    let mut light = LightField::new(&world);
    let camera = Camera::look_at(
        DVec3::new(-3.5, 9.0, 8.0),
        DVec3::new(-3.5, 0.0, 0.5),
        60.0,
        0.1,
        200.0,
    )
    .unwrap();
    let mut r = shadowed(&ctx, &world, slanted_sun(Technique::SortedQuads));
    let before = frame(&ctx, &mut r, &camera);
    let mut edit = |world: &mut World, light: &mut LightField, id| {
        for y in 1..=4 {
            world
                .set_block_lit(light, WorldPos::new(0, y, 0), id)
                .unwrap();
        }
        let meshes = mesh_dirty_lit(world, light).unwrap();
        for (pos, m) in &meshes {
            r.upload_chunk(*pos, m).unwrap();
        }
        let chunks: Vec<_> = meshes.iter().map(|(p, _)| *p).collect();
        r.update_sun_shadows(world, &chunks);
        frame(&ctx, &mut r, &camera)
    };
    let placed = edit(&mut world, &mut light, STONE);
    placed
        .save_png(&out_dir("light").join("sun_pillar.png"))
        .unwrap();
    // The sun rises two blocks a block: the pillar, 4 high, shades the ground 2 blocks in -x
    // of it; the ground at x = -1 lies in its shadow, x = -5 does not.
    let ground = |img: &Image, x| floor_pixel_world(img, &camera, [x, 0, 0]);
    let (b, p) = (ground(&before, -1), ground(&placed, -1));
    assert!(p[0] + 20 < b[0], "the pillar's shadow: {p:?}, before {b:?}");
    assert_eq!(
        ground(&before, -5),
        ground(&placed, -5),
        "beyond the shadow"
    );
    let removed = edit(&mut world, &mut light, BlockId::AIR);
    assert_eq!(
        diff(&before, &removed).max,
        0,
        "the shadow is gone with the pillar"
    );
}

/// A region the shadow volume cannot hold, or a world over another registry, is an error
/// that changes nothing; sun shadows off again draw as before they were on.
#[test]
fn bad_sun_regions_are_errors_and_shadows_turn_off() {
    let Some(ctx) = gpu() else { return };
    let world = room(RED_GLASS);
    let camera = floor_camera();
    let c = slanted_sun(Technique::SortedQuads);
    let mut r = renderer(&ctx, &world, c.clone(), true);
    let off = frame(&ctx, &mut r, &camera);
    let too_big = SunRegion {
        min: voxel_core::ChunkPos::new(0, 0, 0),
        chunks: [MAX_SUN_CHUNKS + 1, 1, 1],
    };
    let e = r.set_sun_shadows(&world, too_big).unwrap_err();
    assert!(e.to_string().contains("chunks an axis"), "{e}");
    let other = World::new(Arc::new(BlockRegistry::default()));
    let region = SunRegion::around(&world, WorldPos::new(0, 0, 0)).unwrap();
    let e = r.set_sun_shadows(&other, region).unwrap_err();
    assert!(e.to_string().contains("registry"), "{e}");
    assert_eq!(r.sun_region(), None);
    assert_eq!(diff(&off, &frame(&ctx, &mut r, &camera)).max, 0);
    r.set_sun_shadows(&world, region).unwrap();
    assert!(
        diff(&off, &frame(&ctx, &mut r, &camera)).max > 20,
        "shadows drawn"
    );
    r.clear_sun_shadows();
    assert_eq!(r.sun_region(), None);
    assert_eq!(
        diff(&off, &frame(&ctx, &mut r, &camera)).max,
        0,
        "and off again"
    );
}

/// Sun shadows under the instanced fetch, WebGL2's limits and wgpu's GL backend (llvmpipe's
/// GLES 3.2, with its own limits and WebGL2's): the same red patch and the same shade under
/// the pane as on Vulkan, in every technique the device runs (the shadow volume is one more
/// 3D texture in the frame's group, within WebGL2's 16 a stage).
#[test]
fn sun_shadows_draw_the_same_on_every_fetch_and_backend() {
    let Some(ctx) = gpu() else { return };
    let world = room(RED_GLASS);
    let camera = floor_camera();
    let shadows = |ctx: &GpuContext, c: RendererConfig| {
        let mut r = shadowed(ctx, &world, c);
        frame(ctx, &mut r, &camera)
    };
    let storage = shadows(&ctx, slanted_sun(Technique::SortedQuads));
    let mut c = slanted_sun(Technique::SortedQuads);
    c.quad_fetch = Some(QuadFetch::Instanced);
    let d = diff(&shadows(&ctx, c), &storage);
    assert_eq!(d.over_one, 0, "instanced against storage: {d:?}");
    let Some(w2) = webgl2() else { return };
    let d = diff(&shadows(&w2, slanted_sun(Technique::SortedQuads)), &storage);
    assert_eq!(d.over_one, 0, "WebGL2's limits against storage: {d:?}");
    for (name, gl) in [("gl", gl()), ("gl with WebGL2's limits", gl_webgl2())] {
        let Some(gl) = gl else { return };
        let mut drawn = 0;
        for technique in Technique::supported(&gl.caps) {
            let img = shadows(&gl, slanted_sun(technique));
            drawn += 1;
            for (x, z) in [(2, 5), (5, 5)] {
                let (got, want) = (
                    floor_pixel(&img, &camera, x, z),
                    floor_pixel(&storage, &camera, x, z),
                );
                for ch in 0..3 {
                    assert!(
                        got[ch].abs_diff(want[ch]) <= 2,
                        "{name}, {}: floor ({x}, {z}) is {got:?}, on Vulkan {want:?}",
                        technique.name()
                    );
                }
            }
        }
        assert!(drawn >= 3, "{name}: {drawn} techniques");
    }
}

/// A stone floor 16 chunks across (x −256 to 255, z −16 to 15) with stone pillars in a
/// row along x, every 12 blocks, 6 high.
fn pillars() -> World {
    let mut world = World::new(Arc::new(BlockRegistry::with_lights()));
    voxel_lab::scene::fill_box(&mut world, [-256, 0, -16], [255, 0, 15], STONE).unwrap();
    for x in (-250..250).step_by(12) {
        voxel_lab::scene::fill_box(&mut world, [x, 1, -1], [x, 6, 1], STONE).unwrap();
    }
    world
}

/// Sun shadows that follow a moving player: a floor 16 chunks across with stone pillars in a
/// row, the volume 4 × 1 × 4 chunks. As the eye walks along the row, `follow_sun_shadows`
/// reads only the chunks that come into the volume (4 a chunk crossed, none while the eye
/// stays in its chunk), and the picture at the end is, bit for bit, that of a renderer whose
/// volume was read whole at that place; the pillars there cast their shadows.
#[test]
fn sun_shadows_follow_the_eye_reading_only_the_chunks_that_come_in() {
    let Some(ctx) = gpu() else { return };
    let world = pillars();
    let camera_at = |x: f64| {
        Camera::look_at(
            DVec3::new(x, 14.0, 12.0),
            DVec3::new(x, 0.0, 0.5),
            60.0,
            0.1,
            300.0,
        )
        .unwrap()
    };
    let start = SunRegion {
        min: voxel_core::ChunkPos::new(-2, 0, -2),
        chunks: [4, 1, 4],
    };
    let c = slanted_sun(Technique::SortedQuads);
    let mut walker = renderer(&ctx, &world, c.clone(), true);
    walker.set_sun_shadows(&world, start).unwrap();
    let mut reads = Vec::new();
    for step in 0..=40 {
        let x = 0.5 + f64::from(step) * 4.0;
        reads.push(walker.follow_sun_shadows(&world, WorldPos::new(x as i32, 1, 0)));
    }
    // 160 blocks walked: 5 chunks crossed, 4 chunks read at each.
    assert_eq!(reads.iter().sum::<usize>(), 5 * 4, "{reads:?}");
    assert!(reads.iter().all(|&r| r == 0 || r == 4), "{reads:?}");
    let end = walker.sun_region().unwrap();
    assert_eq!(end.min, voxel_core::ChunkPos::new(3, 0, -2));
    let camera = camera_at(160.5);
    let walked = frame(&ctx, &mut walker, &camera);
    let mut fresh = renderer(&ctx, &world, c.clone(), true);
    fresh.set_sun_shadows(&world, end).unwrap();
    let direct = frame(&ctx, &mut fresh, &camera);
    walked
        .save_png(&out_dir("light").join("sun_follow.png"))
        .unwrap();
    assert_eq!(
        diff(&walked, &direct).max,
        0,
        "the walked volume is the one read whole"
    );
    let unshaded = frame(&ctx, &mut renderer(&ctx, &world, c, true), &camera);
    assert!(
        diff(&walked, &unshaded).differing > 300,
        "the pillars cast shadows there"
    );
}

/// Sun shadows over a lit streamer's chunks (`SunFeed`): the pillars' floor streamed with
/// light around an eye that walks along the row (each step streamed to idle), the feed
/// reading each chunk as its blocks come in and following the eye. At the end the picture
/// is, bit for bit, the one drawn with the volume read whole from the streamer's world
/// there, and the pillars cast their shadows; the light volume the feed keeps (crates under
/// a red glass roof lit by it) is likewise the one read whole.
#[test]
fn sun_shadows_follow_a_lit_streamer() {
    let Some(ctx) = gpu() else { return };
    // Red glass over the row where the walk ends: the sky light under it is tinted.
    let mut world = pillars();
    voxel_lab::scene::fill_box(&mut world, [60, 8, -3], [100, 8, 3], RED_GLASS).unwrap();
    let config = StreamConfig {
        view_distance: 3,
        vertical_distance: 1,
        ..StreamConfig::default()
    };
    let mut streamer = ChunkStreamer::new(world.registry().clone(), world.clone(), config)
        .unwrap()
        .with_light();
    let c = slanted_sun(Technique::SortedQuads);
    let mut r = Renderer::new(&ctx, world.registry(), c).unwrap();
    let mut feed = SunFeed::new();
    let mut eye = DVec3::new(0.5, 14.0, 12.0);
    for step in 0..=10 {
        eye.x = 0.5 + f64::from(step) * 8.0;
        // Not idle within two minutes: a streamer that never settles.
        let start = std::time::Instant::now();
        loop {
            let f = streamer.update(eye, &mut r).unwrap();
            assert!(f.failed.is_empty(), "{:?}", f.failed);
            feed.update(&mut r, &streamer, eye, &f).unwrap();
            if streamer.is_idle() {
                break;
            }
            assert!(start.elapsed().as_secs() < 120, "step {step}: not idle");
            std::thread::sleep(std::time::Duration::from_micros(300));
        }
    }
    let region = r.sun_region().unwrap();
    assert_eq!(region.chunks, [MAX_SUN_CHUNKS; 3]);
    let camera = Camera::look_at(eye, DVec3::new(eye.x, 0.0, 0.5), 60.0, 0.1, 300.0).unwrap();
    // The light volume followed too: crates among the pillars, under the glass, are lit
    // by it as by one read whole from the streamer's light there.
    let light_region = r.light_region().unwrap();
    assert_eq!(light_region.chunks, [MAX_LIGHT_CHUNKS; 3]);
    assert!(light_region.contains(WorldPos::containing(eye.to_array()).split().0));
    let crates = Content {
        particles: Vec::new(),
        entities: (0..6)
            .map(|i| crate_box(DVec3::new(eye.x - 9.0 + 4.0 * f64::from(i), 1.5, 0.5), 1.0))
            .collect(),
    };
    let lit_things = |r: &mut Renderer| {
        let mut game = ContentStages::new(r, crates.clone()).unwrap();
        frame_with(&ctx, r, &camera, &mut game)
    };
    let fed_things = lit_things(&mut r);
    let light = |p: voxel_core::ChunkPos| streamer.light_chunk(p);
    r.set_light_volume(streamer.world(), &light, light_region)
        .unwrap();
    let whole_things = lit_things(&mut r);
    assert_eq!(
        diff(&fed_things, &whole_things).max,
        0,
        "the fed light volume is the one read whole"
    );
    r.clear_light_volume();
    assert!(
        diff(&fed_things, &lit_things(&mut r)).differing > 50,
        "the crates are lit by the volume"
    );
    let fed = frame(&ctx, &mut r, &camera);
    fed.save_png(&out_dir("light").join("sun_streamed.png"))
        .unwrap();
    r.clear_sun_shadows();
    let unshaded = frame(&ctx, &mut r, &camera);
    r.set_sun_shadows(streamer.world(), region).unwrap();
    let whole = frame(&ctx, &mut r, &camera);
    assert_eq!(
        diff(&fed, &whole).max,
        0,
        "the fed volume is the one read whole"
    );
    assert!(
        diff(&fed, &unshaded).differing > 300,
        "the pillars cast shadows: {} pixels differ",
        diff(&fed, &unshaded).differing
    );
}

/// A grey crate of 1 block centred on `center`, of `opacity`.
fn crate_box(center: DVec3, opacity: f32) -> Entity {
    Entity {
        center,
        half_extents: [0.5; 3],
        rotation: DQuat::IDENTITY,
        color: [200, 200, 200],
        opacity,
        emissive: 0.0,
    }
}

/// One frame of `renderer` with `game`.
fn frame_with(
    ctx: &GpuContext,
    renderer: &mut Renderer,
    camera: &Camera,
    game: &mut impl GameStages,
) -> Image {
    let (w, h) = renderer.size();
    let target = Offscreen::new(ctx, w, h);
    renderer
        .render_and_submit(&target.view, camera, game)
        .unwrap();
    target.read(ctx).unwrap()
}

/// `world` lit and drawn with `config` and a crate of `opacity` on the floor at (5, 1, 5),
/// the light volume over the world where `volume`.
fn crate_in(
    ctx: &GpuContext,
    world: &World,
    config: RendererConfig,
    opacity: f32,
    volume: bool,
) -> Image {
    let mut r = renderer(ctx, world, config, true);
    if volume {
        let field = LightField::new(world);
        let region = SunRegion::around(world, WorldPos::new(5, 1, 5)).unwrap();
        r.set_light_volume(world, &|p| field.shared(p), region)
            .unwrap();
    }
    let crates = Content {
        particles: Vec::new(),
        entities: vec![crate_box(DVec3::new(5.5, 1.5, 5.5), opacity)],
    };
    let mut game = ContentStages::new(&r, crates).unwrap();
    frame_with(ctx, &mut r, &floor_camera(), &mut game)
}

/// A game's things are lit by the light field where the renderer has a light volume
/// (`Renderer::set_light_volume`), as the world's faces are: a crate under the red pane
/// takes the pane's filter on its top as the floor does; in a closed dark room it is
/// black, by a torch warm; a translucent one is tinted in every technique; the instanced
/// fetch, WebGL2's limits and GL draw the same. Without a volume it is lit as before, by
/// the sun and the ambient light alone. A region the volume cannot hold is refused.
#[test]
fn a_games_things_are_lit_by_the_light_volume() {
    let Some(ctx) = gpu() else { return };
    let camera = floor_camera();
    let top = |img: &Image| {
        let (x, y) = pixel(&camera, DVec3::new(5.5, 2.0, 5.5));
        img.pixel(x, y)
    };
    let pane = room(RED_GLASS);
    let field = LightField::new(&pane);
    // The cells the top face's corners sample (half a block above it) lie in the pane's
    // beam: one level.
    let level = field.get(WorldPos::new(5, 2, 5)).unwrap();
    for x in 4..=6 {
        for z in 4..=6 {
            assert_eq!(field.get(WorldPos::new(x, 2, z)).unwrap(), level);
        }
    }
    let sq = config(Technique::SortedQuads);
    let unlit = crate_in(&ctx, &pane, sq.clone(), 1.0, false);
    let lit = crate_in(&ctx, &pane, sq.clone(), 1.0, true);
    let dir = out_dir("light");
    unlit.save_png(&dir.join("crate_unlit.png")).unwrap();
    lit.save_png(&dir.join("crate_under_the_pane.png")).unwrap();
    let (u, l) = (top(&unlit), top(&lit));
    assert!(
        u[0] > 100,
        "without a volume the crate is lit by the sky: {u:?}"
    );
    for ch in 0..3 {
        let want = to_srgb(to_linear(u[ch]) * f32::from(level.sky[ch]) / 255.0);
        assert!(
            (f32::from(l[ch]) - want).abs() <= 2.0,
            "channel {ch} of the crate's top under the pane is {} (unlit {}), want {want:.1}",
            l[ch],
            u[ch]
        );
    }
    // The same on the instanced fetch, under WebGL2's limits and on GL.
    let mut instanced = sq.clone();
    instanced.quad_fetch = Some(QuadFetch::Instanced);
    let mut others = vec![("instanced", crate_in(&ctx, &pane, instanced, 1.0, true))];
    for (name, other) in [
        ("webgl2", webgl2()),
        ("gl", gl()),
        ("gl webgl2", gl_webgl2()),
    ] {
        if let Some(other) = other {
            others.push((name, crate_in(&other, &pane, sq.clone(), 1.0, true)));
        }
    }
    for (name, img) in &others {
        let t = top(img);
        assert!(
            (0..3).all(|ch| t[ch].abs_diff(l[ch]) <= 2),
            "{name}: the crate's top is {t:?}, with the storage fetch on Vulkan {l:?}"
        );
    }
    // A closed room: black without a torch, warm by one.
    let dark = room(STONE);
    let d = top(&crate_in(&ctx, &dark, sq.clone(), 1.0, true));
    assert_eq!(
        &d[..3],
        &[0, 0, 0],
        "a crate in a dark room is black: {d:?}"
    );
    let mut torch = room(STONE);
    voxel_lab::scene::fill_box(&mut torch, [5, 1, 7], [5, 1, 7], TORCH).unwrap();
    let by_torch = crate_in(&ctx, &torch, sq.clone(), 1.0, true);
    by_torch
        .save_png(&dir.join("crate_by_a_torch.png"))
        .unwrap();
    let t = top(&by_torch);
    assert!(
        t[0] > 40 && t[0] > t[1] && t[1] > t[2],
        "a crate by a torch is lit warm: {t:?}"
    );
    // A translucent crate under the pane: redder lit than unlit, in every technique.
    for technique in Technique::ALL.into_iter().filter(|t| t.draws()) {
        let c = config(technique);
        let u = top(&crate_in(&ctx, &pane, c.clone(), 0.6, false));
        let l = top(&crate_in(&ctx, &pane, c, 0.6, true));
        let red = |p: [u8; 4]| f32::from(p[0]) / f32::from(p[1].max(1));
        assert!(
            red(l) > red(u) + 0.1,
            "{}: a glass crate under the pane is tinted: {l:?} lit, {u:?} unlit",
            technique.name()
        );
    }
    // Bad regions change nothing.
    let mut r = renderer(&ctx, &pane, sq, true);
    for chunks in [[MAX_LIGHT_CHUNKS + 1, 1, 1], [0, 1, 1]] {
        let region = SunRegion {
            min: voxel_core::ChunkPos::new(0, 0, 0),
            chunks,
        };
        match r.set_light_volume(&pane, &|p| field.shared(p), region) {
            Err(Error::InvalidSetting(why)) => assert!(why.contains("light volume"), "{why}"),
            other => panic!("{chunks:?}: {other:?}"),
        }
        assert_eq!(r.light_region(), None);
    }
}
