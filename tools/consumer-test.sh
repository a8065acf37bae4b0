#!/usr/bin/env bash
# The SDK as an engine meets it (issue 14): installs BUILD_DIR with `cmake --install` into a temporary
# prefix, builds tests/consumer (a C-only project) out of tree against it twice — with
# find_package(glow) and with pkg-config (glow.pc) — and runs both on a bake. Also checks that the
# prefix holds the package files and that a GL-less consumer needs no C++ compiler.
# Then add_subdirectory: a C-only parent project with its own build type and output folders pulls in
# this source tree with -DGLOW_BUILD_PRECOMPUTE=OFF (the GPU runtime without the bake toolchain: no
# Embree or assimp may be looked up), builds glow::gl and its consumer, and must find its cache and
# folders as it set them. Last, a shared build (BUILD_SHARED_LIBS) installed and consumed both ways, its
# libraries checked for SONAME and for exporting the public API only.
#   usage: tools/consumer-test.sh [BUILD_DIR]   (default: build; configure and build it first)
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=$(cd "${1:-$root/build}" && pwd)
bake=$root/tests/data/seed_cornell_tiny.glow
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
prefix=$tmp/prefix
cmake --install "$build" --prefix "$prefix" >/dev/null
for f in include/glow/glow.h; do
  [ -f "$prefix/$f" ] || { echo "consumer-test: $f not installed" >&2; exit 1; }
done
cfg=$(find "$prefix" -name glowConfig.cmake | head -1)
ver=$(find "$prefix" -name glowConfigVersion.cmake | head -1)
pc=$(find "$prefix" -name glow.pc | head -1)
lib=$(find "$prefix" -name libglow_runtime.a | head -1)
for v in cfg ver pc lib; do
  [ -n "${!v}" ] || { echo "consumer-test: no $v file under the prefix" >&2; exit 1; }
done
echo "consumer-test: installed $(find "$prefix" -type f | wc -l) files into a temporary prefix"

# 1. find_package(glow), C only (no C++ compiler: CMAKE_CXX_COMPILER is not even looked up)
cmake -S "$root/tests/consumer" -B "$tmp/cmake" -G Ninja -DCMAKE_PREFIX_PATH="$prefix" \
  -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$tmp/cmake" >/dev/null
"$tmp/cmake/glow_consumer" "$bake"
# a version this install is not
mkdir -p "$tmp/wrong"
sed 's/find_package(glow 0.1 /find_package(glow 9.9 /' "$root/tests/consumer/CMakeLists.txt" > "$tmp/wrong/CMakeLists.txt"
cp "$root/tests/consumer/consumer.c" "$tmp/wrong/"
if cmake -S "$tmp/wrong" -B "$tmp/wrong/build" -DCMAKE_PREFIX_PATH="$prefix" >/dev/null 2>&1; then
  echo "consumer-test: find_package(glow 9.9) accepted version $(grep -o 'PACKAGE_VERSION "[^"]*"' "$ver" | head -1)" >&2
  exit 1
fi
echo "consumer-test: find_package(glow 9.9) refused, as it must be"

# 2. pkg-config
PKG_CONFIG_PATH=$(dirname "$pc") pkg-config --exists glow
cc -std=c11 -O2 "$root/tests/consumer/consumer.c" -o "$tmp/pc_consumer" \
  $(PKG_CONFIG_PATH=$(dirname "$pc") pkg-config --cflags --libs glow)
"$tmp/pc_consumer" "$bake"

# 3. add_subdirectory from a C-only parent, GPU runtime without the linker
parent=$tmp/parent
mkdir -p "$parent"
cp "$root/tests/consumer/consumer.c" "$parent/"
cat > "$parent/CMakeLists.txt" <<EOT
cmake_minimum_required(VERSION 3.25)
project(parent LANGUAGES C)
set(CMAKE_RUNTIME_OUTPUT_DIRECTORY \${CMAKE_BINARY_DIR}/parent-bin)
set(GLOW_BUILD_PRECOMPUTE OFF CACHE BOOL "")
add_subdirectory("$root" glow)
add_executable(parent_consumer consumer.c)
target_link_libraries(parent_consumer PRIVATE glow::runtime glow::gl)
EOT
cmake -S "$parent" -B "$parent/build" -G Ninja -DCMAKE_BUILD_TYPE=Debug >"$tmp/parent.log" 2>&1 ||
  { cat "$tmp/parent.log" >&2; echo "consumer-test: add_subdirectory configure failed" >&2; exit 1; }
grep -q '^CMAKE_BUILD_TYPE:STRING=Debug$' "$parent/build/CMakeCache.txt" ||
  { echo "consumer-test: the parent's CMAKE_BUILD_TYPE was changed" >&2; exit 1; }
if grep -qiE '^(embree_DIR|assimp_DIR|CMAKE_CXX_COMPILER):' "$parent/build/CMakeCache.txt"; then
  echo "consumer-test: a GPU-only add_subdirectory looked up Embree, assimp or a C++ compiler:" >&2
  grep -iE '^(embree_DIR|assimp_DIR|CMAKE_CXX_COMPILER):' "$parent/build/CMakeCache.txt" >&2
  exit 1
fi
cmake --build "$parent/build" --target parent_consumer glow_gl >"$tmp/parent-build.log" 2>&1 ||
  { tail -20 "$tmp/parent-build.log" >&2; echo "consumer-test: add_subdirectory build failed" >&2; exit 1; }
[ -x "$parent/build/parent-bin/parent_consumer" ] && [ ! -d "$parent/build/bin" ] && [ ! -d "$parent/build/lib" ] ||
  { echo "consumer-test: output folders: Glow wrote into the parent's bin/ or lib/" >&2; exit 1; }
"$parent/build/parent-bin/parent_consumer" "$bake"

# 4. shared libraries: a GPU-runtime build of this tree with BUILD_SHARED_LIBS (only the two libraries
# the install holds are built), installed; the consumer links libglow_runtime.so.0.1 (find_package and
# pkg-config), which exports the public API only. Debug: what is checked (SONAME, exports, linking, a run)
# does not depend on optimisation, and GCC takes 48 s at -O3 on the cache-lighting kernel against 11 at -O0.
cmake -S "$root" -B "$tmp/shared" -G Ninja -DCMAKE_BUILD_TYPE=Debug -DBUILD_SHARED_LIBS=ON \
  -DGLOW_BUILD_PRECOMPUTE=OFF -DGLOW_BUILD_TESTS=OFF -DGLOW_BUILD_SAMPLES=OFF >"$tmp/shared.log" 2>&1 &&
  cmake --build "$tmp/shared" --target glow_runtime_shared glow_gl_shared >>"$tmp/shared.log" 2>&1 ||
  { tail -20 "$tmp/shared.log" >&2; echo "consumer-test: shared build failed" >&2; exit 1; }
sprefix=$tmp/sprefix
cmake --install "$tmp/shared" --prefix "$sprefix" >/dev/null
so=$(find "$sprefix" -name 'libglow_runtime.so.*.*' -type f | head -1)
[ -n "$so" ] && [ -z "$(find "$sprefix" -name 'libglow_runtime.a')" ] ||
  { echo "consumer-test: the shared install holds no libglow_runtime.so or also the static library" >&2; exit 1; }
soname=$(objdump -p "$so" | awk '/SONAME/ { print $2 }')
[ "$soname" = libglow_runtime.so.0.1 ] || { echo "consumer-test: SONAME '$soname', wanted libglow_runtime.so.0.1" >&2; exit 1; }
for lib in "$so" "$(find "$sprefix" -name 'libglow_gl.so.*.*' -type f | head -1)"; do
  [ -f "$lib" ] || { echo "consumer-test: no libglow_gl.so installed" >&2; exit 1; }
  bad=$(nm -D --defined-only "$lib" | awk '$2 ~ /^[TDBR]$/ && $3 !~ /^glow_[a-z]/ { print $3 }' | head -5)
  internal=$(nm -D --defined-only "$lib" | awk '$3 ~ /^glow__/ { print $3 }' | head -5)
  [ -z "$bad$internal" ] || { echo "consumer-test: $(basename "$lib") exports more than the API: $bad $internal" >&2; exit 1; }
done
cmake -S "$root/tests/consumer" -B "$tmp/scmake" -G Ninja -DCMAKE_PREFIX_PATH="$sprefix" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$tmp/scmake" >/dev/null
objdump -p "$tmp/scmake/glow_consumer" | grep -q 'NEEDED *libglow_runtime.so.0.1' ||
  { echo "consumer-test: the find_package consumer does not load libglow_runtime.so.0.1" >&2; exit 1; }
"$tmp/scmake/glow_consumer" "$bake"
spc=$(find "$sprefix" -name glow.pc | head -1)
cc -std=c11 -O2 "$root/tests/consumer/consumer.c" -o "$tmp/spc_consumer" \
  $(PKG_CONFIG_PATH=$(dirname "$spc") pkg-config --cflags --libs glow)
LD_LIBRARY_PATH=$(dirname "$so") "$tmp/spc_consumer" "$bake"
echo "consumer-test: shared: $(basename "$so") (SONAME $soname), $(nm -D --defined-only "$so" | grep -c ' glow_') exported functions"
echo "consumer-test: OK (find_package, pkg-config, add_subdirectory with the GPU runtime only, shared libraries)"
