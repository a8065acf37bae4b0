#!/usr/bin/env bash
# Builds the libFuzzer targets (clang, -fsanitize=fuzzer,address,undefined) in their own build
# directory and fuzzes each for SECONDS (default 60):
#   fuzz_bake_reader  glow_bake_load (tests/fuzz/fuzz_bake_reader.c)
#   fuzz_bake_solver  load + 3 updates, every output finite (tests/fuzz/fuzz_bake_solver.c)
#     both seeded from tests/data/*.glow (the hand-built golden bake and four tiny real bakes of
#     builtin:cornell written by glow-bake, one with link subsets, one with a lightmap detail, one
#     with a refined grid)
#   fuzz_scene_json   the scene JSON reader (tests/fuzz/fuzz_scene_json.c), seeded from scenes/*.json
#                     and, where present, ../shared/scenes/*/*.json
#   fuzz_mesh_import  mesh import through assimp and our cleaning (tests/fuzz/fuzz_mesh_import.c),
#                     seeded from tests/data/scenes (OBJ, glTF, GLB) and, where present, the shared
#                     Cornell boxes; leaks inside libassimp are suppressed (tests/fuzz/lsan.supp)
# Exits non-zero when a fuzzer finds a crash, leak, sanitizer report, broken invariant or timeout
# (the reproducer is written to BUILD/fuzz-artifacts/TARGET/); every target runs either way.
#
# Usage: tools/fuzz-smoke.sh [SECONDS]
#   GLOW_FUZZ_BUILD_DIR  build directory (default: <repo>/build-fuzz)
#   GLOW_FUZZ_JOBS       parallel fuzzing processes per target (default 1)
#   GLOW_FUZZ_PARALLEL   targets fuzzed at once (default: the core count, at most 4)
set -euo pipefail
secs=${1:-60}
case "$secs" in '' | *[!0-9]*) echo "usage: $0 [SECONDS]" >&2; exit 2 ;; esac
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${GLOW_FUZZ_BUILD_DIR:-$root/build-fuzz}
jobs=${GLOW_FUZZ_JOBS:-1}

# The linker library is not built (no Embree): the import fuzzer compiles only import.c and what it
# calls (tests/fuzz/CMakeLists.txt).
CC=clang CXX=clang++ cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DGLOW_FUZZ=ON -DGLOW_BUILD_PRECOMPUTE=OFF -DGLOW_WITH_GL=OFF -DGLOW_BUILD_TESTS=ON >/dev/null
cmake --build "$build" --target fuzz_bake_reader fuzz_bake_solver fuzz_scene_json fuzz_mesh_import

# Each target for SECONDS: the bake reader, "load + 3 updates" (outputs must stay finite), the scene
# JSON reader, mesh import.
shared=$root/../shared/scenes
# fuzz_one TARGET: fuzzes one target for SECONDS, its output in LOG; exit status 0 = no finding
fuzz_one() {
  local target=$1 log=$2
  local corpus=$build/fuzz-corpus/$target # grows across runs
  local seeds=$build/fuzz-seeds/$target
  local artifacts=$build/fuzz-artifacts/$target
  mkdir -p "$corpus" "$seeds" "$artifacts"
  local extra=()
  case $target in
    bake_*) cp "$root"/tests/data/*.glow "$seeds/" ;;
    scene_json)
      cp "$root"/scenes/*.json "$seeds/"
      if [ -d "$shared" ]; then cp "$shared"/*/*.json "$seeds/" 2>/dev/null || true; fi ;;
    mesh_import)
      cp "$root"/tests/data/scenes/*.obj "$root"/tests/data/scenes/*.gltf "$root"/tests/data/scenes/*.glb "$seeds/"
      if [ -d "$shared/cornell-box" ]; then cp "$shared"/cornell-box/CornellBox-Original.obj "$seeds/"; fi
      extra=(-max_len=65536) ;;
  esac
  # mesh import: the slow (DWARF) unwinder, so that leak stacks reach into libassimp (built without
  # frame pointers) and lsan.supp can match them by module
  local asan=${ASAN_OPTIONS:-}
  if [ "$target" = mesh_import ]; then asan=fast_unwind_on_malloc=0${asan:+:$asan}; fi
  local args=(-max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1
              -artifact_prefix="$artifacts/" "${extra[@]}")
  if [ "$jobs" -gt 1 ]; then args+=(-jobs="$jobs" -workers="$jobs"); fi
  ASAN_OPTIONS=$asan LSAN_OPTIONS=suppressions=$root/tests/fuzz/lsan.supp \
    "$build/bin/fuzz_$target" "${args[@]}" "$corpus" "$seeds" >"$log" 2>&1
}

# GLOW_FUZZ_PARALLEL targets fuzz at once (default: one per core, at most 4), each for SECONDS: the
# smoke's wall time is SECONDS x 4 / that, with the same fuzzing time per target. Each target's output
# goes to a log, printed when it ends (its stats; the whole log when it fails).
par=${GLOW_FUZZ_PARALLEL:-$(nproc)}
case "$par" in '' | *[!0-9]* | 0) par=1 ;; esac
[ "$par" -le 4 ] || par=4
logs=$build/fuzz-logs
mkdir -p "$logs"
failed=0
targets=(bake_reader bake_solver scene_json mesh_import)
for ((i = 0; i < ${#targets[@]}; i += par)); do
  batch=("${targets[@]:i:par}")
  pids=()
  for target in "${batch[@]}"; do
    echo "fuzz-smoke: fuzz_$target for ${secs}s (corpus $build/fuzz-corpus/$target)"
    fuzz_one "$target" "$logs/$target.log" &
    pids+=($!)
  done
  for k in "${!batch[@]}"; do
    target=${batch[$k]}
    set +e
    wait "${pids[$k]}"
    rc=$?
    set -e
    if [ $rc -ne 0 ]; then
      cat "$logs/$target.log" >&2
      echo "fuzz-smoke: fuzz_$target FAILED (exit $rc); reproducers in $build/fuzz-artifacts/$target:" >&2
      ls -l "$build/fuzz-artifacts/$target" >&2 || true
      failed=1
    else
      grep -E '^(Done |stat::(number_of_executed_units|new_units_added|peak_rss_mb))' "$logs/$target.log" | sed "s/^/fuzz_$target: /" || true
    fi
  done
done
[ $failed = 0 ] || exit 1
echo "fuzz-smoke: OK, no crashes in ${secs}s per target"
