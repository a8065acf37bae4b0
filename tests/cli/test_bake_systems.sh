#!/usr/bin/env bash
# glow-bake --system-area (issue 16, item 2: a scene split into systems): the world manifest and one
# valid bake per system, the partition (every triangle in one system, no system above the area unless
# it is a single triangle, systems' areas summing to the scene's), budgets per system_area (surfels in
# proportion to each system's area), the same bytes for any thread count, each system loading and
# updating in the runtime, and the error paths (a bad --system-area: exit 2; too many systems and an
# unwritable manifest: exit 1 naming the file, no system bake left behind).
#   usage: test_bake_systems.sh BIN_DIR SHARED_DIR
set -u
BIN=$1
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
. "$(dirname "$0")/lib/common.sh"
BUDGET=(--surfels 1024 --links 16 --lightmap-caches 300 --lightmap-detail 1 -q)

mkdir -p "$T/w" "$T/w1" "$T/one"
expect 0 "pillar hall in systems of at most 100 m²" "$BIN/glow-bake" builtin:pillar-hall --system-area 100 "${BUDGET[@]}" \
  -o "$T/w/hall.json" --threads 2
grep -q "systems   4" "$T/out" && pass "  the summary names 4 systems" || { fail "  summary:"; head -3 "$T/out"; }
python3 - "$T/w/hall.json" <<'PY' && pass "  manifest: 4 systems, areas sum to the scene's 306.33, each <= 100, surfels ~ 1024 x area / 100" || fail "  manifest wrong"
import json, os, sys
m = json.load(open(sys.argv[1]))
assert m["glow_world"] == 1 and m["source"] == "builtin:pillar-hall" and m["system_area"] == 100, m
s = m["systems"]
assert len(s) == 4, len(s)
assert abs(sum(x["area"] for x in s) - 306.33) < 0.01, sum(x["area"] for x in s)
assert sum(x["triangles"] for x in s) == 236
for i, x in enumerate(s):
    assert x["index"] == i and x["file"] == "hall.s%03d.glow" % i, x
    assert 0 < x["area"] <= 100.0, x
    assert abs(x["surfels"] - 1024 * x["area"] / 100.0) <= 1, x
    assert x["bytes"] == os.path.getsize(os.path.join(os.path.dirname(sys.argv[1]), x["file"])), x
    assert all(a <= b for a, b in zip(x["bounds_min"], x["bounds_max"])), x
PY
for i in 0 1 2 3; do
  "$BIN/glow-bake" --info "$T/w/hall.s00$i.glow" > "$T/info" 2>&1 && grep -q "(valid)" "$T/info" || fail "  system $i: --info"
done
pass "  every system's bake is valid (--info)"
[ ! -e "$T/w/hall.glow" ] && [ -z "$(ls "$T/w" | grep -v -e '^hall.json$' -e '^hall.s00[0-3].glow$')" ] \
  && pass "  nothing else written (no temporaries)" || fail "  stray files: $(ls "$T/w")"

expect 0 "again with 1 thread" "$BIN/glow-bake" builtin:pillar-hall --system-area 100 "${BUDGET[@]}" -o "$T/w1/hall.json" --threads 1
same=1
for f in hall.json hall.s000.glow hall.s001.glow hall.s002.glow hall.s003.glow; do cmp -s "$T/w/$f" "$T/w1/$f" || { same=0; fail "  $f differs"; }; done
[ $same = 1 ] && pass "  the same bytes for 1 and 2 threads"

expect 0 "a system updates in the runtime (glow-bench, exact host)" "$BIN/glow-bench" "$T/w/hall.s002.glow" \
  "$ROOT/scenes/pillar-hall.json" --frames 2 --warmup 1 --threads 1 --no-machine -q

expect 0 "one system when the area is above the scene's" "$BIN/glow-bake" builtin:pillar-hall --system-area 1000 "${BUDGET[@]}" \
  -o "$T/one/hall.json"
python3 -c "import json,sys; m=json.load(open(sys.argv[1])); assert len(m['systems'])==1 and m['systems'][0]['surfels']==int(round(1024*306.33/1000))" \
  "$T/one/hall.json" && pass "  1 system, surfels 1024 x 306.33 / 1000" || fail "  one-system manifest"

expect 2 "--system-area 0" "$BIN/glow-bake" builtin:pillar-hall --system-area 0 -o "$T/bad.json"; err_has "--system-area"
expect 2 "--system-area -5" "$BIN/glow-bake" builtin:pillar-hall --system-area -5 -o "$T/bad.json"; err_has "--system-area"
expect 2 "--system-area abc" "$BIN/glow-bake" builtin:pillar-hall --system-area abc -o "$T/bad.json"; err_has "--system-area"
SPONZA="${2:-}/scenes/sponza/dabrovic/sponza.obj"
if [ -f "$SPONZA" ]; then
  mkdir -p "$T/many"
  expect 1 "more than 1000 systems (Sponza in 1 m² systems)" "$BIN/glow-bake" "$SPONZA" --system-area 1 "${BUDGET[@]}" -o "$T/many/w.json"
  err_has "at most 1000"
  [ -z "$(ls "$T/many")" ] && pass "  nothing written" || fail "  left behind: $(ls "$T/many")"
else
  echo "skip more than 1000 systems (no shared Sponza at $SPONZA)"
fi
expect 1 "an unwritable manifest" "$BIN/glow-bake" builtin:pillar-hall --system-area 100 "${BUDGET[@]}" -o "$T/no/such/dir/w.json"
err_has "w.json"
expect 2 "--audit-radiance with systems" "$BIN/glow-bake" builtin:pillar-hall --system-area 100 --audit-radiance "$T/x" -o "$T/a.json"
err_has "one system"
echo "$fails failure(s)"
[ "$fails" = 0 ]
