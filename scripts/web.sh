#!/usr/bin/env bash
# The web page (docs/browser.md).
#   bash scripts/web.sh build   builds a page for wasm32 into the output folder (index.html,
#                               <crate>.js, <crate>_bg.wasm); installs the wasm32 target
#                               and wasm-bindgen's CLI (the version in Cargo.lock) when
#                               missing
#   bash scripts/web.sh serve   builds, then serves the output folder on
#                               http://127.0.0.1:8000 (PORT=... for another port)
#
# From the environment:
#   WEB_CRATE         the page's crate folder (its Cargo.toml and index.html): default web/
#                     (the crate's own page); a game's own crate elsewhere (templates/web-game)
#   WEB_OUT           the output folder: default out/web in this checkout
#   CARGO_TARGET_DIR  cargo's target folder: default the crate's workspace's target/
# With WEB_OUT and CARGO_TARGET_DIR outside it, nothing is written into this checkout (it
# may be read-only): the crate's own page builds with --locked, so Cargo.lock is read,
# never rewritten. A game's crate (WEB_CRATE) builds with its own Cargo.lock, in its folder.
set -euo pipefail
checkout="$(cd "$(dirname "$0")/.." && pwd)"
cd "$checkout"
source scripts/ensure-toolchain.sh
source scripts/ensure-browser.sh

crate="$(cd "${WEB_CRATE:-web}" && pwd)"
locked=()
if [ -z "${WEB_CRATE:-}" ]; then
    locked=(--locked)
fi
out="${WEB_OUT:-$checkout/out/web}"

# The crate's name (its [package] name), as a library file name.
lib_name() {
    awk '/^\[package\]/ { p = 1; next } /^\[/ { p = 0 } p && /^name *=/ { gsub(/name *= *|"/, ""); gsub(/-/, "_"); print; exit }' "$crate/Cargo.toml"
}

# Where cargo puts the crate's wasm32 build.
target_dir() {
    if [ -n "${CARGO_TARGET_DIR:-}" ]; then
        echo "$CARGO_TARGET_DIR"
    else
        cargo metadata --format-version 1 --no-deps "${locked[@]}" --manifest-path "$crate/Cargo.toml" |
            python3 -c 'import json, sys; print(json.load(sys.stdin)["target_directory"])'
    fi
}

build() {
    ensure_toolchain
    ensure_wasm_tools
    local name target want have
    name="$(lib_name)"
    if [ -z "$name" ]; then
        echo "error: no [package] name in $crate/Cargo.toml" >&2
        return 1
    fi
    # The CLI must be the version the crate's build links (its own Cargo.lock, if any).
    if [ -f "$crate/Cargo.lock" ]; then
        want="$(cd "$crate" && locked_version wasm-bindgen)"
        have="$(wasm-bindgen --version | awk '{ print $2 }')"
        if [ -n "$want" ] && [ "$want" != "$have" ]; then
            echo "error: $crate/Cargo.lock has wasm-bindgen $want, the CLI is $have;" \
                "run: cargo install wasm-bindgen-cli --version =$want" >&2
            return 1
        fi
    fi
    # A cdylib whatever the crate's Cargo.toml says (voxel-web is an rlib, so that a game's
    # page that links it, built in the same target folder, never overwrites this module).
    cargo rustc --release "${locked[@]}" --target wasm32-unknown-unknown \
        --manifest-path "$crate/Cargo.toml" --lib --crate-type cdylib
    target="$(target_dir)"
    mkdir -p "$out"
    wasm-bindgen --target web --no-typescript --out-dir "$out" \
        "$target/wasm32-unknown-unknown/release/$name.wasm"
    cp "$crate/index.html" "$out/index.html"
    echo "built $out ($(du -k "$out/${name}_bg.wasm" | cut -f1) KiB of WebAssembly)" >&2
}

case "${1:-}" in
    build)
        build
        ;;
    serve)
        build
        port="${PORT:-8000}"
        echo "serving $out on http://127.0.0.1:$port (Ctrl-C stops)" >&2
        exec python3 -m http.server "$port" --bind 127.0.0.1 --directory "$out"
        ;;
    *)
        echo "usage: bash scripts/web.sh build|serve (WEB_CRATE, WEB_OUT, CARGO_TARGET_DIR: see the script)" >&2
        exit 2
        ;;
esac
