//! The demo's library: the interactive window (winit + egui). The headless tools and the
//! lab live in `voxel-lab`, which has no window.

pub mod app;
pub mod error;

pub use error::{Error, Result};
