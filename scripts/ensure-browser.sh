#!/usr/bin/env bash
# Makes sure what the browser test and `web.sh build` need is present: Chromium (Debian's
# `chromium`, which runs headless with WebGPU on SwiftShader and WebGL2 on ANGLE), the
# wasm32-unknown-unknown target and wasm-bindgen's CLI at exactly the version of
# wasm-bindgen in Cargo.lock. Installs what is missing (Chromium with apt-get when running
# as root on Debian/Ubuntu; otherwise says what to install and fails). Sourced by web.sh
# and test.sh.

source "$(dirname "${BASH_SOURCE[0]}")/setup-step.sh"

# The version of a package in Cargo.lock.
locked_version() {
    awk -v name="$1" '$0 == "name = \"" name "\"" { getline; gsub(/version = |"/, ""); print; exit }' Cargo.lock
}

# Chromium's binary (Debian's `chromium`, or `chromium-browser`), or nothing.
chromium_binary() {
    command -v chromium || command -v chromium-browser || true
}

ensure_chromium() {
    if [ -n "$(chromium_binary)" ]; then
        return 0
    fi
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
        echo "installing chromium with apt-get" >&2
        local by_hand="sudo apt-get update && sudo apt-get install -y chromium"
        setup_step chromium "$by_hand" apt-get update -qq
        DEBIAN_FRONTEND=noninteractive setup_step chromium "$by_hand" \
            apt-get install -y -qq --no-install-recommends chromium >/dev/null
    else
        echo "error: missing chromium; install with: sudo apt-get install -y chromium" >&2
        return 1
    fi
}

ensure_wasm_tools() {
    if ! rustup target list --installed 2>/dev/null | grep -qx wasm32-unknown-unknown; then
        echo "installing the wasm32-unknown-unknown target with rustup" >&2
        setup_step "wasm32 target" "rustup target add wasm32-unknown-unknown" \
            rustup target add wasm32-unknown-unknown
    fi
    local want
    want="$(locked_version wasm-bindgen)"
    if [ -z "$want" ]; then
        echo "error: no wasm-bindgen in Cargo.lock" >&2
        return 1
    fi
    local have
    # `|| true`: under `set -euo pipefail` (test.sh, web.sh) a missing CLI must reach the
    # install below, not end the script with wasm-bindgen's status 127.
    have="$( (wasm-bindgen --version 2>/dev/null || true) | awk '{ print $2 }')"
    if [ "$have" != "$want" ]; then
        echo "installing wasm-bindgen-cli $want with cargo install (was: ${have:-none})" >&2
        # Not --locked: the CLI's own lock file may name dependency versions a registry
        # mirror does not have yet (webpki-roots here); the CLI's version is what must match.
        # --force: cargo's record of what it installed can say the CLI is there when its
        # binary is gone (deleted or moved off the PATH); then a plain install does nothing.
        setup_step wasm-bindgen "cargo install --force wasm-bindgen-cli --version =$want" \
            cargo install --quiet --force wasm-bindgen-cli --version "=$want"
        have="$( (wasm-bindgen --version 2>/dev/null || true) | awk '{ print $2 }')"
        if [ "$have" != "$want" ]; then
            echo "error: setup step 'wasm-bindgen' installed wasm-bindgen-cli $want, but the" \
                "wasm-bindgen on the PATH is ${have:-none}; put cargo's bin folder" \
                "(${CARGO_HOME:-\$HOME/.cargo}/bin) first on the PATH" >&2
            return 1
        fi
    fi
}
