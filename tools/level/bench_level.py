#!/usr/bin/env python3
"""bench_level.py — bake time, peak memory and file size against level size and rank count (issue 16,
item 6): the source mesh tiled 1x1, 2x2, 4x4, 8x8 (tools/level/make_level.py), each baked in systems
(glow-bake --system-area) with the default preset, one bake after the other on this machine, and the
rank series (mpirun -np R glow-bake --mpi) on the levels named. Writes a CSV and a gnuplot chart.

    tools/level/bench_level.py ../shared/scenes/sponza/dabrovic/sponza.obj --tiles 1,2,4,8 \\
        --rank-series 4:2,4 --rank-series 8:4 \\
        --csv docs/results/level_bake.csv --png docs/results/level_bake.png

Each row is one bake: copies (N x N), ranks, threads a rank, the level's triangles and area, systems,
the bake's wall time (the whole mpirun for ranks > 1), its links stage (rank 0), the peak resident
memory of the largest process (GNU time's %M around every rank), the bytes of every file written (the
manifest and the systems' bakes), caches, the lightmap's texels per unit (a level's sparsest system, from
the manifest), and the ratios to "one
copy": the source baked as one system with the default preset (`glow-bake SOURCE`, the issue's "one
Sponza"), measured in the same run right before the levels. A rank count needs glow-bake built with
MPI and mpirun (tools/setup.sh installs OpenMPI); the ranks run on the loopback (TCP), oversubscribed
when they outnumber the cores, as tests/cli/test_bake_mpi.sh does. Needs build/bin/glow-bake (or
--bin DIR), /usr/bin/time (Debian's `time`) and gnuplot for the chart."""
import argparse
import csv
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
TIME = "/usr/bin/time"
# The shared Sponza's surface as the linker first measured it for a system's budget (docs/benchmarks.md,
# "Big levels"): every level figure in the docs uses it, so the default keeps them comparable.
SPONZA_SYSTEM_AREA = 7506.0

FIELDS = ["copies", "ranks", "threads", "triangles", "area", "systems", "bake_s", "links_s", "peak_rss_mib",
          "file_mb", "caches", "grid", "lightmap", "texels_per_unit", "x_one", "area_x_one"]


def fail(msg):
    print("bench_level.py: " + msg, file=sys.stderr)
    sys.exit(1)


def parse_series(specs, ap):
    """--rank-series N:R1,R2 -> {N: [R1, R2]}"""
    out = {}
    for s in specs:
        try:
            n, rs = s.split(":")
            out.setdefault(int(n), []).extend(int(r) for r in rs.split(","))
        except ValueError:
            ap.error("--rank-series wants N:R1,R2,... (e.g. 4:2,4), got '%s'" % s)
    for n, rs in out.items():
        if n < 1 or n > 64 or any(r < 1 or r > 64 for r in rs):
            ap.error("--rank-series: N in 1..64, ranks in 1..64")
    return out


def bake(a, scene, out, ranks, threads, rss_dir, extra):
    """one bake; returns (its --json summary, wall seconds, peak RSS in KiB over its processes)"""
    for f in os.listdir(rss_dir):
        os.remove(os.path.join(rss_dir, f))
    # every process writes its own peak to rss_dir/rss.<rank> (OpenMPI names the rank in the environment)
    wrap = [TIME, "-f", "%M", "-o"]
    cmd = [os.path.join(a.bin, "glow-bake"), scene, "-o", out, "-q", "--json", "--threads", str(threads)] + extra
    env = dict(os.environ)
    if ranks > 1:
        env.update(OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OMPI_MCA_rmaps_base_oversubscribe="1")
        inner = " ".join("'%s'" % c for c in cmd[1:])
        run = ["mpirun", "--mca", "btl", "self,tcp", "--mca", "btl_tcp_if_include", "lo", "-np", str(ranks), "sh", "-c",
               "exec %s -f %%M -o '%s'/rss.$OMPI_COMM_WORLD_RANK '%s' --mpi %s" % (TIME, rss_dir, cmd[0], inner)]
    else:
        run = wrap + [os.path.join(rss_dir, "rss.0")] + cmd
    t0 = time.monotonic()
    p = subprocess.run(run, capture_output=True, text=True, env=env)
    wall = time.monotonic() - t0
    if p.returncode != 0:
        fail("%s failed (%d): %s" % (" ".join(run), p.returncode, p.stderr.strip()[-800:]))
    rss = []
    for f in sorted(os.listdir(rss_dir)):
        with open(os.path.join(rss_dir, f)) as h:
            lines = [x for x in h.read().split() if x.isdigit()]
        if lines:
            rss.append(int(lines[-1]))
    if len(rss) != ranks:
        fail("%d of %d processes reported their peak memory (%s)" % (len(rss), ranks, rss_dir))
    try:
        j = json.loads(p.stdout)
    except ValueError:
        fail("%s: no JSON summary on stdout" % " ".join(run))
    return j, wall, max(rss)


def out_bytes(folder):
    return sum(os.path.getsize(os.path.join(folder, f)) for f in os.listdir(folder))


def row_of(j, copies, ranks, threads, wall, rss_kib, nbytes, one, manifest=None):
    st = {s["name"]: s for s in j["stages"]}
    c = j["caches"]
    density = c["texel_density"]
    if manifest:  # a world: its sparsest system's lightmap (every rank's systems are in the manifest)
        with open(manifest) as f:
            density = min(s["texel_density"] for s in json.load(f)["systems"])
    r = {"copies": copies, "ranks": ranks, "threads": threads, "triangles": j["scene_stats"]["triangles"],
         "area": round(j["scene_stats"]["area"], 1), "systems": j.get("systems", 1), "bake_s": round(wall, 2),
         "links_s": round(st["links"]["seconds"], 2), "peak_rss_mib": round(rss_kib / 1024.0, 1),
         "file_mb": round(nbytes / 1e6, 1), "caches": c["total"], "grid": c["grid"], "lightmap": c["lightmap"],
         "texels_per_unit": round(density, 4), "x_one": "", "area_x_one": ""}
    if one:
        r["x_one"] = round(wall / one["bake_s"], 2)
        r["area_x_one"] = round(j["scene_stats"]["area"] / one["area"], 2)
    return r


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("source")
    ap.add_argument("--tiles", default="1,2,4", help="N for N x N levels baked by one process, comma-separated "
                    "(default 1,2,4; 8 takes about 15 min and 3 GB on 2 cores)")
    ap.add_argument("--rank-series", action="append", default=[], metavar="N:R1,R2",
                    help="also bake the N x N level over R1, R2, ... MPI ranks (repeatable)")
    ap.add_argument("--street", type=float, default=6.0)
    ap.add_argument("--system-area", type=float, default=SPONZA_SYSTEM_AREA,
                    help="glow-bake --system-area for the levels (default %g, the shared Sponza's surface as "
                    "every figure in docs/benchmarks.md used it)" % SPONZA_SYSTEM_AREA)
    ap.add_argument("--threads", type=int, default=0, help="threads of a one-process bake (default: all CPUs); "
                    "a rank gets CPUs / ranks, at least 1")
    ap.add_argument("--bin", default=os.path.join(HERE, "..", "..", "build", "bin"))
    ap.add_argument("--bake-args", default="", help="extra glow-bake arguments, e.g. '--quality low'")
    ap.add_argument("--csv", required=True)
    ap.add_argument("--png")
    ap.add_argument("--plot-only", action="store_true", help="draw --png from an existing --csv, bake nothing")
    a = ap.parse_args()
    if a.plot_only:
        if not a.png:
            ap.error("--plot-only needs --png")
        plot(a.csv, a.png)
        return
    try:
        tiles = [int(t) for t in a.tiles.split(",") if t]
    except ValueError:
        ap.error("--tiles must be whole numbers, e.g. 1,2,4")
    if any(t < 1 or t > 64 for t in tiles):
        ap.error("--tiles: each in 1..64")
    series = parse_series(a.rank_series, ap)
    if not (a.system_area > 0):
        ap.error("--system-area must be > 0")
    if not os.access(os.path.join(a.bin, "glow-bake"), os.X_OK):
        fail("%s/glow-bake is not built" % a.bin)
    if not os.access(TIME, os.X_OK):
        fail("%s is missing (Debian package 'time')" % TIME)
    if any(r > 1 for rs in series.values() for r in rs):
        v = subprocess.run([os.path.join(a.bin, "glow-bake"), "--version"], capture_output=True, text=True).stdout
        if "--mpi on" not in v:
            fail("--rank-series needs glow-bake built with MPI (its --version says '--mpi on')")
        if not shutil.which("mpirun"):
            fail("--rank-series needs mpirun (tools/setup.sh installs openmpi-bin)")
    cpus = os.cpu_count() or 1
    one_threads = a.threads or cpus
    extra = a.bake_args.split()
    rows = []
    with tempfile.TemporaryDirectory(prefix="glow_level_") as tmp:
        rss_dir = os.path.join(tmp, "rss")
        os.mkdir(rss_dir)
        # one copy, as one system with the default preset: the "one Sponza"
        out = os.path.join(tmp, "one.glow")
        j, wall, rss = bake(a, a.source, out, 1, one_threads, rss_dir, extra)
        one = row_of(j, 1, 1, one_threads, wall, rss, os.path.getsize(out), None)
        one["area"] = j["scene_stats"]["area"]
        one["systems"] = 0  # marks the one-system reference row in the CSV
        os.remove(out)
        print("  one copy as one system: %.1f s, peak %.0f MiB, %.1f MB" % (wall, one["peak_rss_mib"], one["file_mb"]),
              flush=True)
        runs = [(n, 1) for n in tiles] + [(n, r) for n in sorted(series) for r in series[n] if (n, r) != (n, 1)]
        for n, ranks in runs:
            d = os.path.join(tmp, "l%d" % n)
            if not os.path.isdir(d):
                subprocess.run([sys.executable, os.path.join(HERE, "make_level.py"), a.source, str(n), str(n),
                                "--street", str(a.street), "-o", d], check=True, stdout=subprocess.DEVNULL)
            w = os.path.join(tmp, "w%d_%d" % (n, ranks))
            os.mkdir(w)
            threads = one_threads if ranks == 1 else max(1, cpus // ranks)
            j, wall, rss = bake(a, os.path.join(d, "level.obj"), os.path.join(w, "world.json"), ranks, threads, rss_dir,
                                ["--system-area", "%g" % a.system_area] + extra)
            row = row_of(j, n * n, ranks, threads, wall, rss, out_bytes(w), one, os.path.join(w, "world.json"))
            rows.append(row)
            shutil.rmtree(w)
            print("  %d copies, %d rank(s) x %d thread(s): %d systems, %d triangles, bake %.1f s (%.2fx one copy, "
                  "%.2fx its area; links %.1f s), peak %.0f MiB a process, %.1f MB, %d caches, >= %.3f texels/unit"
                  % (row["copies"], ranks, threads, row["systems"], row["triangles"], row["bake_s"], row["x_one"],
                     row["area_x_one"], row["links_s"], row["peak_rss_mib"], row["file_mb"], row["caches"],
                     row["texels_per_unit"]), flush=True)
    one["area"] = round(one["area"], 1)
    one["x_one"], one["area_x_one"] = 1.0, 1.0
    with open(a.csv, "w", newline="") as f:
        wr = csv.DictWriter(f, fieldnames=FIELDS)
        wr.writeheader()
        wr.writerow(one)
        wr.writerows(rows)
    if a.png:
        plot(a.csv, a.png)


def plot(csv_path, png):
    """left: time, memory and size against copies (one process); right: time and memory against ranks"""
    with open(csv_path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows or rows[0]["systems"] != "0":
        fail("%s: the first row must be the one-copy reference (systems 0)" % csv_path)
    one = float(rows[0]["bake_s"])
    tmp = tempfile.mkdtemp(prefix="glow_level_plot_")
    try:
        single = os.path.join(tmp, "single.dat")
        with open(single, "w") as f:
            for r in rows[1:]:
                if r["ranks"] == "1":
                    f.write("%s %s %s %s %s\n" % (r["copies"], r["bake_s"], r["peak_rss_mib"], r["file_mb"], r["area_x_one"]))
        levels = sorted({int(r["copies"]) for r in rows[1:] if r["ranks"] != "1"})
        plots = []
        for c in levels:
            p = os.path.join(tmp, "ranks%d.dat" % c)
            with open(p, "w") as f:
                for r in sorted((r for r in rows[1:] if int(r["copies"]) == c), key=lambda r: int(r["ranks"])):
                    f.write("%s %s %s\n" % (r["ranks"], r["bake_s"], r["peak_rss_mib"]))
            plots.append("'%s' using 1:2 with linespoints title '%d copies: bake time (s)', "
                         "'' using 1:3 with linespoints dashtype 3 title '%d copies: peak RSS a rank (MiB)'" % (p, c, c))
        right = ("plot " + ", ".join(plots)) if plots else "set label 'no rank series' at graph 0.3,0.5\nplot 1/0 notitle"
        script = f"""set terminal pngcairo size 1200,460 font ',10'
set output '{png}'
set multiplot layout 1,2
set key inside left top Left reverse
set grid
set logscale xy
set xlabel 'copies of the source mesh (N x N), baked in systems by one process'
set ylabel 'seconds / MiB / MB'
set xrange [0.8:*]
plot '{single}' using 1:2 with linespoints title 'bake time (s)', \\
     '' using 1:3 with linespoints title 'peak RSS (MiB)', \\
     '' using 1:4 with linespoints title 'files (MB)', \\
     '' using 1:($5*{one}) with lines dashtype 2 title 'one copy as one system ({one:.1f} s) x the level area / its area'
unset logscale x
set logscale y
set xrange [0.5:*]
set xtics 1
set xlabel 'MPI ranks on this machine (mpirun -np R glow-bake --mpi)'
set ylabel 'seconds / MiB'
{right}
unset multiplot
"""
        subprocess.run(["gnuplot"], input=script, text=True, check=True)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
