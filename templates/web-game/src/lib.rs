//! A game's own web page: streamed terrain (chunks made on the page's thread within a
//! budget each frame), the game's things (fireflies over the water, a glass box turning)
//! moved every frame, on WebGPU or WebGL2 with everything `voxel_web::run` gives: the
//! fallback, a new device after a loss, the canvas following the window, the technique
//! picker and the fly camera.

use std::sync::Arc;

use glam::{DQuat, DVec3};
use voxel_core::{BlockRegistry, TerrainConfig, TerrainGenerator};
use voxel_render::content::{Content, Entity, Particle};
use voxel_render::{Camera, ChunkStreamer, StreamConfig};
use voxel_web::game::{Blocks, GamePage, Tick};
use wasm_bindgen::prelude::*;

/// The page's entry point: `voxel_web::run` with what the game shows.
#[wasm_bindgen(start)]
pub fn start() {
    voxel_web::run(|| page().map_err(|e| e.to_string()));
}

/// Fireflies around the structure, and a glass box above it.
const FIREFLIES: usize = 40;

fn page() -> Result<GamePage, Box<dyn std::error::Error>> {
    let registry = Arc::new(BlockRegistry::default());
    let terrain = TerrainGenerator::new(TerrainConfig {
        seed: 7,
        ..TerrainConfig::default()
    });
    // Where to look: the terrain's own showcase (a structure by the water).
    let view = terrain
        .showcase(1)?
        .ok_or("no structure near the origin for this seed")?;
    let (eye, target) = (DVec3::from(view.eye), DVec3::from(view.target));
    let camera = Camera::look_at(eye, target, 70.0, 0.1, 600.0)?;
    // On wasm32 the streamer works on the page's thread: 6 ms of chunk making a frame.
    let config = StreamConfig {
        view_distance: 3,
        vertical_distance: 1,
        local_budget: std::time::Duration::from_millis(6),
        ..StreamConfig::default()
    };
    let streamer = ChunkStreamer::new(registry, terrain, config)?;
    let centre = target + DVec3::new(0.0, 3.0, 0.0);
    Ok(
        GamePage::new("web-game", Blocks::Stream(Box::new(streamer)), camera)
            .with_content(things(centre, 0.0))
            .on_frame(move |tick: Tick, _| Some(things(centre, tick.seconds))),
    )
}

/// The things at `t` seconds: fireflies circling `centre`, a glass box turning above it.
fn things(centre: DVec3, t: f64) -> Content {
    let particles = (0..FIREFLIES)
        .map(|i| {
            let a = i as f64 / FIREFLIES as f64 * std::f64::consts::TAU + t * 0.4;
            let r = 4.0 + (i % 5) as f64;
            Particle {
                center: centre + DVec3::new(r * a.cos(), (t * 1.3 + i as f64).sin(), r * a.sin()),
                half_size: 0.12,
                color: [255, 220, 90],
                opacity: 0.9,
                emissive: 3.0,
            }
        })
        .collect();
    let glass = Entity {
        center: centre + DVec3::new(0.0, 4.0, 0.0),
        half_extents: [1.0; 3],
        rotation: DQuat::from_rotation_y(t * 0.5),
        color: [60, 200, 120],
        opacity: 0.45,
        emissive: 0.0,
    };
    Content {
        particles,
        entities: vec![glass],
    }
}
