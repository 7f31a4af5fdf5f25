#!/usr/bin/env python3
"""Whether two builds give the same results, bit for bit: the same `paloverde improve` runs with each
build's program, comparing the meshes written (byte for byte), the summaries (--summary, without
their seconds and file names) and what the program printed (without its timings) and its exit code.
For a change meant to make things faster and nothing else (docs/benchmarks.md).

    /usr/bin/python3 scripts/compare_builds.py OLD_BIN NEW_BIN [--case 'MESH [ARGS...]'...] [--work DIR]

OLD_BIN, NEW_BIN: the folders holding each build's `paloverde` (a worktree of the old commit built
with `bash scripts/setup.sh build`, say). Without --case, the shared meshes below (hexahedra, mixed
cells, tetrahedra with and without targets, triangles, quadrilaterals, a sliding boundary, the
local smoother), with the solvers' defaults unless the case says otherwise; each --case adds a mesh of your own (a Gmsh or
TetGen mesh, fandisk-2M) with the flags after it. Prints one line per case; exits 1 if any differ.
"""
import argparse
import json
import os
import re
import shlex
import subprocess
import sys
import tempfile

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "shared", "data")
CASES = [
    "mesquite/hexes/sph-10-zsquare.vtk",
    "mesquite/hexes/hex_5_tangled.vtk",
    "mesquite/hexes/1000hex-block-internal-bias.vtk",
    "mesquite/mixed/mixed-hex-pyr-tet.vtk",
    "mesquite/tets/tire.vtk",
    "mesquite/tets/tet_4_tangled.vtk",
    "mesquite/tets/tire.vtk --keep size,aspect",
    "mesquite/tris/tri_20258.vtk",
    "mesquite/tris/tangled_tri.vtk",
    "mesquite/quads/tangled_horse1.vtk",
    "stellar/house2.node",
    "tetwild/octopus-vol.mesh --iterations 60",
    "tetwild/armadillo.mesh --iterations 40 --boundary slide",
    "tetwild/octopus-vol.mesh --method local --iterations 5",
]
# Keys of a summary that differ from run to run or name the output file.
VOLATILE = re.compile(r"second|^mesh$|^output$")
# Printed lines that carry a timing.
TIMING = re.compile(r"\d\s*s\b|seconds|elapsed")


def stable(value):
    if isinstance(value, dict):
        return {k: stable(v) for k, v in value.items() if not VOLATILE.search(k)}
    if isinstance(value, list):
        return [stable(v) for v in value]
    return value


def run(bin_dir, mesh, args, folder):
    os.makedirs(folder, exist_ok=True)
    out, summary = os.path.join(folder, "out.vtu"), os.path.join(folder, "summary.json")
    done = subprocess.run([os.path.join(bin_dir, "paloverde"), "improve", mesh, "-o", out, "--summary", summary,
                           "--threads", "2", "-q", *args], capture_output=True, text=True)
    printed = [line for line in (done.stdout + done.stderr).splitlines() if not TIMING.search(line)]
    written = open(out, "rb").read() if os.path.exists(out) else None
    report = stable(json.load(open(summary))) if os.path.exists(summary) else None
    return done.returncode, written, report, printed


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("old_bin")
    parser.add_argument("new_bin")
    parser.add_argument("--case", action="append", default=[], help="'MESH [ARGS...]', a mesh of your own")
    parser.add_argument("--work", help="where the outputs go (default: a temporary folder)")
    args = parser.parse_args()
    cases = [os.path.join(DATA, c) for c in CASES] + args.case
    differ = 0
    with tempfile.TemporaryDirectory() as scratch:
        work = args.work or scratch
        for i, case in enumerate(cases):
            mesh, *flags = shlex.split(case)
            old = run(args.old_bin, mesh, flags, os.path.join(work, str(i), "old"))
            new = run(args.new_bin, mesh, flags, os.path.join(work, str(i), "new"))
            what = [name for name, a, b in zip(("exit code", "mesh", "summary", "output"), old, new) if a != b]
            differ += bool(what)
            label = os.path.relpath(mesh, DATA) if mesh.startswith(DATA) else mesh
            print(f"{label} {' '.join(flags)}: {'differs: ' + ', '.join(what) if what else 'same'} (exit {new[0]})",
                  flush=True)
    print(f"{len(cases) - differ} of {len(cases)} the same")
    sys.exit(1 if differ else 0)


if __name__ == "__main__":
    main()
