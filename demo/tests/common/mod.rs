//! What the demo's command-line tests share: running the binary without a display.

use std::process::{Command, Output};

/// Runs the demo with `args`, no display in its environment (so no window can open).
pub fn demo(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_demo"))
        .args(args)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap()
}
