//! Scenes: a world and the cameras to look at it with, from generated terrain, from a
//! hand-written TOML file, from a MagicaVoxel `.vox` file, or built in code.
//!
//! The file format (every key but `name` and one camera is optional; the camera too when
//! the scene has models):
//!
//! ```toml
//! name = "Stained-glass corridor"
//! description = "many layers of different colours"
//! size = [640, 360]                 # output size when the command gives none
//! light = true                     # drawn with the light field (docs/light.md); adds the
//!                                   # blocks torch, lava and glow_glass
//! sun_shadows = false               # with light: no sun shadows (default true)
//!
//! [terrain]                         # generated terrain, chunk coordinates inclusive
//! seed = 1
//! min_chunk = [-2, 0, -2]
//! max_chunk = [1, 1, 1]
//!
//! [[blocks]]                        # extra block types, usable by name below
//! name = "smoky_glass"
//! color = [90, 90, 100]             # sRGB
//! opacity = 0.5                     # below 1: translucent
//! class = "translucent"             # opaque, cutout or translucent (default: from opacity)
//! pattern = "framed"                # noise, leaves, framed, grass (with soil = [r, g, b])
//! absorption = 0.2                  # translucent: a volume, light kept exp(-0.2 d) over d blocks
//! medium = "water"                  # cutout: stands in this (earlier) block, as kelp in water
//! texture = "smoky.png"             # a PNG for every face, relative to this file
//! top = "smoky_top.png"             # top, bottom, side: one face group (over texture)
//!
//! [[boxes]]                         # filled boxes, corners inclusive, in order
//! block = "red_glass"
//! min = [0, 0, 0]
//! max = [3, 5, 0]
//!
//! [[particles]]                    # a game's particles: camera-facing translucent squares
//! min = [-6.0, -7.0, -8.0]          # scattered uniformly in this box (world units)
//! max = [6.0, 2.5, 2.0]
//! count = 2000                      # at most 1 000 000 in a scene
//! seed = 7                          # where they fall (default 1)
//! size = 0.12                       # half side, blocks (default 0.25)
//! color = [225, 240, 255]           # sRGB
//! opacity = 0.45                    # in (0, 1)
//!
//! [[entities]]                      # a game's entities: boxes at any angle
//! center = [3.5, 0.2, -3.0]
//! size = [2.5, 2.5, 2.5]            # full extents, blocks
//! rotation = [35.0, 25.0, 10.0]     # yaw, pitch, roll in degrees (default none)
//! color = [150, 220, 235]
//! opacity = 0.45                    # 1 (default): opaque, else translucent
//!
//! [[cameras]]
//! eye = [0.5, 3.5, 12.0]
//! target = [0.5, 3.5, 0.0]
//! fov = 60.0                        # vertical, degrees
//! near = 0.1
//! far = 1000.0
//! path_to = [6.5, 3.5, 12.0]        # the flicker test moves the eye here in 60 frames
//! ```
//!
//! Boxes and models are applied in the order the file lists them (terrain first); a
//! model's voxels set blocks, its empty cells leave what was there. Each palette entry a
//! model uses becomes a block type named after the file (`harbour#165`; see
//! [`voxel_core::vox`] for the mapping of MagicaVoxel's materials). Without `[[cameras]]`,
//! a scene with models gets [`framing_camera`]'s view of them.
//!
//! Particles and entities are not blocks: the renderer draws them through its frame stages
//! (voxel_render::stages) with the game's own shaders, so every technique composes them
//! with the world, and the ray march intersects them exactly (squares facing the camera
//! and boxes, lit as the content's shader lights them).
//!
//! A bare `.vox` file is a scene too ([`Scene::load`]): its model with the lowest corner at
//! the origin, seen by [`framing_camera`].

use crate::{Error, Result};

mod blocks;
mod content;
mod fields;
mod format;
mod parse;
#[cfg(test)]
mod tests;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::DVec3;
use voxel_core::{
    BlockRegistry, TerrainConfig, TerrainGenerator, VoxFile, VoxPlacement, World, WorldPos,
};
use voxel_render::Camera;

use voxel_render::content::Content;

pub use content::MAX_PARTICLES;
pub use parse::{parse, parse_in};

/// A world with cameras.
#[derive(Debug, Clone)]
pub struct Scene {
    /// Name, for reports.
    pub name: String,
    /// What the scene is for.
    pub description: String,
    /// The blocks.
    pub world: World,
    /// Cameras, at least one.
    pub cameras: Vec<Camera>,
    /// Per camera: where its eye moves in the flicker test, if anywhere.
    pub paths: Vec<Option<DVec3>>,
    /// Output size the scene asks for.
    pub size: Option<(u32, u32)>,
    /// A game's particles and entities ([`voxel_render::content`]), drawn through the renderer's
    /// stages.
    pub content: Content,
    /// Whether the world is drawn with its light field ([`voxel_core::LightField`], meshed
    /// with `Mesher::mesh_lit`); false: unlit.
    pub light: bool,
    /// With `light`: whether the sun casts shadows over the whole world (or the chunks of
    /// it nearest the first camera that fit: [`voxel_render::SunRegion::around`]).
    pub sun_shadows: bool,
}

impl Scene {
    /// A scene of `world` with one camera and nothing else; the camera's medium is taken
    /// from the world at its eye.
    pub fn new(name: &str, world: World, camera: Camera) -> Self {
        let camera = camera.in_medium(world.medium_at(camera.eye.to_array()));
        Self {
            name: name.to_owned(),
            description: String::new(),
            world,
            cameras: vec![camera],
            paths: vec![None],
            size: None,
            content: Content::default(),
            light: false,
            sun_shadows: true,
        }
    }

    /// Reads a scene file (at most [`crate::limits::MAX_SCENE_FILE_BYTES`]: a longer
    /// file, or an endless one like `/dev/zero`, is an error after that many bytes), or a
    /// bare `.vox` model ([`Scene::from_vox`]). Errors name the file, the line and the
    /// field.
    pub fn load(path: &Path) -> Result<Self> {
        if is_vox(path) {
            return Self::from_vox(path);
        }
        let text = read_limited(path, crate::limits::MAX_SCENE_FILE_BYTES)?;
        let dir = path.parent().unwrap_or(Path::new(""));
        parse_in(&text, dir).map_err(|e| e.in_file(path.display()))
    }

    /// A MagicaVoxel model as a scene: its blocks with the lowest corner at the origin
    /// (palette entries as its materials say), seen by [`framing_camera`]. Named after the
    /// file. Errors name the file and what is wrong with it.
    pub fn from_vox(path: &Path) -> Result<Self> {
        let file = VoxFile::load(path)?;
        let name = model_name(path);
        let mut registry = BlockRegistry::default();
        let blocks = file
            .register_blocks(&name, &[], &mut registry)
            .map_err(|source| Error::Model {
                path: path.to_owned(),
                source,
            })?;
        let mut world = World::new(Arc::new(registry));
        let placed = file
            .place(&name, &blocks, VoxPlacement::default(), &mut world)
            .map_err(|source| Error::Model {
                path: path.to_owned(),
                source,
            })?
            .ok_or_else(|| Error::EmptyModel {
                path: path.to_owned(),
            })?;
        let (camera, path_to) = framing_camera(placed.0, placed.1)?;
        let mut scene = Scene::new(&name, world, camera);
        scene.description = format!(
            "MagicaVoxel model {}",
            path.file_name()
                .map_or(name.clone(), |f| f.to_string_lossy().into_owned())
        );
        scene.paths = vec![Some(path_to)];
        Ok(scene)
    }
}

/// Whether `path` names a MagicaVoxel file (by its extension).
pub fn is_vox(path: &Path) -> bool {
    path.extension()
        .is_some_and(|x| x.eq_ignore_ascii_case("vox"))
}

/// The name a model's blocks and scene take: the file's stem.
fn model_name(path: &Path) -> String {
    path.file_stem()
        .map_or_else(|| "model".to_owned(), |s| s.to_string_lossy().into_owned())
}

/// The default view of the blocks `min..=max` (inclusive): a three-quarter view from above,
/// as MagicaVoxel opens a model: from the front right (MagicaVoxel's front, its −y, is our
/// +z), 35° above the horizon, looking at the box's centre from just far enough that the
/// whole box lies within 92 % of a 60° field of view both ways (so any picture at least as
/// wide as high shows all of it). Also returns where the flicker test moves the eye: 10°
/// further round the box.
pub fn framing_camera(min: WorldPos, max: WorldPos) -> Result<(Camera, DVec3)> {
    let lo = DVec3::new(f64::from(min.x), f64::from(min.y), f64::from(min.z));
    let hi = DVec3::new(f64::from(max.x), f64::from(max.y), f64::from(max.z)) + DVec3::ONE;
    let centre = (lo + hi) * 0.5;
    let (fov, elevation) = (60.0f64, 35.0f64.to_radians());
    let direction = |azimuth: f64| {
        DVec3::new(
            azimuth.sin() * elevation.cos(),
            elevation.sin(),
            azimuth.cos() * elevation.cos(),
        )
    };
    let d = direction(45.0f64.to_radians());
    let right = DVec3::Y.cross(d).normalize();
    let up = d.cross(right);
    // A corner c (from the centre) is in view when |c·up| and |c·right| stay within
    // tan(fov/2) times its depth, distance − c·d.
    let tan = (fov * 0.5).to_radians().tan() * 0.92;
    let mut distance: f64 = 1.0;
    for k in 0..8 {
        let pick = |bit: i32, a: f64, b: f64| if k & bit == 0 { a } else { b };
        let c = DVec3::new(
            pick(1, lo.x, hi.x),
            pick(2, lo.y, hi.y),
            pick(4, lo.z, hi.z),
        ) - centre;
        let spread = c.dot(up).abs().max(c.dot(right).abs());
        distance = distance.max(c.dot(d) + spread / tan);
    }
    let radius = (hi - lo).length() * 0.5;
    let eye = centre + d * distance;
    let camera = Camera::look_at(eye, centre, fov, 0.1, distance + 2.0 * radius + 16.0)?;
    let path_to = centre + direction(55.0f64.to_radians()) * distance;
    Ok((camera, path_to))
}

/// The text of `path`, reading at most `limit` bytes: more is an error naming the file
/// and the limit, as is text that is not UTF-8.
pub fn read_limited(path: &Path, limit: u64) -> Result<String> {
    use std::io::Read as _;
    let file = std::fs::File::open(path).map_err(Error::io(path))?;
    let mut bytes = Vec::new();
    file.take(limit + 1)
        .read_to_end(&mut bytes)
        .map_err(Error::io(path))?;
    if bytes.len() as u64 > limit {
        return Err(Error::FileTooLarge {
            path: path.to_owned(),
            limit,
        });
    }
    String::from_utf8(bytes).map_err(|source| Error::NotUtf8 {
        path: path.to_owned(),
        source,
    })
}

/// Chunks generated around the default scene's structure, in each horizontal direction.
pub const DEFAULT_RADIUS: i32 = 6;

/// The default scene for `seed`: terrain `DEFAULT_RADIUS` chunks around the greenhouse
/// nearest the origin, the camera on the land side looking through it at the sea.
pub fn default_scene(seed: u32) -> Result<Scene> {
    default_scene_with_radius(seed, DEFAULT_RADIUS)
}

/// [`default_scene`] with `radius` chunks of terrain each way (1 to 16).
pub fn default_scene_with_radius(seed: u32, radius: i32) -> Result<Scene> {
    let generator = TerrainGenerator::new(TerrainConfig {
        seed,
        ..TerrainConfig::default()
    });
    let view = generator
        .showcase(radius)?
        .ok_or(Error::NoGlassStructure { seed })?;
    let world = view.world;
    let (eye, dir) = (DVec3::from(view.eye), DVec3::from(view.water_dir));
    let camera = Camera::look_at(eye, DVec3::from(view.target), 70.0, 0.1, 600.0)?
        .in_medium(world.medium_at(view.eye));
    // The flicker path slides sideways, keeping the greenhouse in view.
    let side = DVec3::new(-dir.z, 0.0, dir.x);
    Ok(Scene {
        name: format!("default (seed {seed})"),
        description: "generated terrain: a greenhouse on the shore, the sea seen through its glass"
            .into(),
        world,
        cameras: vec![camera],
        paths: vec![Some(eye + side * 6.0)],
        size: None,
        content: Content::default(),
        light: false,
        sun_shadows: true,
    })
}

/// Fills a box of blocks (corners inclusive).
pub fn fill_box(
    world: &mut World,
    min: [i32; 3],
    max: [i32; 3],
    id: voxel_core::BlockId,
) -> Result<()> {
    world
        .fill_box(
            WorldPos::new(min[0], min[1], min[2]),
            WorldPos::new(max[0], max[1], max[2]),
            id,
        )
        .map_err(Error::Core)
}

/// The scene files of a folder (`.toml` scenes and bare `.vox` models), sorted.
pub fn scene_files(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(Error::io(dir))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml") || is_vox(p))
        .collect();
    v.sort();
    if v.is_empty() {
        return Err(Error::NoScenes {
            dir: Some(dir.to_owned()),
        });
    }
    Ok(v)
}
