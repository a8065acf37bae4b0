#!/bin/bash
# Runs on the GPU machine (see pack.sh): the GL tests on the real driver, then glow-bench's GL backend
# on Sponza moderate and high (three runs each, timer queries and glFinish timing), and the CPU solver
# on the same host for scale. Output: $OUT/log.txt and glow-bench's JSON.
exec > >(tee "${OUT:-/tmp}/log.txt") 2>&1
for f in .gl/*.deb; do dpkg -x "$f" /; done; ldconfig
if [ ! -e /usr/share/glvnd/egl_vendor.d/10_nvidia.json ] && [ -e /usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json ]; then
  export __EGL_VENDOR_LIBRARY_FILENAMES=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
fi
ROOT=$PWD; cd .dev
unxz() { if command -v xz > /dev/null; then xz -dc "$1"; else python3 -c "import lzma,sys;sys.stdout.buffer.write(lzma.open(sys.argv[1]).read())" "$1"; fi; }
unxz libs.tar.xz | tar -C lib -xf -; unxz mod.glow.xz > mod.glow; unxz high.glow.xz > high.glow
export LD_LIBRARY_PATH=$PWD/lib GLOW_GLCTX=egl
D=$PWD B=bin/glow-bench J=sponza-sun.json
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.mem --format=csv; nproc; ldd bin/* | grep "not found"
# test_gl_lights bakes its scenes with the glow-bake of the build tree it was compiled in
bindir=$(strings bin/test_gl_lights | grep -m1 "/build[^ ']*/bin$" || true)
[ -n "$bindir" ] && mkdir -p "$bindir" && cp bin/glow-bake "$bindir/"
for t in test_glctx test_gl_shading test_gl_agreement test_gl_lights; do
  echo "=== $t"; (cd /tmp && timeout 200 "$D/bin/$t"); echo "=== $t rc=$?"
done
for i in 1 2 3; do for b in mod high; do
  echo "=== GL $b, run $i"; timeout 60 $B $b.glow $J --backend gl --frames 300 --warmup 30 --no-machine
done; done
for b in mod high; do
  timeout 60 $B $b.glow $J --backend gl --frames 300 --warmup 30 --no-machine --json -q > "${OUT:-/tmp}/${b}_gl.json"
  echo "=== GL $b, glFinish timing"; timeout 60 $B $b.glow $J --backend gl --frames 300 --warmup 30 --no-machine --gl-timing finish
  echo "=== CPU $b, all threads"; timeout 90 $B $b.glow $J --frames 60
done
echo "=== done"
