#!/usr/bin/env bash
# Installs everything Glow needs to build and test, from Debian 12 packages only.
# Usage: tools/setup.sh            (uses sudo when not root)
set -euo pipefail
PKGS=(
  build-essential cmake ninja-build pkg-config git
  libembree-dev        # Embree 3: every ray in the linker
  libassimp-dev        # scene import (OBJ/MTL, glTF, ...)
  libstb-dev           # stb_image: decodes albedo textures (JPEG/PNG) that assimp only names
  zlib1g-dev           # crc32 reference in the format tests
  libcmocka-dev        # unit tests
  libcjson-dev         # scene description files (integration/: glow_scene.h)
  clang                # libFuzzer target for the bake reader
  libglfw3-dev libosmesa6-dev libegl-dev libgl-dev libcglm-dev   # integration (later issues)
  libopenexr-dev glslang-tools gnuplot-nox                       # evaluation, shaders, charts
  python3              # tools/glow-eval (the sweep driver) and its CLI test
  xvfb xauth           # the GL samples' window path in ctest (xvfb-run: GLFW + GLX on llvmpipe)
  libopenmpi-dev openmpi-bin   # glow-bake --mpi (optional at build time; its test runs 2-3 ranks)
)
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#PKGS[@]} packages already installed"
  exit 0
fi
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
echo "setup: installing ${missing[*]}"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
