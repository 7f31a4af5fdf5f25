#!/usr/bin/env python3
"""The fixed cost of a run (docs/benchmarks.md, "The fixed cost of a run"): what `paloverde
improve MESH --iterations 0` spends (read, reports, the solver's set-up, write), in streaming
objective passes of the same mesh. The run's CPU seconds (user + system, `/usr/bin/time`) and the
benchmark's objective pass (`paloverde_benchmark MESH --iterations 0`, one thread) are measured in
turns, so that the machine's load weighs on both alike; one CSV row per round.

    /usr/bin/python3 examples/fixed_cost.py MESH [--bin build/bin] [--rounds 6] [--csv docs/data/fixed_cost_2M.csv]

MESH: docs/benchmarks.md uses fandisk-2M as ASCII legacy VTK (`examples/benchmark_meshes.sh 2M`, then
`paloverde convert fandisk-2M.node fandisk-2M.vtk --ascii`).
"""
import argparse
import csv
import os
import re
import subprocess
import sys
import tempfile


def objective_pass_ns(bin_dir, mesh):
    out = subprocess.run([os.path.join(bin_dir, "paloverde_benchmark"), mesh, "--iterations", "0"],
                         env={**os.environ, "OMP_NUM_THREADS": "1"}, check=True, capture_output=True, text=True)
    m = re.search(r"objective pass ([0-9.]+)", out.stdout + out.stderr)
    if not m:
        sys.exit("paloverde_benchmark printed no objective pass")
    return float(m.group(1))


def run_seconds(bin_dir, mesh, out_mesh):
    """Wall, user and system seconds of one run, from /usr/bin/time."""
    out = subprocess.run(["/usr/bin/time", "-f", "TIME %e %U %S", os.path.join(bin_dir, "paloverde"), "improve", mesh,
                          "-o", out_mesh, "--threads", "1", "-q", "--iterations", "0"],
                         check=True, capture_output=True, text=True)
    m = re.search(r"TIME ([0-9.]+) ([0-9.]+) ([0-9.]+)", out.stderr)
    return tuple(float(x) for x in m.groups())


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("mesh")
    parser.add_argument("--bin", default="build/bin")
    parser.add_argument("--rounds", type=int, default=6)
    parser.add_argument("--csv", default="docs/data/fixed_cost_2M.csv")
    args = parser.parse_args()
    build = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    elements = None
    rows = []
    with tempfile.TemporaryDirectory() as work:
        for r in range(1, args.rounds + 1):
            ns = objective_pass_ns(args.bin, args.mesh)
            wall, user, system = run_seconds(args.bin, args.mesh, os.path.join(work, "out.vtu"))
            if elements is None:
                info = subprocess.run([os.path.join(args.bin, "paloverde"), "quality", args.mesh], capture_output=True,
                                      text=True).stdout
                elements = int(re.search(r"elements (\d+)", info).group(1))
            cpu = user + system
            passes = cpu / (ns * 1e-9 * elements)
            rows.append({"round": r, "build": build, "wall_s": wall, "cpu_s": round(cpu, 2), "user_s": user,
                         "objective_pass_ns_per_tet": ns, "streaming_passes_cpu": round(passes)})
            print(f"round {r}: {cpu:.2f} CPU s, objective pass {ns} ns, {passes:.0f} passes", flush=True)
    with open(args.csv, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)


if __name__ == "__main__":
    main()
