//! Scenes: a world and the cameras to look at it with. The default scene is generated
//! terrain around the greenhouse nearest the origin, seen from the land side so that the
//! view goes through glass onto the sea.

use std::sync::Arc;

use glam::DVec3;
use voxel_core::{BlockRegistry, ChunkPos, SiteKind, TerrainConfig, TerrainGenerator, World};
use voxel_render::Camera;

/// A world with named cameras.
#[derive(Debug, Clone)]
pub struct Scene {
    /// Name, for reports.
    pub name: String,
    /// The blocks.
    pub world: World,
    /// Cameras, at least one.
    pub cameras: Vec<Camera>,
}

/// Chunks generated around the default scene's structure, in each horizontal direction.
pub const DEFAULT_RADIUS: i32 = 6;

/// The default scene for `seed`: terrain `DEFAULT_RADIUS` chunks around the greenhouse
/// nearest the origin, the camera on the land side looking through it at the sea.
pub fn default_scene(seed: u32) -> Result<Scene, String> {
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
            ChunkPos::new(cx - DEFAULT_RADIUS, 0, cz - DEFAULT_RADIUS),
            ChunkPos::new(cx + DEFAULT_RADIUS, 1, cz + DEFAULT_RADIUS),
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
    let camera = Camera::look_at(eye, target, 70.0, 0.1, 600.0).map_err(|e| e.to_string())?;
    Ok(Scene {
        name: format!("default (seed {seed})"),
        world,
        cameras: vec![camera],
    })
}
