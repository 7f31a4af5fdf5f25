#!/usr/bin/env python3
"""Improves the shared meshes with the boundary fixed and prints the table of docs/global_solver.md:
minimum dihedral angle of the tetrahedra with a free vertex, minimum and mean aspect ratio, time.

    python3 examples/peer_table.py [--paloverde build/bin/paloverde] [--data ../shared/data]
                                   [--method global|local] [--metric aspect_ratio|dihedral_sine|...]
"""
import argparse
import json
import os
import subprocess
import tempfile

MESHES = ["stellar/house2.node", "mesquite/tets/tire.vtk", "mesquite/tets/cube-clip-5.vtk",
          "mesquite/tets/flat-tet-sphere.vtk", "mesquite/tets/cub_wedge_like.vtk"]

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--paloverde", default="build/bin/paloverde")
parser.add_argument("--data", default="../shared/data")
parser.add_argument("--threads", default="1")
parser.add_argument("--method", default="global")
parser.add_argument("--metric", default="aspect_ratio", help="the metric the solver raises (the table shows dihedral and aspect)")
args = parser.parse_args()

print("| mesh | tets | min dihedral before | after | min aspect before | after | mean aspect before | after | iterations | time (s) |")
print("|---|---|---|---|---|---|---|---|---|---|")
with tempfile.TemporaryDirectory() as scratch:
    for mesh in MESHES:
        summary_file = os.path.join(scratch, "summary.json")
        subprocess.run([args.paloverde, "improve", os.path.join(args.data, mesh), "-o", os.path.join(scratch, "out.vtu"),
                        "--summary", summary_file, "--threads", args.threads, "--method", args.method,
                        "--metric", args.metric, "-q"], check=True)
        s = json.load(open(summary_file))
        before, after = s["before"]["metrics"], s["after"]["metrics"]
        row = [os.path.basename(mesh), s["before"]["elements"],
               "%.2f°" % before["min_dihedral_deg"]["movable"]["min"], "%.2f°" % after["min_dihedral_deg"]["movable"]["min"],
               "%.4f" % before["aspect_ratio"]["movable"]["min"], "%.4f" % after["aspect_ratio"]["movable"]["min"],
               "%.4f" % before["aspect_ratio"]["mean"], "%.4f" % after["aspect_ratio"]["mean"],
               s["iterations"], "%.2f" % s["seconds"]]
        print("| " + " | ".join(str(x) for x in row) + " |")
