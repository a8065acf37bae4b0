#!/usr/bin/env bash
# glow-bench --backend gl (issue 5): the GL solver on a headless context reports every stage from timer
# queries, and its caches (read back, sampled by the C reference) give the CPU solver's indirect light at
# the probes within 1e-3 relative. Both sides light the surfels with shadow maps of the same design
# (GPU: glow_gl_lights; CPU: glow_host shadow-map kind). Prints SKIP and passes when there is no GL 4.5
# context (no EGL/OSMesa), as the C GPU tests do with exit 77.
set -u
BIN=$1
source "$(dirname "$0")/lib/common.sh"
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
"$BIN/glow-bake" builtin:cornell -o "$T/c.glow" --quality low >/dev/null 2>&1 || { echo "FAIL bake"; exit 1; }
SCENE=$ROOT/scenes/cornell-builtin-point.json
"$BIN/glow-bench" "$T/c.glow" "$SCENE" --backend gl --frames 4 --warmup 1 --json >"$T/gl.json" 2>"$T/gl.err"
rc=$?
if [ $rc -ne 0 ] && grep -q "no OpenGL 4.5 context" "$T/gl.err"; then
  echo "SKIP: $(cat "$T/gl.err")"; exit 0
fi
[ $rc -eq 0 ] && pass "glow-bench --backend gl runs" || { fail "glow-bench --backend gl: exit $rc"; cat "$T/gl.err"; }
expect 0 "glow-bench cpu (shadow-map host)" "$BIN/glow-bench" "$T/c.glow" "$SCENE" --host shadow-map --frames 4 --warmup 1 --json --no-machine
cp "$T/out" "$T/cpu.json"
# budgets on the GPU: a caches cap with an unbudgeted GL twin (the report gives its error), and a still
# light under converged_epsilon gathers nothing once converged
expect 0 "glow-bench --backend gl --budget-caches 64" "$BIN/glow-bench" "$T/c.glow" "$SCENE" --backend gl --frames 4 --warmup 1 --json --budget-caches 64
python3 -c "import json,sys; b=json.load(open(sys.argv[1]))['budget']; assert 64 <= b['median_caches_gathered'] <= 79 and 0 < b['luma_error_max'] < 1, b" "$T/out" \
  && pass "  64 caches (4 groups) gathered on the GPU, error against the GL twin reported" || fail "  GL budget JSON: $(head -c 300 "$T/out")"
expect 0 "glow-bench --backend gl --still --converge" "$BIN/glow-bench" "$T/c.glow" "$SCENE" --backend gl --frames 4 --warmup 40 --json --still --converge 0.01
python3 -c "import json,sys; b=json.load(open(sys.argv[1]))['budget']; assert b['median_caches_gathered'] == 0 and b['luma_error_max'] < 0.05, b" "$T/out" \
  && pass "  still light on the GPU: converged caches cost nothing" || fail "  GL converge JSON: $(head -c 300 "$T/out")"
python3 - "$T/gl.json" "$T/cpu.json" <<'PY' && pass "stages timed, probes agree with the CPU solver" || fail "GL bench output"
import json, sys
g = json.load(open(sys.argv[1])); c = json.load(open(sys.argv[2]))
assert g["backend"] == "gl" and c["backend"] == "cpu", (g.get("backend"), c.get("backend"))
ms = g["median_ms"]
for k in ("surfel_lighting", "pull", "cache_lighting", "output", "total"):
    assert ms[k] > 0, (k, ms[k])
assert ms["total"] >= ms["cache_lighting"]
worst = 0.0
for pg, pc in zip(g["probes"], c["probes"]):
    assert pg["ok"] and pc["ok"]
    for a, b in zip(pg["diffuse_up_rgb"], pc["diffuse_up_rgb"]):
        worst = max(worst, abs(a - b) / max(abs(b), 1e-6))
print("  worst probe difference GL vs CPU: %.2e relative; GL total %.3f ms on %s" % (worst, ms["total"], g["renderer"]))
assert worst < 1e-3, worst
PY
# A sky through openings (the shared Sponza, when present): the GPU hook gets each surfel's traced sky
# visibility (glow_host_sky_visibility -> glow_gl_lights_set_sky_visibility), so GL and CPU agree there too.
SP=$2/scenes/sponza
if [ -f "$SP/sponza-sun.json" ] && [ -f "$SP/dabrovic/sponza.obj" ]; then
  "$BIN/glow-bake" "$SP/dabrovic/sponza.obj" -o "$T/s.glow" --quality low >/dev/null 2>&1 || fail "bake sponza"
  expect 0 "sponza: gl" "$BIN/glow-bench" "$T/s.glow" "$SP/sponza-sun.json" --backend gl --frames 2 --warmup 1 --json
  cp "$T/out" "$T/sgl.json"
  expect 0 "sponza: cpu (shadow-map host)" "$BIN/glow-bench" "$T/s.glow" "$SP/sponza-sun.json" --host shadow-map --frames 2 --warmup 1 --json --no-machine
  python3 - "$T/sgl.json" "$T/out" <<'PY' && pass "  sponza probes agree (sky visibility on the GPU)" || fail "  sponza probes differ"
import json, sys
g = json.load(open(sys.argv[1])); c = json.load(open(sys.argv[2]))
worst = max(abs(a - b) / max(abs(b), 1e-6) for pg, pc in zip(g["probes"], c["probes"])
            for a, b in zip(pg["diffuse_up_rgb"], pc["diffuse_up_rgb"]))
print("  sponza worst probe difference GL vs CPU: %.2e relative" % worst)
assert worst < 2e-3, worst
PY
else
  echo "SKIP: shared Sponza missing: sky visibility agreement not checked"
fi
expect 0 "glow-bench --backend gl --gl-timing finish" "$BIN/glow-bench" "$T/c.glow" "$SCENE" --backend gl --gl-timing finish --frames 3 --warmup 1 --json
python3 -c "import json,sys; j=json.load(open('$T/out')); m=j['median_ms']; assert j['gl_timing']=='finish'; assert all(m[k]>0 for k in ('surfel_lighting','pull','cache_lighting','output','total')), m" \
  && pass "  every stage timed by glFinish" || fail "  finish timing"
expect 2 "bad --gl-timing" "$BIN/glow-bench" "$T/c.glow" "$SCENE" --backend gl --gl-timing never
expect 2 "bad --backend" "$BIN/glow-bench" "$T/c.glow" "$SCENE" --backend vulkan
err_has "--backend must be cpu or gl"
exit $fails
