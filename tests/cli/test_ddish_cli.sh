#!/usr/bin/env bash
# glow-render --ddish and glow-eval ddish on bad input: a clear message and a non-zero exit, nothing
# run (each case is refused before any work; the method itself is tests/eval/test_render_ddish.c).
set -u
BIN=$1
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fail=0
expect() { # expect CODE PATTERN -- command...
    local code=$1 pat=$2
    shift 3
    "$@" >"$T/out" 2>"$T/err"
    local rc=$?
    if [ "$rc" != "$code" ] || ! grep -q -- "$pat" "$T/err"; then
        echo "FAIL: $* -> exit $rc (want $code), stderr:"; cat "$T/err"; fail=1
    fi
}
S=$ROOT/scenes/cornell-builtin.json
expect 2 "go with --ddish BAKE" -- "$BIN/glow-render" "$S" --out "$T/x" --ddish-rays 4
expect 2 "in \[0, 1)" -- "$BIN/glow-render" "$S" --out "$T/x" --ddish b.glow --ddish-hysteresis 1
expect 2 "1..65536" -- "$BIN/glow-render" "$S" --out "$T/x" --ddish b.glow --ddish-rays 0
expect 2 "one view at a time" -- "$BIN/glow-render" "$S" --out "$T/x" --ddish b.glow --glow b.glow
expect 2 "goes with --ddish-move" -- "$BIN/glow-render" "$S" --out "$T/x" --ddish b.glow --ddish-move-frame 3
expect 2 "needs --ddish-ref" -- "$BIN/glow-render" "$S" --out "$T/x" --ddish b.glow --ddish-ref-add a.exr
expect 2 "go together" -- "$BIN/glow-render" "$S" --out "$T/x" --glow b.glow --glow-move "$S"
expect 1 "$T/none.glow" -- "$BIN/glow-render" "$S" --out "$T/x" --ddish "$T/none.glow" -q
expect 2 "1..65536" -- python3 "$ROOT/tools/glow-eval" ddish "$S" --out "$T/e" --bin "$BIN" --ddish-rays 0
expect 2 "no such scene" -- python3 "$ROOT/tools/glow-eval" ddish "$S" --out "$T/e" --bin "$BIN" --move "$T/nope.json"
expect 2 "unknown preset" -- python3 "$ROOT/tools/glow-eval" ddish "$S" --out "$T/e" --bin "$BIN" --ddish-bake huge
exit $fail
