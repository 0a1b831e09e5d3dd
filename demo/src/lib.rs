//! The demo's library: scenes, headless rendering, and the lab behind `demo eval`.

pub mod app;
pub mod args;
pub mod charts;
pub mod eval;
pub mod headless;
pub mod metrics;
pub mod report;
pub mod scene;
pub mod stability;
