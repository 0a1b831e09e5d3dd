#!/usr/bin/env bash
# Makes sure the Rust toolchain that rust-toolchain.toml names (1.97.1, which Bevy 0.20 and
# so voxel-bevy need) is installed with its components (rustfmt, clippy) and the wasm32
# target. rustup would install it on the first cargo call anyway; doing it here says so and
# fails early with a clear message when rustup is missing. Sourced by run.sh, test.sh, web.sh.

source "$(dirname "${BASH_SOURCE[0]}")/setup-step.sh"

ensure_toolchain() {
    if ! command -v rustup >/dev/null; then
        echo "error: rustup not found; install Rust with https://rustup.rs (the checkout's rust-toolchain.toml names the version)" >&2
        return 1
    fi
    local want
    want="$(awk -F'"' '/^channel/ { print $2 }' rust-toolchain.toml)"
    if ! rustup toolchain list 2>/dev/null | grep -q "^${want}-"; then
        echo "installing Rust ${want} (rust-toolchain.toml) with rustup" >&2
    fi
    # With no argument rustup installs the toolchain the toolchain file names, with its
    # components and targets; a no-op when all are present.
    setup_step "Rust toolchain" "rustup toolchain install $want --component rustfmt clippy --target wasm32-unknown-unknown" \
        rustup_install_quietly
}

# `rustup toolchain install`, its output shown only when it fails.
rustup_install_quietly() {
    local output
    if ! output="$(rustup toolchain install 2>&1)"; then
        echo "$output" >&2
        return 1
    fi
}
