#!/usr/bin/env bash
# The GL samples (samples/01_cornell, samples/03_dynamic_object): bakes builtin:cornell --quality low,
# runs each headless --frames 3 --out DIR and checks the exit status, the PNGs (signature, 320x240),
# the per-frame stats lines (GPU ms per stage, bounce count), that frames differ (01: the moving light;
# 01 --static-light --view surfels: the animated lamp alone; 03: the moving sphere), every debug view,
# a scene JSON, and the error paths (missing or bad bake / scene: exit 1 naming the file; bad options:
# exit 2). Without an OpenGL 4.5 context the samples exit 77: this script then prints SKIP and exits 0
# (ctest's SKIP_RETURN_CODE is set for the C tests only).
#   usage: test_samples_gl.sh BIN_DIR SHARED_DIR
set -u
BAKE=$1/glow-bake
S1=$1/sample-01_cornell
S3=$1/sample-03_dynamic_object
SCENES=$(cd "$(dirname "$0")/../../scenes" && pwd)
. "$(dirname "$0")/lib/common.sh"
for s in "$S1" "$S3"; do
  if [ ! -x "$s" ]; then echo "FAIL $s not built (samples need GLOW_BUILD_SAMPLES and GLOW_WITH_GL)"; exit 1; fi
done

expect 0 "bake cornell" "$BAKE" builtin:cornell -o "$T/c.glow" --quality low -q --threads 2

# GL 4.5 available? (the first real run decides; exit 77 = no context, with the reason)
"$S1" "$T/c.glow" --headless --frames 3 --out "$T/p1" >"$T/out" 2>"$T/err"; rc=$?
if [ "$rc" = 77 ]; then
  echo "SKIP: no OpenGL 4.5 context: $(cat "$T/err")"; exit 0
fi
[ "$rc" = 0 ] && pass "01_cornell 3 frames (exit 0)" || { fail "01_cornell 3 frames: exit $rc"; sed 's/^/     /' "$T/err" | head -5; }
cp "$T/out" "$T/run1.txt"; cat "$T/run1.txt"

is_png() { # FILE W H: a PNG of that size
  [ -s "$1" ] || return 1
  [ "$(head -c 8 "$1" | od -An -tx1 | tr -d ' \n')" = 89504e470d0a1a0a ] || return 1
  local wh; wh=$(od -An -tu1 -j16 -N8 "$1" | awk '{ print $1*16777216 + $2*65536 + $3*256 + $4, $5*16777216 + $6*65536 + $7*256 + $8 }')
  [ "$wh" = "$2 $3" ]
}
check_run() { # NAME OUT_TXT PNG_DIR FRAMES W H
  local n; n=$(grep -c '^frame ' "$2")
  [ "$n" = "$4" ] && pass "  $1: $4 frame lines" || fail "  $1: $n frame lines, wanted $4"
  if awk '/^frame / { if ($0 ~ /GPU ms: surfels [0-9.]+ \(hook [0-9.]+\) pull [0-9.]+ caches [0-9.]+ outputs [0-9.]+ total [0-9.]+ draw [0-9.]+  bounces [0-9]+  intensity [0-9.]+/) ok++ }
          END { exit !(ok == '"$4"') }' "$2"; then
    pass "  $1: GPU ms per stage, bounces and intensity on every frame"
  else
    fail "  $1: stats lines malformed"
  fi
  local f last=$(( $4 - 1 ))
  for f in $(seq 0 "$last"); do
    is_png "$3/frame_$(printf %03d "$f").png" "$5" "$6" || { fail "  $1: $3/frame_$(printf %03d "$f").png missing, not a PNG or not $5x$6"; return; }
  done
  pass "  $1: $4 PNGs of $5x$6"
}
check_run 01_cornell "$T/run1.txt" "$T/p1" 3 320 240
grep -q '^frame 2 .*bounces 3 ' "$T/run1.txt" && pass "  01_cornell: one bounce per update" || fail "  01_cornell: bounce count"
grep -q 'emissive surfels, animated' "$T/run1.txt" && pass "  01_cornell: the lamp is animated" || fail "  01_cornell: no animated lamp"
grep -q 'an emission texture of 64 x 4 texels through its UVs' "$T/run1.txt" &&
  pass "  01_cornell: the lamp is driven by glow_system_set_emission_texture (builtin:cornell's lamp UVs)" ||
  fail "  01_cornell: the lamp is not driven by an emission texture"
if ! cmp -s "$T/p1/frame_001.png" "$T/p1/frame_002.png"; then pass "  01_cornell: frames 1 and 2 differ (moving light)"; else fail "  01_cornell: frames 1 and 2 identical"; fi
# the animated area light on its own: the light stands still, the surfels view shows direct light + emission
# (no bounce), so only the lamp's emission can change the picture
expect 0 "01_cornell --static-light --view surfels" "$S1" "$T/c.glow" --headless --frames 3 --out "$T/ps" --static-light --view surfels
if ! cmp -s "$T/ps/frame_001.png" "$T/ps/frame_002.png"; then pass "  the lamp's emission changes between frames"; else fail "  the lamp does not change"; fi
expect 0 "01_cornell --static-light --view direct" "$S1" "$T/c.glow" --headless --frames 2 --out "$T/pd" --static-light --view direct
if cmp -s "$T/pd/frame_000.png" "$T/pd/frame_001.png"; then pass "  direct view of a static light: frames identical"; else fail "  direct view of a static light changes"; fi

# 03: the sphere moves
expect 0 "03_dynamic_object 3 frames" "$S3" "$T/c.glow" --headless --frames 3 --out "$T/p3"
cp "$T/out" "$T/run3.txt"; cat "$T/run3.txt"
check_run 03_dynamic_object "$T/run3.txt" "$T/p3" 3 320 240
grep -q 'shaded from the grid' "$T/run3.txt" && pass "  03: sphere shaded from the grid" || fail "  03: no grid sphere"
if ! cmp -s "$T/p3/frame_001.png" "$T/p3/frame_002.png"; then pass "  03: frames 1 and 2 differ (moving sphere)"; else fail "  03: frames 1 and 2 identical"; fi

# every view, other sizes, a scene file, a spot light, no --out
for v in indirect direct surfels charts links clusters lit-clusters; do
  expect 0 "03 --view $v" "$S3" "$T/c.glow" --headless --frames 1 --view "$v" --width 96 --height 64 --out "$T/v_$v"
  is_png "$T/v_$v/frame_000.png" 96 64 && pass "  96x64 PNG" || fail "  $v: no 96x64 PNG"
done
expect 0 "01 --scene cornell-builtin-spot.json" "$S1" "$T/c.glow" --headless --frames 2 --scene "$SCENES/cornell-builtin-spot.json" --width 64 --height 64
grep -q 'light 0: spot, moving' "$T/out" && pass "  the scene's spot light moves" || fail "  scene light not used"
expect 0 "01 --spot --bounce 0.5 --iterations 2 --exposure 2 --no-direct" "$S1" "$T/c.glow" --headless --frames 2 --spot --bounce 0.5 --iterations 2 --exposure 2 --no-direct --width 64 --height 48
grep -q '^frame 1 .*bounces 4  intensity 0.50' "$T/out" && pass "  2 iterations per update, intensity 0.5" || fail "  bounce settings not applied"
expect 0 "01 no --out" "$S1" "$T/c.glow" --headless --frames 1 --width 32 --height 32
grep -q '^frame 0 ' "$T/out" && pass "  one frame" || fail "  no frame line"

# errors: a missing or corrupt bake / scene is exit 1 naming the file; bad command lines are exit 2
for s in "$S1" "$S3"; do
  n=$(basename "$s")
  expect 1 "$n: missing bake" "$s" "$T/nope.glow" --headless --frames 1; err_has "nope.glow"
  head -c 1000 "$T/c.glow" > "$T/cut.glow"
  expect 1 "$n: truncated bake" "$s" "$T/cut.glow" --headless --frames 1; err_has "cut.glow"
  expect 1 "$n: missing scene" "$s" "$T/c.glow" --headless --frames 1 --scene "$T/nope.json"; err_has "nope.json"
  : > "$T/file"
  expect 1 "$n: --out is a file" "$s" "$T/c.glow" --headless --frames 1 --out "$T/file"; err_has "$T/file"
  mkdir -p "$T/blocked/frame_000.png"
  expect 1 "$n: PNG cannot be written" "$s" "$T/c.glow" --headless --frames 1 --width 32 --height 32 --out "$T/blocked"; err_has "frame_000.png"
  expect 2 "$n: no arguments" "$s"
  expect 2 "$n: unknown option" "$s" "$T/c.glow" --headless --frobnicate; err_has "frobnicate"
  expect 2 "$n: bad --view" "$s" "$T/c.glow" --headless --view sideways; err_has "sideways"
  expect 2 "$n: bad --width" "$s" "$T/c.glow" --headless --width 9 --height 64; err_has "width"
  expect 2 "$n: --width without --height" "$s" "$T/c.glow" --headless --width 64
  expect 2 "$n: bad --bounce" "$s" "$T/c.glow" --headless --bounce 2; err_has "bounce"
  expect 2 "$n: bad --pick" "$s" "$T/c.glow" --headless --pick 1,2; err_has "pick"
  expect 2 "$n: bad --frames" "$s" "$T/c.glow" --headless --frames 0; err_has "frames"
  expect 2 "$n: two bakes" "$s" "$T/c.glow" "$T/c.glow" --headless
  expect 0 "$n: --help" "$s" --help
  grep -q "usage" "$T/out" && pass "  usage printed" || fail "  no usage"
done

[ "$fails" = 0 ] && echo "all passed" || echo "$fails failed"
exit $((fails > 0))
