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
nsys=$(sed -n 's/^  systems   \([0-9]*\).*/\1/p' "$T/out")
# 306 m² in cells of at most 100 m²: at least 4; the split at the least crossed of the cell's planes
# (not its middle) may take a few more
[ -n "$nsys" ] && [ "$nsys" -ge 4 ] && [ "$nsys" -le 8 ] && pass "  the summary names $nsys systems (4..8)" \
  || { fail "  summary:"; head -3 "$T/out"; }
python3 - "$T/w/hall.json" "$nsys" <<'PY' && pass "  manifest: $nsys systems, areas sum to the scene's 306.33, each <= 100, surfels ~ 1024 x area / 100" || fail "  manifest wrong"
import json, os, sys
m = json.load(open(sys.argv[1]))
assert m["glow_world"] == 1 and m["source"] == "builtin:pillar-hall" and m["system_area"] == 100, m
s = m["systems"]
assert len(s) == int(sys.argv[2]), len(s)
assert abs(sum(x["area"] for x in s) - 306.33) < 0.01, sum(x["area"] for x in s)
# the hall's 236 triangles, of which the 88 with an edge longer than a quarter of sqrt(100) m are cut
# in four (pipeline.c, split_large_triangles): 236 + 3 x 88
assert sum(x["triangles"] for x in s) == 500, sum(x["triangles"] for x in s)
import re
for i, x in enumerate(s):
    assert x["index"] == i and re.fullmatch(r"hall\.s[0-9]+-[0-9a-f]+-[0-9a-f]{16}\.glow", x["file"]), x
    assert x["file"].endswith(x["key"] + ".glow"), x
    assert 0 < x["area"] <= 100.0, x
    assert abs(x["surfels"] - 1024 * x["area"] / 100.0) <= 1, x
    assert x["bytes"] == os.path.getsize(os.path.join(os.path.dirname(sys.argv[1]), x["file"])), x
    assert all(a <= b for a, b in zip(x["bounds_min"], x["bounds_max"])), x
PY
files() { python3 -c "import json,sys; print(' '.join(x['file'] for x in json.load(open(sys.argv[1]))['systems']))" "$1"; }
ok=1
for f in $(files "$T/w/hall.json"); do
  "$BIN/glow-bake" --info "$T/w/$f" > "$T/info" 2>&1 && grep -q "(valid)" "$T/info" || { ok=0; fail "  $f: --info"; }
done
[ $ok = 1 ] && pass "  every system's bake is valid (--info)"
[ "$(ls "$T/w" | sort | tr '\n' ' ')" = "$( (echo hall.json; files "$T/w/hall.json" | tr ' ' '\n') | sort | tr '\n' ' ')" ] \
  && pass "  nothing else written (no temporaries)" || fail "  stray files: $(ls "$T/w")"

expect 0 "again with 1 thread" "$BIN/glow-bake" builtin:pillar-hall --system-area 100 "${BUDGET[@]}" -o "$T/w1/hall.json" --threads 1
same=1
for f in hall.json $(files "$T/w/hall.json"); do cmp -s "$T/w/$f" "$T/w1/$f" || { same=0; fail "  $f differs"; }; done
[ $same = 1 ] && pass "  the same bytes for 1 and 2 threads"
expect 0 "again into the same world: every system unchanged" "$BIN/glow-bake" builtin:pillar-hall --system-area 100 \
  "${BUDGET[@]}" -o "$T/w1/hall.json" --threads 2
grep -q "0 of them baked and $nsys unchanged" "$T/out" && pass "  0 baked, $nsys kept" || { fail "  summary:"; head -3 "$T/out"; }
same=1
for f in hall.json $(files "$T/w/hall.json"); do cmp -s "$T/w/$f" "$T/w1/$f" || { same=0; fail "  $f differs"; }; done
[ $same = 1 ] && pass "  the same bytes"

first=$(files "$T/w/hall.json" | cut -d' ' -f3)
expect 0 "a system updates in the runtime (glow-bench, exact host)" "$BIN/glow-bench" "$T/w/$first" \
  "$ROOT/scenes/pillar-hall.json" --frames 2 --warmup 1 --threads 1 --no-machine -q

# the whole world in the runtime (glow-bench WORLD.json: every system in one glow_world, issue 17 item 1):
# all systems update, their dependencies attached; a time budget far too small updates one a frame
expect 0 "the world updates in the runtime (glow-bench WORLD.json)" "$BIN/glow-bench" "$T/w/hall.json" \
  "$ROOT/scenes/pillar-hall.json" --frames 3 --warmup 1 --threads 1 --no-machine -q --json
cp "$T/out" "$T/bench_all.json"
expect 0 "the world under a 0.001 ms budget (glow-bench --budget-ms 0.001 --walk)" "$BIN/glow-bench" "$T/w/hall.json" \
  "$ROOT/scenes/pillar-hall.json" --frames 3 --warmup 1 --threads 1 --no-machine -q --json --budget-ms 0.001 --walk
cp "$T/out" "$T/bench_budget.json"
python3 - "$T/bench_all.json" "$T/bench_budget.json" "$nsys" <<'PY' && pass "  every system updated and linked; under the budget one a frame, its error against the twin reported" \
  || fail "  glow-bench's world report is wrong"
import json, sys
def load(p):
    t = open(p).read()
    return json.loads(t[t.index("{"):])
a, b, n = load(sys.argv[1]), load(sys.argv[2]), int(sys.argv[3])
assert a["systems"] == n and a["median_systems_updated"] == n and a["dependencies_attached"] > 0, a
assert a["median_update_ms"] > 0 and a["median_caches_gathered"] == a["caches"], a
assert b["systems"] == n and b["median_systems_updated"] == 1 and b["median_caches_gathered"] < b["caches"], b
assert b["budget"]["luma_error_mean"] > 0 and "walk_near_error_mean" in b["budget"], b
PY
# --stream R: only the systems within R of the walking focus loaded; the rest streamed in (a new system,
# its host prepared) and out (destroyed) between updates; each streamed-in system's first update counted
expect 0 "the world streamed along the walk (glow-bench --budget-ms 0.001 --walk --stream 2)" "$BIN/glow-bench" \
  "$T/w/hall.json" "$ROOT/scenes/pillar-hall.json" --frames 24 --warmup 1 --threads 1 --no-machine -q --json \
  --budget-ms 0.001 --walk --stream 2
python3 - "$T/out" "$nsys" <<'PY' && pass "  systems streamed in and out; each streamed-in one updated first and alone (one system a frame)" \
  || fail "  glow-bench's stream report is wrong"
import json, sys
t = open(sys.argv[1]).read()
b, n = json.loads(t[t.index("{"):]), int(sys.argv[2])
st = b["budget"]["stream"]
assert st["streamed_in"] >= 1 and st["streamed_out"] >= 1 and st["median_systems_loaded"] < n, st
assert 1 <= st["first_updates"] <= st["streamed_in"] and b["median_systems_updated"] == 1, b
assert b["budget"]["updates_over_1_25x_budget"] >= 0 and b["budget"]["max_update_ms"] > 0, b
PY
expect 2 "--stream without --walk" "$BIN/glow-bench" "$T/w/hall.json" "$ROOT/scenes/pillar-hall.json" --budget-ms 1 \
  --stream 2 --no-machine -q
err_has "--stream"
printf '{"glow_world": 1, "systems": []}' > "$T/empty.json"
expect 1 "glow-bench on a manifest with no systems" "$BIN/glow-bench" "$T/empty.json" "$ROOT/scenes/pillar-hall.json" \
  --frames 1 --no-machine -q
err_has "empty.json: not a world manifest"

# An incremental re-bake (issue 16, item 3): 16 boxes in a 4 x 4 grid, 3 m apart; one box moves. Only
# the systems whose inputs changed are baked again, and the world is byte for byte a full bake of the
# edited scene; the file of the box's old system is gone.
boxes() { # boxes OUT.obj LIFT: unit boxes, box 0 lifted by LIFT
  python3 - "$1" "$2" <<'PY'
import sys
out, lift = sys.argv[1], float(sys.argv[2])
f = open(out, "w"); v = 0
for i in range(4):
    for j in range(4):
        x0, z0, y0 = 3.0 * i, 3.0 * j, (lift if i == 0 and j == 0 else 0.0)
        c = [(x0 + a, y0 + b, z0 + d) for a in (0, 1) for b in (0, 1) for d in (0, 1)]
        for p in c: f.write("v %g %g %g\n" % p)
        for q in ((0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)):
            f.write("f %d %d %d %d\n" % tuple(v + k + 1 for k in q))
        v += 8
PY
}
boxes "$T/a.obj" 0; boxes "$T/b.obj" 0.25
SMALL=(--system-area 12 --surfels 256 --links 16 --lightmap-caches 64 --lightmap-detail 1 -q)
mkdir -p "$T/inc" "$T/full"
expect 0 "boxes: a world" "$BIN/glow-bake" "$T/a.obj" "${SMALL[@]}" -o "$T/inc/w.json"
n=$(python3 -c "import json,sys; print(len(json.load(open(sys.argv[1]))['systems']))" "$T/inc/w.json")
cp "$T/b.obj" "$T/a.obj"
cp "$T/inc/w.json" "$T/old.json"
expect 0 "boxes: box 0 moved, re-baked into the same world" "$BIN/glow-bake" "$T/a.obj" "${SMALL[@]}" -o "$T/inc/w.json"
# baked again: the systems whose own inputs changed (the moved box's) and those that link their trees
# (light across systems: a system's key holds its neighbours' own keys), nothing else
python3 - "$T/old.json" "$T/inc/w.json" "$T/out" <<'PY' && pass "  baked again: exactly the systems whose inputs changed and those that link a changed tree" \
  || fail "  the wrong systems were baked again"
import json, re, sys
old = json.load(open(sys.argv[1]))["systems"]; new = json.load(open(sys.argv[2]))["systems"]
old_files = {x["file"] for x in old}
old_tree = {x["system_key"] for x in old}; old_in = {x["inputs_key"] for x in old}
baked = [x for x in new if x["file"] not in old_files]
# a system's inputs: its triangles and the occluders it traces; its tree key: what its surfels and tree
# (which the systems that link it index) follow from, its triangles and the occluders near it
changed_tree = {x["system_key"] for x in new if x["system_key"] not in old_tree}
want = [x for x in new if x["inputs_key"] not in old_in or any(d in changed_tree for d in x["dependencies"])]
assert [x["index"] for x in baked] == [x["index"] for x in want], (baked, want)
assert 1 <= len(changed_tree) < len(new) and len(baked) < len(new), (changed_tree, len(baked))
print("  (%d systems' trees changed, %d of %d baked again)" % (len(changed_tree), len(baked), len(new)))
summary = open(sys.argv[3]).read()
assert re.search(r"systems   %d, %d of them baked and %d unchanged" % (len(new), len(baked), len(new) - len(baked)), summary), summary[:300]
# the trees those systems link that did not change are read from their previous bakes (PTRE), not built
# again: in index order, each neighbour's tree once, unless the old world lacks it or it was baked (and
# so built) before
have, read = set(), 0
for x in sorted(baked, key=lambda x: x["index"]):
    for d in x["dependencies"]:
        if d not in have and d in old_tree:
            read += 1
        have.add(d)
    have.add(x["system_key"])
m = re.search(r"proxy nodes; (\d+) neighbours' trees read from their bakes", summary)
assert m and int(m.group(1)) == read >= 1, (m and m.group(0), read)
print("  (%d neighbours' trees read from their previous bakes)" % read)
PY
expect 0 "boxes: a full bake of the edited scene" "$BIN/glow-bake" "$T/a.obj" "${SMALL[@]}" -o "$T/full/w.json"
[ "$(ls "$T/inc" | tr '\n' ' ')" = "$(ls "$T/full" | tr '\n' ' ')" ] && pass "  the same files (the moved box's old one removed)" \
  || fail "  files differ: $(ls "$T/inc") / $(ls "$T/full")"
same=1
for f in $(ls "$T/full"); do cmp -s "$T/inc/$f" "$T/full/$f" || { same=0; fail "  $f differs"; }; done
[ $same = 1 ] && pass "  byte for byte the full bake"
# A previous bake's PTRE that fails its CRC is not read: the re-bake builds those trees again and
# writes the same bytes (the kept files are the damaged ones, so only the baked ones are compared).
mkdir -p "$T/cor"
boxes "$T/a0.obj" 0
expect 0 "boxes: a world whose PTRE sections are then damaged" "$BIN/glow-bake" "$T/a0.obj" "${SMALL[@]}" -o "$T/cor/w.json"
python3 - "$T/cor" <<'PY' && pass "  a byte of every PTRE payload flipped" || fail "  could not damage PTRE"
import os, struct, sys
d = sys.argv[1]; hit = 0
for f in os.listdir(d):
    if not f.endswith(".glow"): continue
    b = bytearray(open(os.path.join(d, f), "rb").read())
    for i in range(struct.unpack_from("<I", b, 12)[0]):
        e = 64 + 32 * i
        if b[e:e + 4] == b"PTRE":
            off, size = struct.unpack_from("<QQ", b, e + 8)
            b[off + size - 1] ^= 0x55; hit += 1
    open(os.path.join(d, f), "wb").write(b)
assert hit >= 2, hit
PY
cp "$T/cor/w.json" "$T/cor_old.json"
expect 0 "boxes: box 0 moved, re-baked over the damaged world" "$BIN/glow-bake" "$T/a.obj" "${SMALL[@]}" -o "$T/cor/w.json"
grep -q "proxy nodes; 0 neighbours' trees read" "$T/out" && pass "  no damaged tree read" \
  || fail "  summary: $(grep 'across  ' "$T/out")"
same=1; nb=0
for f in $(python3 -c "import json,sys; o={x['file'] for x in json.load(open(sys.argv[1]))['systems']}; print(' '.join(x['file'] for x in json.load(open(sys.argv[2]))['systems'] if x['file'] not in o))" "$T/cor_old.json" "$T/cor/w.json"); do
  nb=$((nb + 1)); cmp -s "$T/cor/$f" "$T/full/$f" || { same=0; fail "  $f differs"; }
done
[ $same = 1 ] && [ $nb -ge 1 ] && pass "  the $nb systems baked again are byte for byte the full bake's"
# Triangles inserted before a system's in the file move their indices (GEOM's `source`) but nothing the
# system's light follows from: a degenerate triangle put first (the importer drops it, every later
# index moves by one) re-indexes every system's file instead of baking it, byte for byte a full bake.
{ printf 'v 0 0 0\nv 0 0 0\nv 1 0 0\nf 1 2 3\n'; awk '/^f /{printf "f"; for (i = 2; i <= NF; i++) printf " %d", $i + 3; print ""; next} {print}' "$T/b.obj"; } >"$T/a.obj"
expect 0 "boxes: a triangle put first in the file, re-baked into the same world" "$BIN/glow-bake" "$T/a.obj" "${SMALL[@]}" -o "$T/inc/w.json"
grep -q "0 of them baked and $n unchanged ($n re-indexed" "$T/out" && pass "  every system re-indexed, none baked" \
  || fail "  summary: $(grep 'systems  ' "$T/out")"
rm -rf "$T/full"; mkdir -p "$T/full"
expect 0 "boxes: a full bake of the re-indexed scene" "$BIN/glow-bake" "$T/a.obj" "${SMALL[@]}" -o "$T/full/w.json"
same=1
[ "$(ls "$T/inc" | tr '\n' ' ')" = "$(ls "$T/full" | tr '\n' ' ')" ] || { same=0; fail "  files differ: $(ls "$T/inc") / $(ls "$T/full")"; }
for f in $(ls "$T/full"); do cmp -s "$T/inc/$f" "$T/full/$f" || { same=0; fail "  $f differs"; }; done
[ $same = 1 ] && pass "  byte for byte the full bake (the old files, named by the old indices, removed)"
python3 - "$T/inc/w.json" <<'PY' && pass "  GEOM names the new indices (the first kept triangle is the file's second)" || fail "  GEOM sources"
import json, os, struct, sys
w = json.load(open(sys.argv[1])); d = os.path.dirname(sys.argv[1])
srcs = []
for x in w["systems"]:
    b = open(os.path.join(d, x["file"]), "rb").read()
    count = struct.unpack_from("<I", b, 12)[0]
    for i in range(count):
        four, ver, off, size = struct.unpack_from("<4sIQQ", b, 64 + 32 * i)
        if four == b"GEOM":
            srcs += [struct.unpack_from("<I", b, off + 64 * t + 52)[0] for t in range(size // 64)]
assert min(srcs) == 1 and max(srcs) == 192 and len(set(srcs)) == 192, (min(srcs), max(srcs), len(srcs))
PY

# Triangles larger than a sixteenth of the system area are cut into pieces, so that no system is a
# single huge triangle (a level's ground quad once reached every system from two systems of its own)
cat > "$T/ground.obj" <<'OBJ'
v -20 0 -20
v 20 0 -20
v 20 0 20
v -20 0 20
f 1 3 2
f 1 4 3
v -15 0 -0.5
v 15 0 -0.5
v 15 2 -0.5
v -15 2 -0.5
v -15 0 0.5
v 15 0 0.5
v 15 2 0.5
v -15 2 0.5
f 5 8 7 6
f 9 10 11 12
f 8 12 11 7
f 5 9 12 8
f 6 7 11 10
OBJ
mkdir -p "$T/gw"
expect 0 "a 40 x 40 m ground quad and a wall across it in systems of 100 m²" "$BIN/glow-bake" "$T/ground.obj" --system-area 100 --surfels 256 \
  --links 16 --lightmap-caches 64 --lightmap-detail 1 -q -o "$T/gw/g.json"
python3 - "$T/gw/g.json" <<'PY' && pass "  the ground's and the wall's long triangles cut into pieces of at most 6.25 m² and 2.5 m a side, at least 16 systems of at most 100 m², linking neighbours" \
  || fail "  the ground's pieces"
import json, sys
s = json.load(open(sys.argv[1]))["systems"]
# pieces of at most 100/16 m² and edges of at most sqrt(100)/4 m (each cut in four halves the edges):
# the ground's 2 triangles (800 m², a 56.6 m diagonal) into 4^5 each, by their diagonal (by their area
# alone, 4^4); the wall's two 30 x 2 m sides and its 30 x 1 m top, 6 triangles, into 4^4 each by their
# 30 m edges (by area, 4^2 and 4); its two 1 x 2 m ends, 4 triangles, stay whole
assert sum(x["triangles"] for x in s) == 2 * 1024 + 6 * 256 + 4, sum(x["triangles"] for x in s)
assert abs(sum(x["area"] for x in s) - (1600 + 2 * 60 + 30 + 2 * 2)) < 0.01, sum(x["area"] for x in s)
assert all(0 < x["area"] <= 100.0 for x in s), [x["area"] for x in s]
assert len(s) >= 16, len(s)
assert all(len(x["dependencies"]) > 0 for x in s) and sum(x["proxies"] > 0 for x in s) >= len(s) // 2  # the texels by the wall see its other systems' parts
PY
# A cell is cut where at least a quarter of its surface lies on either side, not in the middle half of
# its centroids' range: a 20 x 10 m floor and a 0.5 m² triangle 180 m away were cut at x = 100 (the
# range's middle, where nothing is crossed), a system of the lone triangle beside two of the floor
cat > "$T/far.obj" <<'OBJ'
v 0 0 0
v 20 0 0
v 20 0 10
v 0 0 10
v 200 0 0
v 201 0 0
v 200 0 1
f 1 4 3 2
f 5 7 6
OBJ
mkdir -p "$T/fw"
expect 0 "a floor and a far triangle in systems of 100 m²" "$BIN/glow-bake" "$T/far.obj" --system-area 100 --surfels 256 \
  --links 16 --lightmap-caches 64 --lightmap-detail 1 -q -o "$T/fw/f.json"
python3 - "$T/fw/f.json" <<'PY' && pass "  no system below a quarter of 100 m² (the far triangle goes with a part of the floor)" \
  || fail "  the partition's halves"
import json, sys
s = json.load(open(sys.argv[1]))["systems"]
a = [x["area"] for x in s]
assert abs(sum(a) - 200.5) < 0.01 and all(25.0 <= v <= 100.0 for v in a), a
PY
expect 0 "one system when the area is above the scene's" "$BIN/glow-bake" builtin:pillar-hall --system-area 1000 "${BUDGET[@]}" \
  -o "$T/one/hall.json"
python3 -c "import json,sys; m=json.load(open(sys.argv[1])); assert len(m['systems'])==1 and m['systems'][0]['surfels']==int(round(1024*306.33/1000))" \
  "$T/one/hall.json" && pass "  1 system, surfels 1024 x 306.33 / 1000" || fail "  one-system manifest"

# Systems named by the user (--system-group): tests/data/scenes/named-objects.obj holds objects house_a,
# house_b (4 m boxes, 96 m² each) and ground (192 m²). house_a is system houseA and gro* system flat,
# whole although above the area; house_b is split by area (4 systems of 24 m² at 30). A re-bake with the
# groups given the other way round keeps every system (the keys follow the content, the named ones their
# names too).
NAMED="$ROOT/tests/data/scenes/named-objects.obj"
mkdir -p "$T/named"
expect 0 "named systems (--system-group houseA=house_a --system-group flat='gro*')" "$BIN/glow-bake" "$NAMED" \
  --system-area 30 --system-group houseA=house_a --system-group 'flat=gro*' "${BUDGET[@]}" -o "$T/named/w.json"
python3 - "$T/named/w.json" <<'PY' && pass "  manifest: houseA (96 m², 192 pieces) and flat (192 m²) named and whole, house_b in 4 systems of 24 m²" || fail "  named manifest wrong"
import json, sys, re
s = json.load(open(sys.argv[1]))["systems"]
named = {x["name"]: x for x in s if "name" in x}
assert set(named) == {"houseA", "flat"}, named.keys()
assert abs(named["houseA"]["area"] - 96) < 1e-3 and abs(named["flat"]["area"] - 192) < 1e-3, named
assert re.fullmatch(r"w\.houseA-[0-9a-f]{16}\.glow", named["houseA"]["file"]), named["houseA"]
rest = [x for x in s if "name" not in x]
assert len(rest) == 4 and all(abs(x["area"] - 24) < 1e-3 for x in rest), [x["area"] for x in rest]
assert abs(sum(x["area"] for x in s) - 384) < 1e-3
PY
cp "$T/named/w.json" "$T/named/w1.json"
expect 0 "the same groups the other way round: an incremental re-bake" "$BIN/glow-bake" "$NAMED" \
  --system-area 30 --system-group 'flat=gro*' --system-group houseA=house_a "${BUDGET[@]}" -o "$T/named/w.json"
grep -q "0 of them baked and 6 unchanged" "$T/out" \
  && pass "  all 6 systems kept" || { fail "  systems re-baked:"; grep systems "$T/out"; }
# --systems FILE.json: the same groups with declared neighbours. houseB declares none, houseA only flat,
# flat is automatic; the same groups without declarations (--system-group) link houseB to flat.
SYS="$T/named/systems.json"
cat > "$SYS" <<'JSON'
{"glow_systems": 1,
 "systems": [
  {"name": "houseA", "objects": ["house_a"], "neighbours": ["flat"]},
  {"name": "houseB", "objects": ["house_b"], "neighbours": []},
  {"name": "flat", "objects": ["gro*"]}
 ]}
JSON
mkdir -p "$T/decl" "$T/auto" "$T/decl2"
expect 0 "declared neighbours (--systems)" "$BIN/glow-bake" "$NAMED" --system-area 30 --systems "$SYS" "${BUDGET[@]}" \
  -o "$T/decl/w.json"
expect 0 "  the same groups, automatic neighbours" "$BIN/glow-bake" "$NAMED" --system-area 30 --system-group houseA=house_a \
  --system-group houseB=house_b --system-group 'flat=gro*' "${BUDGET[@]}" -o "$T/auto/w.json"
python3 - "$T/decl/w.json" "$T/auto/w.json" <<'PY' && pass "  houseB links no neighbour (1 automatic), houseA only flat, flat both houses; the manifest names the declarations" || fail "  declared neighbours wrong"
import json, sys
d = {x["name"]: x for x in json.load(open(sys.argv[1]))["systems"] if "name" in x}
a = {x["name"]: x for x in json.load(open(sys.argv[2]))["systems"] if "name" in x}
assert set(d) == {"houseA", "houseB", "flat"}, d.keys()
assert d["houseA"]["declared_neighbours"] == ["flat"] and d["houseB"]["declared_neighbours"] == [], d
assert "declared_neighbours" not in d["flat"] and all("declared_neighbours" not in x for x in a.values()), d
assert d["houseB"]["dependencies"] == [] and d["houseB"]["proxies"] == 0, d["houseB"]
assert a["houseB"]["dependencies"] == [a["flat"]["system_key"]] and a["houseB"]["proxies"] > 0, a["houseB"]
assert d["houseA"]["dependencies"] == [d["flat"]["system_key"]], d["houseA"]
assert sorted(d["flat"]["dependencies"]) == sorted([d["houseA"]["system_key"], d["houseB"]["system_key"]]), d["flat"]
assert d["flat"]["file"] == a["flat"]["file"] and d["houseB"]["file"] != a["houseB"]["file"], (d, a)
PY
sed 's/"neighbours": \["flat"\]/"neighbours": []/' "$SYS" > "$T/named/systems2.json"
expect 0 "  houseA's declaration changed: an incremental re-bake" "$BIN/glow-bake" "$NAMED" --system-area 30 \
  --systems "$T/named/systems2.json" "${BUDGET[@]}" -o "$T/decl/w.json"
grep -q "systems   3, 1 of them baked and 2 unchanged" "$T/out" && pass "  only houseA baked again (1 of 3)" \
  || { fail "  systems re-baked:"; grep systems "$T/out"; }
expect 0 "  the same declarations into an empty world" "$BIN/glow-bake" "$NAMED" --system-area 30 \
  --systems "$T/named/systems2.json" "${BUDGET[@]}" -o "$T/decl2/w.json"
same=1
for f in w.json $(files "$T/decl2/w.json"); do cmp -s "$T/decl/w.json" "$T/decl2/w.json" && cmp -s "$T/decl/$f" "$T/decl2/$f" || { same=0; fail "  $f differs"; }; done
[ $same = 1 ] && [ "$(ls "$T/decl" | wc -l)" = "$(ls "$T/decl2" | wc -l)" ] && pass "  byte for byte the full bake, no stale file"
systems_file() { printf '{"glow_systems": 1, "systems": [%s]}' "$1" > "$T/named/s.json"; }
systems_file '{"name": "a", "objects": ["house_a"], "neighbours": ["c"]}, {"name": "b", "objects": ["house_b"], "neighbours": ["a"]},
  {"name": "c", "objects": ["gro*"], "neighbours": ["b", "a"]}'
mkdir -p "$T/cyc"
expect 0 "declared neighbours in a cycle (a -> c -> b -> a): allowed, light goes both ways" "$BIN/glow-bake" "$NAMED" \
  --system-area 30 --systems "$T/named/s.json" "${BUDGET[@]}" -o "$T/cyc/w.json"
err_has "system b: declared neighbour a is beyond its reach"
bad_systems() { # NAME MESSAGE JSON-SYSTEMS: exit 1, the message names the file, nothing written
  systems_file "$3"
  rm -rf "$T/bs" && mkdir -p "$T/bs"
  expect 1 "$1" "$BIN/glow-bake" "$NAMED" --system-area 30 --systems "$T/named/s.json" "${BUDGET[@]}" -o "$T/bs/w.json"
  err_has "s.json"; err_has "$2"
  [ -z "$(ls "$T/bs")" ] && pass "  nothing written" || fail "  left behind: $(ls "$T/bs")"
}
bad_systems "--systems: an unknown neighbour" "neighbour 'towr' is no named system" \
  '{"name": "a", "objects": ["house_a"], "neighbours": ["towr"]}'
bad_systems "--systems: a declared neighbour missing from the scene" "declared neighbour b is missing" \
  '{"name": "a", "objects": ["house_a"], "neighbours": ["b"]}, {"name": "b", "objects": ["no_such_object"]}'
bad_systems "--systems: a system its own neighbour" "names itself" '{"name": "a", "objects": ["house_a"], "neighbours": ["a"]}'
bad_systems "--systems: a neighbour named twice" "named twice" \
  '{"name": "a", "objects": ["house_a"], "neighbours": ["b", "b"]}, {"name": "b", "objects": ["house_b"]}'
bad_systems "--systems: a system named twice" "named twice" '{"name": "a", "objects": ["x"]}, {"name": "a", "objects": ["y"]}'
bad_systems "--systems: no objects" '"objects" must be' '{"name": "a"}'
bad_systems "--systems: neighbours not a list" '"neighbours" must be' '{"name": "a", "objects": ["x"], "neighbours": "b"}'
bad_systems "--systems: not JSON" "line 1: not valid JSON" '{"name": "a" "objects": ["x"]}'
printf '{"glow_systems": 2, "systems": []}' > "$T/named/s.json"
expect 1 "--systems: another version" "$BIN/glow-bake" "$NAMED" --system-area 30 --systems "$T/named/s.json" "${BUDGET[@]}" \
  -o "$T/bs/w.json"; err_has "version 1"
expect 1 "--systems: no such file" "$BIN/glow-bake" "$NAMED" --system-area 30 --systems "$T/named/none.json" "${BUDGET[@]}" \
  -o "$T/bs/w.json"; err_has "none.json: cannot read"
expect 2 "--systems without --system-area" "$BIN/glow-bake" "$NAMED" --systems "$SYS" -o "$T/bs/w.json"; err_has "--system-area"
expect 2 "--systems with --system-group" "$BIN/glow-bake" "$NAMED" --system-area 30 --systems "$SYS" --system-group a=b \
  -o "$T/bs/w.json"; err_has "one place"
expect 0 "a group that matches nothing: warned" "$BIN/glow-bake" "$NAMED" --system-area 500 --system-group none=nothing_* \
  "${BUDGET[@]}" -o "$T/named/n.json"; err_has "no object of the scene matches"
expect 1 "--system-group on a built-in scene" "$BIN/glow-bake" builtin:pillar-hall --system-area 100 --system-group a=b \
  "${BUDGET[@]}" -o "$T/named/b.json"; err_has "names no objects"
expect 2 "--system-group without --system-area" "$BIN/glow-bake" "$NAMED" --system-group a=b -o "$T/bad.glow"; err_has "--system-area"
expect 2 "--system-group with a bad name" "$BIN/glow-bake" "$NAMED" --system-area 30 --system-group 'a b=c' -o "$T/bad.json"
err_has "only A-Z"
expect 2 "--system-group without a pattern" "$BIN/glow-bake" "$NAMED" --system-area 30 --system-group a= -o "$T/bad.json"
err_has "NAME=PATTERN"
expect 2 "--system-group named twice" "$BIN/glow-bake" "$NAMED" --system-area 30 --system-group a=b --system-group a=c \
  -o "$T/bad.json"; err_has "named twice"

expect 2 "--system-area 0" "$BIN/glow-bake" builtin:pillar-hall --system-area 0 -o "$T/bad.json"; err_has "--system-area"
expect 2 "--system-area -5" "$BIN/glow-bake" builtin:pillar-hall --system-area -5 -o "$T/bad.json"; err_has "--system-area"
expect 2 "--system-area abc" "$BIN/glow-bake" builtin:pillar-hall --system-area abc -o "$T/bad.json"; err_has "--system-area"
expect 2 "--system-reach 5" "$BIN/glow-bake" builtin:pillar-hall --system-area 100 --system-reach 5 -o "$T/bad.json"; err_has "--system-reach"
expect 2 "--system-reach without --system-area" "$BIN/glow-bake" builtin:pillar-hall --system-reach 0.5 -o "$T/bad.glow"; err_has "--system-area"
expect 2 "--sh-links with --system-area" "$BIN/glow-bake" builtin:pillar-hall --system-area 100 --sh-links -o "$T/bad.json"; err_has "--sh-links"
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
