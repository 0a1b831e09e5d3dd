#!/usr/bin/env bash
# The web demo (docs/browser.md).
#   bash scripts/web.sh build   builds web/ for wasm32 into out/web (index.html, voxel_web.js,
#                               voxel_web_bg.wasm); installs the wasm32 target and
#                               wasm-bindgen's CLI (the version in Cargo.lock) when missing
#   bash scripts/web.sh serve   builds, then serves out/web on http://127.0.0.1:8000
#                               (PORT=... for another port)
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ensure-toolchain.sh
source scripts/ensure-browser.sh

OUT=out/web

build() {
    ensure_toolchain
    ensure_wasm_tools
    cargo build --release --target wasm32-unknown-unknown -p voxel-web
    mkdir -p "$OUT"
    wasm-bindgen --target web --no-typescript --out-dir "$OUT" \
        target/wasm32-unknown-unknown/release/voxel_web.wasm
    cp web/index.html "$OUT/index.html"
    echo "built $OUT ($(du -k "$OUT/voxel_web_bg.wasm" | cut -f1) KiB of WebAssembly)" >&2
}

case "${1:-}" in
    build)
        build
        ;;
    serve)
        build
        port="${PORT:-8000}"
        echo "serving $OUT on http://127.0.0.1:$port (Ctrl-C stops)" >&2
        exec python3 -m http.server "$port" --bind 127.0.0.1 --directory "$OUT"
        ;;
    *)
        echo "usage: bash scripts/web.sh build|serve" >&2
        exit 2
        ;;
esac
