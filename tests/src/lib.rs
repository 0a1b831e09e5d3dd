//! Helpers of the integration tests: a GPU that is never silently missing under CI, small
//! hand-built scenes, rendering to images, and comparisons that leave pictures behind.

#![allow(clippy::unwrap_used, clippy::missing_panics_doc)] // test support: panics are failures

pub mod vox_models;

use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::sync::Arc;

use glam::DVec3;
use voxel_core::{BlockId, BlockRegistry, World};
use voxel_render::{
    Camera, GpuContext, Image, LimitsPreset, NoGame, Renderer, RendererConfig, Technique, readback,
};

pub use voxel_lab::headless::{Offscreen, renderer_for};
pub use voxel_lab::scene::Scene;

/// A headless Vulkan context (lavapipe on machines without a GPU). Without an adapter, a
/// test skips with a loud message, unless `CI` is set: then a missing adapter fails.
pub fn gpu() -> Option<GpuContext> {
    match GpuContext::headless(wgpu::Backends::VULKAN) {
        Ok(ctx) => Some(ctx),
        Err(e) if std::env::var_os("CI").is_some() => {
            panic!("CI is set but no Vulkan adapter was found ({e}); install mesa-vulkan-drivers")
        }
        Err(e) => {
            eprintln!(
                "\n!!!! SKIPPING GPU TEST: no Vulkan adapter ({e}). Install mesa-vulkan-drivers. !!!!\n"
            );
            None
        }
    }
}

/// A headless context on wgpu's GL backend (Mesa's llvmpipe through EGL, a GLES 3.2
/// device, on machines without a GPU), or `None` as [`gpu`]: without an adapter a test
/// skips loudly, unless `CI` is set, when it fails.
pub fn gl() -> Option<GpuContext> {
    context_or_skip(
        wgpu::Backends::GL,
        LimitsPreset::Adapter,
        "a GL adapter (install libegl1 libegl-mesa0 libgles2 libgl1-mesa-dri)",
    )
}

/// A Vulkan device with WebGL2's limits and no optional feature
/// ([`LimitsPreset::WebGl2`]): what a browser's WebGL2 or a GLES 3.0 phone gives, as far
/// as limits and features go. `None` as [`gpu`].
pub fn webgl2() -> Option<GpuContext> {
    context_or_skip(
        wgpu::Backends::VULKAN,
        LimitsPreset::WebGl2,
        "a Vulkan adapter (install mesa-vulkan-drivers)",
    )
}

/// wgpu's GL backend with WebGL2's limits and no optional feature: the closest to a
/// browser's WebGL2 this machine has (GLSL ES from naga, no storage buffers). `None` as
/// [`gpu`].
pub fn gl_webgl2() -> Option<GpuContext> {
    context_or_skip(
        wgpu::Backends::GL,
        LimitsPreset::WebGl2,
        "a GL adapter (install libegl1 libegl-mesa0 libgles2 libgl1-mesa-dri)",
    )
}

fn context_or_skip(
    backends: wgpu::Backends,
    limits: LimitsPreset,
    what: &str,
) -> Option<GpuContext> {
    match GpuContext::headless_with(backends, limits) {
        Ok(ctx) => Some(ctx),
        Err(e) if std::env::var_os("CI").is_some() => {
            panic!("CI is set but no device was made on {what}: {e}")
        }
        Err(e) => {
            eprintln!("\n!!!! SKIPPING GPU TEST: no device on {what}: {e} !!!!\n");
            None
        }
    }
}

/// `target/test-output/<name>/`, created. Pictures of every test land here.
pub fn out_dir(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../target/test-output")
        .join(name);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A world of boxes of blocks (inclusive corners) over the default registry.
pub fn box_world(boxes: &[([i32; 3], [i32; 3], BlockId)]) -> World {
    boxes_in(BlockRegistry::default(), boxes)
}

/// A world of boxes of blocks (inclusive corners) over `registry`.
fn boxes_in(registry: BlockRegistry, boxes: &[([i32; 3], [i32; 3], BlockId)]) -> World {
    let mut world = World::new(Arc::new(registry));
    for &(min, max, id) in boxes {
        voxel_lab::scene::fill_box(&mut world, min, max, id).unwrap();
    }
    world
}

/// [`box_world`] with its water a thin surface: a block of the built-in water's colour,
/// opacity and pattern with no absorption, for tests of the order of surfaces and
/// objects, which the volume's absorption along the path would blur (volumes are tested
/// in `tests/volumes.rs`).
pub fn thin_water_world(boxes: &[([i32; 3], [i32; 3], BlockId)]) -> World {
    let mut registry = BlockRegistry::default();
    let water = registry.get(voxel_core::blocks::WATER).unwrap().clone();
    let thin = registry
        .register(voxel_core::BlockDef {
            name: "thin_water".into(),
            absorption: 0.0,
            ..water
        })
        .unwrap();
    let thin_boxes: Vec<_> = boxes
        .iter()
        .map(|&(min, max, id)| {
            let id = if id == voxel_core::blocks::WATER {
                thin
            } else {
                id
            };
            (min, max, id)
        })
        .collect();
    boxes_in(registry, &thin_boxes)
}

/// A scene of `world` seen by one camera at `eye` looking at `target` (fov 60°).
pub fn scene(name: &str, world: World, eye: [f64; 3], target: [f64; 3]) -> Scene {
    let camera = Camera::look_at(DVec3::from(eye), DVec3::from(target), 60.0, 0.1, 500.0).unwrap();
    Scene::new(name, world, camera)
}

/// Renders `scene`'s first camera with `technique` at `width`×`height`.
pub fn render(
    ctx: &GpuContext,
    scene: &Scene,
    technique: Technique,
    width: u32,
    height: u32,
) -> Image {
    render_with(ctx, scene, technique_config(technique, width, height))
}

/// The default renderer settings with `technique`, drawing `width` × `height` pixels.
pub fn technique_config(technique: Technique, width: u32, height: u32) -> RendererConfig {
    let mut config = RendererConfig {
        width,
        height,
        ..RendererConfig::default()
    };
    config.oit.technique = technique;
    config
}

/// Renders `scene`'s first camera with `config`.
pub fn render_with(ctx: &GpuContext, scene: &Scene, config: RendererConfig) -> Image {
    let (w, h) = (config.width, config.height);
    let mut r = renderer_for(ctx, scene, config).unwrap();
    let target = Offscreen::new(ctx, w, h);
    voxel_lab::headless::render_image(ctx, &mut r, &target, &scene.cameras[0]).unwrap()
}

/// The renderer's HDR scene colour, as f32 RGBA.
pub fn read_hdr(ctx: &GpuContext, texture: &wgpu::Texture) -> Vec<[f32; 4]> {
    let bytes = readback::read_texture(ctx, texture, 8).unwrap();
    bytes
        .chunks_exact(8)
        .map(|p| {
            let h = |i: usize| readback::f16_to_f32(u16::from_le_bytes([p[i], p[i + 1]]));
            [h(0), h(2), h(4), h(6)]
        })
        .collect()
}

/// The pixel of a `size` picture of `camera` that world point `p` projects to.
pub fn project(camera: &Camera, size: (u32, u32), p: DVec3) -> (u32, u32) {
    let vp = camera.view_proj(f64::from(size.0) / f64::from(size.1));
    let clip = vp * (p - camera.eye).as_vec3().extend(1.0);
    let ndc = clip.truncate() / clip.w;
    let x = (ndc.x + 1.0) / 2.0 * size.0 as f32;
    let y = (1.0 - ndc.y) / 2.0 * size.1 as f32;
    (x as u32, y as u32)
}

/// Renders with `renderer` into a fresh target and returns the picture.
pub fn frame(ctx: &GpuContext, renderer: &mut Renderer, camera: &Camera) -> Image {
    let (w, h) = renderer.size();
    let target = Offscreen::new(ctx, w, h);
    renderer
        .render_and_submit(&target.view, camera, &mut NoGame)
        .unwrap();
    target.read(ctx).unwrap()
}

/// What [`compact_terrain`] saw.
#[derive(Debug)]
pub struct Compacted {
    /// The renderer's chunk memory with all the terrain uploaded.
    pub before: voxel_render::low_level::ChunkMemory,
    /// Its chunk memory after the unloads and a frame per page it had.
    pub after: voxel_render::low_level::ChunkMemory,
    /// The quads of the chunks kept.
    pub kept_quads: usize,
    /// The compacted renderer's picture.
    pub compacted: Image,
    /// The picture of a fresh renderer given only the chunks kept.
    pub fresh: Image,
}

/// Generated terrain (chunks (-3, 0, -3) to (3, 1, 3), the default terrain settings) meshed
/// and uploaded into a renderer `new` makes; every chunk outside the corner x ≥ 1, z ≥ 1
/// removed, then a frame drawn per page the terrain took (each compacts at most one away);
/// then `camera`'s picture of it and of a fresh renderer given only the chunks kept.
pub fn compact_terrain(
    ctx: &GpuContext,
    camera: &Camera,
    new: impl Fn(&World) -> Renderer,
) -> Compacted {
    let world = voxel_core::TerrainGenerator::new(voxel_core::TerrainConfig::default())
        .generate_world(
            Arc::new(BlockRegistry::default()),
            voxel_core::ChunkPos::new(-3, 0, -3),
            voxel_core::ChunkPos::new(3, 1, 3),
        )
        .unwrap();
    let all: Vec<_> = world.iter().map(|(p, _)| p).collect();
    let meshes = voxel_mesh::mesh_chunks(&world, &all).unwrap();
    let kept = |p: &voxel_core::ChunkPos| p.x >= 1 && p.z >= 1;
    let mut compacted = new(&world);
    for (pos, m) in &meshes {
        compacted.upload_chunk(*pos, m).unwrap();
    }
    let before = compacted.chunk_memory();
    for (pos, _) in meshes.iter().filter(|(p, _)| !kept(p)) {
        compacted.remove_chunk(*pos);
    }
    for _ in 0..before.pages {
        frame(ctx, &mut compacted, camera);
    }
    let after = compacted.chunk_memory();
    let mut fresh = new(&world);
    for (pos, m) in meshes.iter().filter(|(p, _)| kept(p)) {
        fresh.upload_chunk(*pos, m).unwrap();
    }
    Compacted {
        before,
        after,
        kept_quads: meshes
            .iter()
            .filter(|(p, _)| kept(p))
            .map(|(_, m)| m.len())
            .sum(),
        compacted: frame(ctx, &mut compacted, camera),
        fresh: frame(ctx, &mut fresh, camera),
    }
}

/// Per-channel comparison of two images of the same size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Diff {
    /// Largest absolute difference of any channel, in 1/255 steps.
    pub max: u8,
    /// Pixels whose largest channel difference is above 1/255.
    pub over_one: usize,
    /// Pixels that differ at all.
    pub differing: usize,
}

/// Compares RGB of `a` and `b`.
pub fn diff(a: &Image, b: &Image) -> Diff {
    assert_eq!(
        (a.width, a.height),
        (b.width, b.height),
        "image sizes differ"
    );
    let mut d = Diff {
        max: 0,
        over_one: 0,
        differing: 0,
    };
    for (p, q) in a.rgba.chunks_exact(4).zip(b.rgba.chunks_exact(4)) {
        let m = (0..3).map(|c| p[c].abs_diff(q[c])).max().unwrap_or(0);
        d.max = d.max.max(m);
        d.over_one += usize::from(m > 1);
        d.differing += usize::from(m > 0);
    }
    d
}

/// A heat map of the per-pixel difference: black where equal, brighter where larger
/// (scaled so that 16/255 is full red).
pub fn diff_image(a: &Image, b: &Image) -> Image {
    let rgba = a
        .rgba
        .chunks_exact(4)
        .zip(b.rgba.chunks_exact(4))
        .flat_map(|(p, q)| {
            let m = (0..3).map(|c| p[c].abs_diff(q[c])).max().unwrap_or(0);
            let v = (u32::from(m) * 16).min(255) as u8;
            [v, if m > 0 { 40 } else { 0 }, 0, 255]
        })
        .collect();
    Image {
        width: a.width,
        height: a.height,
        rgba,
    }
}

/// Asserts that `actual` is within `tolerance`/255 of `expected` on every channel. Writes
/// `actual.png`, `expected.png` and `diff.png` under [`out_dir`]`(name)` either way, so a
/// person can look; the message says where.
pub fn assert_close(name: &str, actual: &Image, expected: &Image, tolerance: u8) {
    let dir = out_dir(name);
    actual.save_png(&dir.join("actual.png")).unwrap();
    expected.save_png(&dir.join("expected.png")).unwrap();
    let d = diff(actual, expected);
    diff_image(actual, expected)
        .save_png(&dir.join("diff.png"))
        .unwrap();
    assert!(
        d.max <= tolerance,
        "{name}: differs by up to {}/255 (tolerance {tolerance}), {} pixels off by more than 1; see {}",
        d.max,
        d.over_one,
        dir.display()
    );
}

/// Number of distinct RGB colours: a blank or flat image has very few.
pub fn distinct_colours(img: &Image) -> usize {
    let mut v: Vec<[u8; 3]> = img
        .rgba
        .chunks_exact(4)
        .map(|p| [p[0], p[1], p[2]])
        .collect();
    v.sort_unstable();
    v.dedup();
    v.len()
}

/// A headless Vulkan context whose device has `limits` changed from the adapter's (to test
/// the renderer at an adapter's limits without a huge render). `None` as [`gpu`].
pub fn gpu_with_limits(change: impl FnOnce(&mut wgpu::Limits)) -> Option<GpuContext> {
    gpu()?;
    let instance = wgpu::Instance::new(voxel_render::instance_descriptor(wgpu::Backends::VULKAN));
    let adapter = pollster::block_on(instance.request_adapter(&Default::default())).unwrap();
    // What a game that requests its own device does: the renderer's request, changed.
    let mut request = voxel_render::device_descriptor(&adapter, LimitsPreset::Adapter);
    change(&mut request.required_limits);
    let (device, queue) = pollster::block_on(adapter.request_device(&request)).unwrap();
    Some(GpuContext::from_device(&adapter, device, queue))
}

/// `n` sheets of a block of `opacity` facing +z, one block apart, in front of a stone
/// wall, seen head-on from in front of the first: `n` layers on every pixel.
pub fn dense_sheets(n: i32, opacity: f32) -> Scene {
    let mut registry = BlockRegistry::default();
    let dense = registry
        .register(voxel_core::BlockDef::new("dense", [200, 120, 60], opacity))
        .unwrap();
    let mut world = World::new(Arc::new(registry));
    let back = -2 * n - 2;
    voxel_lab::scene::fill_box(
        &mut world,
        [-40, -40, back - 1],
        [40, 40, back],
        voxel_core::blocks::STONE,
    )
    .unwrap();
    for i in 0..n {
        let z = -2 * i;
        voxel_lab::scene::fill_box(&mut world, [-40, -40, z], [40, 40, z], dense).unwrap();
    }
    scene("dense_sheets", world, [0.5, 0.5, 8.0], [0.5, 0.5, -10.0])
}

/// Skips a test that needs a display or an adapter with a loud message, unless `CI` is set:
/// then it fails.
pub fn skip_or_fail(why: &str) {
    if std::env::var_os("CI").is_some() {
        panic!("CI is set but {why}");
    }
    eprintln!("\n!!!! SKIPPING WINDOW TEST: {why} !!!!\n");
}

/// An Xvfb server on a display it picks itself (-displayfd), killed on drop.
#[derive(Debug)]
pub struct Xvfb {
    child: Child,
    /// The display, `:N`.
    pub display: String,
}

impl Xvfb {
    /// Starts a 1280x800 server, or `None` when Xvfb cannot run.
    pub fn start() -> Option<Self> {
        let mut child = Command::new("Xvfb")
            .args([
                "-displayfd",
                "1",
                "-screen",
                "0",
                "1280x800x24",
                "-nolisten",
                "tcp",
            ])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .ok()?;
        let mut line = String::new();
        BufReader::new(child.stdout.take()?)
            .read_line(&mut line)
            .ok()?;
        let n: u32 = line.trim().parse().ok()?;
        Some(Self {
            child,
            display: format!(":{n}"),
        })
    }

    /// A command for `program` on this display (no Wayland, a private runtime folder).
    pub fn command(&self, program: impl AsRef<std::ffi::OsStr>) -> Command {
        let runtime = std::env::temp_dir().join(format!("voxel-oit-xdg-{}", std::process::id()));
        std::fs::create_dir_all(&runtime).unwrap();
        let mut c = Command::new(program);
        c.env("DISPLAY", &self.display)
            .env_remove("WAYLAND_DISPLAY")
            .env("XDG_RUNTIME_DIR", &runtime);
        c
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The binary of example `name` of `voxel-render`: `cargo test` builds the workspace's
/// examples beside the tests (`target/release/examples`); a test run alone builds it.
pub fn example_binary(name: &str) -> PathBuf {
    let exe = std::env::current_exe().expect("the test's own path");
    let profile = exe
        .parent()
        .and_then(|deps| deps.parent())
        .expect("target/<profile>/deps");
    let path = profile.join("examples").join(name);
    if !path.exists() {
        let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
        let status = Command::new(cargo)
            .args([
                "build",
                "--release",
                "-p",
                "voxel-render",
                "--example",
                name,
            ])
            .status()
            .expect("cargo runs");
        assert!(status.success(), "building the {name} example failed");
    }
    path
}

/// Writes a PNG whose header says `width` × `height` (8-bit RGBA) followed by a few bytes
/// of image data and the end: a "header bomb" that is tiny on disk and huge decoded.
pub fn png_header_bomb(path: &std::path::Path, width: u32, height: u32) {
    fn crc32(bytes: &[u8]) -> u32 {
        let mut crc = !0u32;
        for &b in bytes {
            crc ^= u32::from(b);
            for _ in 0..8 {
                crc = if crc & 1 == 1 {
                    (crc >> 1) ^ 0xedb8_8320
                } else {
                    crc >> 1
                };
            }
        }
        !crc
    }
    let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut chunk = |kind: &[u8; 4], data: &[u8]| {
        out.extend((data.len() as u32).to_be_bytes());
        let start = out.len();
        out.extend(kind);
        out.extend(data);
        let crc = crc32(&out[start..]);
        out.extend(crc.to_be_bytes());
    };
    let mut ihdr = Vec::new();
    ihdr.extend(width.to_be_bytes());
    ihdr.extend(height.to_be_bytes());
    ihdr.extend([8, 6, 0, 0, 0]); // 8 bits, RGBA, deflate, adaptive filters, no interlace
    chunk(b"IHDR", &ihdr);
    // A zlib stream of one stored empty block: far too little data for the image.
    chunk(
        b"IDAT",
        &[
            0x78, 0x01, 0x01, 0x00, 0x00, 0xff, 0xff, 0x00, 0x00, 0x00, 0x01,
        ],
    );
    chunk(b"IEND", &[]);
    std::fs::write(path, out).expect("writing the test PNG");
}
