#!/usr/bin/env bash
# Link gradients (glow-bake --link-subsets gradient; docs/linker.md "Link gradients"): a small bake of
# builtin:pillar-hall says how many links carry a gradient and --info says the mode; glow-render --glow
# and glow-bench (CPU) run with it and the indirect light stays within a few percent of the link-subsets
# bake's (finite: glow-compare's mean ratio); glow-bench --backend gl runs it too and its probes agree
# with the CPU solver's within 1e-3 relative (SKIP without a GL 4.5 context; gpu/test_gl_agreement
# compares every cache coefficient).
#   usage: test_link_gradients.sh BIN_DIR SHARED_DIR
set -u
BIN=$1
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
. "$(dirname "$0")/lib/common.sh"
B=(builtin:pillar-hall --surfels 1024 --texel-density 0.5 --grid-spacing 1.5 --links 32)
SCENE=$ROOT/scenes/pillar-hall.json
expect 0 "bake --link-subsets gradient" "$BIN/glow-bake" "${B[@]}" --link-subsets gradient -o "$T/g.glow"
err_has "link gradients: "
grep -q "link subsets gradient" "$T/out" && pass "  the summary says 'link subsets gradient'" || fail "  the summary lacks the mode: $(grep links "$T/out")"
expect 0 "default bake (link gradients since 2026-11-29)" "$BIN/glow-bake" "${B[@]}" -o "$T/dflt.glow"
grep -q "link subsets gradient" "$T/out" && pass "  the default is link gradients" || fail "  default mode: $(grep links "$T/out")"
expect 2 "bake --link-subsets bogus" "$BIN/glow-bake" "${B[@]}" --link-subsets bogus -o "$T/x.glow"
err_has "on, off or gradient"
expect 0 "--info" "$BIN/glow-bake" --info "$T/g.glow"
grep -q "link subsets gradient" "$T/out" && pass "  --info says 'link subsets gradient'" || fail "  --info lacks the mode: $(grep links "$T/out")"
expect 0 "bake with link subsets" "$BIN/glow-bake" "${B[@]}" --link-subsets on -o "$T/d.glow"
R=(--spp 4 --width 64 --height 36 -q)
expect 0 "glow-render --glow (gradients)" "$BIN/glow-render" "$SCENE" --glow "$T/g.glow" "${R[@]}" --out "$T/g"
expect 0 "glow-render --glow (link subsets)" "$BIN/glow-render" "$SCENE" --glow "$T/d.glow" "${R[@]}" --out "$T/d"
expect 0 "glow-compare gradients vs link subsets" "$BIN/glow-compare" "$T/g_indirect.exr" "$T/d_indirect.exr" --no-flip
ratio=$(awk '/mean ratio/ {print $3}' "$T/out")
python3 -c "import math,sys; r=float(sys.argv[1]); sys.exit(0 if math.isfinite(r) and 0.9 < r < 1.1 else 1)" "${ratio:-nan}" \
  && pass "  indirect finite, mean ratio $ratio to the link-subsets bake's" || fail "  indirect mean ratio '$ratio'"
expect 0 "glow-bench (CPU) with gradients" "$BIN/glow-bench" "$T/g.glow" "$SCENE" --frames 2 --warmup 1
"$BIN/glow-bench" "$T/g.glow" "$SCENE" --backend gl --frames 4 --warmup 1 --json >"$T/gl.json" 2>"$T/err"
rc=$?
if [ $rc -ne 0 ] && grep -q "no OpenGL 4.5 context" "$T/err"; then
  echo "SKIP: glow-bench --backend gl ($(head -c 200 "$T/err"))"
else
  [ $rc -eq 0 ] && pass "glow-bench --backend gl runs the bake" || fail "glow-bench --backend gl exit $rc: $(head -c 400 "$T/err")"
  grep -q "GLOW_ERROR" "$T/err" && fail "  glow-bench --backend gl logged an error: $(grep GLOW_ERROR "$T/err" | head -3)" \
    || pass "  no error logged"
  # its probes against the CPU solver lit the same way (shadow maps of the same design, as cli/test_bench_gl)
  expect 0 "glow-bench cpu (shadow-map host) with gradients" "$BIN/glow-bench" "$T/g.glow" "$SCENE" --host shadow-map \
    --frames 4 --warmup 1 --json --no-machine
  cp "$T/out" "$T/cpu.json"
  python3 - "$T/gl.json" "$T/cpu.json" <<'PY' && pass "  GL probes agree with the CPU solver's" || fail "  GL vs CPU probes with link gradients"
import json, sys
g = json.load(open(sys.argv[1])); c = json.load(open(sys.argv[2]))
worst = 0.0
for pg, pc in zip(g["probes"], c["probes"]):
    assert pg["ok"] and pc["ok"]
    for a, b in zip(pg["diffuse_up_rgb"], pc["diffuse_up_rgb"]):
        worst = max(worst, abs(a - b) / max(abs(b), 1e-6))
print("     worst probe difference GL vs CPU: %.2e relative (%d probes)" % (worst, len(g["probes"])))
assert len(g["probes"]) > 0 and worst < 1e-3, worst
PY
fi
# the audit (glow-bake --audit-radiance, single-bounce surfel radiance under the scene's light): the
# quantised codes the runtime reads gather closer to the exact sum than the link subsets (pillar hall,
# 32 links: 0.030 against 0.064) and within 10 % of the unquantised gradient (0.029)
expect 0 "surfel radiance (glow-stability audit)" "$BIN/glow-stability" audit "$T/d.glow" "$SCENE" --probes 8 --samples 8 \
  --radiance-out "$T/radiance.bin"
rms() { grep "link alternatives audit" "$T/err" | sed -n "s/.*$1: \/ exact [0-9.]*, rel\. RMS error \([0-9.]*\),.*/\1/p"; }
expect 0 "audit, link subsets" "$BIN/glow-bake" "${B[@]}" --link-subsets on -o "$T/x.glow" --audit-radiance "$T/radiance.bin"
sub=$(rms "its link subsets (what this bake's runtime reads)")
expect 0 "audit, link gradients" "$BIN/glow-bake" "${B[@]}" -o "$T/x.glow" --audit-radiance "$T/radiance.bin" --link-subsets gradient
grd=$(rms "its link gradient codes (what this bake's runtime reads)")
ideal=$(rms "its node's mean moved by the response gradient to the flux centroid")
echo "     rel. RMS over the caches: link subsets $sub, gradient codes $grd, unquantised gradient $ideal"
python3 -c "import sys; s, g, i = map(float, sys.argv[1:]); sys.exit(0 if g < s and g < 1.1 * i else 1)" "${sub:-nan}" "${grd:-nan}" "${ideal:-nan}" \
  && pass "  the gradient codes beat the subsets and lose under 10 % to quantisation" || fail "  audit: subsets '$sub', codes '$grd', gradient '$ideal'"
[ $fails -eq 0 ] && echo "all passed" || { echo "$fails failed"; exit 1; }
