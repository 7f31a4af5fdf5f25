#!/usr/bin/env python3
"""Untangling study (issue 15): solvable tangles, their mirrored copies, 1/2/4 ranks, global vs local.

For each mesh, amount and seed: `paloverde perturb` moves a fraction of the interior vertices by
up to AMOUNT local edge lengths (the boundary stays, so the original placement is a valid answer),
a mirrored copy swaps corners 1 and 2 of every element (the other orientation convention), and
`paloverde improve --untangle` runs on each: the global solver serially, under `mpirun -n 2` and
`-n 4`, on the mirror, and the local smoother. Prints a markdown table: how many of the runs
untangled (no element left inverted), the worst aspect ratio reached, the time, and whether the
2- and 4-rank outputs equal the serial one bit for bit.

  python3 examples/untangle_study.py [--meshes M1 M2 ...] [--amounts 1.0 1.5] [--seeds 5]
      [--fraction 0.3] [--work DIR] [--mpirun "mpirun --allow-run-as-root --oversubscribe"]

Run by hand after `bash scripts/setup.sh build`; one thread per process (OMP_NUM_THREADS=1).
"""
import argparse
import json
import os
import re
import shlex
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PALOVERDE = os.path.join(os.environ.get("PALOVERDE_BUILD_DIR", os.path.join(ROOT, "build")), "bin", "paloverde")
SHARED = os.path.join(ROOT, "..", "shared", "data")
DEFAULT_MESHES = [os.path.join(SHARED, "mesquite", "tets", name + ".vtk")
                  for name in ("tire", "cube-clip-5", "flat-tet-sphere", "cub_wedge_like")]


def mirror(source, target):
    """Swaps corners 1 and 2 of every tetrahedron and triangle of an ASCII legacy VTK file."""
    lines = open(source).read().split("\n")
    out, k = [], 0
    while k < len(lines):
        out.append(lines[k])
        if lines[k].startswith("CELLS"):
            count = int(lines[k].split()[1])
            cells, pending = [], []
            k += 1
            while len(cells) < count:
                pending += lines[k].split()
                k += 1
                while pending and len(pending) >= 1 + int(pending[0]):
                    size = int(pending[0])
                    cell, pending = pending[:1 + size], pending[1 + size:]
                    if size in (3, 4):
                        cell[2], cell[3] = cell[3], cell[2]
                    cells.append(" ".join(cell))
            out += cells
            continue
        k += 1
    open(target, "w").write("\n".join(out))


def points(path):
    """The POINTS block of an ASCII legacy VTK file, as text (to compare outputs bit for bit)."""
    text = open(path).read()
    start = text.index("POINTS")
    return text[start:text.index("CELLS", start)]


def improve(prefix, mesh, output, extra):
    command = prefix + [PALOVERDE, "improve", mesh, "-o", output, "--untangle", "--summary", output + ".json"] + extra
    started = time.time()
    result = subprocess.run(command, capture_output=True, text=True, env=dict(os.environ, OMP_NUM_THREADS="1"))
    seconds = time.time() - started
    if not os.path.exists(output + ".json"):
        sys.exit("failed: " + " ".join(command) + "\n" + result.stdout + result.stderr)
    summary = json.load(open(output + ".json"))
    return {"untangled": summary["inverted_after"] == 0, "worst": summary["worst_after"], "seconds": seconds}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--meshes", nargs="+", default=DEFAULT_MESHES)
    parser.add_argument("--amounts", nargs="+", type=float, default=[1.0, 1.5])
    parser.add_argument("--fraction", type=float, default=0.3)
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--work", default=os.path.join(ROOT, "build", "untangle_study"))
    parser.add_argument("--mpirun", default="mpirun --allow-run-as-root --oversubscribe")
    args = parser.parse_args()
    os.makedirs(args.work, exist_ok=True)
    mpirun = shlex.split(args.mpirun)

    print("| mesh | amount | inverted (range) | global | worst (min) | time (s) | 2 ranks | 4 ranks | "
          "same mesh at 1/2/4 ranks | mirrored | local |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for mesh in args.meshes:
        name = re.sub(r"\.(vtk|vtu|msh|mesh|node)$", "", os.path.basename(mesh))
        for amount in args.amounts:
            rows = []
            for seed in range(1, args.seeds + 1):
                base = os.path.join(args.work, f"{name}-a{amount}-s{seed}")
                perturbed, mirrored = base + ".vtk", base + "-mirror.vtk"
                made = subprocess.run([PALOVERDE, "perturb", mesh, "-o", perturbed, "--ascii", "--fraction",
                                       str(args.fraction), "--amount", str(amount), "--seed", str(seed), "--json"],
                                      capture_output=True, text=True, check=True)
                inverted = json.loads(made.stdout)["inverted"]
                mirror(perturbed, mirrored)
                runs = {"serial": improve([], perturbed, base + "-global.vtk", ["--ascii"]),
                        "np2": improve(mpirun + ["-n", "2"], perturbed, base + "-np2.vtk", ["--ascii"]),
                        "np4": improve(mpirun + ["-n", "4"], perturbed, base + "-np4.vtk", ["--ascii"]),
                        "mirror": improve([], mirrored, base + "-mirror-out.vtk", []),
                        "local": improve([], perturbed, base + "-local.vtk", ["--method", "local"])}
                same = points(base + "-global.vtk") == points(base + "-np2.vtk") == points(base + "-np4.vtk")
                rows.append((inverted, runs, same))
            count = len(rows)
            ok = lambda key: sum(r[1][key]["untangled"] for r in rows)
            print(f"| {name} | {amount} | {min(r[0] for r in rows):,}-{max(r[0] for r in rows):,} | "
                  f"{ok('serial')}/{count} | {min(r[1]['serial']['worst'] for r in rows):.3g} | "
                  f"{sum(r[1]['serial']['seconds'] for r in rows):.1f} | {ok('np2')}/{count} | {ok('np4')}/{count} | "
                  f"{sum(r[2] for r in rows)}/{count} | {ok('mirror')}/{count} | {ok('local')}/{count} |", flush=True)


if __name__ == "__main__":
    main()
