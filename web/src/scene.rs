//! The default scene, as the lab makes it (`voxel_lab::scene::default_scene_with_radius`:
//! generated terrain, the greenhouse nearest the origin, looked at from the land side with
//! the sea behind its glass), without the lab, which does not build for a browser.

use std::sync::Arc;

use glam::DVec3;
use voxel_core::{BlockRegistry, ChunkPos, SiteKind, TerrainConfig, TerrainGenerator, World};
use voxel_render::Camera;

use crate::{Error, Result};

/// Chunks of terrain each way around the greenhouse that the page loads by default: the
/// lab's radius (6) costs a browser seconds of generation and meshing on one thread.
pub const PAGE_RADIUS: i32 = 4;

/// The world and the camera of the default scene.
#[derive(Debug)]
pub struct DefaultScene {
    /// Terrain `radius` chunks each way around the greenhouse, two chunks high.
    pub world: World,
    /// The lab's camera of the scene.
    pub camera: Camera,
}

/// The default scene of `seed` with `radius` chunks of terrain each way (1 to 16): the
/// lab's default scene, block for block and with its camera.
pub fn default_scene(seed: u32, radius: i32) -> Result<DefaultScene> {
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
        .ok_or(Error::NoGlassStructure { seed })?;
    let c = site.center;
    let cx = c[0].div_euclid(32) as i32;
    let cz = c[2].div_euclid(32) as i32;
    let world = generator.generate_world(
        Arc::new(BlockRegistry::default()),
        ChunkPos::new(cx - radius, 0, cz - radius),
        ChunkPos::new(cx + radius, 1, cz + radius),
    )?;
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
    let camera =
        Camera::look_at(eye, target, 70.0, 0.1, 600.0)?.in_medium(world.medium_at(eye.to_array()));
    Ok(DefaultScene { world, camera })
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;

    /// The same world and camera as the lab's default scene.
    #[test]
    fn is_the_labs_default_scene() {
        let ours = default_scene(1, 2).expect("the default scene");
        let lab = voxel_lab::scene::default_scene_with_radius(1, 2).expect("the lab's");
        assert_eq!(ours.camera, lab.cameras[0]);
        let blocks = |w: &World| {
            let mut v: Vec<_> = w.iter().map(|(p, c)| (p, c.to_dense())).collect();
            v.sort_by_key(|(p, _)| *p);
            v
        };
        let (a, b) = (blocks(&ours.world), blocks(&lab.world));
        assert_eq!(a.len(), 50, "5 x 2 x 5 chunks");
        assert!(a == b, "the worlds differ");
    }
}
