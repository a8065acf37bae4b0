#!/usr/bin/env bash
# The README's test command: installs dependencies, builds with warnings as errors, runs the
# libFuzzer smoke on the bake reader, the test suite under ASan+UBSan, then the test suite on the
# optimised build (its ctest summary is the last thing printed).
#   GLOW_FUZZ_SECONDS   fuzz smoke duration (default 30; 0 skips it)
#   GLOW_SKIP_ASAN=1    skip the sanitizer pass
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
jobs=$(nproc)

if [ "${GLOW_SKIP_ASAN:-0}" != 1 ]; then
  echo "== build + tests under ASan/UBSan"
  cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=Debug -DGLOW_SANITIZE=ON -DGLOW_WERROR=ON >/dev/null
  cmake --build build-asan -j "$jobs"
  ASAN_OPTIONS=detect_leaks=1:abort_on_error=0 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    ctest --test-dir build-asan --output-on-failure -j "$jobs" -LE slow
fi

fuzz_s=${GLOW_FUZZ_SECONDS:-30}
if [ "$fuzz_s" != 0 ]; then
  echo "== libFuzzer smoke on the bake reader (${fuzz_s} s)"
  bash tools/fuzz-smoke.sh "$fuzz_s"
fi

echo "== build (RelWithDebInfo, -Werror) + tests"
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DGLOW_WERROR=ON >/dev/null
cmake --build build -j "$jobs"
ctest --test-dir build --output-on-failure -j "$jobs"
