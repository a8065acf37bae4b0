#!/usr/bin/env bash
# The README's first command: installs dependencies, builds Glow and runs its main job on the
# built-in Cornell box. For now the main job is the bake (the runtime issue extends this).
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build build -j "$(nproc)"
build/bin/glow-bake builtin:cornell -o build/cornell.glow "$@"
build/bin/glow-bake --info build/cornell.glow
