#!/usr/bin/env python3
"""Improves Mesquite's meshes of quadrilaterals, hexahedra, wedges, pyramids and mixed cells with the
boundary fixed, by the global solver and the local smoother, and prints the table of docs/cells.md:
cells by type, inverted cells and worst aspect ratio (of the cells' worst corners) before and after,
mean aspect ratio, iterations, time.

    python3 examples/cells_table.py [--paloverde build/bin/paloverde] [--data ../shared/data]
                                    [--threads 1] [MESH ...]
"""
import argparse
import glob
import json
import os
import subprocess
import tempfile

FOLDERS = ["hexes", "quads", "prisms", "pyramids", "mixed"]

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--paloverde", default="build/bin/paloverde")
parser.add_argument("--data", default="../shared/data")
parser.add_argument("--threads", default="1")
parser.add_argument("meshes", nargs="*", help="paths (default: every file of Mesquite's cell folders)")
args = parser.parse_args()

meshes = args.meshes or sorted(m for f in FOLDERS for m in glob.glob(os.path.join(args.data, "mesquite", f, "*.vtk")))


def types(report):
    return ", ".join("%d %s" % (t["count"], name) for name, t in report.get("cell_types", {}).items())


print("| mesh | cells | method | inverted before | after | worst aspect before | after | mean before | after | iterations | time (s) |")
print("|---|---|---|---|---|---|---|---|---|---|---|")
with tempfile.TemporaryDirectory() as scratch:
    for mesh in meshes:
        for method in ["global", "local"]:
            summary_file = os.path.join(scratch, "summary.json")
            run = subprocess.run([args.paloverde, "improve", mesh, "-o", os.path.join(scratch, "out.vtk"),
                                  "--summary", summary_file, "--threads", args.threads, "--method", method, "-q"],
                                 capture_output=True, text=True)
            if not os.path.exists(summary_file):
                print("| %s | | %s | failed (exit %d): %s |" % (os.path.basename(mesh), method, run.returncode,
                                                               run.stderr.strip().splitlines()[-1] if run.stderr else ""))
                continue
            s = json.load(open(summary_file))
            os.remove(summary_file)
            before, after = s["before"], s["after"]
            row = [os.path.relpath(mesh, os.path.join(args.data, "mesquite")), types(before) or before["elements"], method,
                   before["inverted"], after["inverted"],
                   "%.4f" % before["metrics"]["aspect_ratio"]["min"], "%.4f" % after["metrics"]["aspect_ratio"]["min"],
                   "%.4f" % before["metrics"]["aspect_ratio"]["mean"], "%.4f" % after["metrics"]["aspect_ratio"]["mean"],
                   s["iterations"], "%.3f" % s["seconds"]]
            print("| " + " | ".join(str(x) for x in row) + " |")
