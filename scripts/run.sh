#!/usr/bin/env bash
# Runs the demo: a window when there is a display, otherwise the headless showcase (every
# technique rendered into out/, and the speed/accuracy chart). Installs the software
# Vulkan driver first when none is present (see ensure-vulkan.sh). Arguments go to the demo.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ensure-toolchain.sh
source scripts/ensure-vulkan.sh
ensure_toolchain
ensure_vulkan
exec cargo run --release -p demo -- "$@"
