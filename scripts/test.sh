#!/usr/bin/env bash
# Runs every test of the workspace, GPU tests included (on Mesa's software Vulkan driver,
# lavapipe, when the machine has no GPU) and the demo's real window under Xvfb. Installs
# what is missing (see ensure-vulkan.sh). One release build serves the tests, the demo and
# the benchmarks' peers.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ensure-vulkan.sh
ensure_vulkan

if cargo fmt --version >/dev/null 2>&1; then
    cargo fmt --all -- --check
fi
cargo test --release --workspace
