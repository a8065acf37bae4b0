#!/usr/bin/env bash
# tools/level/make_level.py (issue 16, item 6): a small textured OBJ tiled 2 x 3 with streets: the
# vertex and face counts, the copies' offsets, the ground (the streets and a border, facing up, not
# under the copies; one quad with --ground full), the material library with "street",
# the textures linked beside the level, deterministic output, a bake of the level that finds its
# textures, and the error paths (bad counts: exit 2; a missing source: exit 1 naming it).
#   usage: test_level.sh BIN_DIR SHARED_DIR
set -u
BIN=$1
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
. "$(dirname "$0")/lib/common.sh"
GEN="$ROOT/tools/level/make_level.py"
SRC="$ROOT/tests/data/scenes/texcase/texcase.obj"
expect 0 "2 x 3 level of texcase.obj" python3 "$GEN" "$SRC" 2 3 --street 0.5 -o "$T/l"
nv=$(grep -c '^v ' "$SRC"); nf=$(grep -c '^f ' "$SRC")
# the ground of a 2 x 3 level: 4 bands along x (the border rows and the 2 streets between rows), and
# in each of the 3 rows of copies the 3 gaps (border, street, border): 13 rectangles
[ "$(grep -c '^v ' "$T/l/level.obj")" = $((6 * nv + 52)) ] && pass "  6 x $nv vertices + the ground's 52" || fail "  vertex count $(grep -c '^v ' "$T/l/level.obj")"
[ "$(grep -c '^f ' "$T/l/level.obj")" = $((6 * nf + 13)) ] && pass "  6 x $nf faces + the ground's 13" || fail "  face count"
grep -q '^newmtl street' "$T/l/level.mtl" && grep -q '^newmtl lower' "$T/l/level.mtl" && pass "  materials: the source's and street" || fail "  level.mtl"
[ -L "$T/l/Checker.PNG" ] && pass "  textures linked beside the level" || fail "  no texture link"
python3 - "$T/l/level.obj" 52 <<'PY' && pass "  copies 1.5 apart in x and z (extent 1 + street 0.5); the ground faces up, covers the streets and the border, and nothing under a copy" || fail "  offsets or ground wrong"
import sys
ng = int(sys.argv[2])
vs = [tuple(map(float, l.split()[1:4])) for l in open(sys.argv[1]) if l.startswith("v ")]
xs = sorted({round(v[0], 4) for v in vs[:-ng]}); zs = sorted({round(v[2], 4) for v in vs[:-ng]})
assert xs == [0.0, 1.0, 1.5, 2.5], xs
assert zs == [0.0, 1.0, 1.5, 2.5, 3.0, 4.0], zs
area = 0.0
for q in range(0, ng, 4):
    g = vs[len(vs) - ng + q:len(vs) - ng + q + 4]
    e1 = [g[1][k] - g[0][k] for k in range(3)]; e2 = [g[2][k] - g[0][k] for k in range(3)]
    ny = e1[2] * e2[0] - e1[0] * e2[2]
    assert ny > 0 and all(abs(v[1] - g[0][1]) < 1e-9 for v in g), (g, ny)
    area += ny
    ga, gb = min(v[0] for v in g), max(v[0] for v in g)
    gc, gd = min(v[2] for v in g), max(v[2] for v in g)
    for cx in (0.0, 1.5):
        for cz in (0.0, 1.5, 3.0):  # no rectangle overlaps a copy's footprint [c, c + 1]^2
            assert not (ga < cx + 1 - 1e-9 and gb > cx + 1e-9 and gc < cz + 1 - 1e-9 and gd > cz + 1e-9), (g, cx, cz)
# the level with its border: (2.5 + 1) x (4 + 1), less 6 unit footprints
assert abs(area - (3.5 * 5.0 - 6.0)) < 1e-6, area
PY
expect 0 "--ground full: one quad under the whole level" python3 "$GEN" "$SRC" 2 3 --street 0.5 --ground full -o "$T/lf"
[ "$(grep -c '^v ' "$T/lf/level.obj")" = $((6 * nv + 4)) ] && [ "$(grep -c '^f ' "$T/lf/level.obj")" = $((6 * nf + 1)) ] && pass "  6 x $nv vertices + 4, 6 x $nf faces + 1" || fail "  --ground full counts"
expect 0 "again: the same bytes" python3 "$GEN" "$SRC" 2 3 --street 0.5 -o "$T/l2"
cmp -s "$T/l/level.obj" "$T/l2/level.obj" && pass "  deterministic" || fail "  level.obj differs between runs"
expect 0 "bake the level" "$BIN/glow-bake" "$T/l/level.obj" -o "$T/l.glow" --surfels 512 --links 16 --texel-density 4 --grid-spacing 1 -q
expect 0 "  --info" "$BIN/glow-bake" --info "$T/l.glow"
grep -q "TEXP" "$T/out" && pass "  the bake names its textures (found through the links)" || fail "  no TEXP section"
expect 2 "zero copies" python3 "$GEN" "$SRC" 0 3 -o "$T/bad"
expect 2 "negative street" python3 "$GEN" "$SRC" 1 1 --street -1 -o "$T/bad"
expect 1 "missing source" python3 "$GEN" "$T/none.obj" 1 1 -o "$T/bad"; err_has "none.obj"
echo "$fails failure(s)"
[ "$fails" = 0 ]
