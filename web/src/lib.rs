//! The voxel OIT renderer in a web page: the default terrain with its water, a technique
//! picker listing what the device runs, and a fly camera, on WebGPU where the browser has
//! it and WebGL2 otherwise (`bash scripts/web.sh build`, then `serve`; docs/browser.md).
//!
//! What the page shows is built here on every target, so that the browser test
//! (`tests/browser.rs`) renders the same world from the same camera natively:
//!
//! - [`scene`]: the default scene (the lab's: a greenhouse on the shore, the sea through its
//!   glass) with a radius of terrain to load.
//! - [`fly`]: the fly camera (WASD, Space and Shift, mouse drag).
//! - [`check`]: what the test page reports for each technique, and the size and frames it
//!   renders them with.
//!
//! - [`game`]: what a game's own page shows ([`game::GamePage`]: its blocks, a world or a
//!   streamer, its camera, its things and what moves them), handed to `run` (wasm32)
//!   from the game's own crate (docs/browser.md, "A game's own page").
//!
//! The page itself (wasm32 only) is `page`: it picks the backend (`gpu`: WebGPU, falling
//! back to WebGL2 where WebGPU fails at any step of start-up), builds the world and draws
//! it every animation frame (`app`: a new device and renderer after a loss, the canvas
//! following the window); with `?test=1` it renders every technique into a texture and
//! posts each picture (or its refusal) to the server that served it. The crate's own page
//! is its `page` feature (on by default): a game's crate depends on this one with
//! `default-features = false` and calls `run` from its own start function.

#![warn(missing_docs)]

pub mod check;
pub mod fly;
pub mod game;
pub mod scene;

#[cfg(target_arch = "wasm32")]
mod app;
#[cfg(target_arch = "wasm32")]
mod gpu;
#[cfg(all(target_arch = "wasm32", feature = "page"))]
mod own;
#[cfg(target_arch = "wasm32")]
mod page;

#[cfg(target_arch = "wasm32")]
pub use page::run;

/// What can go wrong building the page's scene.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The world generator or the world.
    #[error("world: {0}")]
    World(#[from] voxel_core::Error),
    /// The mesher.
    #[error("mesher: {0}")]
    Mesh(#[from] voxel_mesh::Error),
    /// The renderer (a bad camera among others).
    #[error("renderer: {0}")]
    Render(#[from] voxel_render::Error),
    /// The terrain of `seed` has no glass structure near the origin to look at.
    #[error("seed {seed}: no glass structure within 768 blocks of the origin")]
    NoGlassStructure {
        /// The seed.
        seed: u32,
    },
}

/// `Result` with this crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
