#!/usr/bin/env python3
"""Draws the documentation's plots from the measured figures kept in docs/data/*.csv.

    /usr/bin/python3 examples/plot_docs.py [--data docs/data] [--out docs]

Needs matplotlib (Debian: python3-matplotlib, hence /usr/bin/python3 where another python3 comes
first on the PATH). It runs nothing: the CSV files hold the figures as measured, and
docs/data/README.md names the command that measured each. Writes:

    race.png             seconds to the local smoother's worst element, global and local (race.csv)
    peers.png            smallest dihedral angle beside Mesquite, Stellar and MMG (global_peers.csv)
    comparison.png       worst and mean aspect ratio per method on the shared meshes (comparison.csv)
    benchmarks_weak.png  weak scaling: seconds per iteration and efficiency (weak.csv)
"""
import argparse
import csv
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--data", default=os.path.join(os.path.dirname(__file__), "..", "docs", "data"))
parser.add_argument("--out", default=os.path.join(os.path.dirname(__file__), "..", "docs"))
args = parser.parse_args()


def rows(name):
    with open(os.path.join(args.data, name), newline="") as f:
        return list(csv.DictReader(f))


def number(text):
    try:
        return float(text)
    except (TypeError, ValueError):
        return None  # empty, "aborts", ...


def bars(ax, labels, series, width=0.8):
    """Grouped bars: series is a list of (name, values); a None value leaves a gap."""
    n = len(series)
    w = width / n
    for k, (name, values) in enumerate(series):
        xs = [i + (k - (n - 1) / 2) * w for i in range(len(labels))]
        ys = [0 if v is None else v for v in values]
        ax.bar(xs, ys, w, label=name)
    ax.set_xticks(range(len(labels)))
    ax.set_xticklabels(labels, rotation=30, ha="right")
    ax.legend(fontsize="small")


def save(fig, name):
    path = os.path.join(args.out, name)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    print("wrote", path)


def race():
    r = rows("race.csv")
    fig, ax = plt.subplots(figsize=(9, 4.5))
    bars(ax, [x["mesh"] for x in r],
         [("global, to the local smoother's worst (--target)", [number(x["global_to_local_worst_seconds"]) for x in r]),
          ("local smoother, to its own worst", [number(x["local_seconds"]) for x in r])])
    ax.set_yscale("log")
    ax.set_ylabel("solver seconds, one thread")
    ax.set_title("Time to the local smoother's worst aspect ratio")
    save(fig, "race.png")


def peers():
    r = rows("global_peers.csv")
    fig, ax = plt.subplots(figsize=(9, 4.5))
    cols = [("input", "input_min_dihedral_deg"), ("Paloverde (global)", "paloverde_min_dihedral_deg"),
            ("Mesquite ShapeImprover", "mesquite_shapeimprover_min_dihedral_deg"),
            ("Stellar (smoothing)", "stellar_smoothing_min_dihedral_deg"), ("MMG (-optim)", "mmg_optim_min_dihedral_deg")]
    bars(ax, [x["mesh"] for x in r], [(name, [number(x[c]) for x in r]) for name, c in cols])
    ax.set_ylabel("smallest dihedral angle (degrees)")
    ax.set_title("Smoothing only, boundary fixed (no bar: no figure, or the tool aborted)")
    save(fig, "peers.png")


def comparison():
    r = rows("comparison.csv")
    meshes = list(dict.fromkeys(x["mesh"] for x in r))
    methods = list(dict.fromkeys(x["method"] for x in r))
    value = {(x["mesh"], x["method"]): x for x in r}
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
    for ax, column, label in ((axes[0], "min_aspect", "worst aspect ratio"), (axes[1], "mean_aspect", "mean aspect ratio")):
        bars(ax, meshes, [(m, [number(value.get((mesh, m), {}).get(column)) for mesh in meshes]) for m in methods])
        ax.set_ylabel(label)
    if axes[1].get_ylim()[1] > 0:
        axes[1].set_ylim(0.6, 0.9)
    fig.suptitle("The shared meshes: input and each method, boundary fixed")
    save(fig, "comparison.png")


def weak():
    r = rows("weak.csv")
    p = [int(x["processes"]) for x in r]
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.plot(p, [number(x["seconds_per_iteration"]) for x in r], "o-", label="seconds per iteration")
    ax.set_xlabel("processes (about 1M tets each)")
    ax.set_ylabel("seconds per iteration")
    ax.set_xticks(p)
    ax.set_ylim(0, 1.3 * max(number(x["seconds_per_iteration"]) for x in r))
    ax2 = ax.twinx()
    ax2.plot(p, [number(x["weak_efficiency"]) for x in r], "s--", color="tab:orange", label="weak efficiency T1/Tp")
    ax2.set_ylabel("weak efficiency")
    ax.set_title("Weak scaling, global solver, 40 iterations")
    ax2.set_ylim(0, 1.3)
    fig.legend(loc="upper center", bbox_to_anchor=(0.5, 0.88), fontsize="small")
    save(fig, "benchmarks_weak.png")


race()
peers()
comparison()
weak()
