#!/usr/bin/env python3
"""Bake benchmark: time and peak memory per stage for the shared Sponza (moderate, high) and the
built-in Cornell box, written as a Markdown table to docs/benchmarks.md (or --out).

    python3 tools/bench_bake.py [--bin build/bin/glow-bake] [--shared ../shared] [--runs 1]
                                [--cases cornell-moderate,sponza-moderate,sponza-high] [--out docs/benchmarks.md]

Each case runs glow-bake --json; with --runs N > 1 the median total time is reported (and the run
with that total is shown per stage). Peak RSS per stage is the kernel's high-water mark reset at
the stage's start (VmHWM after clear_refs), i.e. the stage's own peak including what earlier stages
still hold."""
import argparse, json, os, platform, statistics, subprocess, sys, tempfile, time

def machine():
    model = "?"
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip(); break
    except OSError:
        pass
    mem = "?"
    try:
        for line in open("/proc/meminfo"):
            if line.startswith("MemTotal"):
                mem = "%.0f GiB" % (int(line.split()[1]) / 1048576); break
    except OSError:
        pass
    return "%s, %d cores online, %s RAM, %s" % (model, os.cpu_count(), mem, platform.platform())

def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", default="build/bin/glow-bake")
    ap.add_argument("--shared", default=os.path.join(os.path.dirname(__file__), "..", "..", "shared"))
    ap.add_argument("--runs", type=int, default=1)
    ap.add_argument("--cases", default="cornell-moderate,sponza-moderate,sponza-high")
    ap.add_argument("--out", default="docs/benchmarks.md")
    ap.add_argument("--extra", default="", help="extra glow-bake arguments for every case")
    a = ap.parse_args()
    sponza = os.path.join(a.shared, "scenes", "sponza", "dabrovic", "sponza.obj")
    cases = {
        "cornell-moderate": ("builtin:cornell", ["--quality", "moderate"]),
        "cornell-high": ("builtin:cornell", ["--quality", "high"]),
        "sponza-low": (sponza, ["--quality", "low"]),
        "sponza-moderate": (sponza, ["--quality", "moderate"]),
        "sponza-high": (sponza, ["--quality", "high"]),
    }
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name in a.cases.split(","):
            scene, args = cases[name]
            runs = []
            for r in range(a.runs):
                out = os.path.join(tmp, name + ".glow")
                cmd = [a.bin, scene, "-o", out, "--json", "-q"] + args + (a.extra.split() if a.extra else [])
                t = time.time()
                p = subprocess.run(cmd, capture_output=True, text=True)
                if p.returncode != 0:
                    sys.exit("%s failed: %s" % (" ".join(cmd), p.stderr))
                j = json.loads(p.stdout)
                j["wall"] = time.time() - t
                j["cmd"] = " ".join(["glow-bake", scene if scene.startswith("builtin:") else os.path.relpath(scene)] + args)
                runs.append(j)
                print("%s run %d: %.2f s" % (name, r + 1, j["total_seconds"]), file=sys.stderr)
            runs.sort(key=lambda j: j["total_seconds"])
            med = runs[len(runs) // 2]
            rows.append((name, med, [j["total_seconds"] for j in runs]))
    stages = [s["name"] for s in rows[0][1]["stages"]]
    lines = []
    lines.append("# Bake benchmarks\n")
    lines.append("Measured with `python3 tools/bench_bake.py --runs %d --cases %s` on: %s.\n" % (a.runs, a.cases, machine()))
    lines.append("Build: RelWithDebInfo (`-O2 -g`). Times are wall-clock seconds per stage (median run of %d);"
                 " peak RSS per stage is the process high-water mark reset at the stage start.\n" % a.runs)
    lines.append("Targets (2 cores): Sponza moderate <= 60 s total, high <= 5 min; links <= 12 bytes (aim 8).\n")
    lines.append("| case | command | surfels | nodes | caches (grid + lightmap) | links | B/link | file MiB | " +
                 " | ".join(stages) + " | total s |")
    lines.append("|" + "---|" * (9 + len(stages)))
    for name, j, totals in rows:
        c = j["caches"]
        lines.append("| %s | `%s` | %d | %d | %d (%d + %d) | %d | %.2f | %.1f | %s | **%.1f** |" % (
            name, j["cmd"], j["surfels"], j["nodes"], c["total"], c["grid"], c["lightmap"], j["links"]["total"],
            j["links"]["bytes_per_link"], j["file_bytes"] / 1048576.0,
            " | ".join("%.2f" % s["seconds"] for s in j["stages"]), j["total_seconds"]))
    lines.append("\nPeak RSS per stage (MiB):\n")
    lines.append("| case | " + " | ".join(stages) + " |")
    lines.append("|" + "---|" * (1 + len(stages)))
    for name, j, totals in rows:
        lines.append("| %s | %s |" % (name, " | ".join("%.0f" % (s["peak_rss_bytes"] / 1048576.0) for s in j["stages"])))
    text = "\n".join(lines) + "\n"
    if a.out == "-":
        print(text)
    else:
        os.makedirs(os.path.dirname(a.out) or ".", exist_ok=True)
        open(a.out, "w").write(text)
        print(text)

if __name__ == "__main__":
    main()
