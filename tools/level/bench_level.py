#!/usr/bin/env python3
"""bench_level.py — bake time, peak memory and file size against level size (issue 16, item 6): the
source mesh tiled 1x1, 2x2, ... (tools/level/make_level.py), each baked with glow-bake's default preset,
one after the other on this machine. Writes a CSV and a gnuplot chart.

    tools/level/bench_level.py ../shared/scenes/sponza/dabrovic/sponza.obj --tiles 1,2,4 \\
        --csv docs/results/level_bake.csv --png docs/results/level_bake.png

Needs build/bin/glow-bake (or --bin DIR) and gnuplot (Debian) for the chart."""
import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("source")
    ap.add_argument("--tiles", default="1,2,4", help="N for N x N levels, comma-separated (default 1,2,4)")
    ap.add_argument("--street", type=float, default=6.0)
    ap.add_argument("--threads", type=int, default=0, help="glow-bake --threads (default: all CPUs)")
    ap.add_argument("--bin", default=os.path.join(HERE, "..", "..", "build", "bin"))
    ap.add_argument("--bake-args", default="", help="extra glow-bake arguments, e.g. '--quality low'")
    ap.add_argument("--csv", required=True)
    ap.add_argument("--png")
    ap.add_argument("--plot-only", action="store_true", help="draw --png from an existing --csv, bake nothing")
    a = ap.parse_args()
    if a.plot_only:
        with open(a.csv, newline="") as f:
            plot(a.csv, a.png, float(next(csv.DictReader(f))["bake_s"]))
        return
    try:
        tiles = [int(t) for t in a.tiles.split(",")]
    except ValueError:
        ap.error("--tiles must be whole numbers, e.g. 1,2,4")
    if any(t < 1 or t > 64 for t in tiles):
        ap.error("--tiles: each in 1..64")
    bake = os.path.join(a.bin, "glow-bake")
    if not os.access(bake, os.X_OK):
        sys.exit("bench_level.py: %s is not built" % bake)
    rows = []
    with tempfile.TemporaryDirectory(prefix="glow_level_") as tmp:
        for n in tiles:
            d = os.path.join(tmp, "l%d" % n)
            subprocess.run([sys.executable, os.path.join(HERE, "make_level.py"), a.source, str(n), str(n),
                            "--street", str(a.street), "-o", d], check=True, stdout=subprocess.DEVNULL)
            out = os.path.join(tmp, "l%d.glow" % n)
            cmd = [bake, os.path.join(d, "level.obj"), "-o", out, "-q", "--json"] + a.bake_args.split()
            if a.threads:
                cmd += ["--threads", str(a.threads)]
            t0 = time.monotonic()
            p = subprocess.run(cmd, capture_output=True, text=True)
            wall = time.monotonic() - t0
            if p.returncode != 0:
                sys.exit("bench_level.py: %s failed (%d): %s" % (" ".join(cmd), p.returncode, p.stderr.strip()[-500:]))
            j = json.loads(p.stdout)
            st = {s["name"]: s for s in j["stages"]}
            c = j["caches"]
            row = {"copies": n * n, "triangles": j["scene_stats"]["triangles"], "area": j["scene_stats"]["area"],
                   "bake_s": round(j["total_seconds"], 2), "wall_s": round(wall, 2),
                   "links_s": round(st["links"]["seconds"], 2),
                   "peak_rss_mib": round(max(s["peak_rss_bytes"] for s in j["stages"]) / 2**20, 1),
                   "file_mb": round(j["file_bytes"] / 1e6, 1), "caches": c["total"], "grid": c["grid"],
                   "lightmap": c["lightmap"], "texels_per_unit": round(c["texel_density"], 4),
                   "charts": c["charts"], "grid_spacing": round(c["grid_spacing"], 3)}
            rows.append(row)
            print("  %d copies: %d triangles, bake %.1f s (links %.1f s), peak %.0f MiB, %.1f MB, %d caches, %.3f texels/unit"
                  % (row["copies"], row["triangles"], row["bake_s"], row["links_s"], row["peak_rss_mib"], row["file_mb"],
                     row["caches"], row["texels_per_unit"]), flush=True)
            os.remove(out)
    with open(a.csv, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    if a.png:
        plot(a.csv, a.png, rows[0]["bake_s"])


def plot(csv_path, png, one):
    if png:
        script = f"""set terminal pngcairo size 900,420 font ',10'
set output '{png}'
set datafile separator ','
set key autotitle columnhead left top
set logscale x 2
set xlabel 'copies of the source mesh (N x N)'
set ylabel 'seconds / MiB / MB'
set logscale y
set grid
plot '{csv_path}' using 1:4 with linespoints title 'bake time (s)', \\
     '' using 1:7 with linespoints title 'peak RSS (MiB)', \\
     '' using 1:8 with linespoints title 'file (MB)', \\
     '' using 1:($1*{one}) with lines dashtype 2 title 'bake time of one copy x copies (linear in area)'
"""
        subprocess.run(["gnuplot"], input=script, text=True, check=True)


if __name__ == "__main__":
    main()
