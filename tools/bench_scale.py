#!/usr/bin/env python3
"""Issue 16's scaling ratio: a scene baked at --surfels N (default 524,288, 16x the moderate count)
against the same scene's moderate default, on this machine, the way docs/benchmarks.md quotes it.

    python3 tools/bench_scale.py [--bin build/bin/glow-bake] [--shared ../shared] [--scene OBJ]
                                 [--surfels 524288] [--pairs 3] [--extra "ARGS"] [--csv FILE]

The bakes alternate, moderate first and last (M, N, M, N, ..., M), and each big bake's ratio is taken
against the mean of the two moderate bakes on either side of it: a shared VM's speed drifts by a
fifth within minutes, and a ratio against one moderate bake an hour away says little. Prints every
bake's stages and each ratio, then the median; --csv writes one row a bake. Both bakes run with
glow-bake's defaults otherwise (2 threads on a 2-core machine), written to a temporary folder.
This is a benchmark, not a test: it asserts nothing and exits 0 unless a bake fails."""
import argparse, csv, json, os, statistics, subprocess, sys, tempfile


def bake(binary, scene, out, args):
    cmd = [binary, scene, "-o", out, "--json", "-q"] + args
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit("bench_scale: %s failed (exit %d): %s" % (" ".join(cmd), p.returncode, p.stderr.strip()))
    j = json.loads(p.stdout)
    return j["total_seconds"], {s["name"]: s["seconds"] for s in j["stages"]}, j.get("surfels")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bin", default="build/bin/glow-bake")
    ap.add_argument("--shared", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "shared"))
    ap.add_argument("--scene", help="a scene file (default: the shared Dabrovic Sponza)")
    ap.add_argument("--surfels", type=int, default=524288)
    ap.add_argument("--pairs", type=int, default=3, help="big bakes (each between two moderate ones)")
    ap.add_argument("--extra", default="", help="extra glow-bake arguments for every bake")
    ap.add_argument("--csv", help="write one row a bake here")
    a = ap.parse_args()
    if a.pairs < 1 or a.surfels < 1:
        sys.exit("bench_scale: --pairs and --surfels must be at least 1")
    scene = a.scene or os.path.join(a.shared, "scenes", "sponza", "dabrovic", "sponza.obj")
    if not os.path.isfile(scene):
        sys.exit("bench_scale: %s: no such scene file (give --scene or --shared)" % scene)
    if not os.access(a.bin, os.X_OK):
        sys.exit("bench_scale: %s: not an executable glow-bake (build first, or give --bin)" % a.bin)
    extra = a.extra.split() if a.extra else []
    rows, ratios = [], []
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "b.glow")
        prev = None
        for i in range(a.pairs + 1):
            t, st, n = bake(a.bin, scene, out, extra)
            rows.append(("moderate", n, t, st))
            print("moderate   %7.2f s  %s" % (t, " ".join("%s %.2f" % kv for kv in st.items())), flush=True)
            if prev is not None:
                r = rows[-2][2] / (0.5 * (prev + t))
                ratios.append(r)
                print("  ratio    %.2fx (against the mean of the moderate bakes around it)" % r, flush=True)
            prev = t
            if i == a.pairs:
                break
            t, st, n = bake(a.bin, scene, out, ["--surfels", str(a.surfels)] + extra)
            rows.append(("surfels %d" % a.surfels, n, t, st))
            print("%-10s %7.2f s  %s" % ("%dk" % (a.surfels // 1024), t, " ".join("%s %.2f" % kv for kv in st.items())),
                  flush=True)
    print("median ratio %.2fx over %d big bakes (%s)" % (statistics.median(ratios), len(ratios),
                                                       ", ".join("%.2fx" % r for r in ratios)))
    if a.csv:
        names = list(rows[0][3].keys())
        with open(a.csv, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["bake", "surfels", "total_s"] + [s + "_s" for s in names])
            for kind, n, t, st in rows:
                w.writerow([kind, n, "%.3f" % t] + ["%.3f" % st.get(s, 0.0) for s in names])


if __name__ == "__main__":
    main()
