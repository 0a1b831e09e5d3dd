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

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::DVec3;
use serde::Deserialize;
use toml::Spanned;
use voxel_core::{
    BlockDef, BlockImage, BlockRegistry, ChunkPos, FaceImages, PaletteOverride, Pattern,
    RenderClass, SiteKind, TerrainConfig, TerrainGenerator, VoxFile, VoxPlacement, World, WorldPos,
};
use voxel_render::{Camera, WORLD_EXTENT};

use crate::content::{Content, Entity, rotation};

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
    /// A game's particles and entities ([`crate::content`]), drawn through the renderer's
    /// stages.
    pub content: Content,
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
        }
    }

    /// Reads a scene file (at most [`crate::limits::MAX_SCENE_FILE_BYTES`]: a longer
    /// file, or an endless one like `/dev/zero`, is an error after that many bytes), or a
    /// bare `.vox` model ([`Scene::from_vox`]). Errors name the file, the line and the
    /// field.
    pub fn load(path: &Path) -> Result<Self, String> {
        if is_vox(path) {
            return Self::from_vox(path);
        }
        let text = read_limited(path, crate::limits::MAX_SCENE_FILE_BYTES)?;
        let dir = path.parent().unwrap_or(Path::new(""));
        parse_in(&text, dir).map_err(|e| format!("{}:{}", path.display(), e))
    }

    /// A MagicaVoxel model as a scene: its blocks with the lowest corner at the origin
    /// (palette entries as its materials say), seen by [`framing_camera`]. Named after the
    /// file. Errors name the file and what is wrong with it.
    pub fn from_vox(path: &Path) -> Result<Self, String> {
        let file = VoxFile::load(path).map_err(|e| e.to_string())?;
        let name = model_name(path);
        let mut registry = BlockRegistry::default();
        let blocks = file
            .register_blocks(&name, &[], &mut registry)
            .map_err(|e| format!("{}: {e}", path.display()))?;
        let mut world = World::new(Arc::new(registry));
        let placed = file
            .place(&name, &blocks, VoxPlacement::default(), &mut world)
            .map_err(|e| format!("{}: {e}", path.display()))?
            .ok_or_else(|| format!("{}: the file places no voxels", path.display()))?;
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
pub fn framing_camera(min: WorldPos, max: WorldPos) -> Result<(Camera, DVec3), String> {
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
    let camera = Camera::look_at(eye, centre, fov, 0.1, distance + 2.0 * radius + 16.0)
        .map_err(|e| e.to_string())?;
    let path_to = centre + direction(55.0f64.to_radians()) * distance;
    Ok((camera, path_to))
}

/// The text of `path`, reading at most `limit` bytes: more is an error naming the file
/// and the limit, as is text that is not UTF-8.
pub fn read_limited(path: &Path, limit: u64) -> Result<String, String> {
    use std::io::Read as _;
    let file = std::fs::File::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut bytes = Vec::new();
    file.take(limit + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| format!("{}: {e}", path.display()))?;
    if bytes.len() as u64 > limit {
        return Err(format!(
            "{}: larger than {limit} bytes, the most a scene file may hold",
            path.display()
        ));
    }
    String::from_utf8(bytes).map_err(|e| format!("{}: not UTF-8 text ({e})", path.display()))
}

/// Chunks generated around the default scene's structure, in each horizontal direction.
pub const DEFAULT_RADIUS: i32 = 6;

/// The default scene for `seed`: terrain `DEFAULT_RADIUS` chunks around the greenhouse
/// nearest the origin, the camera on the land side looking through it at the sea.
pub fn default_scene(seed: u32) -> Result<Scene, String> {
    default_scene_with_radius(seed, DEFAULT_RADIUS)
}

/// [`default_scene`] with `radius` chunks of terrain each way (1 to 16).
pub fn default_scene_with_radius(seed: u32, radius: i32) -> Result<Scene, String> {
    let radius = radius.clamp(1, 16);
    let config = TerrainConfig {
        seed,
        ..TerrainConfig::default()
    };
    let sea = f64::from(config.sea_level);
    let generator = TerrainGenerator::new(config);
    let sites = generator.sites_in(-768, -768, 768, 768);
    let site = sites
        .iter()
        .filter(|s| s.kind == SiteKind::Greenhouse)
        .min_by_key(|s| s.center[0].pow(2) + s.center[2].pow(2))
        .or_else(|| sites.first())
        .copied()
        .ok_or_else(|| {
            format!("seed {seed}: no glass structure within 768 blocks of the origin")
        })?;
    let c = site.center;
    let cx = c[0].div_euclid(32) as i32;
    let cz = c[2].div_euclid(32) as i32;
    let world = generator
        .generate_world(
            Arc::new(BlockRegistry::default()),
            ChunkPos::new(cx - radius, 0, cz - radius),
            ChunkPos::new(cx + radius, 1, cz + radius),
        )
        .map_err(|e| e.to_string())?;
    let dir = DVec3::new(
        f64::from(site.water_dir[0]),
        0.0,
        f64::from(site.water_dir[1]),
    )
    .normalize();
    let center = DVec3::new(c[0] as f64 + 0.5, c[1] as f64, c[2] as f64 + 0.5);
    // Back from the structure on the land side, above the ground there.
    let mut eye = center - dir * 18.0 + DVec3::Y * 11.0;
    let ground = generator.height_at(eye.x.floor() as i64, eye.z.floor() as i64) as f64;
    eye.y = eye.y.max(ground + 3.5);
    let target = center + dir * 12.0 + DVec3::Y * (sea - center.y + 1.0);
    let camera = Camera::look_at(eye, target, 70.0, 0.1, 600.0)
        .map_err(|e| e.to_string())?
        .in_medium(world.medium_at(eye.to_array()));
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
    })
}

/// A fixed-length array in a scene file: exactly `N` values (serde's arrays take the first
/// `N` of a longer list and ignore the rest).
fn exact<'de, D, T, const N: usize>(d: D) -> Result<[T; N], D::Error>
where
    D: serde::Deserializer<'de>,
    T: Deserialize<'de>,
{
    let v = Vec::<T>::deserialize(d)?;
    let n = v.len();
    v.try_into().map_err(|_| {
        serde::de::Error::invalid_length(n, &format!("an array of length {N}").as_str())
    })
}

/// [`exact`] for an optional array.
fn exact_opt<'de, D, T, const N: usize>(d: D) -> Result<Option<[T; N]>, D::Error>
where
    D: serde::Deserializer<'de>,
    T: Deserialize<'de>,
{
    exact(d).map(Some)
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    name: String,
    #[serde(default)]
    description: String,
    size: Option<Spanned<Vec<u32>>>,
    terrain: Option<Spanned<TerrainDef>>,
    #[serde(default)]
    blocks: Vec<Spanned<BlockDefFile>>,
    #[serde(default)]
    boxes: Vec<Spanned<BoxDef>>,
    #[serde(default)]
    models: Vec<Spanned<ModelDef>>,
    #[serde(default)]
    particles: Vec<Spanned<ParticlesDef>>,
    #[serde(default)]
    entities: Vec<Spanned<EntityDef>>,
    #[serde(default)]
    cameras: Vec<Spanned<CameraDef>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ParticlesDef {
    #[serde(deserialize_with = "exact")]
    min: [f64; 3],
    #[serde(deserialize_with = "exact")]
    max: [f64; 3],
    count: usize,
    #[serde(default = "default_particle_seed")]
    seed: u64,
    #[serde(default = "default_particle_size")]
    size: f32,
    #[serde(deserialize_with = "exact")]
    color: [u8; 3],
    opacity: f32,
}

fn default_particle_seed() -> u64 {
    1
}

fn default_particle_size() -> f32 {
    0.25
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct EntityDef {
    #[serde(deserialize_with = "exact")]
    center: [f64; 3],
    #[serde(deserialize_with = "exact")]
    size: [f32; 3],
    #[serde(default, deserialize_with = "exact")]
    rotation: [f64; 3],
    #[serde(deserialize_with = "exact")]
    color: [u8; 3],
    #[serde(default = "default_entity_opacity")]
    opacity: f32,
}

fn default_entity_opacity() -> f32 {
    1.0
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ModelDef {
    file: Spanned<String>,
    #[serde(default, deserialize_with = "exact")]
    at: [i32; 3],
    rotate: Option<Spanned<i64>>,
    #[serde(default)]
    palette: Vec<Spanned<PaletteDef>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PaletteDef {
    index: Spanned<i64>,
    class: Spanned<String>,
    opacity: Option<f32>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TerrainDef {
    #[serde(default = "default_seed")]
    seed: u32,
    #[serde(deserialize_with = "exact")]
    min_chunk: [i32; 3],
    #[serde(deserialize_with = "exact")]
    max_chunk: [i32; 3],
}

fn default_seed() -> u32 {
    1
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BlockDefFile {
    name: String,
    #[serde(deserialize_with = "exact")]
    color: [u8; 3],
    opacity: f32,
    /// `opaque`, `cutout` or `translucent`; by default from the opacity.
    class: Option<Spanned<String>>,
    /// `noise`, `leaves`, `framed` or `grass`; by default the class's.
    pattern: Option<Spanned<String>>,
    /// The soil colour of the `grass` pattern.
    #[serde(default, deserialize_with = "exact_opt")]
    soil: Option<[u8; 3]>,
    /// A translucent block's absorption per block: a volume (0, the default: a thin
    /// surface).
    absorption: Option<Spanned<f32>>,
    /// A cutout block standing in this medium (a translucent block named before it).
    medium: Option<Spanned<String>>,
    /// A PNG file for every face, relative to the scene file.
    texture: Option<Spanned<String>>,
    /// PNG files for the top, bottom and side faces (over `texture`).
    top: Option<Spanned<String>>,
    bottom: Option<Spanned<String>>,
    side: Option<Spanned<String>>,
}

/// A render class by its scene-file name.
fn class_named(name: &str) -> Option<RenderClass> {
    match name {
        "opaque" => Some(RenderClass::Opaque),
        "cutout" => Some(RenderClass::Cutout),
        "translucent" => Some(RenderClass::Translucent),
        _ => None,
    }
}

/// The block a `[[blocks]]` entry declares: class, pattern and images checked, images read
/// relative to `dir`. Errors read `LINE: blocks.key: message`.
fn block_def(
    text: &str,
    dir: &Path,
    b: &Spanned<BlockDefFile>,
    registry: &BlockRegistry,
) -> Result<BlockDef, String> {
    let d = b.get_ref();
    let mut def = BlockDef::new(d.name.clone(), d.color, d.opacity);
    if let Some(a) = &d.absorption {
        def = def.with_absorption(*a.get_ref());
    }
    if let Some(m) = &d.medium {
        let id = registry.id(m.get_ref()).map_err(|_| {
            at_line(
                text,
                m.span().start,
                format!(
                    "blocks.medium: no block {:?} before this one (a medium is a translucent block)",
                    m.get_ref()
                ),
            )
        })?;
        def = def.in_medium(id);
    }
    if let Some(class) = &d.class {
        def.class = class_named(class.get_ref()).ok_or_else(|| {
            at_line(
                text,
                class.span().start,
                format!(
                    "blocks.class: {:?} is not a class: opaque, cutout or translucent",
                    class.get_ref()
                ),
            )
        })?;
        if def.class == RenderClass::Cutout {
            def.pattern = Pattern::Leaves;
        }
    }
    if let Some(pattern) = &d.pattern {
        let at = pattern.span().start;
        def.pattern = match pattern.get_ref().as_str() {
            "noise" => Pattern::Noise,
            "leaves" => Pattern::Leaves,
            "framed" => Pattern::Framed,
            "grass" => Pattern::Grass {
                soil: d.soil.ok_or_else(|| {
                    at_line(
                        text,
                        at,
                        "blocks.pattern: \"grass\" needs a soil = [r, g, b] colour",
                    )
                })?,
            },
            other => {
                return Err(at_line(
                    text,
                    at,
                    format!(
                        "blocks.pattern: {other:?} is not a pattern: noise, leaves, framed or grass"
                    ),
                ));
            }
        };
    }
    let image = |key: &str, file: &Option<Spanned<String>>| -> Result<Option<BlockImage>, String> {
        let Some(file) = file else { return Ok(None) };
        voxel_render::textures::load_block_image(&dir.join(file.get_ref()))
            .map(Some)
            .map_err(|e| at_line(text, file.span().start, format!("blocks.{key}: {e}")))
    };
    let all = image("texture", &d.texture)?;
    def.images = FaceImages {
        top: image("top", &d.top)?.or_else(|| all.clone()),
        bottom: image("bottom", &d.bottom)?.or_else(|| all.clone()),
        side: image("side", &d.side)?.or(all),
    };
    Ok(def)
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BoxDef {
    block: Spanned<String>,
    #[serde(deserialize_with = "exact")]
    min: [i32; 3],
    #[serde(deserialize_with = "exact")]
    max: [i32; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraDef {
    #[serde(deserialize_with = "exact")]
    eye: [f64; 3],
    #[serde(deserialize_with = "exact")]
    target: [f64; 3],
    #[serde(default = "default_fov")]
    fov: f64,
    #[serde(default = "default_near")]
    near: f64,
    #[serde(default = "default_far")]
    far: f64,
    #[serde(default, deserialize_with = "exact_opt")]
    path_to: Option<[f64; 3]>,
}

fn default_fov() -> f64 {
    60.0
}
fn default_near() -> f64 {
    0.1
}
fn default_far() -> f64 {
    1000.0
}

/// Most chunks a scene's terrain may generate (64 × 8 × 64 = 32768 chunks would not fit in
/// memory: this keeps a typo from taking the machine down).
const MAX_TERRAIN_CHUNKS: i128 = 4096;
/// Most blocks all boxes together may fill.
const MAX_BOX_BLOCKS: i128 = 20_000_000;
/// Most chunks all boxes together may touch (a box counts every chunk its corners span):
/// a thin row of blocks touches a chunk per 32 blocks, and a chunk holding part of a box
/// costs up to about 40 KiB, so 20 M blocks in a row (625 000 chunks) would take tens of
/// GiB. 16 384 chunks hold a 4096 × 4096 floor.
const MAX_BOX_CHUNKS: i128 = 16_384;

/// `line N: message` for the byte offset `at` of `text`.
fn at_line(text: &str, at: usize, message: impl std::fmt::Display) -> String {
    let line = text[..at.min(text.len())].matches('\n').count() + 1;
    format!("{line}: {message}")
}

/// The `table.key` written on the line holding byte `at` (the key before `=`, the table
/// from the nearest header above), for error messages.
fn field_at(text: &str, at: usize) -> String {
    let at = at.min(text.len());
    let start = text[..at].rfind('\n').map_or(0, |i| i + 1);
    let line = text[start..].lines().next().unwrap_or("");
    let header = |l: &str| l.trim().starts_with('[');
    // On a table's own header (a table missing a field): that table, no key.
    let key = if header(line) {
        ""
    } else {
        line.split_once('=').map(|(k, _)| k.trim()).unwrap_or("")
    };
    let table = text[..start + line.len()]
        .lines()
        .rev()
        .map(str::trim)
        .find(|l| header(l))
        .map(|l| l.trim_matches(|c| c == '[' || c == ']'))
        .unwrap_or("");
    match (table, key) {
        ("", k) | (k, "") => k.to_owned(),
        (t, k) => format!("{t}.{k}"),
    }
}

/// Parses the text of a scene file; errors read `LINE: field: message`. Model files are
/// found relative to the working folder; [`parse_in`] names another.
pub fn parse(text: &str) -> Result<Scene, String> {
    parse_in(text, Path::new(""))
}

/// What a `[[models.palette]]` entry asks for, checked.
fn palette_override(text: &str, p: &Spanned<PaletteDef>) -> Result<PaletteOverride, String> {
    let d = p.get_ref();
    let index = u8::try_from(*d.index.get_ref())
        .ok()
        .filter(|i| *i >= 1)
        .ok_or_else(|| {
            at_line(
                text,
                d.index.span().start,
                format!(
                    "models.palette.index: {} is not a colour index (1 to 255)",
                    d.index.get_ref()
                ),
            )
        })?;
    let class = class_named(d.class.get_ref()).ok_or_else(|| {
        at_line(
            text,
            d.class.span().start,
            format!(
                "models.palette.class: {:?} is not a class: opaque, cutout or translucent",
                d.class.get_ref()
            ),
        )
    })?;
    let opacity = match (class, d.opacity) {
        (RenderClass::Translucent, Some(a)) if a.is_finite() && a > 0.0 && a < 1.0 => a,
        (RenderClass::Translucent, _) => {
            return Err(at_line(
                text,
                p.span().start,
                "models.palette.opacity: a translucent entry needs an opacity above 0 and below 1",
            ));
        }
        (_, None) => 1.0,
        (_, Some(1.0)) => 1.0,
        (_, Some(_)) => {
            return Err(at_line(
                text,
                p.span().start,
                "models.palette.opacity: only a translucent entry has an opacity below 1",
            ));
        }
    };
    Ok(PaletteOverride {
        index,
        class,
        opacity,
    })
}

/// [`parse`], with model files found relative to `dir` (the scene file's folder).
pub fn parse_in(text: &str, dir: &Path) -> Result<Scene, String> {
    let file: SceneFile = toml::from_str(text).map_err(|e| match e.span() {
        Some(s) => {
            let field = field_at(text, s.start);
            let message = e.message().trim();
            if field.is_empty() {
                at_line(text, s.start, message)
            } else {
                at_line(text, s.start, format!("{field}: {message}"))
            }
        }
        None => format!("?: {}", e.message().trim()),
    })?;

    let mut registry = BlockRegistry::default();
    for b in &file.blocks {
        let def = block_def(text, dir, b, &registry)?;
        registry
            .register(def)
            .map_err(|e| at_line(text, b.span().start, format!("blocks: {e}")))?;
    }
    // Models are read (and their block types registered) before the world exists: the
    // world's registry is fixed once it is made.
    let mut models = Vec::new();
    let mut voxels: i128 = 0;
    for m in &file.models {
        let (span, def) = (m.span(), m.get_ref());
        let path = dir.join(def.file.get_ref());
        let line = def.file.span().start;
        let vox =
            VoxFile::load(&path).map_err(|e| at_line(text, line, format!("models.file: {e}")))?;
        voxels += i128::from(vox.voxel_count());
        if voxels > MAX_BOX_BLOCKS {
            return Err(at_line(
                text,
                span.start,
                format!("models: more than {MAX_BOX_BLOCKS} voxels in all"),
            ));
        }
        let turns = match &def.rotate {
            None => 0,
            Some(r) if r.get_ref().rem_euclid(90) == 0 => (r.get_ref().rem_euclid(360) / 90) as u8,
            Some(r) => {
                return Err(at_line(
                    text,
                    r.span().start,
                    format!(
                        "models.rotate: {} is not a multiple of 90 degrees",
                        r.get_ref()
                    ),
                ));
            }
        };
        let overrides = def
            .palette
            .iter()
            .map(|p| palette_override(text, p))
            .collect::<Result<Vec<_>, _>>()?;
        let name = model_name(&path);
        let blocks = vox
            .register_blocks(&name, &overrides, &mut registry)
            .map_err(|e| at_line(text, span.start, format!("models: {}: {e}", path.display())))?;
        let placement = VoxPlacement {
            at: def.at,
            quarter_turns: turns,
        };
        models.push((span.start, path, vox, blocks, placement));
    }
    let registry = Arc::new(registry);
    let mut world = match &file.terrain {
        Some(t) => {
            let (span, t) = (t.span(), t.get_ref());
            // i128: three extents of up to 2^32 each cannot overflow it.
            let count: i128 = (0..3)
                .map(|i| i128::from(t.max_chunk[i]) - i128::from(t.min_chunk[i]) + 1)
                .product();
            if (0..3).any(|i| t.min_chunk[i] > t.max_chunk[i]) || count > MAX_TERRAIN_CHUNKS {
                return Err(at_line(
                    text,
                    span.start,
                    format!(
                        "terrain: min_chunk..max_chunk must be a non-empty box of at most {MAX_TERRAIN_CHUNKS} chunks"
                    ),
                ));
            }
            let generator = TerrainGenerator::new(TerrainConfig {
                seed: t.seed,
                ..TerrainConfig::default()
            });
            let min = ChunkPos::new(t.min_chunk[0], t.min_chunk[1], t.min_chunk[2]);
            let max = ChunkPos::new(t.max_chunk[0], t.max_chunk[1], t.max_chunk[2]);
            generator
                .generate_world(registry.clone(), min, max)
                .map_err(|e| at_line(text, span.start, format!("terrain: {e}")))?
        }
        None => World::new(registry.clone()),
    };
    let mut filled: i128 = 0;
    // Boxes and models in the order the file lists them.
    enum Item<'a> {
        Box(&'a Spanned<BoxDef>),
        Model(usize),
    }
    let mut items: Vec<(usize, Item<'_>)> = file
        .boxes
        .iter()
        .map(|b| (b.span().start, Item::Box(b)))
        .chain(
            models
                .iter()
                .enumerate()
                .map(|(i, m)| (m.0, Item::Model(i))),
        )
        .collect();
    items.sort_by_key(|(at, _)| *at);
    let mut model_bounds: Option<(WorldPos, WorldPos)> = None;
    // Chunks the boxes and models touch, bounded like the blocks they fill.
    let mut touched: i128 = 0;
    let chunks_between = |lo: [i32; 3], hi: [i32; 3]| {
        let chunk = |v: i32| i128::from(v.div_euclid(voxel_core::CHUNK_SIZE as i32));
        (0..3)
            .map(|i| chunk(hi[i]) - chunk(lo[i]) + 1)
            .product::<i128>()
    };
    for (_, item) in items {
        let b = match item {
            Item::Box(b) => b,
            Item::Model(i) => {
                let (at, path, vox, blocks, placement) = &models[i];
                let placed = vox
                    .place(&path.display().to_string(), blocks, *placement, &mut world)
                    .map_err(|e| at_line(text, *at, format!("models: {e}")))?;
                if let Some((lo, hi)) = placed {
                    touched += chunks_between([lo.x, lo.y, lo.z], [hi.x, hi.y, hi.z]);
                    if touched > MAX_BOX_CHUNKS {
                        return Err(at_line(
                            text,
                            *at,
                            format!(
                                "models: boxes and models touch more than {MAX_BOX_CHUNKS} chunks in all"
                            ),
                        ));
                    }
                    let (mut a, mut b) = model_bounds.unwrap_or((lo, hi));
                    (a.x, a.y, a.z) = (a.x.min(lo.x), a.y.min(lo.y), a.z.min(lo.z));
                    (b.x, b.y, b.z) = (b.x.max(hi.x), b.y.max(hi.y), b.z.max(hi.z));
                    model_bounds = Some((a, b));
                }
                continue;
            }
        };
        let (span, def) = (b.span(), b.get_ref());
        let id = registry
            .id(def.block.get_ref())
            .map_err(|e| at_line(text, def.block.span().start, format!("boxes.block: {e}")))?;
        if (0..3).any(|i| def.min[i] > def.max[i]) {
            return Err(at_line(
                text,
                span.start,
                "boxes: min must not exceed max on any axis",
            ));
        }
        filled += (0..3)
            .map(|i| i128::from(def.max[i]) - i128::from(def.min[i]) + 1)
            .product::<i128>();
        if filled > MAX_BOX_BLOCKS {
            return Err(at_line(
                text,
                span.start,
                format!("boxes: more than {MAX_BOX_BLOCKS} blocks in all"),
            ));
        }
        touched += chunks_between(def.min, def.max);
        if touched > MAX_BOX_CHUNKS {
            return Err(at_line(
                text,
                span.start,
                format!("boxes: they touch more than {MAX_BOX_CHUNKS} chunks in all"),
            ));
        }
        fill_box(&mut world, def.min, def.max, id)
            .map_err(|e| at_line(text, span.start, format!("boxes: {e}")))?;
    }
    let mut cameras = Vec::new();
    let mut paths = Vec::new();
    if file.cameras.is_empty() {
        let (lo, hi) = model_bounds
            .ok_or("1: cameras: a scene needs at least one [[cameras]] entry (or a model)")?;
        let (camera, path_to) = framing_camera(lo, hi)?;
        cameras.push(camera.in_medium(world.medium_at(camera.eye.to_array())));
        paths.push(Some(path_to));
    }
    for c in &file.cameras {
        let (span, d) = (c.span(), c.get_ref());
        let camera = Camera::look_at(
            DVec3::from(d.eye),
            DVec3::from(d.target),
            d.fov,
            d.near,
            d.far,
        )
        .map_err(|e| at_line(text, span.start, format!("cameras: {e}")))?;
        // The flicker test moves the eye to `path_to`: the camera there must be valid too,
        // so that every command accepts or refuses the same files.
        if let Some(to) = d.path_to {
            Camera::look_at(DVec3::from(to), DVec3::from(d.target), d.fov, d.near, d.far)
                .map_err(|e| at_line(text, span.start, format!("cameras.path_to: {e}")))?;
        }
        cameras.push(camera.in_medium(world.medium_at(d.eye)));
        paths.push(d.path_to.map(DVec3::from));
    }
    let size = match &file.size {
        Some(s) => {
            let &[w, h] = s.get_ref().as_slice() else {
                return Err(at_line(
                    text,
                    s.span().start,
                    format!(
                        "size: {} values, expected 2 (width and height)",
                        s.get_ref().len()
                    ),
                ));
            };
            let size = (w, h);
            crate::limits::check_size("size", size)
                .map_err(|e| at_line(text, s.span().start, e))?;
            Some(size)
        }
        None => None,
    };
    let content = content_of(text, &file)?;
    Ok(Scene {
        name: file.name,
        description: file.description,
        world,
        cameras,
        paths,
        size,
        content,
    })
}

/// Most particles a scene file may ask for, in all: a frame draws each one (36 vertices),
/// and the ray march bins them per picture.
pub const MAX_PARTICLES: usize = 1_000_000;

/// The particles and entities of a scene file, checked.
fn content_of(text: &str, file: &SceneFile) -> Result<Content, String> {
    let mut content = Content::default();
    let finite = |v: &[f64]| v.iter().all(|x| x.is_finite() && x.abs() < WORLD_EXTENT);
    for p in &file.particles {
        let (span, d) = (p.span(), p.get_ref());
        let bad = |why: &str| Err(at_line(text, span.start, format!("particles: {why}")));
        if !finite(&d.min) || !finite(&d.max) || (0..3).any(|i| d.min[i] > d.max[i]) {
            return bad("min and max must be finite, inside the world, min not above max");
        }
        if content.particles.len() + d.count > MAX_PARTICLES {
            return bad(&format!("more than {MAX_PARTICLES} particles in all"));
        }
        if !(d.size.is_finite() && d.size > 0.0 && d.size <= 64.0) {
            return bad("size (half a side, blocks) must be above 0 and at most 64");
        }
        if !(d.opacity.is_finite() && d.opacity > 0.0 && d.opacity <= 1.0) {
            return bad("opacity must be above 0 and at most 1");
        }
        content.particles.extend(Content::scatter(
            DVec3::from(d.min),
            DVec3::from(d.max),
            d.count,
            d.seed,
            d.size,
            d.color,
            d.opacity,
        ));
    }
    for e in &file.entities {
        let (span, d) = (e.span(), e.get_ref());
        let bad = |why: &str| Err(at_line(text, span.start, format!("entities: {why}")));
        if !finite(&d.center) || !d.rotation.iter().all(|r| r.is_finite()) {
            return bad("center and rotation must be finite, the centre inside the world");
        }
        if !d
            .size
            .iter()
            .all(|s| s.is_finite() && *s > 0.0 && *s <= 256.0)
        {
            return bad("size must be above 0 and at most 256 blocks on each axis");
        }
        if !(d.opacity.is_finite() && d.opacity > 0.0 && d.opacity <= 1.0) {
            return bad("opacity must be above 0 and at most 1 (1: opaque)");
        }
        content.entities.push(Entity {
            center: DVec3::from(d.center),
            half_extents: d.size.map(|s| s / 2.0),
            rotation: rotation(d.rotation),
            color: d.color,
            opacity: d.opacity,
        });
    }
    Ok(content)
}

/// Fills a box of blocks (corners inclusive).
pub fn fill_box(
    world: &mut World,
    min: [i32; 3],
    max: [i32; 3],
    id: voxel_core::BlockId,
) -> Result<(), String> {
    world
        .fill_box(
            WorldPos::new(min[0], min[1], min[2]),
            WorldPos::new(max[0], max[1], max[2]),
            id,
        )
        .map_err(|e| e.to_string())
}

/// The scene files of a folder (`.toml` scenes and bare `.vox` models), sorted.
pub fn scene_files(dir: &Path) -> Result<Vec<PathBuf>, String> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| format!("{}: {e}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml") || is_vox(p))
        .collect();
    v.sort();
    if v.is_empty() {
        return Err(format!("{}: no .toml or .vox scene files", dir.display()));
    }
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"
name = "test"
size = [64, 32]

[[blocks]]
name = "smoky_glass"
color = [90, 90, 100]
opacity = 0.5

[[boxes]]
block = "smoky_glass"
min = [0, 0, 0]
max = [3, 2, 0]

[[cameras]]
eye = [0.5, 1.0, 10.0]
target = [0.5, 1.0, 0.0]
path_to = [3.0, 1.0, 10.0]
"#;

    #[test]
    fn a_good_file_parses() {
        let s = parse(GOOD).unwrap();
        assert_eq!(s.name, "test");
        assert_eq!(s.size, Some((64, 32)));
        assert_eq!(s.cameras.len(), 1);
        assert_eq!(s.paths[0], Some(DVec3::new(3.0, 1.0, 10.0)));
        let smoky = s.world.registry().id("smoky_glass").unwrap();
        assert_eq!(s.world.get_block(WorldPos::new(3, 2, 0)), smoky);
        assert_eq!(
            s.world.get_block(WorldPos::new(4, 2, 0)),
            voxel_core::BlockId::AIR
        );
    }

    #[test]
    fn blocks_take_textures_patterns_and_classes_from_the_file() {
        let dir = std::env::temp_dir().join(format!("voxel_scene_tex_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let png = |name: &str, w: u32, h: u32, rgba: [u8; 4]| {
            voxel_render::Image {
                width: w,
                height: h,
                rgba: rgba.repeat((w * h) as usize),
            }
            .save_png(&dir.join(name))
            .unwrap();
        };
        png("all.png", 8, 8, [200, 10, 10, 255]);
        png("top.png", 4, 4, [10, 200, 10, 255]);
        png("wide.png", 8, 4, [0, 0, 0, 255]);
        let text = |extra: &str| {
            format!(
                "name = \"t\"\n[[blocks]]\nname = \"b\"\ncolor = [1, 2, 3]\nopacity = 1.0\n{extra}\n\
                 [[cameras]]\neye = [0.0, 0.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\n"
            )
        };
        let block = |extra: &str| {
            let scene = parse_in(&text(extra), &dir).unwrap();
            let r = scene.world.registry().clone();
            r.get(r.id("b").unwrap()).unwrap().clone()
        };
        let b = block("texture = \"all.png\"\ntop = \"top.png\"\nclass = \"cutout\"");
        assert_eq!(b.class, RenderClass::Cutout);
        assert_eq!(b.pattern, Pattern::Leaves);
        let top = b.images.top.unwrap();
        assert_eq!((top.size(), top.texel(0, 0)), (4, [10, 200, 10, 255]));
        assert_eq!(b.images.side.unwrap().texel(3, 3), [200, 10, 10, 255]);
        assert_eq!(b.images.bottom.unwrap().size(), 8);
        let g = block("pattern = \"grass\"\nsoil = [9, 8, 7]");
        assert_eq!(g.pattern, Pattern::Grass { soil: [9, 8, 7] });
        assert!(g.images.is_empty());
        let err = |extra: &str| parse_in(&text(extra), &dir).unwrap_err();
        let e = err("side = \"wide.png\"");
        assert!(
            e.starts_with("6: blocks.side: ") && e.contains("wide.png") && e.contains("square"),
            "{e}"
        );
        let e = err("top = \"missing.png\"");
        assert!(
            e.starts_with("6: blocks.top: ") && e.contains("missing.png"),
            "{e}"
        );
        let e = err("pattern = \"marble\"");
        assert!(e.contains("blocks.pattern") && e.contains("marble"), "{e}");
        let e = err("pattern = \"grass\"");
        assert!(e.contains("soil"), "{e}");
        let e = err("class = \"gas\"");
        assert!(e.contains("blocks.class") && e.contains("gas"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn the_framing_camera_shows_the_whole_box_tightly() {
        for (min, max) in [
            ([0, 0, 0], [0, 0, 0]),
            ([0, 0, 0], [63, 23, 55]),
            ([-40, 5, 7], [300, 9, 12]),
            ([0, 0, 0], [3, 200, 3]),
        ] {
            let (lo, hi) = (
                WorldPos::new(min[0], min[1], min[2]),
                WorldPos::new(max[0], max[1], max[2]),
            );
            let (cam, path_to) = framing_camera(lo, hi).unwrap();
            // The renderer's own projection, square: every corner inside, one near an edge.
            let vp = cam.view_proj(1.0);
            let mut widest = 0.0f32;
            for k in 0..8 {
                let pick =
                    |bit: i32, a: i32, b: i32| f64::from(if k & bit == 0 { a } else { b + 1 });
                let c = DVec3::new(
                    pick(1, min[0], max[0]),
                    pick(2, min[1], max[1]),
                    pick(4, min[2], max[2]),
                ) - cam.eye;
                let p = vp * c.as_vec3().extend(1.0);
                let ndc = p.truncate() / p.w;
                assert!(p.w > 0.0 && ndc.z > 0.0 && ndc.z < 1.0, "{min:?}: {ndc}");
                assert!(ndc.x.abs() <= 0.93 && ndc.y.abs() <= 0.93, "{min:?}: {ndc}");
                widest = widest.max(ndc.x.abs()).max(ndc.y.abs());
            }
            assert!(widest > 0.85, "{min:?}..{max:?}: framed loosely ({widest})");
            // From above, and the flicker path stays as far from the box.
            assert!(cam.forward.y < -0.5);
            let centre = DVec3::new(
                f64::from(min[0] + max[0] + 1),
                f64::from(min[1] + max[1] + 1),
                f64::from(min[2] + max[2] + 1),
            ) * 0.5;
            let (a, b) = ((cam.eye - centre).length(), (path_to - centre).length());
            assert!((a - b).abs() < 1e-6 * a);
        }
    }

    #[test]
    fn an_unknown_block_names_the_line_and_lists_the_known_ones() {
        let bad = GOOD.replace("block = \"smoky_glass\"", "block = \"lava\"");
        let e = parse(&bad).unwrap_err();
        assert!(
            e.starts_with("11: boxes.block: unknown block name \"lava\""),
            "{e}"
        );

        assert!(e.contains("water") && e.contains("smoky_glass"), "{e}");
    }

    #[test]
    fn syntax_and_type_errors_name_line_and_field() {
        let e = parse(&GOOD.replace("max = [3, 2, 0]", "max = [3, 2]")).unwrap_err();
        assert!(
            e.starts_with("13: boxes.max:") && e.contains("length 3"),
            "{e}"
        );

        let e = parse(&GOOD.replace("fov", "x").replace("path_to", "pathto")).unwrap_err();
        assert!(e.contains("pathto"), "unknown keys are named: {e}");
        let e = parse("name = \"x\"\n[[cameras]]\neye = [0, 0, 0]\n").unwrap_err();
        assert!(e.contains("target"), "missing keys are named: {e}");
        let e = parse("name = \"x\"\nsize = [64, 32\n").unwrap_err();
        assert!(e.starts_with("2:") || e.starts_with("3:"), "{e}");
    }

    /// Fixed-length arrays take exactly their length (a longer list is an error naming
    /// the field, not its first values), and a table missing a field names that table.
    #[test]
    fn arrays_of_the_wrong_length_and_missing_fields_name_their_table() {
        for (from, to, field) in [
            (
                "eye = [0.5, 1.0, 10.0]",
                "eye = [0.5, 1.0, 10.0, 4.0]",
                "cameras.eye",
            ),
            ("size = [64, 32]", "size = [64, 32, 3]", "size"),
            ("max = [3, 2, 0]", "max = [3, 2, 0, 0]", "boxes.max"),
            (
                "color = [90, 90, 100]",
                "color = [90, 90, 100, 1]",
                "blocks.color",
            ),
        ] {
            assert!(GOOD.contains(from), "{from}");
            let e = parse(&GOOD.replace(from, to)).unwrap_err();
            assert!(
                e.contains(field) && (e.contains('3') || e.contains('2')),
                "{to}: {e}"
            );
        }
        let particles = |extra: &str| {
            format!(
                "{GOOD}\n[[particles]]\nmin = [0.0, 0.0, 0.0]\nmax = [1.0, 1.0, 1.0]\n\
                 color = [1, 2, 3]\nopacity = 0.5\n{extra}"
            )
        };
        parse(&particles("count = 3")).unwrap();
        let e = parse(&particles("")).unwrap_err();
        assert!(e.contains("particles") && e.contains("count"), "{e}");
        assert!(!e.contains("boxes") && !e.contains("cameras"), "{e}");
        let e = parse(&particles("count = 3").replace("color = [1, 2, 3]", "color = [1, 2, 3, 4]"))
            .unwrap_err();
        assert!(
            e.contains("particles.color") && e.contains("length 3"),
            "{e}"
        );
        let e = parse(&format!(
            "{GOOD}\n[[entities]]\ncenter = [0.0, 0.0, 0.0]\nsize = [1.0, 1.0]\ncolor = [1, 2, 3]\n"
        ))
        .unwrap_err();
        assert!(e.contains("entities.size") && e.contains("length 3"), "{e}");
    }

    #[test]
    fn bad_values_are_errors_not_panics() {
        let e = parse(&GOOD.replace("target = [0.5, 1.0, 0.0]", "target = [0.5, 1.0, 10.0]"))
            .unwrap_err();
        assert!(e.contains("cameras") && e.contains("zero"), "{e}");
        let e = parse(&GOOD.replace("opacity = 0.5", "opacity = 1.5")).unwrap_err();
        assert!(e.starts_with("5: blocks:"), "{e}");
        let e = parse(&GOOD.replace("max = [3, 2, 0]", "max = [-3, 2, 0]")).unwrap_err();
        assert!(e.contains("min must not exceed max"), "{e}");
        let e = parse(&GOOD.replace("size = [64, 32]", "size = [0, 32]")).unwrap_err();
        assert!(e.starts_with("3: size"), "{e}");
        let e = parse(&format!(
            "{GOOD}\n[terrain]\nmin_chunk = [0, 0, 0]\nmax_chunk = [100, 8, 100]\n"
        ))
        .unwrap_err();
        assert!(e.contains("at most 4096 chunks"), "{e}");
        let e = parse(&GOOD.replace("max = [3, 2, 0]", "max = [3000, 3000, 3000]")).unwrap_err();
        assert!(e.contains("blocks in all"), "{e}");
        // Volumes whose i64 product wraps: the whole i32 range on two or three axes.
        for (min, max) in [
            (
                "[-2147483648, 0, -2147483648]",
                "[2147483647, 0, 2147483647]",
            ),
            (
                "[-2147483648, -2147483648, -2147483648]",
                "[2147483647, 2147483647, 2147483647]",
            ),
        ] {
            let text = GOOD
                .replace("min = [0, 0, 0]", &format!("min = {min}"))
                .replace("max = [3, 2, 0]", &format!("max = {max}"));
            let e = parse(&text).unwrap_err();
            assert!(e.contains("20000000 blocks in all"), "{e}");
        }
        let e = parse(&format!(
            "{GOOD}\n[terrain]\nmin_chunk = [-2147483648, -2147483648, -2147483648]\nmax_chunk = [2147483647, 2147483647, 2147483647]\n"
        ))
        .unwrap_err();
        assert!(e.contains("at most 4096 chunks"), "{e}");
    }

    /// Issue 26: 20 M blocks in one row pass the block count but touch 625 000 chunks:
    /// an error before any chunk is made. A 4096 × 4096 floor (16 384 chunks) is fine.
    #[test]
    fn the_box_check_bounds_chunks_too() {
        let row = GOOD.replace("max = [3, 2, 0]", "max = [19999999, 0, 0]");
        let e = parse(&row).unwrap_err();
        assert!(e.contains("16384 chunks"), "{e}");
        let floor = GOOD.replace("max = [3, 2, 0]", "max = [4095, 0, 4095]");
        let s = parse(&floor).unwrap();
        assert_eq!(s.world.len(), 16_384);
        let beyond = GOOD.replace("max = [3, 2, 0]", "max = [4096, 0, 4095]");
        assert!(parse(&beyond).unwrap_err().contains("chunks"));
    }

    /// Issue 26: a `path_to` where no camera can be (NaN, infinite, on the target, outside
    /// the world) is an error at parsing, for every command alike.
    #[test]
    fn a_bad_path_to_is_an_error() {
        for bad in [
            "[nan, 1.0, 10.0]",
            "[inf, 1.0, 10.0]",
            "[0.5, 1.0, 0.0]",
            "[3e10, 1.0, 0.0]",
        ] {
            let e = parse(&GOOD.replace("path_to = [3.0, 1.0, 10.0]", &format!("path_to = {bad}")))
                .unwrap_err();
            assert!(e.contains("cameras.path_to"), "{bad}: {e}");
        }
    }

    /// Issue 26: sizes past the lab's caps are errors naming the field and the cap.
    #[test]
    fn sizes_past_the_caps_are_errors() {
        for (size, word) in [("[16384, 16384]", "8192"), ("[8192, 8192]", "pixels")] {
            let e = parse(&GOOD.replace("size = [64, 32]", &format!("size = {size}"))).unwrap_err();
            assert!(e.starts_with("3: size") && e.contains(word), "{e}");
        }
    }

    /// Issue 26: an endless or huge file is read only up to the limit; the error names the
    /// file and the limit.
    #[test]
    fn scene_files_are_read_with_a_size_limit() {
        let limit = crate::limits::MAX_SCENE_FILE_BYTES;
        for endless in ["/dev/zero", "/dev/urandom"] {
            if Path::new(endless).exists() {
                let e = Scene::load(Path::new(endless)).unwrap_err();
                assert!(e.contains(endless) && e.contains(&limit.to_string()), "{e}");
            }
        }
        let dir = std::env::temp_dir().join(format!("voxel_scene_limit_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let big = dir.join("big.toml");
        let mut text = GOOD.to_owned();
        text.push_str(&"# padding\n".repeat(limit as usize / 10 + 1));
        std::fs::write(&big, &text).unwrap();
        assert!(Scene::load(&big).unwrap_err().contains("larger than"));
        let ok = dir.join("ok.toml");
        std::fs::write(&ok, GOOD).unwrap();
        Scene::load(&ok).unwrap();
        let bad = dir.join("bad.toml");
        std::fs::write(&bad, [0xffu8, 0xfe, 0x00]).unwrap();
        assert!(Scene::load(&bad).unwrap_err().contains("UTF-8"));
        let _ = std::fs::remove_dir_all(dir);
    }
}
