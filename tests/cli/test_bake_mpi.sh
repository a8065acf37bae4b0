#!/usr/bin/env bash
# glow-bake --mpi (issue 16, item 4): a bake over 2 and 3 ranks of an MPI job on this machine's
# loopback writes the same bytes as the one-process bake (cmp); a rank that dies mid-bake stops the
# job with a message from the survivor, a non-zero exit and no output (not even a temporary file).
# A glow-bake built without MPI must refuse --mpi with a message (exit 2) and bake as before.
#   usage: test_bake_mpi.sh BIN_DIR SHARED_DIR
set -u
BIN=$1
. "$(dirname "$0")/lib/common.sh"
B="$BIN/glow-bake"
ARGS=(builtin:cornell --quality low --surfels 2048 --links 32 --threads 1 -q)

expect 0 "one-process bake" "$B" "${ARGS[@]}" -o "$T/one.glow"
if "$B" --version | grep -q -- "--mpi off"; then
  expect 2 "built without MPI: --mpi refused" "$B" --mpi "${ARGS[@]}" -o "$T/x.glow"
  err_has "built without MPI"
  [ ! -e "$T/x.glow" ] && pass "  and nothing written" || fail "  wrote $T/x.glow"
  [ "$fails" = 0 ] && echo "all passed" || echo "$fails failed"
  exit $((fails > 0))
fi
"$B" --version | grep -q -- "--mpi on" && pass "glow-bake --version: --mpi on" || fail "glow-bake --version says nothing of MPI"
command -v mpirun >/dev/null || { fail "glow-bake has MPI but mpirun is missing (tools/setup.sh installs openmpi-bin)"; exit 1; }
# root in CI containers; two or three ranks on a 2-core machine; TCP on the loopback only
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
# OpenMPI's own allocations at start-up are not Glow's leaks (the same code runs without MPI in the
# other tests); UBSan and ASan's other checks stay on
export ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0"
MPI=(timeout 300 mpirun --mca btl self,tcp --mca btl_tcp_if_include lo)
expect 0 "--mpi without mpirun (a one-rank job)" timeout 300 "$B" --mpi "${ARGS[@]}" -o "$T/single.glow"
cmp -s "$T/one.glow" "$T/single.glow" && pass "  the same bytes" || fail "  bytes differ"
for n in 2 3; do
  expect 0 "$n ranks" "${MPI[@]}" -np $n "$B" --mpi "${ARGS[@]}" -o "$T/mpi$n.glow"
  cmp "$T/one.glow" "$T/mpi$n.glow" && pass "  the one-process bake's bytes" || fail "  bytes differ from the one-process bake"
done
expect 0 "2 ranks, 2 threads each (the default threads)" "${MPI[@]}" -np 2 "$B" --mpi builtin:cornell --quality low \
  --surfels 2048 --links 32 -q -o "$T/mpi2t.glow"
cmp -s "$T/one.glow" "$T/mpi2t.glow" && pass "  the same bytes" || fail "  bytes differ"

# a bake split into systems (--system-area): each system's links over the ranks, the same files
SYS=(builtin:pillar-hall --system-area 100 --surfels 1024 --links 16 --lightmap-caches 300 --lightmap-detail 1 --threads 1 -q)
# world_twice LABEL A B ARGS...: a world bake into A in one process and into B over 2 ranks, then every
# file compared; sets $files to the world's system files
world_twice() {
  local label=$1 a=$2 b=$3 f same=1; shift 3
  mkdir -p "$a" "$b"
  expect 0 "$label, one process" "$B" "$@" -o "$a/w.json"
  expect 0 "$label, 2 ranks" "${MPI[@]}" -np 2 "$B" --mpi "$@" -o "$b/w.json"
  files=$(python3 -c "import json,sys; print(' '.join(x['file'] for x in json.load(open(sys.argv[1]))['systems']))" "$a/w.json")
  for f in w.json $files; do cmp -s "$a/$f" "$b/$f" || { same=0; fail "  $f differs"; }; done
  [ $same = 1 ] && pass "  the manifest and the $(echo $files | wc -w) systems' bakes: the same bytes"
}
world_twice systems "$T/s1" "$T/s2" "${SYS[@]}"
sysfiles=$files
nsys=$(echo $sysfiles | wc -w)
# (this said "= 4" until 2026-11-30, and printed nothing once the hall became 6 systems)
[ "$nsys" -ge 2 ] || fail "  the hall was not split into systems ($nsys)"
mkdir -p "$T/s3"
expect 0 "systems, 3 ranks (whole systems per rank)" "${MPI[@]}" -np 3 "$B" --mpi "${SYS[@]}" --json -o "$T/s3/w.json"
cp "$T/out" "$T/s3.json"
same=1
for f in w.json $sysfiles; do cmp -s "$T/s1/$f" "$T/s3/$f" || { same=0; fail "  $f differs"; }; done
[ $same = 1 ] && pass "  the same bytes"
# rank 0's summary is the world's, as one process's: every figure but the times, threads, peak memory
mkdir -p "$T/s4"
expect 0 "systems, one process, --json" "$B" "${SYS[@]}" --json -o "$T/s4/w.json"
python3 - "$T/out" "$T/s3.json" <<'PY' && pass "  3 ranks' --json summary: the one process's figures" || fail "  3 ranks' --json summary differs"
import json, sys
def figures(path):
    j = json.load(open(path))
    for k in ("total_seconds", "stages", "threads", "output"):
        j.pop(k)
    j["caches"].pop("sky_seconds")
    return j
a, b = figures(sys.argv[1]), figures(sys.argv[2])
for k in sorted(set(a) | set(b)):
    if a.get(k) != b.get(k):
        print("  %s: one process %s, 3 ranks %s" % (k, a.get(k), b.get(k)))
sys.exit(a != b)
PY
expect 0 "systems, 3 ranks into the same world (nothing to bake)" "${MPI[@]}" -np 3 "$B" --mpi "${SYS[@]}" -o "$T/s3/w.json"
cmp -s "$T/s1/w.json" "$T/s3/w.json" && [ "$(ls "$T/s3" | wc -l)" = $((nsys + 1)) ] && pass "  the same manifest, the same $nsys bakes" \
  || fail "  manifest or files changed: $(ls "$T/s3")"

# systems named by the user with declared neighbours (--systems): every rank reads the file, the same bytes
NAMED="$(cd "$(dirname "$0")/../.." && pwd)/tests/data/scenes/named-objects.obj"
cat > "$T/systems.json" <<'JSON'
{"glow_systems": 1, "systems": [{"name": "houseA", "objects": ["house_a"], "neighbours": []},
                                {"name": "houseB", "objects": ["house_b"], "neighbours": ["houseA"]}]}
JSON
DECL=("$NAMED" --system-area 30 --systems "$T/systems.json" --surfels 1024 --links 16 --lightmap-caches 300 --lightmap-detail 1 --threads 1 -q)
world_twice "declared neighbours (--systems)" "$T/d1" "$T/d2" "${DECL[@]}"
[ "$(echo $files | wc -w)" -ge 3 ] || fail "  expected houseA, houseB and the ground's systems: $files"

# rank 1 dies (SIGKILL) at its first exchange: mpirun stops the job
out="$T/dead.glow"
GLOW_BAKE_MPI_FAIL_RANK=1 "${MPI[@]}" -np 2 "$B" --mpi "${ARGS[@]}" -o "$out" >"$T/out" 2>"$T/err"
rc=$?
[ "$rc" != 0 ] && [ "$rc" != 124 ] && pass "a rank dies: the job fails (exit $rc)" || fail "a rank dies: exit $rc"
err_has "rank 1 of 2"
err_has "rank 0 of 2: stopped: another rank of this MPI bake failed"
ls "$T"/dead.glow* >/dev/null 2>&1 && fail "  output left behind: $(ls "$T"/dead.glow*)" || pass "  no output, no temporary file"

# a world bake: the ranks write their systems before the manifest. Rank 1 dies at the closing exchange,
# after every system is written: no part of the new world may stay, and an old world stays whole.
mkdir -p "$T/dw"
GLOW_BAKE_MPI_FAIL_RANK=1 "${MPI[@]}" -np 2 "$B" --mpi "${SYS[@]}" -o "$T/dw/w.json" >"$T/out" 2>"$T/err"
rc=$?
[ "$rc" != 0 ] && [ "$rc" != 124 ] && pass "a rank dies in a world bake: the job fails (exit $rc)" || fail "a rank dies in a world bake: exit $rc"
err_has "rank 0 of 2: stopped"
[ -z "$(ls -A "$T/dw")" ] && pass "  no system file, manifest or temporary left" || fail "  left behind: $(ls -A "$T/dw")"
cp -p "$T/s1"/* "$T/dw/"
( cd "$T/dw" && ls -A | sort && md5sum * ) > "$T/dw.before"
GLOW_BAKE_MPI_FAIL_RANK=1 "${MPI[@]}" -np 2 "$B" --mpi "${SYS[@]}" --seed 7 -o "$T/dw/w.json" >"$T/out" 2>"$T/err"
rc=$?
[ "$rc" != 0 ] && [ "$rc" != 124 ] && pass "a rank dies re-baking a world (another seed: every system new) (exit $rc)" \
  || fail "a rank dies re-baking a world: exit $rc"
( cd "$T/dw" && ls -A | sort && md5sum * ) > "$T/dw.after"
cmp -s "$T/dw.before" "$T/dw.after" && pass "  the old world whole: its manifest and $nsys files, nothing added" \
  || { fail "  the old world changed:"; diff "$T/dw.before" "$T/dw.after" | head -5; }
# rank 0 dies after it wrote the manifest: rank 1, stopped at the closing barrier, keeps the world
rm -rf "$T/dw" && mkdir -p "$T/dw"
GLOW_BAKE_MPI_FAIL_RANK=0 GLOW_BAKE_MPI_FAIL_AT=end "${MPI[@]}" -np 2 "$B" --mpi "${SYS[@]}" -o "$T/dw/w.json" >"$T/out" 2>"$T/err"
rc=$?
[ "$rc" != 0 ] && [ "$rc" != 124 ] && pass "rank 0 dies after writing the world (exit $rc)" || fail "rank 0 dies after writing the world: exit $rc"
same=1
for f in w.json $sysfiles; do cmp -s "$T/s1/$f" "$T/dw/$f" || { same=0; fail "  $f missing or differs"; }; done
[ $same = 1 ] && [ "$(ls -A "$T/dw" | wc -l)" = $((nsys + 1)) ] && pass "  the world written stays: its manifest and $nsys files" \
  || fail "  the world: $(ls -A "$T/dw")"

[ "$fails" = 0 ] && echo "all passed" || echo "$fails failed"
exit $((fails > 0))
