//! Far views in levels of detail (`demo far`): the default terrain to a view distance of
//! hundreds of chunks in rings of coarser levels ([`voxel_mesh::levels`]), built straight
//! from the generator, drawn by every technique; what it costs (time to build, GPU memory
//! per level, bytes per chunk of view distance), and, where full detail fits, how the
//! picture compares with full detail of the same view ([`compare`]).

use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::DVec3;
use serde::Serialize;
use voxel_core::{BlockRegistry, ChunkPos, TerrainConfig, TerrainGenerator};
use voxel_mesh::ChunkMeshes;
use voxel_mesh::levels::{LevelRings, mesh_level_chunks};
use voxel_render::far::{FarConfig, FarField};
use voxel_render::low_level::MeshKind;
use voxel_render::{Camera, GpuContext, Image, NoGame, Renderer, RendererConfig, Technique};

use crate::headless::Offscreen;
use crate::summary::write_json;
use crate::{Error, Result};

/// The largest view distance `demo far` takes, in chunks.
pub const MAX_FAR_DISTANCE: u32 = 2048;

/// What `demo far` runs.
#[derive(Clone, Debug)]
pub struct FarOptions {
    /// Full detail to this many chunks from the eye (even, 2 to 64).
    pub full_detail: u32,
    /// The view distance in chunks (at least `full_detail`, at most [`MAX_FAR_DISTANCE`]).
    pub view_distance: u32,
    /// Picture size.
    pub size: (u32, u32),
    /// Terrain seed.
    pub seed: u32,
    /// The techniques drawn.
    pub techniques: Vec<Technique>,
    /// Also render the same view in full detail to the view distance and score the levels
    /// against it ([`compare`]); at most 64 chunks.
    pub compare: bool,
    /// Frames flown after the view is built, at [`FLIGHT_SPEED`] blocks a second and 60
    /// frames a second (each frame's update timed), 0 to 100 000.
    pub fly_frames: usize,
    /// Output folder.
    pub out: PathBuf,
}

/// How fast the flight of `demo far` goes, blocks a second (issue 50's flight).
pub const FLIGHT_SPEED: f64 = 20.0;

impl Default for FarOptions {
    fn default() -> Self {
        Self {
            full_detail: 32,
            view_distance: 512,
            size: (1280, 720),
            seed: 1,
            techniques: vec![Technique::SortedQuads],
            compare: false,
            fly_frames: 600,
            out: PathBuf::from("far-out"),
        }
    }
}

impl FarOptions {
    /// Checks the options a user gives.
    pub fn validate(&self) -> Result<()> {
        if !(2..=64).contains(&self.full_detail) || !self.full_detail.is_multiple_of(2) {
            return Err(Error::option(
                "--full-detail",
                format!("{}: it must be even, from 2 to 64 chunks", self.full_detail),
            ));
        }
        if !(self.full_detail..=MAX_FAR_DISTANCE).contains(&self.view_distance) {
            return Err(Error::option(
                "--view-distance",
                format!(
                    "{}: it must be from the full detail ({}) to {MAX_FAR_DISTANCE} chunks",
                    self.view_distance, self.full_detail
                ),
            ));
        }
        if self.compare && self.view_distance > 64 {
            return Err(Error::option(
                "--compare",
                "full detail is drawn to at most 64 chunks: give --view-distance 64 or less",
            ));
        }
        if self.fly_frames > 100_000 {
            return Err(Error::option("--fly-frames", "at most 100000"));
        }
        if self.techniques.is_empty() {
            return Err(Error::option("--techniques", "no technique given"));
        }
        Ok(())
    }
}

/// One level's share of a far view.
#[derive(Clone, Debug, Default, Serialize)]
pub struct LevelRow {
    /// The level (0: full detail).
    pub level: u8,
    /// Blocks per cell in x and z.
    pub cell_blocks: i64,
    /// From this many full-detail chunks from the eye (at least) to `to_chunks`.
    pub from_chunks: i64,
    /// To this many full-detail chunks from the eye (at least).
    pub to_chunks: i64,
    /// Its chunks (those with no face included).
    pub chunks: usize,
    /// Its chunks with a mesh.
    pub chunks_drawn: usize,
    /// Opaque, cutout and translucent quads.
    pub quads: [usize; 3],
    /// GPU bytes: 8 a quad and a 32-byte record a chunk drawn.
    pub bytes: u64,
    /// `bytes` per chunk of the view distance it spans (`to_chunks − from_chunks`).
    pub bytes_per_chunk_of_distance: f64,
}

/// What `demo far` measured.
#[derive(Clone, Debug, Serialize)]
pub struct FarReport {
    /// The adapter.
    pub adapter: String,
    /// Full detail to, in chunks.
    pub full_detail: u32,
    /// How far the coarsest level reaches at least, in chunks.
    pub view_distance: i64,
    /// The coarsest level.
    pub coarsest: u8,
    /// Per level, full detail first.
    pub levels: Vec<LevelRow>,
    /// From nothing to the first view drawn (the coarsest level alone), wall-clock ms, the
    /// far field's worker meshing on this machine's cores.
    pub horizon_ms: f64,
    /// From nothing to the finished view drawn, ms.
    pub built_ms: f64,
    /// The views swapped in until then (coarse first: one per level).
    pub views: usize,
    /// The flight after it: [`FarField::update`]'s time per frame on the frame's thread
    /// (planning, taking meshes, the swaps' uploads), ms.
    pub flight_update_ms: crate::stream::Spread,
    /// Frames flown.
    pub flight_frames: usize,
    /// Views swapped in during the flight.
    pub flight_swaps: usize,
    /// The most chunks a view being built lacked during the flight.
    pub flight_most_missing: usize,
    /// The renderer's chunk memory after the upload: arena pages, records and draws.
    pub gpu_buffer_bytes: u64,
    /// Of those, bytes holding quads.
    pub gpu_quad_bytes: u64,
    /// The pictures written, one per technique.
    pub pictures: Vec<String>,
    /// The comparison with full detail, when asked for.
    pub compare: Option<Comparison>,
}

/// The default far view's eye and target: above the showcase's structure, looking over it
/// to the sea and the horizon (the eye 40 blocks above the structure's floor, pitched
/// 0.12 rad down).
pub fn default_view(generator: &TerrainGenerator) -> Result<Camera> {
    let show = generator
        .showcase(1)?
        .ok_or_else(|| Error::option("--seed", "no structure within 768 blocks of the origin"))?;
    let eye = DVec3::from(show.eye) + DVec3::new(0.0, 40.0, 0.0);
    let dir = DVec3::from(show.water_dir).normalize_or(DVec3::X);
    let forward = (dir * 0.12f64.cos()) - DVec3::new(0.0, 0.12f64.sin(), 0.0);
    Ok(Camera::look_at(
        eye,
        eye + forward * 100.0,
        60.0,
        0.1,
        f64::from(MAX_FAR_DISTANCE) * 32.0 * 2.0,
    )?)
}

/// Every level's meshes for `camera`'s eye.
pub fn build(
    generator: &TerrainGenerator,
    registry: &BlockRegistry,
    rings: &LevelRings,
    camera: &Camera,
) -> Result<Vec<(u8, ChunkPos, ChunkMeshes)>> {
    let eye = camera.eye.to_array();
    let chunks = rings.all(eye);
    Ok(mesh_level_chunks(generator, registry, rings, eye, &chunks)?)
}

/// Uploads level meshes to `renderer`.
pub fn upload(renderer: &mut Renderer, meshes: &[(u8, ChunkPos, ChunkMeshes)]) -> Result<()> {
    for (l, p, m) in meshes {
        renderer.upload_level_chunk(*l, *p, m)?;
    }
    Ok(())
}

/// Renders `camera` and reads the picture back.
pub fn picture(
    ctx: &GpuContext,
    renderer: &mut Renderer,
    target: &Offscreen,
    camera: &Camera,
) -> Result<Image> {
    renderer.render_and_submit(&target.view, camera, &mut NoGame)?;
    target.read(ctx)
}

/// Per level, the chunks, quads and bytes `renderer` holds.
pub fn held_rows(rings: &LevelRings, renderer: &Renderer) -> Vec<LevelRow> {
    let r = i64::from(rings.radius);
    let mut rows: Vec<LevelRow> = (0..=rings.coarsest)
        .map(|level| LevelRow {
            level,
            cell_blocks: voxel_core::level_scale(level),
            from_chunks: if level == 0 { 0 } else { r << (level - 1) },
            to_chunks: r << level,
            ..LevelRow::default()
        })
        .collect();
    for c in voxel_render::low_level::chunks(renderer).iter() {
        let Some(row) = rows.get_mut(usize::from(c.level())) else {
            continue;
        };
        row.chunks += 1;
        row.chunks_drawn += 1;
        row.bytes += 32;
        for (k, kind) in [MeshKind::Opaque, MeshKind::Cutout, MeshKind::Translucent]
            .into_iter()
            .enumerate()
        {
            let q = c.mesh(kind).map_or(0, |a| a.quads as usize);
            row.quads[k] += q;
            row.bytes += 8 * q as u64;
        }
    }
    for row in &mut rows {
        row.bytes_per_chunk_of_distance =
            row.bytes as f64 / (row.to_chunks - row.from_chunks).max(1) as f64;
    }
    rows
}

/// Builds the far view of `opts` through a [`FarField`] from nothing (timing the first
/// and the finished view), draws it with each technique, flies on, and writes the
/// pictures and `far.json` into `opts.out`.
pub fn run(ctx: &GpuContext, opts: &FarOptions) -> Result<FarReport> {
    opts.validate()?;
    let generator = Arc::new(TerrainGenerator::new(TerrainConfig {
        seed: opts.seed,
        ..TerrainConfig::default()
    }));
    let registry = Arc::new(BlockRegistry::default());
    let rings = LevelRings::reaching(opts.full_detail, opts.view_distance);
    let camera = default_view(&generator)?;
    let (width, height) = opts.size;
    let config = RendererConfig {
        width,
        height,
        ..RendererConfig::default()
    };
    let mut renderer = Renderer::new(ctx, &registry, config)?;
    let mut field = FarField::new(
        Arc::clone(&generator),
        Arc::clone(&registry),
        FarConfig {
            rings: rings.clone(),
            ..FarConfig::default()
        },
    )?;
    let t = Instant::now();
    let (mut horizon_ms, mut views) = (None, 0);
    loop {
        let s = field.update(&mut renderer, camera.eye)?;
        if s.swapped {
            views += 1;
            horizon_ms.get_or_insert(t.elapsed().as_secs_f64() * 1e3);
        }
        if s.drawn_finest == Some(0) {
            break;
        }
        if t.elapsed().as_secs() > 1800 {
            return Err(Error::option(
                "--view-distance",
                "the view took over 30 minutes to build",
            ));
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    let built_ms = t.elapsed().as_secs_f64() * 1e3;
    let memory = renderer.chunk_memory();
    let levels = held_rows(&rings, &renderer);
    let target = Offscreen::new(ctx, width, height);
    let mut pictures = Vec::new();
    for &t in &opts.techniques {
        renderer.set_technique(t)?;
        let image = picture(ctx, &mut renderer, &target, &camera)?;
        let name = format!("far-{}.png", t.name());
        image.save_png(&opts.out.join(&name))?;
        pictures.push(name);
    }
    // The flight: along the view's horizontal direction at FLIGHT_SPEED, 60 frames a second.
    let dir = DVec3::new(camera.forward.x, 0.0, camera.forward.z).normalize_or(DVec3::X);
    let frame = Duration::from_secs_f64(1.0 / 60.0);
    let (mut times, mut swaps, mut most_missing) = (Vec::new(), 0, 0);
    for f in 0..opts.fly_frames {
        let start = Instant::now();
        let eye = camera.eye + dir * (FLIGHT_SPEED * (f + 1) as f64 / 60.0);
        let s = field.update(&mut renderer, eye)?;
        times.push(start.elapsed().as_secs_f64() * 1e3);
        swaps += usize::from(s.swapped);
        most_missing = most_missing.max(s.missing);
        std::thread::sleep(frame.saturating_sub(start.elapsed()));
    }
    let compare = match opts.compare {
        true => {
            let full = LevelRings {
                radius: (opts.view_distance as i32 + 1) & !1,
                coarsest: 0,
                finest: 0,
                y: rings.y.clone(),
            };
            let levels = build(&generator, &registry, &rings, &camera)?;
            let c = compare(
                ctx,
                &mut renderer,
                &target,
                &camera,
                &levels,
                &build(&generator, &registry, &full, &camera)?,
                &rings,
                &opts.out,
            )?;
            Some(c)
        }
        false => None,
    };
    let report = FarReport {
        adapter: ctx.caps.adapter_name.clone(),
        full_detail: opts.full_detail,
        view_distance: rings.view_distance(),
        coarsest: rings.coarsest,
        levels,
        horizon_ms: horizon_ms.unwrap_or(built_ms),
        built_ms,
        views,
        flight_update_ms: crate::stream::Spread::of(&times),
        flight_frames: opts.fly_frames,
        flight_swaps: swaps,
        flight_most_missing: most_missing,
        gpu_buffer_bytes: memory.arena_bytes
            + memory.record_bytes
            + memory.indirect_bytes
            + memory.light_bytes,
        gpu_quad_bytes: memory.quad_bytes,
        pictures,
        compare,
    };
    write_json(&opts.out.join("far.json"), &report)?;
    Ok(report)
}

/// A far view's picture against full detail of the same view.
#[derive(Clone, Debug, Serialize)]
pub struct Comparison {
    /// Pixels where the far view shows the sky through the ground (below its skyline in the
    /// column) where full detail draws something, of all.
    pub holes: f64,
    /// Pixels where the skyline differs (sky in one picture above the other's skyline in
    /// the column: a far tree or hill top sampled away or in), of all.
    pub skyline: f64,
    /// Pixels where full detail shows something beyond the full-detail ring (the levels'
    /// part of the picture), of all.
    pub far_pixels: f64,
    /// Of those, water (full detail's picture changes where its translucent meshes are
    /// left out).
    pub far_water_pixels: f64,
    /// The same in the far view's picture (each picture's far water is its own).
    pub far_water_pixels_levels: f64,
    /// The mean colour of the far water, full detail and levels (sRGB, 0 to 255).
    pub far_water_mean: [[f64; 3]; 2],
    /// The mean colour of the rest of the far pixels, full detail and levels.
    pub far_ground_mean: [[f64; 3]; 2],
    /// The mean of |levels − full detail| over the far pixels of full detail, per channel,
    /// /255.
    pub far_mean_abs: f64,
}

impl Comparison {
    /// The largest channel difference of the far water's mean colour, /255.
    pub fn water_step(&self) -> f64 {
        step(&self.far_water_mean)
    }

    /// The largest channel difference of the rest of the far pixels' mean colour, /255.
    pub fn ground_step(&self) -> f64 {
        step(&self.far_ground_mean)
    }
}

fn step(m: &[[f64; 3]; 2]) -> f64 {
    (0..3)
        .map(|c| (m[0][c] - m[1][c]).abs())
        .fold(0.0, f64::max)
}

/// `meshes` without their translucent meshes.
fn dry(meshes: &[(u8, ChunkPos, ChunkMeshes)]) -> Vec<(u8, ChunkPos, ChunkMeshes)> {
    meshes
        .iter()
        .map(|(l, p, m)| {
            let mut m = m.clone();
            m.translucent.clear();
            (*l, *p, m)
        })
        .collect()
}

/// Scores the far view of the level meshes `levels` against full detail `full` (level-0
/// meshes of the whole view) from the same `camera`, both drawn with `renderer`'s
/// technique (its chunks are replaced). Which pixels are far, water or sky is read off
/// pictures with parts left out: the sky (no chunk), the full-detail ring of `rings` alone
/// (far pixels: where a picture differs from it), and each picture without its
/// translucent meshes (water: where it differs from them). Writes `full.png`, `levels.png`
/// and `compare-map.png` (the far view, its holes magenta, the skyline's differences red,
/// its far water yellow) into `out`.
#[allow(clippy::too_many_arguments)]
pub fn compare(
    ctx: &GpuContext,
    renderer: &mut Renderer,
    target: &Offscreen,
    camera: &Camera,
    levels: &[(u8, ChunkPos, ChunkMeshes)],
    full: &[(u8, ChunkPos, ChunkMeshes)],
    rings: &LevelRings,
    out: &std::path::Path,
) -> Result<Comparison> {
    let eye = camera.eye.to_array();
    let mut draw = |meshes: &[(u8, ChunkPos, ChunkMeshes)]| -> Result<Image> {
        renderer.clear_chunks();
        upload(renderer, meshes)?;
        picture(ctx, renderer, target, camera)
    };
    let sky = draw(&[])?;
    let near: Vec<_> = full
        .iter()
        .filter(|(_, p, _)| rings.contains(0, *p, eye))
        .cloned()
        .collect();
    let ring = draw(&near)?;
    let pictures = [draw(full)?, draw(levels)?];
    let dry = [draw(&dry(full))?, draw(&dry(levels))?];
    renderer.clear_chunks();
    pictures[0].save_png(&out.join("full.png"))?;
    pictures[1].save_png(&out.join("levels.png"))?;

    let (w, h) = (sky.width as usize, sky.height as usize);
    let n = w * h;
    let px = |im: &Image, i: usize| [0, 1, 2].map(|c| f64::from(im.rgba[i * 4 + c]));
    let differs = |a: [f64; 3], b: [f64; 3]| (0..3).any(|c| (a[c] - b[c]).abs() > 2.0);
    // Each picture's skyline: per column, the first row (from the top) that is not sky.
    let skyline = |im: &Image| -> Vec<usize> {
        (0..w)
            .map(|x| {
                (0..h)
                    .find(|&y| differs(px(im, y * w + x), px(&sky, y * w + x)))
                    .unwrap_or(h)
            })
            .collect()
    };
    let tops = [skyline(&pictures[0]), skyline(&pictures[1])];
    let mut map = pictures[1].clone();
    let (mut holes, mut sky_diff) = (0usize, 0usize);
    let mut far = [0usize; 2];
    let mut water = [0usize; 2];
    let mut sums = [[[0.0; 3]; 2]; 2];
    let mut abs = 0.0;
    for i in 0..n {
        let (x, y) = (i % w, i / w);
        let s = px(&sky, i);
        let [a, l] = [px(&pictures[0], i), px(&pictures[1], i)];
        if differs(a, s) != differs(l, s) {
            if y >= tops[0][x].max(tops[1][x]) {
                // Below both skylines: sky where the ground should be, or the reverse.
                if differs(a, s) {
                    holes += 1;
                    map.rgba[i * 4..i * 4 + 3].copy_from_slice(&[255, 0, 255]);
                }
            } else {
                sky_diff += 1;
                map.rgba[i * 4..i * 4 + 3].copy_from_slice(&[255, 0, 0]);
            }
        }
        let r = px(&ring, i);
        for k in 0..2 {
            let p = px(&pictures[k], i);
            if !differs(p, r) {
                continue;
            }
            far[k] += 1;
            let wet = differs(p, px(&dry[k], i));
            water[k] += usize::from(wet);
            for c in 0..3 {
                sums[usize::from(!wet)][k][c] += p[c];
            }
            if k == 0 {
                abs += (0..3).map(|c| (a[c] - l[c]).abs()).sum::<f64>() / 3.0;
            } else if wet {
                map.rgba[i * 4..i * 4 + 3].copy_from_slice(&[255, 255, 0]);
            }
        }
    }
    map.save_png(&out.join("compare-map.png"))?;
    let mean = |s: [[f64; 3]; 2], count: [usize; 2]| {
        [0, 1].map(|k| s[k].map(|x| x / count[k].max(1) as f64))
    };
    let ground = [far[0] - water[0], far[1] - water[1]];
    Ok(Comparison {
        holes: holes as f64 / n as f64,
        skyline: sky_diff as f64 / n as f64,
        far_pixels: far[0] as f64 / n as f64,
        far_water_pixels: water[0] as f64 / n as f64,
        far_water_pixels_levels: water[1] as f64 / n as f64,
        far_water_mean: mean(sums[0], water),
        far_ground_mean: mean(sums[1], ground),
        far_mean_abs: abs / far[0].max(1) as f64,
    })
}
