#!/usr/bin/env python3
"""Runtime benchmark (issue 3): bakes the shared Sponza and Cornell box at moderate and high, runs
glow-bench on each with the shared scene files and prints a markdown table for docs/benchmarks.md.

  python3 tools/bench_runtime.py [--build build] [--frames 100] [--runs 5] [--out /tmp/glow-bench]

With --runs N every case runs N times, the cases interleaved (a shared VM's speed changes between
windows of seconds, and interleaving spreads those windows over the cases); the table gives the
median over runs of each run's per-stage median, the "min" columns the fastest run's.
"""
import argparse, json, os, statistics, subprocess, sys

ap = argparse.ArgumentParser()
ap.add_argument("--build", default="build")
ap.add_argument("--frames", type=int, default=100)
ap.add_argument("--out", default="/tmp/glow-bench")
ap.add_argument("--shared", default=os.path.join(os.path.dirname(__file__), "..", "..", "shared"))
ap.add_argument("--host", default="exact")
ap.add_argument("--runs", type=int, default=1)
ap.add_argument("--cases", default="", help="comma-separated, e.g. sponza-moderate (default: all four)")
args = ap.parse_args()
os.makedirs(args.out, exist_ok=True)
bin_dir = os.path.join(args.build, "bin")
scenes = [("Sponza", os.path.join(args.shared, "scenes/sponza/sponza-sun.json"), os.path.join(args.shared, "scenes/sponza/dabrovic/sponza.obj")),
          ("Cornell", os.path.join(args.shared, "scenes/cornell-box/cornell.json"), os.path.join(args.shared, "scenes/cornell-box/CornellBox-Original.obj"))]
cases = []
for name, scene_json, mesh in scenes:
    for q in ("moderate", "high"):
        if args.cases and f"{name.lower()}-{q}" not in args.cases.split(","):
            continue
        bake = os.path.join(args.out, f"{name.lower()}-{q}.glow")
        if not os.path.exists(bake):
            subprocess.run([os.path.join(bin_dir, "glow-bake"), mesh, "-o", bake, "--quality", q, "-q"], check=True,
                           stdout=subprocess.DEVNULL)
        cases.append((name, q, bake, scene_json))
runs = {c[:2]: [] for c in cases}
for k in range(args.runs):
    for name, q, bake, scene_json in cases:
        r = subprocess.run([os.path.join(bin_dir, "glow-bench"), bake, scene_json, "--frames", str(args.frames),
                            "--host", args.host, "--json", "-q"], check=True, capture_output=True, text=True)
        runs[(name, q)].append(json.loads(r.stdout))
        print(r.stdout, file=sys.stderr)
def med(js, f):
    return statistics.median(f(j) for j in js)
rows = []
for name, q, _, _ in cases:
    js = runs[(name, q)]
    j = dict(js[0])
    keys = js[0]["median_ms"].keys()
    j["median_ms"] = {k: med(js, lambda x: x["median_ms"][k]) for k in keys}
    j["min_total"] = min(x["median_ms"]["total"] for x in js)
    j["min_wo_hook"] = min(x["median_ms"]["total"] - x["median_ms"]["host_hook"] for x in js)
    j["cache_lighting"] = {k: med(js, lambda x: x["cache_lighting"][k]) for k in ("ns_per_link", "gb_per_s", "gflop_per_s", "flops_per_link")}
    j["machine"] = {k: med(js, lambda x: x["machine"][k]) for k in ("fraction_of_triad", "fraction_of_fma_peak", "stream_triad_gb_per_s", "fma_peak_gflop_per_s")}
    j["machine"]["fma_isa"], j["machine"]["bound"] = js[0]["machine"]["fma_isa"], js[0]["machine"]["bound"]
    j["machine"]["fma_peak_range"] = (min(x["machine"]["fma_peak_gflop_per_s"] for x in js), max(x["machine"]["fma_peak_gflop_per_s"] for x in js))
    # best against best: the fastest run's cache lighting against the highest FMA peak measured (the
    # two probes of one run may fall in different speed windows of a shared VM)
    best_gflops = max(x["cache_lighting"]["gflop_per_s"] for x in js)
    best_triad = max(x["machine"]["stream_triad_gb_per_s"] for x in js)
    j["best_fma_frac"] = best_gflops / j["machine"]["fma_peak_range"][1] if j["machine"]["fma_peak_range"][1] > 0 else -1
    j["best_triad_frac"] = max(x["cache_lighting"]["gb_per_s"] for x in js) / best_triad if best_triad > 0 else -1
    rows.append((name, q, j))
print(f"Medians over {args.runs} run(s) of each run's median of {args.frames} updates; min = the fastest run's.\n")
print("| scene | preset | surfels | caches x links | l luma/chroma | surfel lighting (host hook) | pull | cache lighting | outputs | total (min) | total w/o hook (min) | ns/link | GB/s | GFLOP/s | % triad (best) | % FMA peak (best) |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
for name, q, j in rows:
    m, c, mc = j["median_ms"], j["cache_lighting"], j["machine"]
    print(f"| {name} | {q} | {j['surfels']} | {j['caches']} x {j['links_per_cache']} | {j['luma']}/{j['chroma']} | "
          f"{m['surfel_lighting']:.3f} ({m['host_hook']:.3f}) | {m['pull']:.3f} | {m['cache_lighting']:.3f} | {m['output']:.3f} | "
          f"**{m['total']:.3f}** ({j['min_total']:.3f}) | {m['total'] - m['host_hook']:.3f} ({j['min_wo_hook']:.3f}) | {c['ns_per_link']:.2f} | {c['gb_per_s']:.2f} | {c['gflop_per_s']:.1f} | "
          f"{100 * mc['fraction_of_triad']:.1f} ({100 * j['best_triad_frac']:.1f}) | {100 * mc['fraction_of_fma_peak']:.1f} ({100 * j['best_fma_frac']:.1f}) |")
j = rows[0][2]["machine"]
print(f"\nMachine (same runs, medians): STREAM triad {j['stream_triad_gb_per_s']:.1f} GB/s, fp32 FMA peak {j['fma_peak_gflop_per_s']:.1f} GFLOP/s "
      f"(runs: {j['fma_peak_range'][0]:.1f}-{j['fma_peak_range'][1]:.1f}; {j['fma_isa']}); bound: {j['bound']}; "
      f"{rows[0][2]['cache_lighting']['flops_per_link']:.0f} FLOPs per link at {rows[0][2]['luma']}/{rows[0][2]['chroma']}")
