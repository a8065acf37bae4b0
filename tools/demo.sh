#!/usr/bin/env bash
# The README's first command: installs dependencies, builds Glow, bakes the built-in Cornell box and
# runs the runtime on it headless: a short update loop with a moving point light (lit by the exact
# Embree host), printing the per-stage timings and the indirect light at a few points.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build build -j "$(nproc)"
build/bin/glow-bake builtin:cornell -o build/cornell.glow "$@"
build/bin/glow-bench build/cornell.glow scenes/cornell-builtin-point.json --frames 30 --no-machine \
    --probe 0,0.5,0 --probe -0.6,1,0 --probe 0.6,1,0
