#!/usr/bin/env python3
"""Runs the global log-barrier solver, the local Freitag-Plassmann smoother and smart Laplace on the
same mesh and writes one markdown table and one plot (worst and mean quality per iteration, and
against time).

    python3 examples/compare_methods.py MESH [MESH ...] [--out docs/comparison] [--paloverde build/bin/paloverde]

Needs matplotlib (Debian: python3-matplotlib) for the plot; the table is printed either way.
"""
import argparse
import csv
import json
import os
import subprocess
import tempfile

METHODS = ["global", "local", "smart-laplace"]

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("meshes", nargs="+")
parser.add_argument("--paloverde", default="build/bin/paloverde")
parser.add_argument("--out", default="comparison", help="prefix of the PNG files written")
parser.add_argument("--threads", default="1")
args = parser.parse_args()

runs = {}
with tempfile.TemporaryDirectory() as scratch:
    for mesh in args.meshes:
        for method in METHODS:
            history, summary = os.path.join(scratch, "h.csv"), os.path.join(scratch, "s.json")
            done = subprocess.run([args.paloverde, "improve", mesh, "-o", os.path.join(scratch, "out.vtu"), "--method",
                                   method, "--history", history, "--summary", summary, "--threads", args.threads, "-q"])
            if done.returncode not in (0, 3):
                print(f"{mesh} {method}: paloverde exited {done.returncode}")
                continue
            runs[(mesh, method)] = (json.load(open(summary)), list(csv.DictReader(open(history))))

print("| mesh | method | min dihedral | min aspect | mean aspect | inverted | iterations | time (s) |")
print("|---|---|---|---|---|---|---|---|")
for mesh in args.meshes:
    first = runs.get((mesh, METHODS[0]))
    if first:
        b = first[0]["before"]["metrics"]
        print(f"| {os.path.basename(mesh)} | input | {b['min_dihedral_deg']['movable']['min']:.2f}° | "
              f"{b['aspect_ratio']['movable']['min']:.4f} | {b['aspect_ratio']['mean']:.4f} | "
              f"{first[0]['inverted_before']} | | |")
    for method in METHODS:
        if (mesh, method) not in runs:
            continue
        s = runs[(mesh, method)][0]
        a = s["after"]["metrics"]
        print(f"| {os.path.basename(mesh)} | {method} | {a['min_dihedral_deg']['movable']['min']:.2f}° | "
              f"{a['aspect_ratio']['movable']['min']:.4f} | {a['aspect_ratio']['mean']:.4f} | {s['inverted_after']} | "
              f"{s['iterations']} | {s['seconds']:.2f} |")

try:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    print("matplotlib not found: no plot (apt-get install python3-matplotlib)")
    raise SystemExit(0)

for mesh in args.meshes:
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for method in METHODS:
        if (mesh, method) not in runs:
            continue
        rows = [r for r in runs[(mesh, method)][1] if r["phase"] == "shape"]
        if not rows:
            continue
        it = [int(r["iteration"]) for r in rows]
        sec = [float(r["seconds"]) for r in rows]
        worst = [float(r["best_worst_quality"]) for r in rows]
        mean = [float(r["mean_quality"]) for r in rows]
        line, = axes[0].plot(it, worst, label=f"{method} worst")
        axes[0].plot(it, mean, "--", color=line.get_color(), label=f"{method} mean")
        axes[1].plot(sec, worst, color=line.get_color(), label=f"{method} worst")
    axes[0].set_xlabel("iteration (local: sweep)")
    axes[1].set_xlabel("seconds")
    axes[1].set_xscale("log")
    for ax in axes:
        ax.set_ylabel("aspect ratio")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(os.path.basename(mesh))
    fig.tight_layout()
    name = f"{args.out}_{os.path.splitext(os.path.basename(mesh))[0]}.png"
    fig.savefig(name, dpi=90)
    print(f"wrote {name}")
