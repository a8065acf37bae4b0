#!/usr/bin/env bash
# CLI behaviour of the evaluation tools: glow-render (reference and Glow's view), glow-compare and
# glow-stability on the built-in Cornell box at CI size (32x32); glow-eval's sweeps are in
# test_eval_sweep_cli.sh (a test of its own, so that ctest runs the two halves side by side). Checks exit codes and messages
# for bad input, that nothing is left behind on failure, that Glow's indirect-only view plus the
# reference's direct image scores exactly what the full Glow view scores, and that glow-eval writes
# its CSV, summary and charts.
#   usage: test_eval_cli.sh BIN_DIR SHARED_DIR
set -u
BIN=$1
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
. "$(dirname "$0")/lib/common.sh"
json_num() { python3 -c "import json,sys; print(json.load(open(sys.argv[1]))[sys.argv[2]])" "$1" "$2"; }

SCENE=$ROOT/scenes/cornell-builtin.json
# --- glow-render: bad input
expect 2 "render: no arguments" "$BIN/glow-render"
expect 2 "render: unknown option" "$BIN/glow-render" "$SCENE" --out "$T/x" --frobnicate; err_has "frobnicate"
expect 2 "render: bad spp" "$BIN/glow-render" "$SCENE" --out "$T/x" --spp 0
expect 2 "render: --luma without --glow" "$BIN/glow-render" "$SCENE" --out "$T/x" --luma 2; err_has "glow"
expect 1 "render: missing scene" "$BIN/glow-render" "$T/none.json" --out "$T/x"; err_has "none.json"
echo '{"mesh": ' > "$T/broken.json"
expect 1 "render: broken JSON" "$BIN/glow-render" "$T/broken.json" --out "$T/x"; err_has "broken.json"
expect 1 "render: missing bake" "$BIN/glow-render" "$SCENE" --glow "$T/none.glow" --out "$T/x"; err_has "none.glow"
expect 1 "render: unwritable output" "$BIN/glow-render" "$SCENE" --out "$T/no/such/dir/x" --spp 1 --width 8 --height 8
if ls "$T"/x* >/dev/null 2>&1; then fail "  output left behind"; else pass "  nothing left behind"; fi

# --- a bake of another mesh is refused
"$BIN/glow-bake" builtin:furnace -o "$T/furnace.glow" --quality low --surfels 512 --links 16 -q >/dev/null 2>&1
expect 1 "render: bake of another mesh" "$BIN/glow-render" "$SCENE" --glow "$T/furnace.glow" --out "$T/x" --spp 1 --width 8 --height 8
err_has "furnace.glow"

# --- reference, Glow's view, indirect-only view
R=(--width 32 --height 32 --spp 16 --seed 7 -q)
expect 0 "render: reference" "$BIN/glow-render" "$SCENE" --out "$T/ref" "${R[@]}"
for f in ref.exr ref_direct.exr ref_indirect.exr ref.png; do [ -s "$T/$f" ] && pass "  wrote $f" || fail "  missing $f"; done
# --near-split: the indirect image is unchanged; the near part is a per-pixel part of it (never above it,
# not zero in a box with corners); a split beyond the scene puts all of it in the near part.
expect 2 "render: --near-split 0" "$BIN/glow-render" "$SCENE" --out "$T/x" --near-split 0; err_has "near-split"
expect 2 "render: --near-split with --glow" "$BIN/glow-render" "$SCENE" --out "$T/x" --near-split 0.1 --glow "$T/none.glow"; err_has "near-split"
expect 0 "render: reference, --near-split 0.1" "$BIN/glow-render" "$SCENE" --out "$T/ns" "${R[@]}" --near-split 0.1
cmp -s "$T/ns_indirect.exr" "$T/ref_indirect.exr" && pass "  indirect image unchanged by the split" || fail "  the split changed the indirect image"
expect 0 "render: reference, --near-split 1000" "$BIN/glow-render" "$SCENE" --out "$T/nall" "${R[@]}" --near-split 1000
cmp -s "$T/nall_indirect_near.exr" "$T/ref_indirect.exr" && pass "  a split beyond the scene: all light is near" || fail "  near != indirect at R = 1000"
expect 0 "compare: near part against the indirect" "$BIN/glow-compare" "$T/ns_indirect_near.exr" "$T/ref_indirect.exr" --blocks-csv "$T/nb.csv" --block 1 --no-flip --json
python3 - "$T" <<'PY' && pass "  near part: within every pixel's indirect, 0 < share < 1" || fail "  near part wrong"
import csv, json, sys
t = sys.argv[1]
rows = list(csv.DictReader(open(t + "/nb.csv")))
assert len(rows) == 32 * 32
for r in rows:
    for c in "rgb":
        assert float(r["test_" + c]) <= float(r["ref_" + c]) + 1e-6 * max(1.0, float(r["ref_" + c])), r
ratio = json.load(open(t + "/out"))["mean_ratio"]
assert 0.005 < ratio < 0.9, ratio
PY
expect 0 "compare: --ref-sub undoes --ref-add" "$BIN/glow-compare" "$T/ref.exr" "$T/ref.exr" --ref-add "$T/ns_indirect_near.exr" --ref-sub "$T/ns_indirect_near.exr" --json --no-flip
python3 -c "import json,sys; sys.exit(0 if json.load(open(sys.argv[1]))['rel_rmse'] < 1e-6 else 1)" "$T/out" \
  && pass "  rel RMSE below 1e-6 (float rounding of a + b - b)" || fail "  rel RMSE $(json_num "$T/out" rel_rmse)"
expect 1 "compare: --ref-sub of a missing image" "$BIN/glow-compare" "$T/ref.exr" "$T/ref.exr" --ref-sub "$T/none.exr"; err_has "none.exr"
"$BIN/glow-bake" builtin:cornell -o "$T/cornell.glow" --quality low -q >/dev/null 2>&1 && pass "bake builtin:cornell (low)" || fail "bake builtin:cornell"
expect 0 "render: Glow's view" "$BIN/glow-render" "$SCENE" --glow "$T/cornell.glow" --out "$T/glow" "${R[@]}" --bounces 64
# glow-bench's CPU path runs under ASan here (cli/test_bench_gl runs only in the release pass)
expect 0 "bench: cpu, exact host" "$BIN/glow-bench" "$T/cornell.glow" "$SCENE" --frames 3 --warmup 1 --no-machine --json
grep -q '"total' "$T/out" && pass "  bench JSON has the update total" || fail "  bench JSON lacks the update total"
# budgets: a caches cap with an unbudgeted twin; the report holds the gathered count and the error
expect 0 "bench: --budget-caches 64" "$BIN/glow-bench" "$T/cornell.glow" "$SCENE" --frames 4 --warmup 1 --no-machine --json --budget-caches 64
python3 -c "import json,sys; b=json.load(open(sys.argv[1]))['budget']; assert 64 <= b['median_caches_gathered'] <= 79 and 0 < b['luma_error_max'] < 1, b" "$T/out" \
  && pass "  64 caches (4 groups) gathered, error against the twin reported" || fail "  budget JSON: $(head -c 300 "$T/out")"
expect 0 "bench: --still --converge" "$BIN/glow-bench" "$T/cornell.glow" "$SCENE" --frames 4 --warmup 40 --no-machine --json --still --converge 0.01
python3 -c "import json,sys; b=json.load(open(sys.argv[1]))['budget']; assert b['median_caches_gathered'] == 0, b" "$T/out" \
  && pass "  still light: converged caches cost nothing" || fail "  converge JSON: $(head -c 300 "$T/out")"
expect 2 "bench: --budget-ms 0" "$BIN/glow-bench" "$T/cornell.glow" "$SCENE" --budget-ms 0
expect 0 "bench: --walk" "$BIN/glow-bench" "$T/cornell.glow" "$SCENE" --frames 8 --warmup 1 --no-machine --json --budget-caches 64 --walk
python3 -c "import json,sys; b=json.load(open(sys.argv[1]))['budget']; assert b['walk_near_radius'] > 0 and 0 <= b['walk_near_error_mean'] <= b['walk_near_error_max'], b" "$T/out" \
  && pass "  the walk reports the error near its focus" || fail "  walk JSON: $(head -c 300 "$T/out")"
expect 2 "bench: --walk without a budget" "$BIN/glow-bench" "$T/cornell.glow" "$SCENE" --walk
# the output planes' format (glow_system_desc.output_planes): named in the report, refused when unknown
for p in rgba16f none; do
  expect 0 "bench: --planes $p" "$BIN/glow-bench" "$T/cornell.glow" "$SCENE" --frames 2 --warmup 1 --no-machine --json --planes $p
  python3 -c "import json,sys; j=json.load(open(sys.argv[1])); assert j['output_planes'] == sys.argv[2], j.get('output_planes')" "$T/out" "$p" \
    && pass "  the report says $p" || fail "  output_planes: $(grep -o '"output_planes"[^,]*' "$T/out")"
done
expect 2 "bench: --planes f8" "$BIN/glow-bench" "$T/cornell.glow" "$SCENE" --planes f8; err_has "--planes must be"
expect 0 "render: Glow's indirect only" "$BIN/glow-render" "$SCENE" --glow "$T/cornell.glow" --out "$T/gi" "${R[@]}" --bounces 64 --indirect-only
cmp -s "$T/glow_indirect.exr" "$T/gi_indirect.exr" && pass "  indirect-only gives the same indirect image" || fail "  indirect images differ"
cmp -s "$T/glow_direct.exr" "$T/ref_direct.exr" && pass "  Glow's direct image is the reference's" || fail "  direct images differ"
# the texel image (Glow's view with a lightmap) and glow-compare's blotches
[ -s "$T/glow_texel.exr" ] && pass "  Glow's view wrote its texel image" || fail "  no glow_texel.exr"
[ ! -e "$T/ref_texel.exr" ] && pass "  the reference writes none" || fail "  the reference wrote a texel image"
cmp -s "$T/glow_texel.exr" "$T/gi_texel.exr" && pass "  indirect-only gives the same texels" || fail "  texel images differ"
expect 0 "compare: --texels" "$BIN/glow-compare" "$T/glow_indirect.exr" "$T/ref_indirect.exr" --texels "$T/glow_texel.exr" --blotch-min-pixels 4 --json --no-flip
python3 -c "import json,sys; b=json.load(open(sys.argv[1]))['blotches']; assert b['texels'] > 4 and 0 < b['judged'] <= b['texels'] and b['bad'] <= b['judged'] and b['min_pixels'] == 4, b" "$T/out" \
  && pass "  texels grouped and judged" || fail "  blotch JSON: $(head -c 400 "$T/out")"
expect 0 "compare: --texels, an image against itself" "$BIN/glow-compare" "$T/glow_indirect.exr" "$T/glow_indirect.exr" --texels "$T/glow_texel.exr" --blotch-min-pixels 1 --json --no-flip
python3 -c "import json,sys; b=json.load(open(sys.argv[1]))['blotches']; assert b['bad'] == 0 and b['blotches'] == 0 and b['worst_rel'] == 0, b" "$T/out" \
  && pass "  no blotch in an exact image" || fail "  blotch JSON: $(head -c 400 "$T/out")"
expect 2 "compare: --blotch-threshold without --texels" "$BIN/glow-compare" "$T/glow.exr" "$T/ref.exr" --blotch-threshold 0.3; err_has "texels"
expect 1 "compare: --texels of a missing file" "$BIN/glow-compare" "$T/glow.exr" "$T/ref.exr" --texels "$T/none.exr" --no-flip; err_has "none.exr"

# --- glow-compare
expect 2 "compare: one file" "$BIN/glow-compare" "$T/ref.exr"
expect 1 "compare: missing file" "$BIN/glow-compare" "$T/none.exr" "$T/ref.exr"; err_has "none.exr"
expect 0 "compare: self" "$BIN/glow-compare" "$T/ref.exr" "$T/ref.exr" --json
cp "$T/out" "$T/self.json"
python3 -c "import sys; sys.exit(0 if float(sys.argv[1]) == 0 else 1)" "$(json_num "$T/self.json" rel_rmse)" && pass "  rel RMSE of an image against itself is 0" || fail "  self rel RMSE not 0"
expect 0 "compare: full view" "$BIN/glow-compare" "$T/glow.exr" "$T/ref.exr" --json; cp "$T/out" "$T/full.json"
expect 0 "compare: indirect-only + reference direct" "$BIN/glow-compare" "$T/gi_indirect.exr" "$T/ref.exr" --add "$T/ref_direct.exr" --json
cp "$T/out" "$T/added.json"
a=$(json_num "$T/full.json" psnr_db); b=$(json_num "$T/added.json" psnr_db)
python3 -c "import sys; a,b=float(sys.argv[1]),float(sys.argv[2]); sys.exit(0 if abs(a-b) < 1e-3 and 10 < a < 90 else 1)" "$a" "$b" \
  && pass "  same PSNR both ways ($a dB)" || fail "  PSNR $a vs $b"

# --- glow-compare: PFM inputs (the referee's format), --ref-add, --panels
# PFMs written with Python's struct: a 32x32 grey constant (big-endian) and an RGB gradient in both byte orders.
python3 - "$T" <<'PY'
import struct, sys
t = sys.argv[1]
open(t + "/const.pfm", "wb").write(b"Pf\n32 32\n1.0\n" + struct.pack(">1024f", *([0.25] * 1024)))
px = [float(x + 4 * y + c) / 8 for y in range(3) for x in range(4) for c in range(3)]  # bottom row first
open(t + "/grad_le.pfm", "wb").write(b"PF\n4 3\n-1.0\n" + struct.pack("<36f", *px))
open(t + "/grad_be.pfm", "wb").write(b"PF\n4 3\n1.0\n" + struct.pack(">36f", *[2 * v for v in px]))
open(t + "/short.pfm", "wb").write(b"PF\n4 3\n-1.0\n" + struct.pack("<20f", *px[:20]))
PY
expect 0 "compare: EXR test, PFM reference" "$BIN/glow-compare" "$T/ref.exr" "$T/const.pfm" --json --no-flip
python3 -c "import json,sys; m=json.load(open(sys.argv[1]))['mean_ref']; sys.exit(0 if m == [0.25, 0.25, 0.25] else 1)" "$T/out" \
  && pass "  grey PFM read as R = G = B = 0.25" || fail "  PFM reference means wrong"
expect 0 "compare: PFM against itself" "$BIN/glow-compare" "$T/grad_le.pfm" "$T/grad_le.pfm" --json
[ "$(json_num "$T/out" rel_rmse)" = 0 ] && pass "  rel RMSE 0" || fail "  self rel RMSE not 0"
expect 0 "compare: little- vs big-endian PFM (twice the values)" "$BIN/glow-compare" "$T/grad_be.pfm" "$T/grad_le.pfm" --json --no-flip
[ "$(json_num "$T/out" mean_ratio)" = 2 ] && pass "  mean ratio 2" || fail "  mean ratio $(json_num "$T/out" mean_ratio), wanted 2"
expect 1 "compare: truncated PFM" "$BIN/glow-compare" "$T/grad_le.pfm" "$T/short.pfm"; err_has "short.pfm"; err_has "truncated PFM"
printf 'P6\n4 3\n255\n' > "$T/p6.pfm"
expect 1 "compare: not a PFM" "$BIN/glow-compare" "$T/p6.pfm" "$T/grad_le.pfm"; err_has "p6.pfm: not an OpenEXR or PFM file"
expect 1 "compare: --add of a truncated PFM" "$BIN/glow-compare" "$T/grad_le.pfm" "$T/grad_le.pfm" --add "$T/short.pfm"; err_has "short.pfm"
expect 0 "compare: --ref-add doubles the reference" "$BIN/glow-compare" "$T/ref.exr" "$T/ref.exr" --ref-add "$T/ref.exr" --json --no-flip
[ "$(json_num "$T/out" mean_ratio)" = 0.5 ] && pass "  mean ratio 0.5" || fail "  mean ratio $(json_num "$T/out" mean_ratio), wanted 0.5"
expect 1 "compare: --ref-add of another size" "$BIN/glow-compare" "$T/ref.exr" "$T/ref.exr" --ref-add "$T/const.pfm" --ref-add "$T/grad_le.pfm"
err_has "grad_le.pfm is 4x3 but"
expect 1 "compare: --ref-add of a truncated PFM" "$BIN/glow-compare" "$T/ref.exr" "$T/ref.exr" --ref-add "$T/short.pfm"; err_has "short.pfm"
expect 2 "compare: --ref-add without an image" "$BIN/glow-compare" "$T/ref.exr" "$T/ref.exr" --ref-add
expect 2 "compare: --panel-exposure without --panels" "$BIN/glow-compare" "$T/ref.exr" "$T/ref.exr" --panel-exposure 2
expect 2 "compare: bad --panel-exposure" "$BIN/glow-compare" "$T/ref.exr" "$T/ref.exr" --panels "$T/p.png" --panel-exposure 0
expect 1 "compare: unwritable --panels" "$BIN/glow-compare" "$T/ref.exr" "$T/ref.exr" --panels "$T/no/such/dir/p.png"; err_has "p.png"
expect 0 "compare: --panels, an image against itself" "$BIN/glow-compare" "$T/ref.exr" "$T/ref.exr" --panels "$T/self.png" --no-flip
expect 0 "compare: --panels, test twice the reference" "$BIN/glow-compare" "$T/ref.exr" "$T/ref.exr" --add "$T/ref.exr" --panels "$T/bright.png" --no-flip
expect 0 "compare: --panels, reference twice the test" "$BIN/glow-compare" "$T/ref.exr" "$T/ref.exr" --ref-add "$T/ref.exr" --panels "$T/dark.png" --block 4 --no-flip
expect 0 "compare: --panels of PFMs, --panel-exposure" "$BIN/glow-compare" "$T/grad_be.pfm" "$T/grad_le.pfm" --panels "$T/grad.png" --panel-exposure 0.25 --no-flip
# --blocks-csv: the block means the block error is made of. 4 x 3 images, --block 2: blocks at x 0, 2 and
# y 0, 2 (the last row a partial block of 2 pixels); the test (big-endian file) is twice the reference.
expect 0 "compare: --blocks-csv" "$BIN/glow-compare" "$T/grad_be.pfm" "$T/grad_le.pfm" --block 2 --blocks-csv "$T/blocks.csv" --no-flip
python3 - "$T" <<'PY' && pass "  blocks CSV: 4 blocks, partial ones sized right, means of both images" || fail "  blocks CSV wrong"
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1] + "/blocks.csv")))
assert [(int(r["x0"]), int(r["y0"]), int(r["pixels"])) for r in rows] == [(0, 0, 4), (2, 0, 4), (0, 2, 2), (2, 2, 2)], rows
# the PFM's rows are stored bottom first: image row y is file row 2 - y; pixel value (x + 4 * row + c) / 8
def mean(x0, y0, c):
    px = [(x + 4 * (2 - y) + c) / 8 for y in range(y0, min(y0 + 2, 3)) for x in range(x0, x0 + 2)]
    return sum(px) / len(px)
for r in rows:
    x0, y0 = int(r["x0"]), int(r["y0"])
    for k, c in enumerate("rgb"):
        assert abs(float(r["ref_" + c]) - mean(x0, y0, k)) < 1e-6, (r, c)
        assert abs(float(r["test_" + c]) - 2 * mean(x0, y0, k)) < 1e-6, (r, c)
    luma = 0.2126 * mean(x0, y0, 0) + 0.7152 * mean(x0, y0, 1) + 0.0722 * mean(x0, y0, 2)
    assert abs(float(r["ref_luma"]) - luma) < 1e-6 and abs(float(r["test_luma"]) - 2 * luma) < 1e-6, r
PY
expect 1 "compare: unwritable --blocks-csv" "$BIN/glow-compare" "$T/grad_le.pfm" "$T/grad_le.pfm" --blocks-csv "$T/no/such/dir/b.csv" --no-flip
err_has "b.csv"; [ ! -e "$T/no/such/dir/b.csv.tmp" ] && pass "  no partial file" || fail "  partial file left"
# A stdlib PNG decoder (8-bit RGB, the 5 filters) checks the panels: 3W x H; TEST and REF as glow-render's
# PNG at the same exposure; the error panel black for equal images, pure red (255) where the test is twice
# the reference, blue round(255 * 0.5) = 128 where it is half, one colour per block.
python3 - "$T" <<'PY' && pass "  panels: 3W x H, images as glow-render's PNG, error map red / blue / black by blocks" || fail "  panels wrong"
import struct, sys, zlib
t = sys.argv[1]
def png(path):
    d = open(path, "rb").read()
    assert d[:8] == b"\x89PNG\r\n\x1a\n"
    pos, idat = 8, b""
    while pos < len(d):
        n, kind = struct.unpack(">I4s", d[pos:pos + 8])
        body = d[pos + 8:pos + 8 + n]
        if kind == b"IHDR": w, h, depth, ctype = struct.unpack(">IIBB", body[:10])
        if kind == b"IDAT": idat += body
        pos += 12 + n
    assert depth == 8 and ctype == 2, (depth, ctype)
    raw, stride, rows, prev = zlib.decompress(idat), 3 * w, [], bytearray(3 * w)
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - 3] if i >= 3 else 0
            b, c = prev[i], prev[i - 3] if i >= 3 else 0
            p = a + b - c
            pr = a if abs(p - a) <= abs(p - b) and abs(p - a) <= abs(p - c) else b if abs(p - b) <= abs(p - c) else c
            line[i] = (line[i] + [0, a, b, (a + b) // 2, pr][f]) & 255
        rows.append(line)
        prev = line
    return w, h, rows
W = 32
ref_w, ref_h, ref = png(t + "/ref.png")
for name, want in (("self", None), ("bright", (255, 0)), ("dark", (0, 128))):
    w, h, rows = png(t + "/" + name + ".png")
    assert (w, h) == (3 * W, W), (name, w, h)
    for y in range(h):
        if name != "dark": assert rows[y][3 * W:6 * W] == ref[y], (name, y, "REF panel")
        if name != "bright": assert rows[y][:3 * W] == ref[y], (name, y, "TEST panel")
    err = [[tuple(rows[y][3 * (2 * W + x):3 * (2 * W + x) + 3]) for x in range(W)] for y in range(h)]
    if want is None:
        assert all(p == (0, 0, 0) for r in err for p in r), name
    else:
        r_max, b_max = want
        assert max(p[0] for r in err for p in r) == r_max and max(p[2] for r in err for p in r) == b_max, name
        assert all(p[1] == 0 and (p[0] == 0 or p[2] == 0) for r in err for p in r), name
        b = 8 if name == "bright" else 4
        assert all(err[y][x] == err[y - y % b][x - x % b] for y in range(h) for x in range(W)), (name, "blocks")
        assert sum(p != (0, 0, 0) for r in err for p in r) > W * W // 2, (name, "mostly coloured")
w, h, rows = png(t + "/grad.png")
assert (w, h) == (12, 3)
# --panel-exposure 0.25: the test panel (twice the values) shows the reference's values at 0.5, top row first:
# the top row is the file's last row (y = 2), pixel 0 R = (0 + 8 + 0) / 8 * 2 = 2 -> x 0.25 = 0.5 -> 188.
assert rows[0][0] == 188, rows[0][:3]
assert rows[0][4 * 3:4 * 3 + 3] == bytes([round(255 * ((1.055 * (v * 0.25) ** (1 / 2.4) - 0.055) if v * 0.25 > 0.0031308 else 12.92 * v * 0.25)) for v in (1.0, 1.125, 1.25)]), rows[0][12:15]
assert all(rows[y][24:36:3] == bytes([255] * 4) for y in range(3)), "error panel red"
PY

# --- glow-stability: the three measurements at toy sizes (they must run and report; the figures are
#     docs/results.md's, from full-size runs)
SCN=$ROOT/scenes
expect 2 "stability: no arguments" "$BIN/glow-stability"
expect 2 "stability: bad number" "$BIN/glow-stability" flicker "$T/cornell.glow" "$SCN/cornell-builtin-moving.json" --frames 0
expect 1 "stability: missing bake" "$BIN/glow-stability" ringing "$T/none.glow" "$SCENE"; err_has "none.glow"
expect 1 "stability: flicker needs a point or spot light" "$BIN/glow-stability" flicker "$T/cornell.glow" "$SCENE" --frames 2
err_has "point or spot"
expect 0 "stability: ringing" "$BIN/glow-stability" ringing "$T/cornell.glow" "$SCENE" --bands-max 3 --dirs 16 --json
python3 -c "import json,sys; r=json.load(open(sys.argv[1])); sys.exit(0 if len(r)==2 and all(0<=x['negative_share']<=1 and x['negative_share_windowed']<=x['negative_share'] for x in r) else 1)" "$T/out" \
  && pass "  ringing JSON: bands 2, 3, windowed share <= plain" || fail "  ringing JSON wrong"
expect 0 "stability: flicker" "$BIN/glow-stability" flicker "$T/cornell.glow" "$SCN/cornell-builtin-moving.json" --frames 4 --probes 8 --samples 16 --csv "$T/flicker.csv"
cp "$T/out" "$T/flicker_full.txt"
expect 0 "stability: flicker --budget-caches 64" "$BIN/glow-stability" flicker "$T/cornell.glow" "$SCN/cornell-builtin-moving.json" --frames 4 --probes 8 --samples 16 --budget-caches 64
grep -q "at most 64 of" "$T/out" && pass "  the budget is named" || fail "  no budget line"
[ "$(grep 'mean |Glow' "$T/out")" != "$(grep 'mean |Glow' "$T/flicker_full.txt")" ] && pass "  a budget changes what Glow shows" || fail "  the budget changed nothing"
[ "$(wc -l < "$T/flicker.csv")" = 6 ] && pass "  flicker CSV: header + 5 frames" || fail "  flicker CSV"
expect 0 "stability: jumps" "$BIN/glow-stability" jumps "$T/cornell.glow" "$SCN/cornell-builtin-spot.json" --pairs 20 --samples 16
grep -q "largest jump" "$T/out" && pass "  jumps reported" || fail "  jumps output"

expect 0 "stability: audit" "$BIN/glow-stability" audit "$T/cornell.glow" "$SCENE" --probes 64 --samples 256 --json --csv "$T/audit.csv"
python3 -c "import json,sys; r=json.load(open(sys.argv[1])); c=r['converged']; sys.exit(0 if 0.85 < c['mean_ratio'] < 1.15 and c['caches_rated'] > 0 and sum(r['visible_solid_angle_hist_2pi_eighths']) == 64 else 1)" "$T/out" \
  && pass "  audit: converged caches within 15 % of the reference on average, histogram of 64 caches" || fail "  audit JSON wrong"
[ "$(wc -l < "$T/audit.csv")" = 65 ] && pass "  audit CSV: header + 64 caches" || fail "  audit CSV"
C2=$(python3 -c "import csv,sys; r=list(csv.DictReader(open(sys.argv[1]))); print(r[3]['cache'] + ',' + r[1]['cache'])" "$T/audit.csv")
expect 0 "stability: audit --caches $C2" "$BIN/glow-stability" audit "$T/cornell.glow" "$SCENE" --samples 64 --caches "$C2" --csv "$T/audit2.csv"
python3 - "$T/audit.csv" "$T/audit2.csv" <<'PY' && pass "  audit --caches: those two caches, in that order, at the same points" || fail "  audit --caches CSV"
import csv, sys
a = list(csv.DictReader(open(sys.argv[1]))); b = list(csv.DictReader(open(sys.argv[2])))
assert [r['cache'] for r in b] == [a[3]['cache'], a[1]['cache']], b
assert [r['x'] for r in b] == [a[3]['x'], a[1]['x']] and [r['glow'] for r in b] == [a[3]['glow'], a[1]['glow']], (a[:4], b)
PY
expect 1 "stability: audit --caches beyond the bake" "$BIN/glow-stability" audit "$T/cornell.glow" "$SCENE" --caches 4000000000; err_has "not a lightmap cache"
expect 2 "stability: --caches with junk" "$BIN/glow-stability" audit "$T/cornell.glow" "$SCENE" --caches 3,x; err_has "'x'"
expect 2 "stability: --caches outside audit" "$BIN/glow-stability" jumps "$T/cornell.glow" "$SCENE" --caches 3; err_has "audit option"

# --- the cut's share of the gather error: surfel radiance from glow-stability, audit in glow-bake
expect 0 "stability: audit writes the surfels' radiance" "$BIN/glow-stability" audit "$T/cornell.glow" "$SCN/cornell-builtin-point.json" \
  --probes 16 --samples 16 --radiance-out "$T/radiance.bin"
[ "$(stat -c %s "$T/radiance.bin")" = $((8192 * 4)) ] && pass "  one float per surfel (8192 at low)" || fail "  radiance file size"
expect 0 "bake: --audit-radiance" "$BIN/glow-bake" builtin:cornell -o "$T/audited.glow" --quality low --audit-radiance "$T/radiance.bin" --audit-csv "$T/cut.csv"
err_has "links audit: gather through the cut / exact"
python3 - "$T/cut.csv" "$T/audited.glow" "$T/cornell.glow" <<'PY' && pass "  audit CSV: every cache, exact gathers > 0, the bake unchanged by the audit" || fail "  audit CSV"
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
assert len(rows) > 1000, len(rows)
assert sum(float(r["exact"]) > 0 for r in rows) > 0.9 * len(rows)
assert all(0 <= float(r["visible_fraction"]) <= 1.0001 for r in rows)
assert open(sys.argv[2], "rb").read() == open(sys.argv[3], "rb").read()
PY
expect 2 "bake: --audit-csv alone" "$BIN/glow-bake" builtin:cornell -o "$T/x.glow" --audit-csv "$T/cut.csv"
expect 1 "bake: missing radiance file" "$BIN/glow-bake" builtin:cornell -o "$T/x.glow" --quality low --audit-radiance "$T/none.bin"
err_has "none.bin"
head -c 100 "$T/radiance.bin" > "$T/short.bin"
expect 1 "bake: radiance of another bake" "$BIN/glow-bake" builtin:cornell -o "$T/x.glow" --quality low --audit-radiance "$T/short.bin"
err_has "8192 surfels"
expect 1 "bake: unwritable audit CSV fails first" "$BIN/glow-bake" builtin:cornell -o "$T/x.glow" --quality low \
  --audit-radiance "$T/radiance.bin" --audit-csv "$T/no/such/dir/cut.csv"
[ -e "$T/x.glow" ] && fail "  a bake was written" || pass "  no bake written"

echo "$fails failure(s)"
[ "$fails" = 0 ]
