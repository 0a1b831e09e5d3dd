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
#   WEB_EXAMPLE       build this example of the crate instead of its library, as Bevy's
#                     examples are built for the web: its `main` runs when the page loads,
#                     the module is named after it, the page is examples/NAME/index.html
#                     (voxel-bevy's `web`: docs/bevy.md)
#   WEB_FEATURES      the crate's features to build with (voxel-bevy: webgl2 or webgpu)
#   WEB_PROFILE       cargo's profile: default release; the browser tests build voxel-bevy's
#                     pages with `web-test` (Cargo.toml: opt-level 1, no debug info), which
#                     takes a third of the CPU of a release build of a Bevy page
# With WEB_OUT and CARGO_TARGET_DIR outside it, nothing is written into this checkout (it
# may be read-only): a crate of this workspace (the crate's own page, voxel-bevy's example)
# builds with --locked, so Cargo.lock is read, never rewritten. A game's crate (WEB_CRATE)
# builds with its own Cargo.lock, in its folder.
set -euo pipefail
checkout="$(cd "$(dirname "$0")/.." && pwd)"
cd "$checkout"
source scripts/ensure-toolchain.sh
source scripts/ensure-browser.sh

# The workspace a crate folder belongs to (its own folder for a game's crate).
workspace_root() {
    cargo metadata --format-version 1 --no-deps --manifest-path "$crate/Cargo.toml" |
        python3 -c 'import json, sys; print(json.load(sys.stdin)["workspace_root"])'
}

crate="$(cd "${WEB_CRATE:-web}" && pwd)"
example="${WEB_EXAMPLE:-}"
features=()
if [ -n "${WEB_FEATURES:-}" ]; then
    features=(--features "$WEB_FEATURES")
fi
locked=()
if [ -z "${WEB_CRATE:-}" ] || [ "$(workspace_root)" = "$checkout" ]; then
    locked=(--locked)
fi
out="${WEB_OUT:-$checkout/out/web}"
profile="${WEB_PROFILE:-release}"

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
    local wasm page
    if [ -n "$example" ]; then
        # An example: a program whose `main` wasm-bindgen makes the module's start.
        name="$example"
        page="$crate/examples/$example/index.html"
        if [ ! -f "$page" ]; then
            echo "error: WEB_EXAMPLE=$example: no page $page" >&2
            return 1
        fi
        cargo build --profile "$profile" "${locked[@]}" "${features[@]}" --target wasm32-unknown-unknown \
            --manifest-path "$crate/Cargo.toml" --example "$example"
        wasm="examples/$example.wasm"
    else
        # A cdylib whatever the crate's Cargo.toml says (voxel-web is an rlib, so that a
        # game's page that links it, built in the same target folder, never overwrites
        # this module).
        page="$crate/index.html"
        cargo rustc --profile "$profile" "${locked[@]}" "${features[@]}" --target wasm32-unknown-unknown \
            --manifest-path "$crate/Cargo.toml" --lib --crate-type cdylib
        wasm="$name.wasm"
    fi
    target="$(target_dir)"
    mkdir -p "$out"
    wasm-bindgen --target web --no-typescript --out-dir "$out" \
        "$target/wasm32-unknown-unknown/$profile/$wasm"
    cp "$page" "$out/index.html"
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
