//! Stability where methods fail: sweeps that change one thing (opacity, number of layers,
//! distance of the stack) and chart each technique's error against it, and a camera path
//! that measures temporal flicker beyond the reference's own change.

use crate::{Error, Result};

use std::sync::Arc;

use glam::DVec3;
use serde::Serialize;
use voxel_core::{BlockDef, BlockId, BlockRegistry, World};

use voxel_render::{Camera, GpuContext, Technique};

use crate::eval::{default_weight, make_renderer, measure, oit_config};
use crate::headless::Offscreen;
use crate::metrics;
use crate::progress::Progress;
use crate::scene::Scene;
use crate::summary::{EvalOptions, write_json};

/// One sweep: a parameter and each technique's mean FLIP at each of its values.
#[derive(Clone, Debug, Serialize)]
pub struct Sweep {
    /// Short name (file stem of its chart).
    pub name: String,
    /// Whether its values are best shown on a log axis.
    pub log: bool,
    /// What is swept.
    pub parameter: String,
    /// The values, in order.
    pub values: Vec<f64>,
    /// Per technique: mean FLIP at each value.
    pub flip: Vec<(String, Vec<f64>)>,
}

/// Temporal flicker along one scene's camera path.
#[derive(Clone, Debug, Serialize)]
pub struct Flicker {
    /// Scene file stem.
    pub scene: String,
    /// Frames of the path.
    pub frames: usize,
    /// The reference's own mean absolute change between frames, in 1/255 steps.
    pub reference_change: f64,
    /// Per technique: mean change beyond the reference's, in 1/255 steps.
    pub excess: Vec<(String, f64)>,
    /// Per technique: the largest change beyond the reference's in one step (the step's
    /// mean, 1/255): a one-frame flash the mean over the path hides.
    pub max_step: Vec<(String, f64)>,
    /// Per technique: the steps that pop (more than [`metrics::POP_SHARE`] of the pixels
    /// change by more than [`metrics::POP_LEVEL`]/255 beyond the reference).
    pub pops: Vec<(String, usize)>,
    /// Per technique: the largest share of one step's pixels changing by more than
    /// [`metrics::POP_LEVEL`]/255 beyond the reference, percent.
    pub worst_pop: Vec<(String, f64)>,
}

/// All stability results.
#[derive(Clone, Debug, Serialize)]
pub struct Stability {
    /// The sweeps.
    pub sweeps: Vec<Sweep>,
    /// Flicker per path.
    pub flicker: Vec<Flicker>,
}

/// Techniques the sweeps chart: all measured ones but the references and opaque-only.
fn swept(opts: &EvalOptions) -> Vec<Technique> {
    opts.techniques
        .iter()
        .copied()
        .filter(|t| !t.is_exact() && *t != Technique::OpaqueOnly)
        .collect()
}

/// `n` values spread over `all` (its first and last always included).
fn pick(all: &[f64], n: usize) -> Vec<f64> {
    if n >= all.len() || n < 2 {
        return all.to_vec();
    }
    (0..n).map(|i| all[i * (all.len() - 1) / (n - 1)]).collect()
}

/// A registry with sweep blocks of `opacity` in the given colours, and their ids.
fn sweep_registry(opacity: f32, colors: &[[u8; 3]]) -> (Arc<BlockRegistry>, Vec<BlockId>) {
    let mut r = BlockRegistry::default();
    let ids = colors
        .iter()
        .enumerate()
        .filter_map(|(i, c)| {
            r.register(BlockDef::new(format!("sweep_{i}"), *c, opacity))
                .ok()
        })
        .collect();
    (Arc::new(r), ids)
}

/// Parallel sheets facing +z at the given z, over a stone and sand back wall.
fn sheets(
    registry: Arc<BlockRegistry>,
    ids: &[BlockId],
    zs: &[i32],
    half: i32,
    eye_z: f64,
) -> Result<Scene> {
    let mut world = World::new(registry);
    let back = zs.iter().min().copied().unwrap_or(0) - 4;
    let fill =
        |w: &mut World, min: [i32; 3], max: [i32; 3], id| crate::scene::fill_box(w, min, max, id);
    fill(
        &mut world,
        [-half - 4, -half - 4, back - 1],
        [half + 4, half + 4, back],
        voxel_core::blocks::STONE,
    )?;
    fill(
        &mut world,
        [-half - 4, -half - 4, back + 1],
        [half + 4, -half / 3, back + 1],
        voxel_core::blocks::SAND,
    )?;
    for (i, &z) in zs.iter().enumerate() {
        fill(
            &mut world,
            [-half, -half, z],
            [half, half, z],
            ids[i % ids.len()],
        )?;
    }
    let camera = Camera::look_at(
        DVec3::new(0.5, 0.5, eye_z),
        DVec3::new(0.5, 0.5, -1.0),
        60.0,
        0.1,
        4000.0,
    )?;
    Ok(Scene::new("sweep", world, camera))
}

/// Mean FLIP of each technique against the reference on `scene`.
fn errors(
    ctx: &GpuContext,
    scene: &Scene,
    opts: &EvalOptions,
    size: (u32, u32),
    techniques: &[Technique],
) -> Result<Vec<f64>> {
    let mut renderer = make_renderer(ctx, scene, size)?;
    let target = Offscreen::new(ctx, size.0, size.1);
    let cam = scene.cameras[0];
    let weight = default_weight();
    let reference = measure(
        ctx,
        &mut renderer,
        &target,
        &cam,
        &oit_config(Technique::Reference, weight),
        0,
        1,
    )?;
    techniques
        .iter()
        .map(|t| {
            let m = measure(
                ctx,
                &mut renderer,
                &target,
                &cam,
                &oit_config(*t, weight),
                opts.warmup,
                1,
            )?;
            Ok(metrics::compare(&reference.image, &m.image).0.flip_mean)
        })
        .collect()
}

const COLORS: [[u8; 3]; 4] = [[210, 60, 40], [40, 90, 210], [60, 180, 70], [230, 200, 60]];

/// Runs the sweeps and the flicker paths, writes `stability/stability.json`.
pub fn run(ctx: &GpuContext, opts: &EvalOptions) -> Result<Stability> {
    let dir = opts.out.join("stability");
    std::fs::create_dir_all(&dir).map_err(Error::io(&dir))?;
    let techniques = swept(opts);
    let size = opts
        .size
        .map(|(w, h)| (w.min(480), h.min(270)))
        .unwrap_or((480, 270));
    let n = opts.sweep_points.max(2);

    let opacities = pick(&[0.05, 0.1, 0.2, 0.35, 0.5, 0.65, 0.8, 0.9, 0.99], n);
    let layers = pick(&[1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0], n);
    let distances = pick(&[1.0, 3.0, 10.0, 30.0, 100.0, 300.0, 1000.0], n);
    let flicker_scenes = flicker_scenes(opts)?;
    let mut progress =
        Progress::new(opacities.len() + layers.len() + distances.len() + flicker_scenes.len());

    let mut sweep = |name: &str,
                     parameter: &str,
                     log: bool,
                     values: &[f64],
                     build: &dyn Fn(f64) -> Result<Scene>|
     -> Result<Sweep> {
        let mut flip = vec![Vec::new(); techniques.len()];
        for &v in values {
            progress.step(&format!("stability: {name} {v}"));
            let scene = build(v)?;
            for (i, e) in errors(ctx, &scene, opts, size, &techniques)?
                .into_iter()
                .enumerate()
            {
                flip[i].push(e);
            }
        }
        Ok(Sweep {
            name: name.to_owned(),
            log,
            parameter: parameter.to_owned(),
            values: values.to_vec(),
            flip: techniques
                .iter()
                .map(|t| t.name().to_owned())
                .zip(flip)
                .collect(),
        })
    };
    let opacity = sweep(
        "opacity",
        "opacity of every layer (6 layers)",
        false,
        &opacities,
        &|a| {
            let (reg, ids) = sweep_registry(a as f32, &COLORS[..2]);
            sheets(reg, &ids, &[0, -2, -4, -6, -8, -10], 12, 14.0)
        },
    )?;
    let layer_count = sweep(
        "layers",
        "number of layers (opacity 0.3)",
        true,
        &layers,
        &|n| {
            let (reg, ids) = sweep_registry(0.3, &COLORS[..3]);
            let zs: Vec<i32> = (0..n as i32).map(|i| -2 * i).collect();
            sheets(reg, &ids, &zs, 14, 8.0)
        },
    )?;
    let distance = sweep(
        "distance",
        "distance from the eye to the stack (blocks)",
        true,
        &distances,
        &|d| {
            let (reg, ids) = sweep_registry(0.4, &COLORS);
            // The stack grows with distance so that it covers the same part of the view.
            let half = (0.7 * d).max(6.0) as i32;
            sheets(reg, &ids, &[0, -2, -4, -6], half, d + 1.0)
        },
    )?;
    let sweeps = vec![opacity, layer_count, distance];
    let mut flicker = Vec::new();
    for (stem, scene) in flicker_scenes {
        progress.step(&format!("stability: flicker {stem}"));
        flicker.push(flicker_path(ctx, &stem, &scene, opts, size, &techniques)?);
    }
    progress.finish();
    let result = Stability { sweeps, flicker };
    write_json(&dir.join("stability.json"), &result)?;
    Ok(result)
}

/// The scenes whose camera paths measure flicker: every scene of the run with a path
/// (`path_to` of its first camera).
fn flicker_scenes(opts: &EvalOptions) -> Result<Vec<(String, Scene)>> {
    let mut out = Vec::new();
    for p in &opts.scenes {
        let s = Scene::load(p)?;
        if s.paths.first().copied().flatten().is_some() {
            let stem = p
                .file_stem()
                .map_or(String::new(), |s| s.to_string_lossy().into_owned());
            out.push((stem, s));
        }
    }
    Ok(out)
}

fn flicker_path(
    ctx: &GpuContext,
    stem: &str,
    scene: &Scene,
    opts: &EvalOptions,
    size: (u32, u32),
    techniques: &[Technique],
) -> Result<Flicker> {
    let start = scene.cameras[0];
    let end = scene.paths[0].unwrap_or(start.eye + DVec3::X * 2.0);
    let frames = opts.flicker_frames.max(2);
    // The eye's medium follows it (a path may cross a water surface).
    let cameras: Vec<Camera> = (0..frames)
        .map(|i| {
            let eye = start.eye.lerp(end, i as f64 / (frames - 1) as f64);
            Camera { eye, ..start }.in_medium(scene.world.medium_at(eye.to_array()))
        })
        .collect();
    let mut renderer = make_renderer(ctx, scene, size)?;
    let target = Offscreen::new(ctx, size.0, size.1);
    let weight = default_weight();
    // Walks the path with technique `t`, handing `visit` each frame's index and picture:
    // only the reference's pictures are kept (at most `MAX_FLICKER_FRAMES` of them), a
    // technique's are compared as they come.
    let path = |renderer: &mut crate::headless::SceneRenderer,
                t: Technique,
                visit: &mut dyn FnMut(usize, voxel_render::Image)|
     -> Result<()> {
        // Settle at the start (pipelines, adaptive peeling), then walk the path.
        measure(
            ctx,
            renderer,
            &target,
            &cameras[0],
            &oit_config(t, weight),
            opts.warmup,
            0,
        )?;
        for (i, c) in cameras.iter().enumerate() {
            renderer.render_and_submit(&target.view, c)?;
            visit(i, target.read(ctx)?);
        }
        Ok(())
    };
    let mut reference = Vec::with_capacity(cameras.len());
    path(&mut renderer, Technique::Reference, &mut |_, img| {
        reference.push(img);
    })?;
    let change = |v: &[voxel_render::Image]| -> f64 {
        v.windows(2)
            .map(|w| metrics::mean_abs_diff(&w[0], &w[1]))
            .sum::<f64>()
            / (v.len() - 1) as f64
    };
    let (mut excess, mut max_step, mut pops, mut worst_pop) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for &t in techniques {
        let mut previous: Option<voxel_render::Image> = None;
        let mut steps = Vec::with_capacity(cameras.len());
        path(&mut renderer, t, &mut |i, img| {
            if let Some(p) = &previous {
                steps.push(metrics::step_excess(
                    p,
                    &img,
                    &reference[i - 1],
                    &reference[i],
                ));
            }
            previous = Some(img);
        })?;
        let name = t.name().to_owned();
        let mean = steps.iter().map(|s| s.mean).sum::<f64>() / steps.len().max(1) as f64;
        excess.push((name.clone(), mean));
        max_step.push((
            name.clone(),
            steps.iter().map(|s| s.mean).fold(0.0, f64::max),
        ));
        pops.push((name.clone(), steps.iter().filter(|s| s.pops()).count()));
        worst_pop.push((
            name,
            100.0 * steps.iter().map(|s| s.over).fold(0.0, f64::max),
        ));
    }
    Ok(Flicker {
        scene: stem.to_owned(),
        frames,
        reference_change: change(&reference),
        excess,
        max_step,
        pops,
        worst_pop,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use voxel_core::WorldPos;

    #[test]
    fn pick_spreads_values_and_keeps_the_ends() {
        let all = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0];
        assert_eq!(pick(&all, 3), vec![1.0, 4.0, 7.0]);
        assert_eq!(pick(&all, 2), vec![1.0, 7.0]);
        assert_eq!(pick(&all, 10), all.to_vec());
    }

    #[test]
    fn sweep_scenes_hold_the_sheets() {
        let (reg, ids) = sweep_registry(0.3, &COLORS[..3]);
        assert_eq!(ids.len(), 3);
        let s = sheets(reg, &ids, &[0, -2, -4], 5, 8.0).unwrap();
        assert_eq!(s.world.get_block(WorldPos::new(0, 0, -2)), ids[1]);
        assert_eq!(s.world.get_block(WorldPos::new(0, 0, -1)), BlockId::AIR);
    }
}
