//! `game.rs` in a web page: its world, fly camera, Bevy cube, glass box and sparks (its own
//! `setup`, `fly` and `keys` systems) drawn into the page's canvas (`index.html` beside this
//! file). Built for wasm32 with voxel-bevy's `webgl2` or `webgpu` feature by scripts/web.sh
//! (docs/bevy.md, "The browser"):
//! `WEB_CRATE=voxel-bevy WEB_EXAMPLE=web WEB_FEATURES=webgl2 bash scripts/web.sh serve`.
//! `?radius=N` loads N chunks each way (default 2: a page generates and meshes on its one
//! thread); `?report=1` posts what the browser test checks (`report.rs`). Natively it is
//! `game.rs` in a window.

#[path = "../game.rs"]
#[allow(dead_code)] // its `main` is this example's own
mod game;
#[cfg(target_arch = "wasm32")]
mod report;

use bevy::prelude::*;
use voxel_bevy::{VoxelPlugin, VoxelWorld};

fn main() {
    let terrain = voxel_core::TerrainGenerator::new(Default::default());
    let world = VoxelWorld::generated(&terrain, radius()).expect("the default terrain");
    // The page's canvas, following the window (natively: a window, as game.rs's).
    let window = Window {
        canvas: Some("#view".into()),
        fit_canvas_to_parent: true,
        ..default()
    };
    let plugins = DefaultPlugins.set(WindowPlugin {
        primary_window: Some(window),
        ..default()
    });
    // In a page: Bevy's log plugin, to the browser's console (the reports keep its errors).
    #[cfg(target_arch = "wasm32")]
    let plugins = plugins.set(report::log_plugin());
    let mut app = App::new();
    app.add_plugins((plugins, VoxelPlugin::default()))
        .insert_resource(world)
        .add_systems(Startup, game::setup)
        .add_systems(Update, (game::fly, game::keys));
    #[cfg(target_arch = "wasm32")]
    report::add(&mut app);
    app.run();
}

/// Chunks each way: `?radius=N` (1 to 8) in a page, else 2; natively game.rs's 3.
fn radius() -> i32 {
    #[cfg(target_arch = "wasm32")]
    {
        report::url_parameter("radius")
            .and_then(|r| r.parse().ok())
            .filter(|r| (1..=8).contains(r))
            .unwrap_or(2)
    }
    #[cfg(not(target_arch = "wasm32"))]
    3
}
