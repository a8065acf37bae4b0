#!/usr/bin/env bash
# CLI behaviour of environment maps (docs/envmap.md): glow-envmap sky and info (a written sky's sun is
# found where it was put, with its irradiance), glow-eval skymap, glow-render of a scene with an
# environment_map (with and without --envmap-bsdf-only), and bad input: a missing or non-EXR map, a
# bad scale, bad generator options, each with a message naming the file or the option. About 3 s.
#   usage: test_envmap_cli.sh BIN_DIR SHARED_DIR
set -u
BIN=$1
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
. "$(dirname "$0")/lib/common.sh"

# --- the generator and the inspector
expect 0 "envmap: sky" "$BIN/glow-envmap" sky --out "$T/sky.exr" --width 128 --sun-elevation 40 --sun-azimuth 90 \
  --sun-radius 2 --sun-irradiance 10,9,8
[ -s "$T/sky.exr" ] && pass "  wrote sky.exr" || fail "  no sky.exr"
expect 0 "envmap: info" "$BIN/glow-envmap" info "$T/sky.exr" --residual "$T/rest.exr"
cp "$T/out" "$T/info.json"
[ -s "$T/rest.exr" ] && pass "  wrote the residual" || fail "  no residual"
python3 -c "
import json, math, sys
i = json.load(open('$T/info.json'))
s = i['sun']
# azimuth 90 from -Z towards +X, elevation 40: (cos 40, sin 40, 0)
want = (math.cos(math.radians(40)), math.sin(math.radians(40)), 0.0)
err = math.degrees(math.acos(min(1.0, sum(a * b for a, b in zip(s['to_sun'], want)))))
ok = s['found'] and err < 0.5 and all(abs(e - w) < 0.01 * w for e, w in zip(s['irradiance'], (10, 9, 8)))
ok = ok and len(i['sh9']) == 9 and i['width'] == 128 and i['height'] == 64
# the split (residual SH9 + the sun as a directional light) lights any normal within 1 % of the maximum
ok = ok and i['irradiance_check']['residual_sh9_plus_sun_error'] < 0.01
print('ok  ' if ok else 'FAIL', '  sun found %.3f deg off, irradiance %s' % (err, s['irradiance']))
sys.exit(0 if ok else 1)" || fails=$((fails + 1))
expect 0 "eval: skymap" python3 "$ROOT/tools/glow-eval" skymap --out "$T/sky2.exr" --bin "$BIN" --width 64 --sun-scale 0
[ -s "$T/sky2.exr" ] && pass "  wrote sky2.exr" || fail "  no sky2.exr"

# --- bad input
expect 2 "envmap: odd width" "$BIN/glow-envmap" sky --out "$T/x.exr" --width 7; err_has "--width"
expect 2 "envmap: bad colour" "$BIN/glow-envmap" sky --out "$T/x.exr" --zenith 1,2; err_has "--zenith"
expect 2 "envmap: no --out" "$BIN/glow-envmap" sky; err_has "--out"
expect 1 "envmap: missing map" "$BIN/glow-envmap" info "$T/none.exr"; err_has "none.exr"
expect 2 "eval: skymap bad elevation" python3 "$ROOT/tools/glow-eval" skymap --out "$T/x.exr" --bin "$BIN" --sun-elevation 95
err_has "elevation"
echo '{"mesh": "builtin:cornell", "environment_map": {"path": "nowhere.exr"}}' > "$T/missing.json"
expect 1 "render: missing map" "$BIN/glow-render" "$T/missing.json" --out "$T/x" -q
err_has "missing.json"; err_has "nowhere.exr"
echo '{"mesh": "builtin:cornell", "environment_map": {"path": "missing.json"}}' > "$T/notexr.json"
expect 1 "render: not an EXR" "$BIN/glow-render" "$T/notexr.json" --out "$T/x" -q; err_has "not an OpenEXR file"
echo '{"mesh": "builtin:cornell", "environment_map": {"path": "sky.exr", "scale": -1}}' > "$T/neg.json"
expect 1 "render: negative scale" "$BIN/glow-render" "$T/neg.json" --out "$T/x" -q
err_has "neg.json"; err_has "environment_map.scale (-1) is negative"
if ls "$T"/x* >/dev/null 2>&1; then fail "  output left behind"; else pass "  nothing left behind"; fi

# --- glow-render with the map: the open court, MIS and BSDF-only; both finite, the sky in view
cat > "$T/court.json" <<EOF
{"mesh": "builtin:pillar-court", "environment_map": {"path": "sky.exr", "rotation_deg": 45},
 "camera": {"position": [-5.5, 1.6, 1.2], "target": [4.0, 1.0, 0.4], "vfov_deg": 60, "width": 32, "height": 18}}
EOF
expect 0 "render: environment_map" "$BIN/glow-render" "$T/court.json" --out "$T/mis" --spp 4
expect 0 "render: --envmap-bsdf-only" "$BIN/glow-render" "$T/court.json" --out "$T/bsdf" --spp 4 --envmap-bsdf-only
"$BIN/glow-compare" "$T/mis.exr" "$T/bsdf.exr" --json --no-flip > "$T/cmp.json" 2>"$T/err" && pass "  images readable" \
  || fail "  glow-compare cannot read them"
python3 -c "
import json, math, sys
c = json.load(open('$T/cmp.json'))
m, b = sum(c['mean_test']) / 3, sum(c['mean_ref']) / 3
ok = math.isfinite(m) and math.isfinite(b) and m > 0.05 and b > 0.05
print('ok  ' if ok else 'FAIL', '  mean radiance MIS %.4g, BSDF only %.4g' % (m, b))
sys.exit(0 if ok else 1)" || fails=$((fails + 1))
echo "$fails failure(s)"
[ "$fails" = 0 ]
