#!/usr/bin/env bash
# CLI behaviour of glow-bake: help, bad options (exit 2), bad inputs (exit 1, message names the file,
# no output left behind), a real bake + --info round trip, JSON summary, determinism across thread
# counts, and a killed bake leaving no file.
#   usage: test_cli.sh BIN_DIR SHARED_DIR
set -u
BIN=$1/glow-bake
SHARED=${2:-}
. "$(dirname "$0")/lib/common.sh"
no_file() { if [ ! -e "$1" ] && ! ls "$1".tmp.* >/dev/null 2>&1; then pass "  no output left at $1"; else fail "  output left at $1"; fi; }

SMALL=(--surfels 1024 --links 32 --grid-spacing 0.5 --texel-density 3 -q)

expect 0 "--help" "$BIN" --help
grep -q -- "--sh-links" "$T/out" && grep -q -- "--texel-density" "$T/out" && pass "  help lists the options" || fail "  help incomplete"
expect 2 "no arguments" "$BIN"
expect 2 "unknown option" "$BIN" builtin:cornell -o "$T/a.glow" --frobnicate; err_has "frobnicate"
expect 2 "bad quality" "$BIN" builtin:cornell -o "$T/a.glow" --quality ultra; err_has "ultra"
expect 2 "negative surfels" "$BIN" builtin:cornell -o "$T/a.glow" --surfels -5; err_has "surfels"
expect 2 "absurd surfels" "$BIN" builtin:cornell -o "$T/a.glow" --surfels 99999999999; err_has "surfels"
expect 2 "bands 9" "$BIN" builtin:cornell -o "$T/a.glow" --bands 9; err_has "bands"
expect 2 "zero links" "$BIN" builtin:cornell -o "$T/a.glow" --links 0
expect 2 "nan grid spacing" "$BIN" builtin:cornell -o "$T/a.glow" --grid-spacing nan
expect 2 "negative texel density" "$BIN" builtin:cornell -o "$T/a.glow" --texel-density -1
expect 2 "zero lightmap caches" "$BIN" builtin:cornell -o "$T/a.glow" --lightmap-caches 0; err_has "lightmap-caches"
expect 0 "a lightmap budget too small for the charts (--lightmap-caches 3)" "$BIN" builtin:cornell -o "$T/lb.glow" \
  --lightmap-caches 3 --surfels 256 -q; err_has "its budget of 3"
expect 2 "texel adapt 9" "$BIN" builtin:cornell -o "$T/a.glow" --texel-adapt 9; err_has "texel-adapt"
expect 2 "texel adapt 0.5" "$BIN" builtin:cornell -o "$T/a.glow" --texel-adapt 0.5; err_has "texel-adapt"
expect 2 "grid refine 3" "$BIN" builtin:cornell -o "$T/a.glow" --grid-refine 3; err_has "grid-refine"
expect 2 "grid refine 8" "$BIN" builtin:cornell -o "$T/a.glow" --grid-refine 8; err_has "grid-refine"
expect 2 "grid refine x" "$BIN" builtin:cornell -o "$T/a.glow" --grid-refine x; err_has "grid-refine"
expect 2 "sky rays 0" "$BIN" builtin:cornell -o "$T/a.glow" --sky-rays 0; err_has "sky-rays"
expect 2 "sky rays huge" "$BIN" builtin:cornell -o "$T/a.glow" --sky-rays 70000; err_has "sky-rays"
expect 2 "surfel adapt 5" "$BIN" builtin:cornell -o "$T/a.glow" --surfel-adapt 5; err_has "surfel-adapt"
expect 2 "lightmap max size 30" "$BIN" builtin:cornell -o "$T/a.glow" --lightmap-max-size 30; err_has "lightmap-max-size"
expect 2 "lightmap max size 8192" "$BIN" builtin:cornell -o "$T/a.glow" --lightmap-max-size 8192; err_has "multiple of 4"
expect 2 "missing value" "$BIN" builtin:cornell -o
expect 2 "no output" "$BIN" builtin:cornell
no_file "$T/a.glow"

expect 1 "missing scene" "$BIN" "$T/nope.obj" -o "$T/b.glow" -q; err_has "nope.obj"; no_file "$T/b.glow"
printf 'this is not a mesh\n\x00\x01\x02' > "$T/garbage.glb"
expect 1 "garbage scene" "$BIN" "$T/garbage.glb" -o "$T/b.glow" -q; err_has "garbage.glb"; no_file "$T/b.glow"
: > "$T/empty.obj"
expect 1 "empty scene" "$BIN" "$T/empty.obj" -o "$T/b.glow" -q; err_has "empty.obj"; no_file "$T/b.glow"
expect 1 "unknown builtin" "$BIN" builtin:teapot -o "$T/b.glow" -q; err_has "teapot"
expect 1 "unwritable output" "$BIN" builtin:cornell -o "$T/no/such/dir/x.glow" "${SMALL[@]}"; err_has "x.glow"

# a real bake, its summary, --info and --json
expect 0 "bake cornell" "$BIN" builtin:cornell -o "$T/c1.glow" "${SMALL[@]}" --threads 1
grep -q "bytes per link" "$T/out" && pass "  summary printed" || fail "  no summary"
expect 0 "--info" "$BIN" --info "$T/c1.glow"
grep -q "valid" "$T/out" && grep -q "surfels   1024" "$T/out" && pass "  info describes the bake" || { fail "  info output"; cat "$T/out"; }
grep -q "SKYT" "$T/out" && pass "  the sky transfer by default" || fail "  no SKYT"
expect 0 "bake --no-sky" "$BIN" builtin:cornell -o "$T/ns.glow" "${SMALL[@]}" --no-sky
expect 0 "--info --no-sky bake" "$BIN" --info "$T/ns.glow"
grep -q "SKYT" "$T/out" && fail "  --no-sky wrote SKYT" || pass "  --no-sky: no SKYT"
expect 0 "--info --json" "$BIN" --info "$T/c1.glow" --json
python3 -c "import json,sys; sys.exit(0 if json.load(open(sys.argv[1]))['surfels'] == 1024 else 1)" "$T/out" \
  && pass "  info json" || fail "  info json"
expect 0 "bake --json" "$BIN" builtin:cornell -o "$T/c2.glow" "${SMALL[@]}" --threads 3 --json
grep -q '"bytes_per_link"' "$T/out" && grep -q '"stages"' "$T/out" && pass "  json summary" || fail "  json summary"
python3 - "$T/out" <<'PY' && pass "  json: the lightmap budget adds up (caches + invalid + gutter + unused = atlas)" || fail "  json: lightmap budget"
import json, sys
c = json.load(open(sys.argv[1]))["caches"]
w, h = c["lightmap_size"]
assert c["lightmap"] + c["lightmap_invalid"] + c["lightmap_gutter"] + c["lightmap_unused"] == w * h * c["lightmap_pages"], c
assert 0.0 < c["lightmap_coverage"] <= 1.0, c
PY
# the lightmap budget: without --texel-density the density is searched so that the texels holding
# a cache land within 20 % of --lightmap-caches (two budgets 4x apart, so a fixed density fails one)
for budget in 300 1200; do
  expect 0 "bake --lightmap-caches $budget" "$BIN" builtin:cornell -o "$T/lb.glow" --surfels 1024 --links 32 -q --json \
    --lightmap-caches "$budget"
  python3 - "$T/out" "$budget" <<'PY' && pass "  lightmap caches within 20 % of $budget" || fail "  lightmap caches miss $budget"
import json, sys
n, want = json.load(open(sys.argv[1]))["caches"]["lightmap"], int(sys.argv[2])
print("     lightmap caches", n)
assert 0.8 * want <= n <= 1.2 * want, (n, want)
PY
done
if cmp -s "$T/c1.glow" "$T/c2.glow"; then pass "same bytes with 1 and 3 threads"; else fail "bake differs across thread counts"; fi
# the error cut is the default; the published cut (PIC 4.5) stays selectable
expect 0 "bake --cut error" "$BIN" builtin:cornell -o "$T/ce.glow" "${SMALL[@]}" --cut error
cmp -s "$T/c1.glow" "$T/ce.glow" && pass "  the default cut is the error cut" || fail "  default differs from --cut error"
expect 0 "bake --cut solid-angle" "$BIN" builtin:cornell -o "$T/cs.glow" "${SMALL[@]}" --cut solid-angle
cmp -s "$T/c1.glow" "$T/cs.glow" && fail "  --cut solid-angle changes nothing" || pass "  --cut solid-angle gives other links"
expect 2 "bad cut" "$BIN" builtin:cornell -o "$T/a.glow" --cut fast; err_has "cut"
expect 0 "bake --link-visibility exact" "$BIN" builtin:cornell -o "$T/cx.glow" "${SMALL[@]}" --link-visibility exact
cmp -s "$T/c1.glow" "$T/cx.glow" && fail "  --link-visibility exact changes nothing" || pass "  clustered visibility (the default) gives other links"
expect 0 "bake --link-visibility clustered" "$BIN" builtin:cornell -o "$T/cc.glow" "${SMALL[@]}" --link-visibility clustered
cmp -s "$T/c1.glow" "$T/cc.glow" && pass "  the default is clustered visibility" || fail "  default differs from --link-visibility clustered"
# a glTF image whose data-URI media type has no '/' crashed assimp 5.2.4 (the fuzz smoke found it):
# refused with a message before assimp reads it
sed 's#data:image/png;base64#data:imageopng;base64#' "$(dirname "$0")/../data/scenes/quad_uv1.gltf" > "$T/badmime.gltf"
expect 1 "glTF with a malformed image media type" "$BIN" "$T/badmime.gltf" -o "$T/badmime.glow" "${SMALL[@]}"; err_has "media type"
no_file "$T/badmime.glow"
expect 2 "bad link visibility" "$BIN" builtin:cornell -o "$T/a.glow" --link-visibility fast; err_has "link-visibility"
expect 2 "bad cluster angle" "$BIN" builtin:cornell -o "$T/a.glow" --link-cluster-angle 2; err_has "link-cluster-angle"
expect 2 "bad cluster rays" "$BIN" builtin:cornell -o "$T/a.glow" --link-cluster-rays 0; err_has "link-cluster-rays"
expect 0 "bake other seed" "$BIN" builtin:cornell -o "$T/c3.glow" "${SMALL[@]}" --seed 7
if cmp -s "$T/c1.glow" "$T/c3.glow"; then fail "seed has no effect"; else pass "seed changes the bake"; fi

# a corrupted bake is refused by --info with a named problem
# (the byte in the middle of the file, inside the LINK payload, inverted so that it surely changes)
cp "$T/c1.glow" "$T/bad.glow"
mid=$(( $(stat -c %s "$T/c1.glow") / 2 ))
old=$(od -An -tu1 -j "$mid" -N1 "$T/c1.glow" | tr -d ' ')
printf "\\$(printf '%03o' $(( 255 - old )))" | dd of="$T/bad.glow" bs=1 seek="$mid" conv=notrunc 2>/dev/null
cmp -s "$T/c1.glow" "$T/bad.glow" && fail "  corruption did not change the file" || pass "  one byte changed"
expect 1 "--info on corrupted bake" "$BIN" --info "$T/bad.glow"; err_has "checksum\|CRC\|crc"
head -c 100 "$T/c1.glow" > "$T/short.glow"
expect 1 "--info on truncated bake" "$BIN" --info "$T/short.glow"; err_has "short.glow"

# existing output survives a failed bake
cp "$T/c1.glow" "$T/keep.glow"
expect 1 "failed bake over existing file" "$BIN" "$T/nope.obj" -o "$T/keep.glow" -q
cmp -s "$T/c1.glow" "$T/keep.glow" && pass "  existing file untouched" || fail "  existing file changed"

# the output is checked before the work (issue 15 D7, D8): an unwritable folder fails before the
# import stage starts, and the input mesh is never the output
expect 1 "output folder missing" "$BIN" builtin:cornell -o "$T/no/such/dir/x.glow" --quality low
err_has "cannot be written"
grep -q "import" "$T/err" && fail "  a stage ran before the failure" || pass "  no stage ran"
if [ -f "$SHARED/scenes/cornell-box/CornellBox-Original.obj" ]; then
  cp "$SHARED/scenes/cornell-box/CornellBox-Original.obj" "$T/mesh.obj"
  expect 1 "output is the input mesh" "$BIN" "$T/mesh.obj" -o "$T/mesh.obj" --quality low -q
  err_has "refusing to overwrite the input"
  cmp -s "$SHARED/scenes/cornell-box/CornellBox-Original.obj" "$T/mesh.obj" && pass "  input mesh untouched" \
    || fail "  input mesh changed"
fi
expect 1 "output is a folder" "$BIN" builtin:cornell -o "$T" --quality low -q
err_has "is a directory"

# a killed bake leaves no bake file
"$BIN" builtin:cornell -o "$T/killed.glow" --surfels 16384 --links 128 -q &
pid=$!
sleep 1
if kill -0 $pid 2>/dev/null; then pass "bake still running after 1 s"; else fail "bake finished before it could be killed"; fi
kill -9 $pid 2>/dev/null; wait $pid 2>/dev/null
no_file "$T/killed.glow"
# a writer killed between create and rename leaves "<out>.tmp.<pid>" (D9): the next bake of that
# output removes it when that process is gone, and keeps a live process's
sleep 30 & live=$!
( exit 0 ) & dead=$!; wait $dead
echo partial > "$T/k.glow.tmp.$dead"; echo partial > "$T/k.glow.tmp.$live"
expect 0 "bake over a killed writer's temporary" "$BIN" builtin:cornell -o "$T/k.glow" "${SMALL[@]}"
[ -e "$T/k.glow.tmp.$dead" ] && fail "  dead writer's temporary kept" || pass "  dead writer's temporary removed"
[ -e "$T/k.glow.tmp.$live" ] && pass "  live writer's temporary kept" || fail "  live writer's temporary removed"
kill $live 2>/dev/null; wait $live 2>/dev/null; rm -f "$T/k.glow.tmp.$live"

# Lightmap pages (issue 16 item 5, bake format 1.7): atlases of at most 28 texels a side force the
# 48x44 atlas of this budget onto 5 pages at the same texel density (not a lower one), the paged bake
# loads, Glow's view of it (each triangle's page) matches the one-page bake's, and a page index beyond
# lightmap_count (resealed, so that only the contents check can catch it) is refused, naming TPAG.
# ~2 s in all (release).
PG=(--surfels 1024 --links 32 --grid-spacing 0.5 --lightmap-caches 1000 --no-sky -q --json)
expect 0 "bake one lightmap page" "$BIN" builtin:cornell -o "$T/pg1.glow" "${PG[@]}"; cp "$T/out" "$T/pg1.json"
expect 0 "bake --lightmap-max-size 28" "$BIN" builtin:cornell -o "$T/pg5.glow" "${PG[@]}" --lightmap-max-size 28
cp "$T/out" "$T/pg5.json"
python3 - "$T/pg1.json" "$T/pg5.json" <<'PY' && pass "  >= 3 pages of 28x28 at the one-page density" || fail "  pages"
import json, sys
a, b = (json.load(open(f))["caches"] for f in sys.argv[1:3])
print("     one page %s at %.5g texels/unit, %d caches; paged %d x %s at %.5g, %d caches" % (a["lightmap_size"],
      a["texel_density"], a["lightmap"], b["lightmap_pages"], b["lightmap_size"], b["texel_density"], b["lightmap"]))
assert a["lightmap_pages"] == 1 and b["lightmap_pages"] >= 3 and b["lightmap_size"] == [28, 28], (a, b)
assert b["texel_density"] == a["texel_density"] and b["lightmap"] == a["lightmap"], (a, b)
PY
expect 0 "--info on the paged bake" "$BIN" --info "$T/pg5.glow"
grep -q "TPAG" "$T/out" && grep -q "pages of 28x28" "$T/out" && pass "  valid, with TPAG" || fail "  info: no pages"
R=$(dirname "$BIN")
SCN=$(cd "$(dirname "$0")/../.." && pwd)/scenes/cornell-builtin.json
for k in 1 5; do
  expect 0 "glow-render the $k-page bake" "$R/glow-render" "$SCN" --out "$T/pg$k" --glow "$T/pg$k.glow" --spp 1 \
    --width 48 --height 48 --indirect-only --bounces 64 -q
done
"$R/glow-compare" "$T/pg5_indirect.exr" "$T/pg1_indirect.exr" --no-flip --json > "$T/cmp.json" 2>"$T/err"
python3 - "$T/cmp.json" <<'PY' && pass "  paged Glow view = one-page view (means within 1 %, block error < 0.01)" || fail "  paged view differs"
import json, sys
c = json.load(open(sys.argv[1]))
print("     block error %.2g, mean ratio %.5f" % (c["block_error"], c["mean_ratio"]))
assert c["block_error"] < 0.01 and abs(c["mean_ratio"] - 1.0) < 0.01, c
assert all(abs(t - r) <= 0.01 * r for t, r in zip(c["mean_test"], c["mean_ref"])), c
PY
python3 - "$T/pg5.glow" "$T/pgbad.glow" <<'PY' && pass "  TPAG page patched and resealed" || fail "  could not patch TPAG"
import struct, sys, zlib
b = bytearray(open(sys.argv[1], "rb").read())
n = struct.unpack_from("<I", b, 12)[0]
for i in range(n):
    e = 64 + 32 * i
    fourcc, _, off, size = struct.unpack_from("<4sIQQ", b, e)
    if fourcc == b"TPAG":
        struct.pack_into("<I", b, off, 99)  # triangle 0 on page 99 of 5
        struct.pack_into("<I", b, e + 24, zlib.crc32(bytes(b[off:off + size])))
        break
else:
    sys.exit(1)
struct.pack_into("<I", b, 28, zlib.crc32(bytes(b[64:64 + 32 * n])))
struct.pack_into("<I", b, 32, 0)
struct.pack_into("<I", b, 32, zlib.crc32(bytes(b[0:64])))
open(sys.argv[2], "wb").write(b)
PY
expect 1 "--info on a bake with a page index out of range" "$BIN" --info "$T/pgbad.glow"; err_has "TPAG triangle 0: lightmap page 99"
python3 - "$T/pg5.glow" "$T/pgnone.glow" <<'PY' && pass "  TPAG renamed (an unknown section) and resealed" || fail "  could not rename TPAG"
import struct, sys, zlib
b = bytearray(open(sys.argv[1], "rb").read())
n = struct.unpack_from("<I", b, 12)[0]
e = next(64 + 32 * i for i in range(n) if b[64 + 32 * i:68 + 32 * i] == b"TPAG")
b[e:e + 4] = b"XPAG"  # readers skip fourccs they do not know: the pages are gone
struct.pack_into("<I", b, 28, zlib.crc32(bytes(b[64:64 + 32 * n])))
struct.pack_into("<I", b, 32, 0)
struct.pack_into("<I", b, 32, zlib.crc32(bytes(b[0:64])))
open(sys.argv[2], "wb").write(b)
PY
expect 1 "--info on a paged bake without TPAG" "$BIN" --info "$T/pgnone.glow"; err_has "missing section 'TPAG'"

# the shared Cornell box (two coincident duplicate faces: skipped and counted)
if [ -n "$SHARED" ] && [ -f "$SHARED/scenes/cornell-box/CornellBox-Original.obj" ]; then
  expect 0 "bake shared CornellBox-Original" "$BIN" "$SHARED/scenes/cornell-box/CornellBox-Original.obj" -o "$T/o.glow" "${SMALL[@]}" --json
  python3 -c "import json,sys; sys.exit(0 if json.load(open(sys.argv[1]))['scene_stats']['skipped_duplicate'] == 4 else 1)" \
    "$T/out" && pass "  2 duplicate quads (4 triangles) skipped" || { fail "  duplicates"; grep skipped "$T/out"; }
else
  echo "skip shared scenes (not found)"
fi

# Winding as exporters leave it (Glow lights front faces only). The window room with two walls wound
# outwards, joined to the rest by shared edges and T-junctions (the window wall's pieces): the import
# turns the walls' 20 triangles back (the table legs' and the sofa's x faces, ties within their own
# boxes, stay) and the bake has no texels facing the wrong way. The room as two
# triangles a quad with 30 % flipped at random: 19 turned back; the floor, one quad of two triangles
# with one flipped, is a tie and stays. The room as authored: neither.
ROOM=$(cd "$(dirname "$0")/../.." && pwd)/scenes/window-room
expect 0 "bake a room with two walls wound outwards" "$BIN" "$ROOM/window-room-outward.obj" -o "$T/wr.glow" "${SMALL[@]}"
err_has "20 triangles turned to agree with the winding of their neighbours"
if grep -q "back faces" "$T/err"; then fail "  back faces left after turning"; else pass "  no back-face warning"; fi
expect 0 "bake a room with mixed winding" "$BIN" "$ROOM/window-room-mixed.obj" -o "$T/wr.glow" "${SMALL[@]}"
err_has "19 triangles turned to agree with the winding of their neighbours"
# a 4 x 3 x 4 m box room, one material a face (no edge joins two faces), its four walls wound outwards:
# nothing to turn, and the floor's and ceiling's texels (47 % of the texels) see the walls' back faces
cat > "$T/box.mtl" <<'MTL'
newmtl floor
Kd 0.6 0.6 0.6
newmtl ceiling
Kd 0.7 0.7 0.7
newmtl wall_a
Kd 0.7 0.7 0.7
newmtl wall_b
Kd 0.7 0.7 0.7
newmtl wall_c
Kd 0.7 0.7 0.7
newmtl wall_d
Kd 0.7 0.7 0.7
newmtl lamp
Kd 0.5 0.5 0.5
Ke 10 10 10
MTL
cat > "$T/box.obj" <<'OBJ'
mtllib box.mtl
v -2 0 -2
v 2 0 -2
v 2 0 2
v -2 0 2
v -2 3 -2
v 2 3 -2
v 2 3 2
v -2 3 2
v -0.3 2.9 -0.3
v 0.3 2.9 -0.3
v 0.3 2.9 0.3
v -0.3 2.9 0.3
usemtl floor
f 4 3 2 1
usemtl ceiling
f 5 6 7 8
usemtl wall_a
f 4 8 5 1
usemtl wall_b
f 6 7 3 2
usemtl wall_c
f 5 6 2 1
usemtl wall_d
f 3 7 8 4
usemtl lamp
f 9 10 11 12
OBJ
expect 0 "bake a box room with its four walls wound outwards" "$BIN" "$T/box.obj" -o "$T/wr.glow" "${SMALL[@]}"
err_has "see mostly back faces"
expect 0 "bake the room as authored" "$BIN" "$ROOM/window-room.obj" -o "$T/wr.glow" "${SMALL[@]}"
if grep -q -E "back faces|turned" "$T/err"; then fail "  a correctly wound room is warned about"; else pass "  no winding warning"; fi

echo "$fails failure(s)"
[ "$fails" = 0 ]
