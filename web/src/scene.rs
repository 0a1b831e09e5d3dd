//! The default scene, as the lab makes it (`voxel_lab::scene::default_scene_with_radius`:
//! `TerrainGenerator::showcase`, generated terrain around the greenhouse nearest the origin,
//! looked at from the land side with the sea behind its glass), without the lab, which does
//! not build for a browser.

use glam::DVec3;
use voxel_core::{ChunkPos, LightField, TerrainConfig, TerrainGenerator, World, WorldPos};
use voxel_mesh::ChunkMeshes;
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
    let generator = TerrainGenerator::new(TerrainConfig {
        seed,
        ..TerrainConfig::default()
    });
    let view = generator
        .showcase(radius)?
        .ok_or(Error::NoGlassStructure { seed })?;
    let world = view.world;
    let camera = Camera::look_at(
        DVec3::from(view.eye),
        DVec3::from(view.target),
        70.0,
        0.1,
        600.0,
    )?
    .in_medium(world.medium_at(view.eye));
    Ok(DefaultScene { world, camera })
}

/// Every chunk of `world` meshed, with the light of a field lit from scratch
/// (`docs/light.md`) when `light`: what the page uploads, and what the browser test draws
/// natively to compare.
pub fn mesh_world(world: &World, light: bool) -> Result<Vec<(ChunkPos, ChunkMeshes)>> {
    let field = light.then(|| LightField::new(world));
    Ok(voxel_mesh::mesh_world(world, field.as_ref())?)
}

/// Sun shadows (`docs/light.md`) over the chunks of `world` nearest its middle, when
/// `meshes` are lit: what the page draws, and the browser test natively.
pub fn sun_shadows(
    renderer: &mut voxel_render::Renderer,
    world: &World,
    meshes: &[(ChunkPos, ChunkMeshes)],
) -> voxel_render::Result<()> {
    if meshes.iter().all(|(_, m)| m.light.is_empty()) || world.is_empty() {
        return Ok(());
    }
    let n = world.len() as i64;
    let sum = world.iter().fold([0i64; 3], |s, (p, _)| {
        [
            s[0] + i64::from(p.x),
            s[1] + i64::from(p.y),
            s[2] + i64::from(p.z),
        ]
    });
    let middle = sum.map(|v| (v / n * voxel_core::CHUNK_SIZE as i64) as i32);
    match voxel_render::SunRegion::around(world, WorldPos::new(middle[0], middle[1], middle[2])) {
        Some(region) => renderer.set_sun_shadows(world, region),
        None => Ok(()),
    }
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
