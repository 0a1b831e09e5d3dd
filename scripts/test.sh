#!/usr/bin/env bash
# Runs every test of the workspace, GPU tests included (on Mesa's software Vulkan driver,
# lavapipe, when the machine has no GPU), the demo's real window under Xvfb and the web page
# in headless Chromium. Installs what is missing (see ensure-vulkan.sh and
# ensure-browser.sh). One release build serves the tests, the demo and the benchmarks' peers.
#   bash scripts/test.sh                 installs what is missing, then runs every test
#   bash scripts/test.sh --setup-only    installs what is missing and stops (what
#                                        tests/tests/setup_scripts.rs runs with stub installers)
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ensure-toolchain.sh
source scripts/ensure-vulkan.sh
source scripts/ensure-browser.sh
ensure_toolchain
ensure_vulkan
ensure_chromium
ensure_wasm_tools
if [ "${1:-}" = --setup-only ]; then
    echo "setup complete: Rust $(awk -F'"' '/^channel/ { print $2 }' rust-toolchain.toml), Vulkan/GL drivers, Xvfb, Chromium, the wasm32 target, wasm-bindgen" >&2
    exit 0
fi

if cargo fmt --version >/dev/null 2>&1; then
    cargo fmt --all -- --check
fi
cargo test --release --workspace
