#!/usr/bin/python3
"""The global solver against the local smoother, from Python: each method on its own copy of each
mesh, one thread, the worst element, the mean and the time.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/global_vs_local.py MESH... [--csv out.csv]

Without meshes it uses four of ../shared/data's Mesquite meshes.
"""
import argparse
import csv
import os
import sys

import paloverde

HERE = os.path.dirname(os.path.abspath(__file__))
SHARED = os.path.join(HERE, "..", "..", "..", "shared", "data", "mesquite", "tets")
DEFAULT = [os.path.join(SHARED, m) for m in ("tire.vtk", "cube-clip-5.vtk", "flat-tet-sphere.vtk", "cub_wedge_like.vtk")]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("meshes", nargs="*", default=DEFAULT)
    parser.add_argument("--csv")
    args = parser.parse_args()
    rows = []
    for path in args.meshes:
        mesh = paloverde.read(path)
        for method in ("global", "local"):
            copy = mesh.copy()
            s = paloverde.improve(copy, method=method, threads=1)
            rows.append({"mesh": os.path.basename(path), "method": method, "status": s["status"],
                         "worst_before": s["worst_before"], "worst_after": s["worst_after"],
                         "mean_after": s["mean_after"], "iterations": s["iterations"], "seconds": s["seconds"]})
            r = rows[-1]
            print(f"{r['mesh']:24} {method:6} worst {r['worst_before']:.4f} -> {r['worst_after']:.4f}  "
                  f"mean {r['mean_after']:.4f}  {r['iterations']:4} iterations  {r['seconds']:.2f} s", flush=True)
    if args.csv:
        with open(args.csv, "w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=list(rows[0]))
            writer.writeheader()
            writer.writerows(rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
