#!/usr/bin/env bash
# The GPU check: the whole scene suite with every technique at 1920x1080 on a machine with
# a GPU, in one markdown table (scene x technique: GPU ms, CPU ms, the counters of what each
# frame asks of the GPU, pixels off the exact reference). Documented in
# docs/measurements.md ("The GPU check").
#
#   scripts/gpu-check.sh pack [--dir DIR]
#       On the build machine: builds the release `demo`, strips and compresses it, and puts
#       it with scenes/ and the Vulkan loader package into DIR (default out/gpu-check,
#       ignored by git; about 10 MB), which a machine without a Rust toolchain runs from.
#   scripts/gpu-check.sh run [--dir DIR] [--out OUT] [--size WxH] [--scenes a,b]
#                            [--techniques list] [--frames N] [--raymarch-width W]
#                            [--budget SECONDS]
#       Runs the check with the packed binary (or target/release/demo when nothing is
#       packed) and writes OUT/check.md (default out/gpu-check-run), beside the lab's
#       summary.json, reference_checks.json, report.md and costs.md and the log. Defaults:
#       1920x1080, every scene of scenes/, every technique, 3 timed frames after 1 warm-up,
#       the ray march that checks each reference at 480 pixels wide (0: none), no FLIP or
#       heat maps, no scene started after 200 s.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"

usage() {
    sed -n '2,20p' "$0" | sed 's/^# \{0,1\}//'
    exit 2
}

[ $# -ge 1 ] || usage
cmd="$1"
shift

dir="out/gpu-check"
out="out/gpu-check-run"
size="1920x1080"
scenes=""
techniques="all"
frames=3
raymarch=480
budget=200
while [ $# -gt 0 ]; do
    case "$1" in
        --dir) dir="$2"; shift 2 ;;
        --out) out="$2"; shift 2 ;;
        --size) size="$2"; shift 2 ;;
        --scenes) scenes="$2"; shift 2 ;;
        --techniques) techniques="$2"; shift 2 ;;
        --frames) frames="$2"; shift 2 ;;
        --raymarch-width) raymarch="$2"; shift 2 ;;
        --budget) budget="$2"; shift 2 ;;
        -h|--help) usage ;;
        *) echo "gpu-check: unknown option $1" >&2; usage ;;
    esac
done

pack() {
    cargo build --release -p demo
    rm -rf "$dir"
    mkdir -p "$dir/debs"
    cp target/release/demo "$dir/demo"
    strip "$dir/demo"
    gzip -9 "$dir/demo"
    cp -r scenes "$dir/scenes"
    # wgpu loads the Vulkan loader at run time; a bare machine with an NVIDIA driver may
    # lack it (the device notes say to bring it). Optional: without a package manager
    # here the run uses the machine's own loader.
    if command -v apt-get >/dev/null; then
        (cd "$dir/debs" && apt-get download libvulkan1 2>/dev/null) ||
            echo "gpu-check: could not download libvulkan1; the run will need the machine's loader" >&2
    fi
    git rev-parse HEAD >"$dir/commit" 2>/dev/null || true
    du -sh "$dir"
    echo "packed into $dir ($(du -sb "$dir" | cut -f1) bytes)"
}

# The Vulkan loader and the NVIDIA driver's manifest where the machine lacks them.
vulkan_setup() {
    if ! ldconfig -p 2>/dev/null | grep -q 'libvulkan\.so\.1'; then
        if [ "$(id -u)" = 0 ] && compgen -G "$dir/debs/*.deb" >/dev/null; then
            for f in "$dir"/debs/*.deb; do dpkg -x "$f" /; done
            ldconfig
        else
            echo "gpu-check: no Vulkan loader (libvulkan.so.1) and none packed" >&2
        fi
    fi
    local icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
    if [ -z "${VK_DRIVER_FILES:-}${VK_ICD_FILENAMES:-}" ] && [ -f "$icd" ] &&
        ! compgen -G "/usr/share/vulkan/icd.d/*.json" >/dev/null &&
        ! compgen -G "/etc/vulkan/icd.d/*.json" >/dev/null; then
        export VK_DRIVER_FILES="$icd"
    fi
}

run() {
    local demo
    if [ -f "$dir/demo.gz" ]; then
        demo="$(mktemp -d)/demo"
        gunzip -c "$dir/demo.gz" >"$demo"
        chmod +x "$demo"
    elif [ -x target/release/demo ]; then
        demo=target/release/demo
    else
        echo "gpu-check: nothing packed in $dir and no target/release/demo: run pack first" >&2
        exit 1
    fi
    local scene_dir=scenes
    [ -d "$dir/scenes" ] && scene_dir="$dir/scenes"
    local args=()
    if [ -n "$scenes" ]; then
        IFS=',' read -ra names <<<"$scenes"
        for n in "${names[@]}"; do
            args+=("$scene_dir/${n%.toml}.toml")
        done
    else
        args+=("$scene_dir")
    fi
    vulkan_setup
    mkdir -p "$out"
    {
        echo "# GPU check"
        echo
        echo "Run by \`scripts/gpu-check.sh run --size $size --frames $frames --raymarch-width $raymarch --budget $budget${scenes:+ --scenes $scenes}\` on $(date -u +%Y-%m-%dT%H:%MZ), binary of commit $(cat "$dir/commit" 2>/dev/null || git rev-parse HEAD 2>/dev/null || echo unknown)."
        echo
        if command -v nvidia-smi >/dev/null; then
            echo '```'
            nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm,clocks.mem --format=csv 2>&1 || true
            echo '```'
            echo
        fi
    } >"$out/check.md"
    local start=$SECONDS
    set +e
    "$demo" eval --scenes "${args[@]}" --techniques "$techniques" --weights none \
        --size "$size" --frames "$frames" --warmup 1 --no-stability --no-flip --no-heatmaps \
        --raymarch-width "$raymarch" --time-budget "$budget" --out "$out" 2>&1 | tee "$out/log.txt"
    local status=${PIPESTATUS[0]}
    set -e
    local took=$((SECONDS - start))
    echo "The lab ran ${took} s (status $status)." >>"$out/check.md"
    echo >>"$out/check.md"
    if command -v nvidia-smi >/dev/null; then
        echo "SM clock after the run: $(nvidia-smi --query-gpu=clocks.sm --format=csv,noheader 2>&1 || true)." >>"$out/check.md"
        echo >>"$out/check.md"
    fi
    if [ -f "$out/costs.md" ]; then
        # costs.md without its title.
        tail -n +2 "$out/costs.md" >>"$out/check.md"
    fi
    echo "gpu-check: wrote $out/check.md in ${took} s"
    return "$status"
}

case "$cmd" in
    pack) pack ;;
    run) run ;;
    *) usage ;;
esac
