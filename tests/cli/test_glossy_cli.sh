#!/usr/bin/env bash
# CLI behaviour of the glossy path (docs/glossy.md): glow-render on a scene with a GGX material
# (reference and Glow's view at 16x16 with a small 3-band bake: PREFIX_specular.exr written, finite,
# part of the indirect image; each --glossy lobe; none = zero specular), and bad input: an unknown
# lobe, --glossy without --glow, a material name the mesh lacks, a roughness out of range;
# glow-eval glossy on a scene without a GGX material or with a bad --roughness. About 8 s.
#   usage: test_glossy_cli.sh BIN_DIR SHARED_DIR
set -u
BIN=$1
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
. "$(dirname "$0")/lib/common.sh"

SCENE=$ROOT/scenes/cornell-builtin-glossy.json
R=(--width 16 --height 16 --spp 8 --seed 3 -q)
# --- bad input
expect 2 "render: unknown lobe" "$BIN/glow-render" "$SCENE" --out "$T/x" --glossy shiny; err_has "zh-ggx"
expect 2 "render: --glossy without --glow" "$BIN/glow-render" "$SCENE" --out "$T/x" --glossy phong; err_has "glossy"
echo '{"mesh": "builtin:cornell", "materials": {"flor": {"ggx": {"roughness": 0.3}}}}' > "$T/name.json"
expect 1 "render: unknown material name" "$BIN/glow-render" "$T/name.json" --out "$T/x" "${R[@]}"
err_has "name.json"; err_has "materials.flor"; err_has "floor"
echo '{"mesh": "builtin:cornell", "materials": {"floor": {"ggx": {"roughness": 1.5}}}}' > "$T/rough.json"
expect 1 "render: roughness out of range" "$BIN/glow-render" "$T/rough.json" --out "$T/x" "${R[@]}"
err_has "rough.json"; err_has "materials.floor.ggx.roughness (1.5) is outside (0, 1]"
if ls "$T"/x* >/dev/null 2>&1; then fail "  output left behind"; else pass "  nothing left behind"; fi
expect 1 "eval: no GGX material" python3 "$ROOT/tools/glow-eval" glossy "$ROOT/scenes/cornell-builtin.json" --out "$T/ev" --bin "$BIN"
err_has "cornell-builtin.json"; err_has "ggx"
expect 2 "eval: bad roughness" python3 "$ROOT/tools/glow-eval" glossy "$SCENE" --out "$T/ev" --bin "$BIN" --roughness 0.3,0
err_has "roughness"

# --- the reference writes the specular image, a part of the indirect one
expect 0 "render: glossy reference" "$BIN/glow-render" "$SCENE" --out "$T/ref" "${R[@]}"
[ -s "$T/ref_specular.exr" ] && pass "  wrote ref_specular.exr" || fail "  missing ref_specular.exr"
expect 0 "render: the scene without its GGX layer" "$BIN/glow-render" "$ROOT/scenes/cornell-builtin.json" --out "$T/lamb" "${R[@]}"
[ ! -e "$T/lamb_specular.exr" ] && pass "  no specular image without a GGX material" || fail "  specular image for a Lambertian scene"
"$BIN/glow-compare" "$T/ref_specular.exr" "$T/ref_indirect.exr" --json --no-flip > "$T/cmp.json" 2>"$T/err" \
  && pass "  specular image readable" || fail "  glow-compare cannot read the specular image"
python3 -c "
import json, math, sys
c = json.load(open('$T/cmp.json'))
ms, mi = sum(c['mean_test']) / 3, sum(c['mean_ref']) / 3
ok = all(math.isfinite(v) for v in c['mean_test'] + c['mean_ref']) and 0 < ms < mi
print('ok  ' if ok else 'FAIL', ' reference specular mean %.5g, indirect %.5g' % (ms, mi))
sys.exit(0 if ok else 1)" || fails=$((fails + 1))

# --- Glow's view with each lobe
"$BIN/glow-bake" builtin:cornell -o "$T/b3.glow" --quality low --surfels 2048 --links 32 --bands 3 -q >/dev/null 2>&1
for lobe in zh-ggx zh-ggx-dominant phong none; do
  expect 0 "render: Glow's view, --glossy $lobe" "$BIN/glow-render" "$SCENE" --glow "$T/b3.glow" --bounces 16 --glossy $lobe \
    --out "$T/g_$lobe" "${R[@]}"
  "$BIN/glow-compare" "$T/g_${lobe}_specular.exr" "$T/ref_specular.exr" --json --no-flip > "$T/g.json" 2>"$T/err" || fail "  unreadable"
  python3 -c "
import json, math, sys
c = json.load(open('$T/g.json'))
m = sum(c['mean_test']) / 3
ok = math.isfinite(m) and ((m == 0) if '$lobe' == 'none' else (m > 0))
print('ok  ' if ok else 'FAIL', '  $lobe: specular mean %.5g (reference %.5g)' % (m, sum(c['mean_ref']) / 3))
sys.exit(0 if ok else 1)" || fails=$((fails + 1))
done
echo "$fails failure(s)"
[ "$fails" = 0 ]
