#!/usr/bin/env python3
"""How much the global solver's result moves when one continuation parameter changes by about 10%
(issue 16; the table in docs/global_solver.md). Run by hand, like the other benchmarks.

    python3 tests/perf/continuation_sensitivity.py MESH [--paloverde build/bin/paloverde]
                                                   [--iterations 500] [--active 10000]
                                                   [--set KEY=VALUE]...

--active is the default barrier_initial_active of MESH (0.5% of its elements, at least 10,000);
the runs set it 10% lower and higher. --set adds a key to every run (e.g.
queue[0].improve.direction=newton).
"""
import argparse
import json
import os
import subprocess
import tempfile

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("mesh")
parser.add_argument("--paloverde", default="build/bin/paloverde")
parser.add_argument("--iterations", default="500")
parser.add_argument("--active", type=float, default=10000.0)
parser.add_argument("--set", action="append", default=[], help="a key for every run, as paloverde improve --set")
args = parser.parse_args()

barrier = "queue[0].improve.objective={name: log_barrier, %s: %s}"
runs = [("defaults", []),
        ("barrier_shrink 0.72", ["--set", barrier % ("barrier_shrink", 0.72)]),
        ("barrier_shrink 0.88", ["--set", barrier % ("barrier_shrink", 0.88)]),
        ("steps_per_mu 4", ["--set", "queue[0].improve.steps_per_mu=4"]),
        ("steps_per_mu 6", ["--set", "queue[0].improve.steps_per_mu=6"]),
        ("gain_tolerance 0.09", ["--set", "queue[0].improve.gain_tolerance=0.09"]),
        ("gain_tolerance 0.11", ["--set", "queue[0].improve.gain_tolerance=0.11"]),
        ("focus_band 0.027", ["--set", "queue[0].improve.focus_band=0.027"]),
        ("focus_band 0.033", ["--set", "queue[0].improve.focus_band=0.033"]),
        ("barrier_initial_active -10%", ["--set", barrier % ("barrier_initial_active", 0.9 * args.active)]),
        ("barrier_initial_active +10%", ["--set", barrier % ("barrier_initial_active", 1.1 * args.active)])]

with tempfile.TemporaryDirectory() as scratch:
    summary = os.path.join(scratch, "summary.json")
    reference = None
    print("| change | worst (at most %s iterations) | vs defaults | iterations | seconds |" % args.iterations)
    print("|---|---|---|---|---|")
    for label, extra in runs:
        subprocess.run([args.paloverde, "improve", args.mesh, "-o", os.path.join(scratch, "out.vtu"), "--iterations",
                        args.iterations, "--threads", "1", "-q", "--summary", summary] + extra +
                       [a for kv in args.set for a in ("--set", kv)], check=True)
        s = json.load(open(summary))
        worst = s["worst_after"]
        reference = worst if reference is None else reference
        print("| %s | %.5f | %+.1f%% | %d | %.1f |" % (label, worst, 100.0 * (worst / reference - 1.0), s["iterations"],
                                                  s["seconds"]), flush=True)
