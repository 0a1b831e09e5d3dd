#!/usr/bin/env bash
# Re-makes results/vox/: the lab's table over the MagicaVoxel scenes (scenes/vox) and the
# gallery of one model under every technique, as shown in the README.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -p demo
rm -rf results/vox
./target/release/demo eval --scenes scenes/vox --size 1280x720 --frames 10 --weights none \
    --no-stability --heatmap-width 320 --out results/vox
./target/release/demo gallery --scene scenes/vox/chapel_interior.toml --size 480x270 \
    --out results/vox/gallery
