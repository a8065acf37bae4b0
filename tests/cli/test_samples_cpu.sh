#!/usr/bin/env bash
# The minimal CPU sample (samples/00_minimal_cpu): bakes builtin:cornell --quality low, runs
# sample-00_minimal_cpu --headless --frames 3 --out DIR and checks the exit status, the PNGs (signature),
# the printed indirect light (finite, > 0), that frames differ as the light moves, and the error paths
# (bad bake: exit 1 naming the file; bad options: exit 2).
#   usage: test_samples_cpu.sh BIN_DIR SHARED_DIR
set -u
BAKE=$1/glow-bake
SAMPLE=$1/sample-00_minimal_cpu
. "$(dirname "$0")/lib/common.sh"
if [ ! -x "$SAMPLE" ]; then
  echo "FAIL $SAMPLE not built (samples need GLOW_BUILD_SAMPLES and GLOW_WITH_GL)"; exit 1
fi

expect 0 "bake cornell" "$BAKE" builtin:cornell -o "$T/c.glow" --quality low -q --threads 2
expect 0 "run 3 frames" "$SAMPLE" "$T/c.glow" --headless --frames 3 --out "$T/png"
cp "$T/out" "$T/run.txt"; cat "$T/run.txt"
[ "$(grep -c '^frame ' "$T/run.txt")" = 3 ] && pass "  3 frame lines" || fail "  wanted 3 frame lines"
grep -q "update [0-9.]* ms" "$T/run.txt" && pass "  update ms printed" || fail "  no update ms"

# indirect light at the centre of the bounds: 3 finite numbers, all > 0, on every frame
if awk '/^frame / { for (i = 1; i <= NF; i++) if ($i == "centre") { n++
          for (c = 1; c <= 3; c++) { v = $(i + c); if (v !~ /^[0-9]+(\.[0-9]+)?$/ || v + 0 <= 0) bad++ } } }
        END { exit !(n == 3 && bad == 0) }' "$T/run.txt"; then
  pass "  centre indirect light finite and > 0"
else
  fail "  centre indirect light missing, not finite or not > 0"
fi

# every frame's PNG exists and is a PNG; the light moves, so the pictures and the numbers change
for f in 000 001 002; do
  png=$T/png/frame_$f.png
  if [ -s "$png" ] && [ "$(head -c 8 "$png" | od -An -tx1 | tr -d ' \n')" = 89504e470d0a1a0a ]; then
    pass "  $png is a PNG"
  else
    fail "  $png missing or not a PNG"
  fi
done
if ! cmp -s "$T/png/frame_001.png" "$T/png/frame_002.png"; then pass "  frames 1 and 2 differ"; else fail "  frames 1 and 2 are identical"; fi
p0=$(grep '^frame 0 ' "$T/run.txt" | sed 's/.*light (\([^)]*\)).*/\1/'); p2=$(grep '^frame 2 ' "$T/run.txt" | sed 's/.*light (\([^)]*\)).*/\1/')
if [ -n "$p0" ] && [ "$p0" != "$p2" ]; then pass "  the light moves ($p0 -> $p2)"; else fail "  the light does not move"; fi
# The light swings from +x towards the red wall (-x): the centre's bounce light gets redder (R/G up by
# 6% from frame 0 to 2). A light that stays put gets slightly less red as the bounces converge (-3%).
if awk '/^frame [02] / { for (i = 1; i <= NF; i++) if ($i == "centre") rg[$2] = $(i + 1) / $(i + 2) }
        END { printf "     R/G at the centre: frame 0 %.4f, frame 2 %.4f\n", rg[0], rg[2]; exit !(rg[2] > 1.02 * rg[0]) }' "$T/run.txt"; then
  pass "  the bounce light follows the light (redder near the red wall)"
else
  fail "  the bounce light does not follow the light"
fi

# no --out: no files, still exit 0
expect 0 "run without --out" "$SAMPLE" "$T/c.glow" --frames 1
grep -q '^frame 0 ' "$T/out" && pass "  one frame" || fail "  no frame line"

# errors: a missing or corrupt bake is exit 1 naming the file; bad command lines are exit 2
expect 1 "missing bake" "$SAMPLE" "$T/nope.glow" --frames 1; err_has "nope.glow"
head -c 1000 "$T/c.glow" > "$T/cut.glow"
expect 1 "truncated bake" "$SAMPLE" "$T/cut.glow" --frames 1; err_has "cut.glow"
: > "$T/file"
expect 1 "--out is a file" "$SAMPLE" "$T/c.glow" --frames 1 --out "$T/file"; err_has "$T/file"
mkdir -p "$T/blocked/frame_000.png"  # a folder where the PNG should go: the write fails
expect 1 "PNG cannot be written" "$SAMPLE" "$T/c.glow" --frames 1 --out "$T/blocked"; err_has "frame_000.png"
expect 2 "no arguments" "$SAMPLE"
expect 2 "unknown option" "$SAMPLE" "$T/c.glow" --frobnicate; err_has "frobnicate"
expect 2 "bad --frames" "$SAMPLE" "$T/c.glow" --frames 0; err_has "frames"
expect 2 "non-numeric --frames" "$SAMPLE" "$T/c.glow" --frames 3x; err_has "3x"
expect 2 "--out without a value" "$SAMPLE" "$T/c.glow" --out
expect 2 "two bakes" "$SAMPLE" "$T/c.glow" "$T/c.glow"
expect 0 "--help" "$SAMPLE" --help
grep -q "usage" "$T/out" && pass "  usage printed" || fail "  no usage"

[ "$fails" = 0 ] && echo "all passed" || echo "$fails failed"
exit $((fails > 0))
