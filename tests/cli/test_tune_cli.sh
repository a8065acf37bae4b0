#!/usr/bin/env bash
# CLI behaviour of glow-tune (docs/tune.md): the bounce tuning report on the built-in Cornell box at
# --quality low, 12 updates. Checks exit codes and messages for bad input, that summary.json parses and
# holds finite, positive energies, that more bounce intensity means more indirect light, that bounce 0
# converges at once, that k bounce iterations per update reach update k*u's energy after u updates, the
# chart (a PNG when gnuplot is installed; "chart": null without it), and the white furnace's exact answer
# (closed cube, albedo 0.5, emission 1: indirect flux = 24 m^2 x pi / (1 - bounce/2)).
#   usage: test_tune_cli.sh BIN_DIR SHARED_DIR
set -u
BIN=$1
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
. "$(dirname "$0")/lib/common.sh"
SCENE=$ROOT/scenes/cornell-builtin-point.json
TUNE=$BIN/glow-tune

"$BIN/glow-bake" builtin:cornell -o "$T/cornell.glow" --quality low -q >/dev/null 2>&1 \
  && pass "bake builtin:cornell (low)" || fail "bake builtin:cornell"

# --- bad command lines: exit 2
expect 2 "no arguments" "$TUNE"
expect 2 "one argument" "$TUNE" "$T/cornell.glow"
expect 2 "unknown option" "$TUNE" "$T/cornell.glow" "$SCENE" --frobnicate; err_has "frobnicate"
expect 2 "--iterations 0" "$TUNE" "$T/cornell.glow" "$SCENE" --iterations 0; err_has "iterations"
expect 2 "--epsilon 1" "$TUNE" "$T/cornell.glow" "$SCENE" --epsilon 1
expect 2 "--bounce out of [0,1]" "$TUNE" "$T/cornell.glow" "$SCENE" --bounce 0,1.5; err_has "bounce"
expect 2 "--per-update 0" "$TUNE" "$T/cornell.glow" "$SCENE" --per-update 1,0
expect 2 "--host unknown" "$TUNE" "$T/cornell.glow" "$SCENE" --host gpu
expect 2 "--chroma above --luma" "$TUNE" "$T/cornell.glow" "$SCENE" --luma 2 --chroma 3
expect 0 "--help" "$TUNE" --help
grep -q "usage: glow-tune" "$T/out" && pass "  usage on stdout" || fail "  no usage on stdout"

# --- bad input: exit 1, the message names the file
expect 1 "missing bake" "$TUNE" "$T/none.glow" "$SCENE" --out "$T/o-missing" -q; err_has "none.glow"
head -c 1000 "$T/cornell.glow" > "$T/cut.glow"
expect 1 "truncated bake" "$TUNE" "$T/cut.glow" "$SCENE" --out "$T/o-cut" -q; err_has "cut.glow"
expect 1 "missing scene" "$TUNE" "$T/cornell.glow" "$T/none.json" --out "$T/o-missing" -q; err_has "none.json"
echo '{"mesh": ' > "$T/broken.json"
expect 1 "broken scene JSON" "$TUNE" "$T/cornell.glow" "$T/broken.json" --out "$T/o-broken" -q; err_has "broken.json"
touch "$T/afile"
expect 1 "output folder is a file" "$TUNE" "$T/cornell.glow" "$SCENE" --out "$T/afile" -q; err_has "afile"

# --- the report
expect 0 "cornell, 12 updates" "$TUNE" "$T/cornell.glow" "$SCENE" --iterations 12 --out "$T/tune"
grep -q "bounce intensity sweep" "$T/out" && pass "  sweep table printed" || fail "  no sweep table"
for f in summary.json convergence.dat convergence.gp; do [ -s "$T/tune/$f" ] && pass "  wrote $f" || fail "  missing $f"; done
python3 - "$T/tune/summary.json" "$(command -v gnuplot >/dev/null && echo yes || echo no)" <<'EOF' \
  && pass "  summary.json: energies finite and positive, bounce 1 > bounce 0, bounce 0 converged within 2, k per update = update k*u, chart" \
  || fail "  summary.json checks"
import json, math, sys
d = json.load(open(sys.argv[1]))
ok = True
def check(cond, what):
    global ok
    if not cond:
        print("     FAIL:", what)
        ok = False
sweep = {r["bounce_intensity"]: r for r in d["bounce_sweep"]}
check(sorted(sweep) == [0, 0.25, 0.5, 0.75, 1], "default bounce sweep %s" % sorted(sweep))
for b, r in sweep.items():
    check(len(r["energy_luma"]) == 12 and len(r["energy_rgb"]) == 12, "12 energies at bounce %g" % b)
    check(all(isinstance(e, float) and math.isfinite(e) and e > 0 for e in r["energy_luma"]), "energies finite > 0 at %g" % b)
    check(all(math.isfinite(c) and c > 0 for e in r["energy_rgb"] for c in e), "RGB energies finite > 0 at %g" % b)
    check(r["median_update_ms"] > 0, "median update time at %g" % b)
e = [sweep[b]["converged_energy_luma"] for b in (0, 0.25, 0.5, 0.75, 1)]
check(e[4] > 1.5 * e[0], "energy(bounce 1) %g > 1.5 x energy(bounce 0) %g" % (e[4], e[0]))
check(all(a < b for a, b in zip(e, e[1:])), "energy grows with bounce intensity %s" % e)
check(all(abs(x - e[0]) < 1e-4 * e[0] for x in [r["energy_luma"][0] for r in sweep.values()]),
      "the first update (single bounce) is the same at every bounce intensity")
b0 = sweep[0]
check(b0["updates_to_converge"] is not None and b0["updates_to_converge"] <= 2, "bounce 0 converges within 2 updates: %s" % b0["updates_to_converge"])
check(max(b0["relative_change"][1:]) < 1e-5, "bounce 0 does not change after update 1")
b1 = sweep[1]
check(b1["updates_to_converge"] is not None and 3 <= b1["updates_to_converge"] <= 11, "bounce 1 converges in 3..11 updates: %s" % b1["updates_to_converge"])
check(0.3 < b1["asymptotic_ratio"] < 0.9, "bounce 1 ratio %s in (0.3, 0.9)" % b1["asymptotic_ratio"])
check(0.9 < b1["asymptotic_transport"] <= 1.01, "closed box: transport %s about 1" % b1["asymptotic_transport"])
check(0.1 < sweep[0.5]["asymptotic_ratio"] < 0.6 * b1["asymptotic_ratio"], "ratio(0.5) about half ratio(1)")
# k bounce iterations per update: update u holds iteration k*u of the one-per-update run (measured, not assumed)
per = {r["iterations_per_update"]: r for r in d["per_update_sweep"]}
check(sorted(per) == [1, 2, 4], "per-update runs %s" % sorted(per))
for k in (2, 4):
    for u in range(1, 12 // k + 1):
        a, b = per[k]["energy_luma"][u - 1], b1["energy_luma"][k * u - 1]
        check(abs(a - b) < 1e-4 * b, "k=%d update %d (%g) = iteration %d (%g)" % (k, u, a, k * u, b))
c = [per[k]["updates_to_converge"] for k in (1, 2, 4)]
check(all(x is not None for x in c) and c[0] > c[1] > c[2] >= 1, "more iterations per update, fewer updates: %s" % c)
check(d["energy"]["unit"] == "W" and d["energy"]["surfels_missed"] == 0, "energy unit W, every surfel sampled")
if sys.argv[2] == "yes":
    check(d["chart"] is not None and d["chart"].endswith("convergence.png"), "chart named: %s" % d["chart"])
else:
    check(d["chart"] is None, "chart null without gnuplot")
sys.exit(0 if ok else 1)
EOF
if command -v gnuplot >/dev/null; then
  [ "$(head -c 8 "$T/tune/convergence.png" | od -An -tx1 | tr -d ' \n')" = 89504e470d0a1a0a ] \
    && pass "  convergence.png is a PNG" || fail "  convergence.png missing or not a PNG"
fi
grep -c '^1 ' "$T/tune/convergence.dat" | grep -qx 8 && pass "  convergence.dat: 5 + 3 runs" || fail "  convergence.dat runs"

# --- --json on stdout equals summary.json; no gnuplot on PATH: warning, "chart": null, exit 0
expect 0 "--json, gnuplot not on PATH" env PATH=/nonexistent "$TUNE" "$T/cornell.glow" "$SCENE" --iterations 3 --bounce 0,1 \
  --per-update 1 --out "$T/nochart" --json
err_has "gnuplot"
cmp -s "$T/out" "$T/nochart/summary.json" && pass "  stdout is summary.json" || fail "  stdout differs from summary.json"
python3 -c "import json,sys; d=json.load(open(sys.argv[1])); sys.exit(0 if d['chart'] is None and len(d['bounce_sweep'])==2 else 1)" \
  "$T/nochart/summary.json" && pass "  \"chart\": null" || fail "  chart not null"
[ ! -e "$T/nochart/convergence.png" ] && pass "  no PNG" || fail "  a PNG without gnuplot"

# --- shadow-map host, other bands, one thread
expect 0 "shadow-map host, luma 2 chroma 1, 1 thread" "$TUNE" "$T/cornell.glow" "$SCENE" --host shadow-map --luma 2 --chroma 1 \
  --threads 1 --iterations 4 --bounce 1 --per-update 1 --no-chart --out "$T/sm" -q
python3 -c "import json,sys; d=json.load(open(sys.argv[1])); s=d['settings']; sys.exit(0 if s['host']=='shadow-map' and s['luma']==2 and s['chroma']==1 and d['chart'] is None else 1)" \
  "$T/sm/summary.json" && pass "  settings recorded" || fail "  settings"

# --- the white furnace: indirect flux arriving at the walls = 24 m^2 x pi x L, L = 1/(1 - bounce/2)
"$BIN/glow-bake" builtin:furnace -o "$T/furnace.glow" --quality low -q >/dev/null 2>&1 && pass "bake builtin:furnace (low)" || fail "bake builtin:furnace"
echo '{"mesh": "builtin:furnace"}' > "$T/furnace.json"
expect 0 "furnace, 40 updates" "$TUNE" "$T/furnace.glow" "$T/furnace.json" --iterations 40 --bounce 0,0.5,1 --per-update 1 --no-chart --out "$T/furnace" -q
python3 - "$T/furnace/summary.json" <<'EOF' && pass "  furnace: 24 pi / (1 - b/2) within 1 %, ratio b/2, transport 1, emitted 24 pi" || fail "  furnace energies"
import json, math, sys
d = json.load(open(sys.argv[1]))
ok = True
for r in d["bounce_sweep"]:
    b = r["bounce_intensity"]
    want = 24 * math.pi / (1 - b / 2)
    got = r["converged_energy_luma"]
    if abs(got - want) > 0.01 * want:
        print("     bounce %g: %g, want %g" % (b, got, want)); ok = False
    if b > 0 and (abs(r["asymptotic_ratio"] - b / 2) > 0.02 or abs(r["asymptotic_transport"] - 1) > 0.02):
        print("     bounce %g: ratio %s transport %s" % (b, r["asymptotic_ratio"], r["asymptotic_transport"])); ok = False
    if abs(r["transport"][0] - 1) > 0.01:
        print("     bounce %g: update 1 gathers %s of what the walls emit, want 1" % (b, r["transport"][0])); ok = False
s = d["sources"]
if abs(s["source_flux_luma"] - 24 * math.pi) > 1e-3 * 24 * math.pi or s["direct_flux_luma"] != 0:
    print("     sources %s, want emitted 24 pi and no direct light" % s); ok = False
sys.exit(0 if ok else 1)
EOF

echo "$fails failure(s)"
[ "$fails" = 0 ]
