//! The demo's library: scenes, headless rendering and the tools behind the `demo` command.

pub mod args;
pub mod headless;
pub mod scene;
