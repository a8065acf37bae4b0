#!/usr/bin/env python3
"""Runtime benchmark (issue 3): bakes the shared Sponza and Cornell box at moderate and high, runs
glow-bench on each with the shared scene files and prints a markdown table for docs/benchmarks.md.

  python3 tools/bench_runtime.py [--build build] [--frames 100] [--out /tmp/glow-bench]
"""
import argparse, json, os, subprocess, sys

ap = argparse.ArgumentParser()
ap.add_argument("--build", default="build")
ap.add_argument("--frames", type=int, default=100)
ap.add_argument("--out", default="/tmp/glow-bench")
ap.add_argument("--shared", default=os.path.join(os.path.dirname(__file__), "..", "..", "shared"))
ap.add_argument("--host", default="exact")
args = ap.parse_args()
os.makedirs(args.out, exist_ok=True)
bin_dir = os.path.join(args.build, "bin")
scenes = [("Sponza", os.path.join(args.shared, "scenes/sponza/sponza-sun.json"), os.path.join(args.shared, "scenes/sponza/dabrovic/sponza.obj")),
          ("Cornell", os.path.join(args.shared, "scenes/cornell-box/cornell.json"), os.path.join(args.shared, "scenes/cornell-box/CornellBox-Original.obj"))]
rows = []
for name, scene_json, mesh in scenes:
    for q in ("moderate", "high"):
        bake = os.path.join(args.out, f"{name.lower()}-{q}.glow")
        if not os.path.exists(bake):
            subprocess.run([os.path.join(bin_dir, "glow-bake"), mesh, "-o", bake, "--quality", q, "-q"], check=True,
                           stdout=subprocess.DEVNULL)
        r = subprocess.run([os.path.join(bin_dir, "glow-bench"), bake, scene_json, "--frames", str(args.frames),
                            "--host", args.host, "--json", "-q"], check=True, capture_output=True, text=True)
        j = json.loads(r.stdout)
        rows.append((name, q, j))
        print(r.stdout, file=sys.stderr)
print("| scene | preset | surfels | caches x links | l luma/chroma | surfel lighting (host hook) | pull | cache lighting | outputs | total | total w/o hook | ns/link | GB/s | GFLOP/s | % triad | % FMA peak |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
for name, q, j in rows:
    m, c, mc = j["median_ms"], j["cache_lighting"], j["machine"]
    print(f"| {name} | {q} | {j['surfels']} | {j['caches']} x {j['links_per_cache']} | {j['luma']}/{j['chroma']} | "
          f"{m['surfel_lighting']:.3f} ({m['host_hook']:.3f}) | {m['pull']:.3f} | {m['cache_lighting']:.3f} | {m['output']:.3f} | "
          f"**{m['total']:.3f}** | {m['total'] - m['host_hook']:.3f} | {c['ns_per_link']:.2f} | {c['gb_per_s']:.2f} | {c['gflop_per_s']:.1f} | "
          f"{100 * mc['fraction_of_triad']:.1f} | {100 * mc['fraction_of_fma_peak']:.1f} |")
j = rows[0][2]["machine"]
print(f"\nMachine (same runs): STREAM triad {j['stream_triad_gb_per_s']:.1f} GB/s, fp32 FMA peak {j['fma_peak_gflop_per_s']:.1f} GFLOP/s ({j['fma_isa']}); bound: {j['bound']}")
