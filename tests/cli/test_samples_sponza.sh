#!/usr/bin/env bash
# samples/02_sponza: bakes the shared Dabrovic Sponza (SHARED_DIR/scenes/sponza) at --quality low, runs
# the sample headless over 4 frames spanning a day (10:00, 16:00, 22:00, 04:00) with the torch on auto,
# and checks: exit 0, the PNGs (320x180), the per-frame lines (time, sun elevation, torch, GPU ms per
# stage, bounce intensity), that frames differ, that the sun's elevation goes from above to below the
# horizon (sun off, torch lit), that the same night frame is brighter with the torch than with
# --torch off (mean display luminance the sample prints), the scene file, and the error paths (bad
# bake: exit 1 naming it; bad options: exit 2). SKIP (exit 0) without an OpenGL 4.5 context (the sample
# exits 77) or without the shared Sponza.
#   usage: test_samples_sponza.sh BIN_DIR SHARED_DIR
set -u
BAKE=$1/glow-bake
S=$1/sample-02_sponza
SPONZA=$2/scenes/sponza
. "$(dirname "$0")/lib/common.sh"
# Mesa's OSMesa leaks a little per context (see tests/gpu/lsan.supp): ctest sets these for *_gl tests only
: "${LSAN_OPTIONS=suppressions=$(cd "$(dirname "$0")/../gpu" && pwd)/lsan.supp}"
export LSAN_OPTIONS
if [ ! -x "$S" ]; then echo "FAIL $S not built (samples need GLOW_BUILD_SAMPLES and GLOW_WITH_GL)"; exit 1; fi
if [ ! -f "$SPONZA/dabrovic/sponza.obj" ]; then echo "SKIP: the shared Sponza is missing ($SPONZA/dabrovic/sponza.obj)"; exit 0; fi

t0=$(date +%s%N)
expect 0 "bake sponza --quality low" "$BAKE" "$SPONZA/dabrovic/sponza.obj" -o "$T/s.glow" --quality low -q --threads 2
echo "     bake: $(( ($(date +%s%N) - t0) / 1000000 )) ms"

# A day in 4 frames, torch on auto. GL 4.5 available? (this first run decides; exit 77 = no context)
DAY=(--headless --frames 4 --day-frames 4 --start-hour 10)
"$S" "$T/s.glow" "${DAY[@]}" --torch auto --out "$T/auto" >"$T/out" 2>"$T/err"; rc=$?
if [ "$rc" = 77 ]; then
  echo "SKIP: no OpenGL 4.5 context: $(cat "$T/err")"; exit 0
fi
[ "$rc" = 0 ] && pass "02_sponza 4 frames, torch auto (exit 0)" || { fail "02_sponza 4 frames: exit $rc"; sed 's/^/     /' "$T/err" | head -5; }
cp "$T/out" "$T/auto.txt"; cat "$T/auto.txt"

is_png() { # FILE W H: a PNG of that size
  [ -s "$1" ] || return 1
  [ "$(head -c 8 "$1" | od -An -tx1 | tr -d ' \n')" = 89504e470d0a1a0a ] || return 1
  local wh; wh=$(od -An -tu1 -j16 -N8 "$1" | awk '{ print $1*16777216 + $2*65536 + $3*256 + $4, $5*16777216 + $6*65536 + $7*256 + $8 }')
  [ "$wh" = "$2 $3" ]
}
# field FILE FRAME WHAT: from the line "time HH:MM  sun elevation E deg (...)  ...  torch on|off (...)  mean luminance L  (frame FRAME)"
field() {
  awk -v f="$2" -v what="$3" '$1 == "time" && $NF == f ")" {
    for (i = 1; i <= NF; i++) {
      if (what == "hour" && i == 2) print $i
      if (what == "elevation" && $i == "elevation") print $(i + 1)
      if (what == "torch" && $i == "torch") print $(i + 1)
      if (what == "luminance" && $i == "luminance") print $(i + 1)
    } }' "$1"
}

n=$(grep -c '^frame ' "$T/auto.txt"); [ "$n" = 4 ] && pass "  4 frame lines" || fail "  $n frame lines, wanted 4"
if awk '/^frame / { if ($0 ~ /GPU ms: surfels [0-9.]+ \(hook [0-9.]+\) pull [0-9.]+ caches [0-9.]+ outputs [0-9.]+ total [0-9.]+ draw [0-9.]+  bounces [0-9]+  intensity [0-9.]+/) ok++ }
        END { exit !(ok == 4) }' "$T/auto.txt"; then
  pass "  GPU ms per stage and bounce intensity on every frame"
else
  fail "  GPU stats lines malformed"
fi
hours=$(for f in 0 1 2 3; do field "$T/auto.txt" $f hour; done | tr '\n' ' ')
[ "$hours" = "10:00 16:00 22:00 04:00 " ] && pass "  times of day: $hours" || fail "  times of day: '$hours', wanted 10:00 16:00 22:00 04:00"
e0=$(field "$T/auto.txt" 0 elevation); e1=$(field "$T/auto.txt" 1 elevation); e2=$(field "$T/auto.txt" 2 elevation)
if awk -v a="$e0" -v b="$e1" -v c="$e2" 'BEGIN { exit !(a > 0 && b > 0 && c < 0 && a != b) }'; then
  pass "  sun elevation $e0, $e1 (day) -> $e2 deg (night)"
else
  fail "  sun elevation '$e0' '$e1' '$e2': wanted two different ones above the horizon, then one below"
fi
torches=$(for f in 0 1 2 3; do field "$T/auto.txt" $f torch; done | tr '\n' ' ')
[ "$torches" = "off off on on " ] && pass "  torch auto: off by day, on at night" || fail "  torch auto: '$torches', wanted off off on on"
ok=1
for f in 0 1 2 3; do is_png "$T/auto/frame_00$f.png" 320 180 || { ok=0; fail "  $T/auto/frame_00$f.png missing, not a PNG or not 320x180"; }; done
[ $ok = 1 ] && pass "  4 PNGs of 320x180"
for a in 0 1 2; do
  b=$((a + 1))
  if ! cmp -s "$T/auto/frame_00$a.png" "$T/auto/frame_00$b.png"; then pass "  frames $a and $b differ"; else fail "  frames $a and $b identical"; fi
done
l0=$(field "$T/auto.txt" 0 luminance); l2=$(field "$T/auto.txt" 2 luminance)
awk -v d="$l0" -v n="$l2" 'BEGIN { exit !(d > n) }' && pass "  noon brighter than night (mean luminance $l0 > $l2)" ||
  fail "  day frame not brighter than night: '$l0' vs '$l2'"

# The same day with the torch off: the night frames are darker, the day frames the same
expect 0 "--torch off" "$S" "$T/s.glow" "${DAY[@]}" --torch off --out "$T/off"
cp "$T/out" "$T/off.txt"
[ "$(field "$T/off.txt" 2 torch)" = off ] && pass "  torch off at night" || fail "  torch not off"
for f in 2 3; do
  on=$(field "$T/auto.txt" $f luminance); off=$(field "$T/off.txt" $f luminance)
  awk -v a="$on" -v b="$off" 'BEGIN { exit !(a > b + 0.005) }' && pass "  night frame $f: torch on brighter ($on > $off)" ||
    fail "  night frame $f: torch on '$on' not brighter than off '$off'"
done
on=$(field "$T/auto.txt" 0 luminance); off=$(field "$T/off.txt" 0 luminance)
awk -v a="$on" -v b="$off" 'BEGIN { d = a - b; exit !(d < 0.001 && d > -0.001) }' && pass "  day frame 0 the same ($on, $off)" ||
  fail "  day frame 0 differs without a torch: '$on' vs '$off'"
expect 0 "--torch on: lit by day too" "$S" "$T/s.glow" --headless --frames 1 --start-hour 12 --torch on --width 64 --height 36
[ "$(field "$T/out" 0 torch)" = on ] && pass "  torch on at noon" || fail "  --torch on ignored"

# The shared scene file (camera, noon sun, day sky), --torch-at, other sizes and views, no --out
if [ -f "$SPONZA/sponza-sun.json" ]; then
  expect 0 "--scene sponza-sun.json" "$S" "$T/s.glow" --headless --frames 2 --scene "$SPONZA/sponza-sun.json" --out "$T/scene"
  grep -q "the scene's sun" "$T/out" && pass "  the scene's sun is the noon sun" || fail "  scene sun not used"
  is_png "$T/scene/frame_001.png" 320 180 && pass "  320x180 PNG" || fail "  no PNG"
fi
expect 0 "--torch-at, --view direct, 96x54" "$S" "$T/s.glow" --headless --frames 1 --start-hour 23 --torch-at -2,1.5,2 --view direct --width 96 --height 54 --out "$T/v"
grep -q 'torch: at (-2.00, 1.50, 2.00)' "$T/out" && pass "  torch placed" || fail "  --torch-at ignored"
is_png "$T/v/frame_000.png" 96 54 && pass "  96x54 PNG" || fail "  no 96x54 PNG"
expect 0 "--torch-at outside the bounds: a warning" "$S" "$T/s.glow" --headless --frames 1 --torch-at 0,100,0 --width 32 --height 32
grep -q 'OUTSIDE' "$T/out" && pass "  warned" || fail "  no warning"

# Textures (bake format 1.1 names them; the sample loads them) and the HUD (off headless by default)
N=(--headless --frames 1 --start-hour 12 --width 160 --height 90)
expect 0 "textured (default)" "$S" "$T/s.glow" "${N[@]}" --out "$T/tex"
grep -q "cannot read the albedo texture" "$T/err" && fail "  a texture could not be read: $(head -1 "$T/err")" || pass "  every albedo texture read"
expect 0 "--no-textures" "$S" "$T/s.glow" "${N[@]}" --no-textures --out "$T/notex"
cmp -s "$T/tex/frame_000.png" "$T/notex/frame_000.png" && fail "  --no-textures draws the same image" || pass "  textures change the image"
expect 0 "--hud off (the default headless)" "$S" "$T/s.glow" "${N[@]}" --hud off --out "$T/hudoff"
cmp -s "$T/tex/frame_000.png" "$T/hudoff/frame_000.png" && pass "  headless PNGs have no HUD by default" || fail "  the default headless PNG differs from --hud off"
expect 0 "--hud on" "$S" "$T/s.glow" "${N[@]}" --hud on --out "$T/hudon"
cmp -s "$T/hudon/frame_000.png" "$T/hudoff/frame_000.png" && fail "  --hud on draws nothing" || pass "  --hud on draws the HUD into the image"
expect 2 "bad --hud" "$S" "$T/s.glow" --headless --hud maybe; err_has "hud"

# Errors: a missing or corrupt bake is exit 1 naming the file; bad command lines are exit 2
expect 1 "missing bake" "$S" "$T/nope.glow" --headless --frames 1; err_has "nope.glow"
head -c 5000 "$T/s.glow" > "$T/cut.glow"
expect 1 "truncated bake" "$S" "$T/cut.glow" --headless --frames 1; err_has "cut.glow"
expect 1 "missing scene" "$S" "$T/s.glow" --headless --frames 1 --scene "$T/nope.json"; err_has "nope.json"
expect 2 "no arguments" "$S"
expect 2 "unknown option" "$S" "$T/s.glow" --headless --frobnicate; err_has "frobnicate"
expect 2 "bad --torch" "$S" "$T/s.glow" --headless --torch sometimes; err_has "sometimes"
expect 2 "bad --torch-at" "$S" "$T/s.glow" --headless --torch-at 1,2; err_has "torch-at"
expect 2 "bad --start-hour" "$S" "$T/s.glow" --headless --start-hour 25; err_has "start-hour"
expect 2 "bad --day-frames" "$S" "$T/s.glow" --headless --day-frames 0; err_has "day-frames"
expect 2 "bad --day-seconds" "$S" "$T/s.glow" --headless --day-seconds x; err_has "day-seconds"
expect 2 "--torch without a value" "$S" "$T/s.glow" --headless --torch; err_has "torch"
expect 2 "bad --view" "$S" "$T/s.glow" --headless --view sideways; err_has "sideways"
expect 0 "--help" "$S" --help
grep -q "usage" "$T/out" && grep -q -- "--torch" "$T/out" && pass "  usage and this sample's options printed" || fail "  no usage"

echo "     total: $(( ($(date +%s%N) - t0) / 1000000 )) ms"
[ "$fails" = 0 ] && echo "all passed" || echo "$fails failed"
exit $((fails > 0))
