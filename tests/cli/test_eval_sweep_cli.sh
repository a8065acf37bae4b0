#!/usr/bin/env bash
# glow-eval's sweeps at CI size (24x24) on the built-in Cornell box: results.csv with the block error
# and mean ratio, summary.md, charts, --bake-seeds averaging with its spread, and bad arguments.
# Split from test_eval_cli.sh (the other evaluation tools) so that the two run side by side.
#   usage: test_eval_sweep_cli.sh BIN_DIR SHARED_DIR
set -u
BIN=$1
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
. "$(dirname "$0")/lib/common.sh"

SCENE=$ROOT/scenes/cornell-builtin.json
# --- glow-eval quick (two settings of one parameter)
expect 0 "glow-eval quick" python3 "$ROOT/tools/glow-eval" sweep "$SCENE" --out "$T/eval" --quick --params chroma --bin "$BIN" \
  --width 24 --height 24 --ref-spp 8 --frames 3
[ "$(wc -l < "$T/eval/results.csv")" -ge 3 ] && pass "  results.csv has the rows" || fail "  results.csv short"
grep -q "rel. RMSE indirect" "$T/eval/summary.md" && pass "  summary.md written" || fail "  summary.md missing"
if command -v gnuplot >/dev/null; then
  [ -s "$T/eval/cornell-builtin_error_vs_time.png" ] && pass "  chart written" || fail "  chart missing"
fi
expect 2 "glow-eval: unknown parameter" python3 "$ROOT/tools/glow-eval" sweep "$SCENE" --out "$T/eval2" --params frob --bin "$BIN"
head -1 "$T/eval/results.csv" | grep -q "block_error_indirect" && head -1 "$T/eval/results.csv" | grep -q "mean_ratio_indirect" \
  && pass "  results.csv has the block error and mean ratio" || fail "  results.csv lacks block error / mean ratio"
# --bake-seeds: each setting baked with two surfel seeds, metrics averaged, block error's spread kept
expect 0 "glow-eval quick --bake-seeds 2" python3 "$ROOT/tools/glow-eval" sweep "$SCENE" --out "$T/eval4" --quick --params chroma \
  --bin "$BIN" --width 24 --height 24 --ref-spp 8 --frames 3 --bake-seeds 2
ls "$T/eval4/bakes/" | grep -q "_seed1.glow" && pass "  a seed-1 bake" || fail "  no seed-1 bake: $(ls "$T/eval4/bakes/")"
python3 - "$T/eval4/results.csv" <<'PY' && pass "  block error averaged over the seeds, with a spread" || fail "  seeds' block errors"
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
assert rows, "no rows"
for r in rows:
    lo, mid, hi = (float(r["block_error_indirect" + s]) for s in ("_min", "", "_max"))
    assert r["bake_seeds"] == "2" and lo <= mid <= hi, r
assert any(float(r["block_error_indirect_min"]) < float(r["block_error_indirect_max"]) for r in rows), "seeds gave equal images"
PY
expect 2 "glow-eval: --bake-seeds 0" python3 "$ROOT/tools/glow-eval" sweep "$SCENE" --out "$T/eval5" --bin "$BIN" --bake-seeds 0
err_has "bake-seeds"
expect 2 "glow-eval: --referee without indirect.pfm" python3 "$ROOT/tools/glow-eval" sweep "$SCENE" --out "$T/eval3" --bin "$BIN" \
  --referee "$T/no-referee"
err_has "indirect.pfm"

echo "$fails failure(s)"
[ "$fails" = 0 ]
