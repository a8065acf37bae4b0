#!/usr/bin/env bash
# Builds the libFuzzer targets (clang, -fsanitize=fuzzer,address,undefined) in their own build
# directory and fuzzes each for SECONDS (default 60), seeded from tests/data/*.glow (the hand-built
# golden bake and a tiny real bake of builtin:cornell written by glow-bake):
#   fuzz_bake_reader  glow_bake_load (tests/fuzz/fuzz_bake_reader.c)
#   fuzz_bake_solver  load + 3 updates, every output finite (tests/fuzz/fuzz_bake_solver.c)
# Exits non-zero when a fuzzer finds a crash, leak, sanitizer report, non-finite output or timeout
# (the reproducer is written to BUILD/fuzz-artifacts/TARGET/); both targets run either way.
#
# Usage: tools/fuzz-smoke.sh [SECONDS]
#   GLOW_FUZZ_BUILD_DIR  build directory (default: <repo>/build-fuzz)
#   GLOW_FUZZ_JOBS       parallel fuzzing processes (default 1)
set -euo pipefail
secs=${1:-60}
case "$secs" in '' | *[!0-9]*) echo "usage: $0 [SECONDS]" >&2; exit 2 ;; esac
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${GLOW_FUZZ_BUILD_DIR:-$root/build-fuzz}
jobs=${GLOW_FUZZ_JOBS:-1}

# Only the runtime is fuzzed: the linker (Embree, assimp) is not needed.
CC=clang CXX=clang++ cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DGLOW_FUZZ=ON -DGLOW_BUILD_PRECOMPUTE=OFF -DGLOW_BUILD_TESTS=ON >/dev/null
cmake --build "$build" --target fuzz_bake_reader fuzz_bake_solver

# Each target for SECONDS: the bake reader, then "load + 3 updates" (outputs must stay finite).
failed=0
for target in bake_reader bake_solver; do
  corpus=$build/fuzz-corpus/$target # grows across runs
  seeds=$build/fuzz-seeds/$target
  artifacts=$build/fuzz-artifacts/$target
  mkdir -p "$corpus" "$seeds" "$artifacts"
  cp "$root"/tests/data/*.glow "$seeds/"
  echo "fuzz-smoke: fuzz_$target for ${secs}s (corpus $corpus)"
  args=(-max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1
        -artifact_prefix="$artifacts/")
  if [ "$jobs" -gt 1 ]; then args+=(-jobs="$jobs" -workers="$jobs"); fi
  set +e
  "$build/bin/fuzz_$target" "${args[@]}" "$corpus" "$seeds"
  rc=$?
  set -e
  if [ $rc -ne 0 ]; then
    echo "fuzz-smoke: fuzz_$target FAILED (exit $rc); reproducers in $artifacts:" >&2
    ls -l "$artifacts" >&2 || true
    failed=1
  fi
done
[ $failed = 0 ] || exit 1
echo "fuzz-smoke: OK, no crashes in ${secs}s per target"
