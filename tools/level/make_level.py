#!/usr/bin/env python3
"""make_level.py — a synthetic big level for the world-scale bake (issue 16, item 6): an OBJ mesh tiled
N x M times on the ground plane with a ground of streets between the copies.

    tools/level/make_level.py ../shared/scenes/sponza/dabrovic/sponza.obj 4 4 --street 6 -o /tmp/level4x4

writes OUT/level.obj, OUT/level.mtl (the source's materials plus "street") and, for every other file
beside the source OBJ (its textures), a symbolic link in OUT, so textures resolve as they do for the
source. Copy (i, j) is the source moved by (i (dx + street), 0, j (dz + street)), dx and dz the source's
extents; vertex, UV and normal lists are repeated per copy (indices stay valid; relative indices are
made absolute). The ground lies at the source's lowest y, facing up: by default (`--ground streets`)
rectangles that cover the streets and a border of one street around the level but not the copies'
footprints, where it would lie under each copy's own floor (coplanar with it where the floor is at the
lowest y, as Sponza's courtyard is: a doubled surface that z-fights in any renderer and reflects its
light twice, and elsewhere buried under the copy); `--ground full` is one quad under the whole level,
as before 2026-11-30. Standard library only; the output is deterministic (same bytes for the same
arguments)."""
import argparse
import os
import sys


def fail(msg):
    print("make_level.py: " + msg, file=sys.stderr)
    sys.exit(1)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("source", help="an OBJ file (with its mtllib beside it)")
    ap.add_argument("nx", type=int, help="copies along x (1..64)")
    ap.add_argument("nz", type=int, help="copies along z (1..64)")
    ap.add_argument("--street", type=float, default=6.0, help="gap between copies, in the mesh's units (default 6)")
    ap.add_argument("--ground", choices=("streets", "full"), default="streets",
                    help="streets (default): the ground between and around the copies only; full: one quad under all")
    ap.add_argument("-o", "--out", required=True, help="output folder (created; level.obj is written there)")
    a = ap.parse_args()
    if not (1 <= a.nx <= 64 and 1 <= a.nz <= 64):
        ap.error("nx and nz must be in 1..64")
    if not (a.street >= 0.0) or a.street != a.street or a.street > 1e6:
        ap.error("--street must be a finite length >= 0")
    try:
        with open(a.source, encoding="utf-8", errors="replace") as f:
            lines = f.read().splitlines()
    except OSError as e:
        fail("%s: %s" % (a.source, e.strerror))
    src_dir = os.path.dirname(os.path.abspath(a.source))
    verts, body, mtllib = [], [], None
    counts = {"v": 0, "vt": 0, "vn": 0}
    for line in lines:
        t = line.split()
        if not t:
            continue
        if t[0] == "v":
            try:
                verts.append(tuple(float(x) for x in t[1:4]))
            except ValueError:
                fail("%s: bad vertex line '%s'" % (a.source, line))
            counts["v"] += 1
            body.append(("v", len(verts) - 1))
        elif t[0] in ("vt", "vn"):
            counts[t[0]] += 1
            body.append(("raw", line))
        elif t[0] == "mtllib":
            mtllib = line.split(None, 1)[1].strip()
        elif t[0] in ("f", "l", "p"):
            body.append(("face", t, counts["v"], counts["vt"], counts["vn"]))
        else:
            body.append(("raw", line))
    if not verts:
        fail("%s: no vertices" % a.source)
    lo = [min(v[k] for v in verts) for k in range(3)]
    hi = [max(v[k] for v in verts) for k in range(3)]
    dx, dz = hi[0] - lo[0] + a.street, hi[2] - lo[2] + a.street
    nv, nvt, nvn = counts["v"], counts["vt"], counts["vn"]
    os.makedirs(a.out, exist_ok=True)
    # the source's other files (textures), linked; its material library, copied with a street material
    for name in sorted(os.listdir(src_dir)):
        p = os.path.join(src_dir, name)
        if name.lower().endswith(".obj") or not os.path.isfile(p) or (mtllib and name == os.path.basename(mtllib)):
            continue
        q = os.path.join(a.out, name)
        if not os.path.lexists(q):
            os.symlink(p, q)
    mtl_text = ""
    if mtllib:
        try:
            with open(os.path.join(src_dir, mtllib), encoding="utf-8", errors="replace") as f:
                mtl_text = f.read()
        except OSError as e:
            fail("%s: %s" % (os.path.join(src_dir, mtllib), e.strerror))
    with open(os.path.join(a.out, "level.mtl"), "w", encoding="utf-8") as f:
        f.write(mtl_text.rstrip("\n") + "\n\nnewmtl street\n\tKd 0.35 0.33 0.30\n")

    def fix(idx, base, n):
        i = int(idx)
        return str(i + base if i > 0 else n + i + 1 + base) if idx else ""

    out = ["# %s tiled %d x %d, street %g (tools/level/make_level.py)" % (os.path.basename(a.source), a.nx, a.nz, a.street),
           "mtllib level.mtl"]
    copy = 0
    for j in range(a.nz):
        for i in range(a.nx):
            ox, oz = i * dx, j * dz
            bv, bt, bn = copy * nv, copy * nvt, copy * nvn
            out.append("o tile_%d_%d" % (i, j))
            for item in body:
                if item[0] == "v":
                    x, y, z = verts[item[1]]
                    out.append("v %.6g %.6g %.6g" % (x + ox, y, z + oz))
                elif item[0] == "raw":
                    if item[1].split()[0] in ("o",):
                        continue
                    out.append(item[1])
                else:
                    t, cv, ct, cn = item[1], item[2], item[3], item[4]
                    refs = []
                    for r in t[1:]:
                        parts = r.split("/")
                        parts[0] = fix(parts[0], bv, cv)
                        if len(parts) > 1:
                            parts[1] = fix(parts[1], bt, ct)
                        if len(parts) > 2:
                            parts[2] = fix(parts[2], bn, cn)
                        refs.append("/".join(parts))
                    out.append(t[0] + " " + " ".join(refs))
            copy += 1
    # the ground, facing up (each rectangle counter-clockwise seen from above)
    g = copy * nv
    ex, ez = hi[0] - lo[0], hi[2] - lo[2]
    x0, x1 = lo[0] - a.street, lo[0] + (a.nx - 1) * dx + ex + a.street
    z0, z1 = lo[2] - a.street, lo[2] + (a.nz - 1) * dz + ez + a.street
    y = lo[1]
    if a.ground == "full":
        rects = [(x0, x1, z0, z1)]
    else:  # the bands between the rows of copies (and the border), then the gaps within each row
        rects = []
        zs = [z0] + [v for j in range(a.nz) for v in (lo[2] + j * dz, lo[2] + j * dz + ez)] + [z1]
        xs = [x0] + [v for i in range(a.nx) for v in (lo[0] + i * dx, lo[0] + i * dx + ex)] + [x1]
        for b in range(0, len(zs), 2):
            rects.append((x0, x1, zs[b], zs[b + 1]))
        for j in range(a.nz):
            for b in range(0, len(xs), 2):
                rects.append((xs[b], xs[b + 1], zs[2 * j + 1], zs[2 * j + 2]))
        rects = [r for r in rects if r[1] > r[0] and r[3] > r[2]]
    out += ["o ground", "usemtl street"]
    for k, (ra, rb, rc, rd) in enumerate(rects):
        out += ["v %.6g %.6g %.6g" % (ra, y, rc), "v %.6g %.6g %.6g" % (ra, y, rd),
                "v %.6g %.6g %.6g" % (rb, y, rd), "v %.6g %.6g %.6g" % (rb, y, rc)]
    for k in range(len(rects)):
        out.append("f %d %d %d %d" % (g + 4 * k + 1, g + 4 * k + 2, g + 4 * k + 3, g + 4 * k + 4))
    with open(os.path.join(a.out, "level.obj"), "w", encoding="utf-8") as f:
        f.write("\n".join(out) + "\n")
    print("make_level.py: %s: %d x %d copies of %s (%d vertices each), %.1f x %.1f units" %
          (os.path.join(a.out, "level.obj"), a.nx, a.nz, os.path.basename(a.source), nv,
           x1 - x0, z1 - z0))


if __name__ == "__main__":
    main()
