#!/bin/bash
# Packs what tools/gpu-check/run.sh needs on a GPU machine that has no Glow dependencies installed
# (the lent NVIDIA machines of docs/benchmarks.md: an Ubuntu image with the driver, nothing else):
# glow-bench, glow-bake and the GL tests from build/bin (stripped), the Debian libraries they load
# (Embree, assimp, OpenMPI, ... xz-compressed to fit a 64 MiB transfer), glvnd's EGL/GL loaders as
# .debs, and two bakes of Sponza. Run from the repository root after a build:
#   bash tools/gpu-check/pack.sh MODERATE.glow HIGH.glow
# It writes .dev/ and .gl/ (both listed in .git/info/exclude). On the GPU machine, from the copy of
# the repository root with .dev and .gl beside it: bash tools/gpu-check/run.sh (results under $OUT).
set -euo pipefail
[ $# -eq 2 ] || { echo "usage: pack.sh MODERATE.glow HIGH.glow" >&2; exit 2; }
for f in "$1" "$2"; do [ -r "$f" ] || { echo "pack.sh: cannot read bake $f" >&2; exit 1; }; done
for d in .dev .gl; do grep -qx "/$d/" .git/info/exclude 2>/dev/null || echo "/$d/" >> .git/info/exclude; done
rm -rf .dev && mkdir -p .dev/bin .dev/lib .gl
cp build/bin/glow-bench build/bin/glow-bake build/bin/test_glctx build/bin/test_gl_agreement \
   build/bin/test_gl_lights build/bin/test_gl_shading .dev/bin/ && strip .dev/bin/*
L=/lib/x86_64-linux-gnu
for l in libtbb.so.12 libcjson.so.1 libglfw.so.3 libX11.so.6 libxcb.so.1 libXau.so.6 libXdmcp.so.6 libbsd.so.0 \
         libmd.so.0 libcmocka.so.0 libminizip.so.1; do cp -L $L/$l .dev/lib/; done
tar -h -C $L -cf - libembree3.so.3 libassimp.so.5 libdraco.so.7 libmpi.so.40 libopen-rte.so.40 libopen-pal.so.40 \
    libhwloc.so.15 libevent_core-2.1.so.7 libevent_pthreads-2.1.so.7 libudev.so.1 | xz -T2 -6 > .dev/libs.tar.xz
xz -T2 -6 -c "$1" > .dev/mod.glow.xz
xz -T2 -6 -c "$2" > .dev/high.glow.xz
cp ../shared/scenes/sponza/sponza-sun.json .dev/ 2>/dev/null || cp "${GLOW_SHARED_DIR:-../shared}/scenes/sponza/sponza-sun.json" .dev/
o='-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/amd64'
mkdir -p /tmp/amd64/partial && apt-get $o update > /dev/null
(cd .gl && apt-get $o download libvulkan1 libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2)
du -sh .dev .gl
