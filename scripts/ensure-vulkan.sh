#!/usr/bin/env bash
# Makes sure a Vulkan driver is present (Mesa's software one, lavapipe, on machines without
# a GPU), Mesa's EGL and GLES with its DRI drivers (wgpu's GL backend: llvmpipe without a
# GPU, what the GL tests draw on), plus Xvfb and the X11 keyboard library winit loads at
# run time. Installs what is missing with apt-get when running as root on Debian/Ubuntu;
# otherwise says what to install and fails. Sourced by run.sh and test.sh.

source "$(dirname "${BASH_SOURCE[0]}")/setup-step.sh"

# SETUP_ROOT (default: none) is a folder the file probes look under instead of /; the setup
# test (tests/tests/setup_scripts.rs) points it at an empty folder to play a fresh machine.
have_vulkan_driver() {
    compgen -G "${SETUP_ROOT:-}/usr/share/vulkan/icd.d/*.json" >/dev/null ||
        compgen -G "${SETUP_ROOT:-}/etc/vulkan/icd.d/*.json" >/dev/null
}

have_lib() {
    ldconfig -p 2>/dev/null | grep -q "$1"
}

# Mesa's software GL driver: swrast_dri.so (or, in newer Mesa, libgallium) in a dri folder.
have_mesa_dri() {
    compgen -G "${SETUP_ROOT:-}/usr/lib/*/dri/swrast_dri.so" >/dev/null ||
        compgen -G "${SETUP_ROOT:-}/usr/lib/dri/swrast_dri.so" >/dev/null ||
        have_lib libgallium
}

ensure_vulkan() {
    local missing=()
    have_vulkan_driver || missing+=(mesa-vulkan-drivers)
    # wgpu's GL backend: the EGL loader, Mesa's EGL, GLES 2/3, the DRI drivers.
    have_lib libEGL.so.1 || missing+=(libegl1)
    have_lib libEGL_mesa.so.0 || missing+=(libegl-mesa0)
    have_lib libGLESv2.so.2 || missing+=(libgles2)
    have_mesa_dri || missing+=(libgl1-mesa-dri)
    command -v Xvfb >/dev/null || missing+=(xvfb)
    have_lib libxkbcommon-x11.so.0 || missing+=(libxkbcommon-x11-0)
    if ((${#missing[@]})); then
        if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
            echo "installing ${missing[*]} with apt-get" >&2
            local by_hand="sudo apt-get update && sudo apt-get install -y ${missing[*]}"
            setup_step "Vulkan/GL drivers" "$by_hand" apt-get update -qq
            DEBIAN_FRONTEND=noninteractive setup_step "Vulkan/GL drivers" "$by_hand" \
                apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
        else
            echo "error: missing ${missing[*]}; install with: sudo apt-get install -y ${missing[*]}" >&2
            return 1
        fi
    fi
    # Mesa's Wayland probe complains without a runtime directory; give it one.
    if [ -z "${XDG_RUNTIME_DIR:-}" ] || [ ! -d "${XDG_RUNTIME_DIR}" ]; then
        export XDG_RUNTIME_DIR="${TMPDIR:-/tmp}/voxel-oit-runtime-$(id -u)"
        mkdir -p "$XDG_RUNTIME_DIR" && chmod 700 "$XDG_RUNTIME_DIR"
    fi
}
