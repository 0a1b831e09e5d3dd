#!/usr/bin/env bash
# The particle table of the README: every technique with 0, 1 000 and 10 000 bubbles in
# view (scenes/particles), error against the A-buffer reference, GPU ms of the translucent
# work and CPU ms (a sorted technique's time ordering the objects in brackets).
# Usage: bash scripts/particle-table.sh [SIZE] (default 640x360); writes results/particles.
set -euo pipefail
cd "$(dirname "$0")/.."
size="${1:-640x360}"
cargo build --release -p demo
target/release/demo eval --scenes scenes/particles --size "$size" --weights none \
  --no-stability --out results/particles
