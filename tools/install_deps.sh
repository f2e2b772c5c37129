#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Installs bvhlab's build dependencies from Debian 12's packages. Idempotent: installs only
# what is missing. Usage: tools/install_deps.sh [--with-fuzz]
# (OpenImageIO is a default dependency since the renderer; --with-oiio is still accepted.)
# (--with-fuzz: clang-14 and libFuzzer, for tools/fuzz.sh)
set -euo pipefail

pkgs=(build-essential cmake git python3 libembree-dev libtinyobjloader-dev libassimp-dev libglm-dev libtbb-dev
      libcli11-dev nlohmann-json3-dev libbenchmark-dev libgtest-dev clang-format-14 libopenimageio-dev pkg-config
      python3-venv python3-dev pybind11-dev python3-numpy python3-pytest python3-matplotlib slurm-wlm munge unzip
      libcpp-httplib-dev libstb-dev chromium)
for arg in "$@"; do
    case "$arg" in
        --with-oiio) ;;  # installed by default
        --with-fuzz) pkgs+=(clang-14 libclang-rt-14-dev) ;;
        -h|--help) echo "usage: $0 [--with-fuzz]"; exit 0 ;;
        *) echo "install_deps.sh: unknown option '$arg' (expected --with-fuzz)" >&2; exit 2 ;;
    esac
done

missing=()
for p in "${pkgs[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
    echo "install_deps.sh: all ${#pkgs[@]} packages already installed"
    exit 0
fi

sudo=""
if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || { echo "install_deps.sh: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
    sudo=sudo
fi
echo "install_deps.sh: installing ${missing[*]}"
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install_deps.sh: done"
