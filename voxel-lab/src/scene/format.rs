//! The scene file's structure as serde reads it: the tables, their fields and defaults.

use serde::Deserialize;
use toml::Spanned;

use super::blocks::BlockDefFile;
use super::fields::{exact, exact_opt};

fn yes() -> bool {
    true
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SceneFile {
    pub(super) name: String,
    #[serde(default)]
    pub(super) description: String,
    /// Whether the world is drawn with its light field (`docs/light.md`): sky light through
    /// translucent blocks and the light of `torch`, `lava` and `glow_glass`, which the scene
    /// may then name. Default false: drawn unlit.
    #[serde(default)]
    pub(super) light: bool,
    /// With `light`: whether the sun casts shadows (`Renderer::set_sun_shadows`). Default
    /// true.
    #[serde(default = "yes")]
    pub(super) sun_shadows: bool,
    pub(super) size: Option<Spanned<Vec<u32>>>,
    pub(super) terrain: Option<Spanned<TerrainDef>>,
    #[serde(default)]
    pub(super) blocks: Vec<Spanned<BlockDefFile>>,
    #[serde(default)]
    pub(super) boxes: Vec<Spanned<BoxDef>>,
    #[serde(default)]
    pub(super) models: Vec<Spanned<ModelDef>>,
    #[serde(default)]
    pub(super) particles: Vec<Spanned<ParticlesDef>>,
    #[serde(default)]
    pub(super) entities: Vec<Spanned<EntityDef>>,
    #[serde(default)]
    pub(super) cameras: Vec<Spanned<CameraDef>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ParticlesDef {
    #[serde(deserialize_with = "exact")]
    pub(super) min: [f64; 3],
    #[serde(deserialize_with = "exact")]
    pub(super) max: [f64; 3],
    pub(super) count: usize,
    #[serde(default = "default_particle_seed")]
    pub(super) seed: u64,
    #[serde(default = "default_particle_size")]
    pub(super) size: f32,
    #[serde(deserialize_with = "exact")]
    pub(super) color: [u8; 3],
    pub(super) opacity: f32,
    /// The light they give off, in multiples of their colour (default 0).
    #[serde(default)]
    pub(super) emissive: f32,
}

fn default_particle_seed() -> u64 {
    1
}

fn default_particle_size() -> f32 {
    0.25
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct EntityDef {
    #[serde(deserialize_with = "exact")]
    pub(super) center: [f64; 3],
    #[serde(deserialize_with = "exact")]
    pub(super) size: [f32; 3],
    #[serde(default, deserialize_with = "exact")]
    pub(super) rotation: [f64; 3],
    #[serde(deserialize_with = "exact")]
    pub(super) color: [u8; 3],
    #[serde(default = "default_entity_opacity")]
    pub(super) opacity: f32,
    /// The light it gives off, in multiples of its colour (default 0).
    #[serde(default)]
    pub(super) emissive: f32,
}

fn default_entity_opacity() -> f32 {
    1.0
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ModelDef {
    pub(super) file: Spanned<String>,
    #[serde(default, deserialize_with = "exact")]
    pub(super) at: [i32; 3],
    pub(super) rotate: Option<Spanned<i64>>,
    #[serde(default)]
    pub(super) palette: Vec<Spanned<PaletteDef>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct PaletteDef {
    pub(super) index: Spanned<i64>,
    pub(super) class: Spanned<String>,
    pub(super) opacity: Option<f32>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TerrainDef {
    #[serde(default = "default_seed")]
    pub(super) seed: u32,
    #[serde(deserialize_with = "exact")]
    pub(super) min_chunk: [i32; 3],
    #[serde(deserialize_with = "exact")]
    pub(super) max_chunk: [i32; 3],
}

fn default_seed() -> u32 {
    1
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct BoxDef {
    pub(super) block: Spanned<String>,
    #[serde(deserialize_with = "exact")]
    pub(super) min: [i32; 3],
    #[serde(deserialize_with = "exact")]
    pub(super) max: [i32; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CameraDef {
    #[serde(deserialize_with = "exact")]
    pub(super) eye: [f64; 3],
    #[serde(deserialize_with = "exact")]
    pub(super) target: [f64; 3],
    #[serde(default = "default_fov")]
    pub(super) fov: f64,
    #[serde(default = "default_near")]
    pub(super) near: f64,
    #[serde(default = "default_far")]
    pub(super) far: f64,
    #[serde(default, deserialize_with = "exact_opt")]
    pub(super) path_to: Option<[f64; 3]>,
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
