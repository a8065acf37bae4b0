#!/usr/bin/env bash
# The README's test command: installs dependencies, builds with warnings as errors, runs the test
# suite under ASan+UBSan (all but the "slow" tests), the libFuzzer smoke (bake reader; load + updates;
# scene JSON; mesh import; two at a time on two cores), then the test suite on the optimised build (all
# but the CLI scripts and GL tests, which ran under the sanitizers: label asan-only) and the installed SDK's consumer
# test (tools/consumer-test.sh). The sanitizer build is -O1 (CMakeLists.txt, GLOW_SANITIZE: about half the
# -O0 test time; the cache-lighting kernel with -g1, which GCC compiles in about a minute). Every stage
# runs even when an earlier one failed (a red sanitizer pass must not hide what the fuzzer or the
# release pass would say); the exit status is non-zero when any failed, and the last lines name the
# stages that did.
#   GLOW_FUZZ_SECONDS   fuzz smoke duration per target (default 20; 0 skips it)
#   GLOW_SKIP_ASAN=1    skip the sanitizer pass
set -uo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh || { echo "test.sh: tools/setup.sh failed" >&2; exit 1; }
jobs=$(nproc)
# The tests call python3 about 150 times (their JSON and CSV checks, glow-eval). Where a version
# manager's shim comes first in PATH (pyenv's is a shell script that looks the version up on every
# call) that costs 0.35 s a call against 0.05 s for the interpreter itself, on this project's 2-core
# machine: the interpreter the shim chooses is looked up once and its folder put first in PATH.
if py=$(python3 -c 'import sys; print(sys.executable)' 2>/dev/null) && [ -x "$py" ]; then
  export PATH="$(dirname "$py"):$PATH"
fi
failed=()

stage() { # stage NAME COMMAND...: runs it, records a failure, never stops the script
  local name=$1; shift
  local t0=$SECONDS
  if "$@"; then echo "== $name: passed ($((SECONDS - t0)) s)"
  else echo "== $name: FAILED ($((SECONDS - t0)) s)"; failed+=("$name"); fi
}

asan_pass() {
  cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=Debug -DGLOW_SANITIZE=ON -DGLOW_WERROR=ON >/dev/null &&
    cmake --build build-asan -j "$jobs" &&
    ASAN_OPTIONS=detect_leaks=1:abort_on_error=0 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
      ctest --test-dir build-asan --output-on-failure -j "$jobs" -LE slow
}
release_pass() {
  cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DGLOW_WERROR=ON >/dev/null &&
    cmake --build build -j "$jobs" &&
    ctest --test-dir build --output-on-failure -j "$jobs" "${release_skip[@]}"
}
# The CLI scripts and GL tests run once, in the sanitizer pass (label asan-only, tests/CMakeLists.txt); with that pass
# skipped the release pass runs them.
release_skip=(-LE asan-only)
[ "${GLOW_SKIP_ASAN:-0}" != 1 ] || release_skip=()

if [ "${GLOW_SKIP_ASAN:-0}" != 1 ]; then
  echo "== build + tests under ASan/UBSan"
  stage "ASan/UBSan tests" asan_pass
fi

fuzz_s=${GLOW_FUZZ_SECONDS:-20}
if [ "$fuzz_s" != 0 ]; then
  echo "== libFuzzer smoke: bake reader, load + 3 updates, scene JSON, mesh import (${fuzz_s} s each)"
  stage "fuzz smoke" bash tools/fuzz-smoke.sh "$fuzz_s"
fi

echo "== build (RelWithDebInfo, -Werror) + tests"
stage "release tests" release_pass

echo "== SDK: install, then out-of-tree consumers (find_package, pkg-config, add_subdirectory)"
stage "SDK consumer" bash tools/consumer-test.sh build

if [ ${#failed[@]} -gt 0 ]; then
  printf 'test.sh: FAILED: %s\n' "${failed[@]}" >&2
  exit 1
fi
echo "test.sh: all stages passed"
