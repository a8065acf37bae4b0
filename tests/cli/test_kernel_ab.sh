#!/usr/bin/env bash
# The paired kernel A/B harness (docs/benchmarks.md): the prebuilt build/bin/kernel_ab (the harness with the
# library's kernel, timed as two versions) on a small bake must give identical outputs (difference 0) and
# the report lines; tools/kernel_ab.sh refuses bad input (exit 2) and a missing bake (exit 1) before it
# compiles anything. Nothing is compiled at test time.
#   usage: test_kernel_ab.sh BIN_DIR SHARED_DIR
set -u
BIN=$1
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
. "$(dirname "$0")/lib/common.sh"
BUILD=$(cd "$BIN/.." && pwd)
AB=$ROOT/tools/kernel_ab.sh

"$BIN/glow-bake" builtin:cornell -o "$T/cornell.glow" --quality low -q >/dev/null 2>&1 \
  && pass "bake builtin:cornell (low)" || fail "bake builtin:cornell"
expect 0 "worktree vs worktree (prebuilt), l = 3/2, 2 threads" "$BIN/kernel_ab" "$T/cornell.glow" 3 2 3 2
grep -q "l = 3/2, 2 thread(s), 3 iterations" "$T/out" && pass "  header" || fail "  no header: $(head -3 "$T/out")"
grep -q "^version 1: min .*max difference to version 0: 0.00e+00" "$T/out" && pass "  identical outputs" \
  || fail "  version 1 line: $(grep '^version 1: min' "$T/out")"
expect 2 "prebuilt: chroma above luma" "$BIN/kernel_ab" "$T/cornell.glow" 3 2 2 3
expect 2 "iteration count not a number" bash "$AB" "$BUILD" "$T/cornell.glow" worktree -- x 1
expect 2 "no revisions" bash "$AB" "$BUILD" "$T/cornell.glow"
expect 2 "chroma above luma" bash "$AB" "$BUILD" "$T/cornell.glow" worktree -- 3 1 2 3
expect 1 "missing bake" bash "$AB" "$BUILD" "$T/none.glow" worktree -- 1 1
[ "$fails" = 0 ] || exit 1
