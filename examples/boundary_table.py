#!/usr/bin/env python3
"""Improves meshes with the boundary fixed and with sliding boundary vertices, and prints the
tables of docs/local_solver.md (--method local) and docs/global_solver.md (--method global): the smallest dihedral angle over *all* tetrahedra (boundary ones
too), the smallest and mean aspect ratio, how far the boundary moved and the volume change.

    python3 examples/boundary_table.py [--paloverde build/bin/paloverde] [--data ../shared/data]
                                       [--method local|global] [--metric aspect_ratio|dihedral_sine|...]
                                       [--feature-angle DEG] [MESH ...]

MESH defaults to the shared tet meshes; others (a Gmsh mesh, fandisk-100k.node) may be added.
"""
import argparse
import json
import os
import subprocess
import tempfile

SHARED = ["stellar/house2.node", "mesquite/tets/tire.vtk", "mesquite/tets/cube-clip-5.vtk",
          "mesquite/tets/flat-tet-sphere.vtk", "mesquite/tets/cub_wedge_like.vtk"]

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("meshes", nargs="*")
parser.add_argument("--paloverde", default="build/bin/paloverde")
parser.add_argument("--data", default="../shared/data")
parser.add_argument("--threads", default="1")
parser.add_argument("--method", default="local")
parser.add_argument("--metric", default="aspect_ratio")
parser.add_argument("--feature-angle", default=None)
args = parser.parse_args()
meshes = args.meshes or [os.path.join(args.data, m) for m in SHARED]

print("| mesh | tets | min dihedral, all tets: input | fixed | slide | min aspect: fixed | slide | "
      "mean aspect: input | fixed | slide | largest distance / diagonal | volume change | time (s): fixed | slide |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
with tempfile.TemporaryDirectory() as scratch:
    for mesh in meshes:
        runs = {}
        for boundary in ("fixed", "slide"):
            summary_file = os.path.join(scratch, "summary.json")
            command = [args.paloverde, "improve", mesh, "-o", os.path.join(scratch, "out.vtu"), "--summary", summary_file,
                       "--threads", args.threads, "--method", args.method, "--metric", args.metric,
                       "--boundary", boundary, "-q"]
            if args.feature_angle and boundary == "slide":
                command += ["--feature-angle", args.feature_angle]
            subprocess.run(command, check=True)
            runs[boundary] = json.load(open(summary_file))
        fixed, slide = runs["fixed"], runs["slide"]
        motion = slide["steps"][0]["summary"]["boundary"]
        change = (motion["volume_after"] - motion["volume_before"]) / abs(motion["volume_before"])
        dihedral = lambda s, when: s[when]["metrics"]["min_dihedral_deg"]["min"]
        aspect = lambda s, when, what: s[when]["metrics"]["aspect_ratio"][what]
        row = [os.path.basename(mesh), fixed["before"]["elements"],
               "%.2f°" % dihedral(fixed, "before"), "%.2f°" % dihedral(fixed, "after"), "%.2f°" % dihedral(slide, "after"),
               "%.4f" % aspect(fixed, "after", "min"), "%.4f" % aspect(slide, "after", "min"),
               "%.4f" % aspect(fixed, "before", "mean"), "%.4f" % aspect(fixed, "after", "mean"),
               "%.4f" % aspect(slide, "after", "mean"),
               "%.1e" % motion["largest_distance"], "%+.2e" % change, "%.2f" % fixed["seconds"], "%.2f" % slide["seconds"]]
        print("| " + " | ".join(str(x) for x in row) + " |", flush=True)
