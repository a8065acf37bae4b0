#!/usr/bin/env bash
# glow-soak (issue 15, item 4) on a tiny bake: a short soak must pass its own checks (finite outputs
# every update, no drift between the converged state before and after, no memory growth, invalid
# artist calls refused), and bad arguments / a missing bake must fail cleanly. The 100k-update run
# is a benchmark (docs/results.md, "Soak").
#   usage: test_soak.sh BIN_DIR SHARED_DIR
set -u
BIN=$1
. "$(dirname "$0")/lib/common.sh"
"$BIN/glow-bake" builtin:cornell --surfels 512 --links 32 --quality low -o "$T/c.glow" -q >/dev/null 2>&1 \
  && pass "bake builtin:cornell" || fail "bake builtin:cornell"
expect 0 "1500-update soak" "$BIN/glow-soak" "$T/c.glow" --updates 1500 --every 250 --threads 2 --csv "$T/soak.csv" -q
grep -q "all checks passed" "$T/out" && pass "  all checks passed" || { fail "  soak checks"; cat "$T/out"; }
grep -q "non-finite outputs      0" "$T/out" && pass "  no non-finite output" || fail "  non-finite outputs"
refused=$(sed -n 's/.*invalid calls refused *\([0-9]*\) (accepted or changed state: 0).*/\1/p' "$T/out")
[ -n "$refused" ] && [ "$refused" -gt 0 ] && pass "  $refused invalid calls refused, none accepted" || fail "  invalid calls: '$refused'"
[ "$(wc -l < "$T/soak.csv")" = 7 ] && pass "  CSV: header + 6 windows" || fail "  CSV rows: $(wc -l < "$T/soak.csv")"
expect 2 "no bake" "$BIN/glow-soak"
expect 2 "--updates 0" "$BIN/glow-soak" "$T/c.glow" --updates 0
expect 2 "--every x" "$BIN/glow-soak" "$T/c.glow" --every x
expect 1 "missing bake" "$BIN/glow-soak" "$T/none.glow"
err_has "none.glow"
echo "$fails failure(s)"
[ "$fails" = 0 ]
