#!/bin/bash
# Paired A/B of cache-lighting kernel versions in one process (tools/bench/kernel_ab.c says why).
#
#   tools/kernel_ab.sh BUILD_DIR BAKE REV [REV...] [-- ITERS THREADS LUMA CHROMA]
#
# REV is a git revision, or "worktree" for the files on disk. Each version's runtime/src/
# cache_lighting.{c,h}, cache_kernel.inc and sh_kernel.h are compiled in their own translation unit
# with renamed symbols; BUILD_DIR's libglow_runtime.a supplies the bake loader. Example:
#   tools/kernel_ab.sh build /tmp/glow-bench/sponza-moderate.glow HEAD~1 worktree -- 200 2
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=$(cd "$1" && pwd); bake=$2; shift 2
revs=(); while [ $# -gt 0 ] && [ "$1" != "--" ]; do revs+=("$1"); shift; done
[ $# -gt 0 ] && shift
[ ${#revs[@]} -ge 1 ] || { echo "kernel_ab.sh: no revisions" >&2; exit 2; }
# Arguments are checked before anything is compiled (each version takes seconds to build, a minute
# under sanitizers); kernel_ab.c checks them again with the same limits.
iters=${1:-200}; threads=${2:-1}; luma=${3:-3}; chroma=${4:-$luma}
for v in "$iters" "$threads" "$luma" "$chroma"; do
  [[ "$v" =~ ^[0-9]+$ ]] || { echo "kernel_ab.sh: '$v' is not a number (ITERS THREADS LUMA CHROMA)" >&2; exit 2; }
done
if [ "$iters" -lt 1 ] || [ "$iters" -gt 10000 ] || [ "$threads" -lt 1 ] || [ "$threads" -gt 64 ] ||
   [ "$luma" -lt 1 ] || [ "$luma" -gt 8 ] || [ "$chroma" -lt 1 ] || [ "$chroma" -gt "$luma" ]; then
  echo "kernel_ab.sh: ITERS 1..10000, THREADS 1..64, 1 <= CHROMA <= LUMA <= 8" >&2; exit 2
fi
[ -f "$bake" ] && [ -r "$bake" ] || { echo "kernel_ab.sh: cannot read bake $bake" >&2; exit 1; }
lib=$build/lib/libglow_runtime.a
[ -f "$lib" ] || { echo "kernel_ab.sh: $lib not found (build first)" >&2; exit 2; }
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
cc=${CC:-cc}
flags=(-O2 -std=c11 -I"$root/runtime/include" -I"$root/runtime/src")
# A sanitizer build's library needs the sanitizer runtime in the harness: only the link takes the
# flags. The kernel versions are compiled as in a release build (they are what is timed);
# instrumenting them made each version take over a minute to compile.
link_flags=()
nm "$lib" > "$tmp/nm.txt" 2>/dev/null || true
if grep -q "__asan_" "$tmp/nm.txt"; then link_flags+=(-fsanitize=address,undefined); fi
objs=(); vlist=""
for i in "${!revs[@]}"; do
  d=$tmp/v$i; mkdir -p "$d"
  for f in cache_lighting.c cache_lighting.h cache_kernel.inc sh_kernel.h; do
    if [ "${revs[$i]}" = worktree ]; then cp "$root/runtime/src/$f" "$d/$f"
    else git -C "$root" show "${revs[$i]}:runtime/src/$f" > "$d/$f"; fi
  done
  cat > "$d/variant.c" <<EOT
#define glow__cl_light_caches V${i}_light
#define glow__cl_best_isa V${i}_best
#define glow__cl_isa_supported V${i}_supported
#define glow__cl_isa_name V${i}_name
#define glow__cl_expand V${i}_expand
#define glow__cl_coeff_scale V${i}_coeff_scale
#define glow__cl_write_plane V${i}_write_plane
#define glow__cl_write_planes V${i}_write_planes
#include "cache_lighting.c"
/* the harness's link subsets (KAB_SUBSETS=1 in its environment; NULL otherwise), for versions whose
 * args have them (the script defines KAB_HAS_SUBSETS then) */
extern const uint16_t *kab_subsets;
extern const uint32_t *kab_ratio;
/* args built here, with this version's header (the struct changed between versions) */
void V${i}_run(const glow_bake_link_block *blocks, uint32_t bpc, const float *rad, uint32_t L, uint32_t C, float *out,
               uint32_t first, uint32_t count) {
    glow__cl_args a = {.blocks = blocks, .blocks_per_cache = bpc, .rad_y = rad, .rad_co = rad + 1, .rad_cg = rad + 2,
                       .rad_stride = 4, .luma = L, .chroma = C, .coeffs = L * L + 2 * C * C, .cache_sh = out,
#ifdef KAB_HAS_SUBSETS
                       .subsets = kab_subsets, .sub_ratio = kab_ratio,
#endif
                       .isa = V${i}_best()};
    V${i}_light(&a, first, count);
}
EOT
  vflags=()
  grep -q "sub_ratio" "$d/cache_lighting.h" && vflags+=(-DKAB_HAS_SUBSETS=1)
  "$cc" "${flags[@]}" "${vflags[@]}" -ffp-contract=fast -Wno-psabi -c "$d/variant.c" -o "$d/variant.o"
  objs+=("$d/variant.o"); vlist="$vlist X($i)"
  echo "version $i: ${revs[$i]}"
done
"$cc" "${flags[@]}" "${link_flags[@]}" "-DVLIST=$vlist" "$root/tools/bench/kernel_ab.c" "${objs[@]}" "$lib" \
  -lm -lpthread -o "$tmp/kernel_ab"
"$tmp/kernel_ab" "$bake" "$@"
