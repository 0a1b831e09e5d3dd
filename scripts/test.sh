#!/usr/bin/env bash
# Runs every test of the workspace, GPU tests included (on Mesa's software Vulkan driver,
# lavapipe, when the machine has no GPU). When no Vulkan driver or no Xvfb is installed and
# this runs as root on Debian/Ubuntu, it installs them with apt-get; otherwise it says what to
# install. One release build serves the tests, the benchmarks' peers and the demo.
set -euo pipefail
cd "$(dirname "$0")/.."

have_vulkan_driver() {
    compgen -G "/usr/share/vulkan/icd.d/*.json" >/dev/null ||
        compgen -G "/etc/vulkan/icd.d/*.json" >/dev/null
}

missing=()
have_vulkan_driver || missing+=(mesa-vulkan-drivers)
command -v Xvfb >/dev/null || missing+=(xvfb)
if ((${#missing[@]})); then
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
        echo "installing ${missing[*]} with apt-get"
        apt-get update -qq
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
    else
        echo "error: missing ${missing[*]}; install with: sudo apt-get install -y ${missing[*]}" >&2
        exit 1
    fi
fi

if cargo fmt --version >/dev/null 2>&1; then
    cargo fmt --all -- --check
fi
cargo test --release --workspace
