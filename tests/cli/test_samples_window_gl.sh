#!/usr/bin/env bash
# The GL samples in a window (issue 5: "each runs in a GLFW window"): under Xvfb (Debian xvfb, installed by
# tools/setup.sh) sample-01_cornell and sample-03_dynamic_object open a GLFW window with a GL 4.5 core
# context (Mesa's llvmpipe through GLX), run a few frames (render, blit, swap, poll) and write the same
# PNGs as headless. Prints SKIP and passes when xvfb-run is missing or the window cannot be made.
set -u
BIN=$1
source "$(dirname "$0")/lib/common.sh"
if ! command -v xvfb-run >/dev/null 2>&1; then echo "SKIP: xvfb-run not installed"; exit 0; fi
"$BIN/glow-bake" builtin:cornell -o "$T/c.glow" --quality low >/dev/null 2>&1 || { echo "FAIL bake"; exit 1; }
for s in 01_cornell 03_dynamic_object; do
  xvfb-run -a -s "-screen 0 800x600x24" "$BIN/sample-$s" "$T/c.glow" --frames 3 --width 160 --height 120 --out "$T/$s" \
    >"$T/out" 2>"$T/err"
  rc=$?
  if [ $rc = 77 ]; then echo "SKIP: $s: no window: $(cat "$T/out" "$T/err" | tail -2)"; continue; fi
  [ $rc = 0 ] && pass "$s in a window (exit 0)" || { fail "$s in a window: exit $rc"; sed 's/^/     /' "$T/err" | tail -5; continue; }
  grep -q "(glfw)" "$T/out" && pass "  GLFW context" || fail "  not a GLFW context"
  grep -q "window (keys:" "$T/out" && pass "  window mode" || fail "  not in window mode"
  n=$(ls "$T/$s"/frame_*.png 2>/dev/null | wc -l)
  [ "$n" = 3 ] && pass "  3 PNGs" || fail "  $n PNGs"
  head -c 8 "$T/$s/frame_000.png" | od -An -tx1 | grep -q "89 50 4e 47" && pass "  PNG signature" || fail "  not a PNG"
done
exit $fails
