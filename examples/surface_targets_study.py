#!/usr/bin/env python3
"""Targets on a surface: the graded Gmsh cylinder of quadrilaterals (examples/surfaces/graded_cylinder.geo),
made poorer along itself, improved by `paloverde improve` without targets (`--keep none`, what
`keep: auto` does on a surface), with the aspect kept and with size and aspect kept.

Poorer: every vertex off the two rims moved along the cylinder, around it and along its axis, by
random steps of up to `--shift` of its shortest edge (as examples/surface_study.py makes its
surfaces poorer), then put back on the cylinder.

Columns: the worst quality against the run's targets (the report's, after), the minimum corner
scaled Jacobian (the sine of the corner's angle, signed by the outward normal), the largest change
of a row's mean height from the unperturbed mesh's ("row"), the first row's height after over the
unperturbed one's, the largest distance from the input surface (the report's, over the bounding
box's diagonal), and the seconds of the call.

    cmake --build build --target paloverde
    /usr/bin/python3 examples/surface_targets_study.py      # writes docs/data/surface_targets.csv

Needs numpy, meshio and gmsh.
"""
import argparse
import csv
import os
import re
import subprocess
import tempfile
import time

import meshio
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def corner_jacobians(points, quads):
    """Each corner's sine of its angle, signed by the cylinder's outward normal there."""
    out = []
    for k in range(4):
        p, a, b = points[quads[:, k]], points[quads[:, (k + 1) % 4]], points[quads[:, (k + 3) % 4]]
        u, w = a - p, b - p
        c = np.cross(u, w)
        outward = p * np.array([1.0, 1.0, 0.0])
        sign = np.sign(np.einsum("ij,ij->i", c, outward))
        out.append(sign * np.linalg.norm(c, axis=1) / (np.linalg.norm(u, axis=1) * np.linalg.norm(w, axis=1)))
    return np.concatenate(out)


def row_heights(points, ring):
    rings = ring.max() + 1
    mean_z = np.array([points[ring == j, 2].mean() for j in range(rings)])
    return np.diff(mean_z)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--paloverde", default=os.path.join(HERE, "..", "build", "bin", "paloverde"))
    parser.add_argument("--shift", type=float, default=0.35)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--csv", default=os.path.join(HERE, "..", "docs", "data", "surface_targets.csv"))
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="surface_targets_") as work:
        study(args, work)


def study(args, work):
    msh = os.path.join(work, "cylinder.msh")
    subprocess.run(["gmsh", "-2", os.path.join(HERE, "surfaces", "graded_cylinder.geo"), "-o", msh],
                   check=True, capture_output=True)
    mesh = meshio.read(msh)
    points = mesh.points.copy()
    quads = np.concatenate([c.data for c in mesh.cells if c.type == "quad"])
    used = np.unique(quads)  # Gmsh keeps the geometry's centre point
    remap = -np.ones(len(points), dtype=int)
    remap[used] = np.arange(len(used))
    points, quads = points[used], remap[quads]

    levels = np.unique(np.round(points[:, 2], 9))
    ring = np.searchsorted(levels, np.round(points[:, 2], 9))
    unperturbed_rows = row_heights(points, ring)
    rows_of = np.diff(levels)

    rng = np.random.default_rng(args.seed)
    around = 2 * np.pi / np.count_nonzero(ring == 0)
    inner = (ring > 0) & (ring < ring.max())
    angle = np.arctan2(points[:, 1], points[:, 0])
    shortest = np.minimum(rows_of[np.clip(ring - 1, 0, len(rows_of) - 1)], rows_of[np.clip(ring, 0, len(rows_of) - 1)])
    shortest = np.minimum(shortest, around)
    poor = points.copy()
    angle = angle + inner * args.shift * shortest * rng.uniform(-1, 1, len(points))
    poor[:, 0], poor[:, 1] = np.cos(angle), np.sin(angle)
    poor[:, 2] += inner * args.shift * shortest * rng.uniform(-1, 1, len(points))
    poor_vtk = os.path.join(work, "poorer.vtk")
    meshio.write(poor_vtk, meshio.Mesh(poor, [("quad", quads)]), binary=False)

    def measure(label, run, result, worst, distance, seconds):
        rows = row_heights(result, ring)
        change = np.abs(rows - unperturbed_rows) / unperturbed_rows
        return {"case": "graded Gmsh cylinder (%d quads)" % len(quads), "run": label, "command": run,
                "worst_vs_targets": worst, "min_scaled_jacobian": round(corner_jacobians(result, quads).min(), 4),
                "row_change": round(change.max(), 4), "first_row_ratio": round(rows[0] / unperturbed_rows[0], 4),
                "distance": distance, "seconds": seconds}

    out = [measure("unperturbed", "", points, "", "", ""), measure("poorer", "", poor, "", "", "")]
    for label, flags in [("--keep none (ideal targets)", ["--keep", "none"]), ("--keep aspect", ["--keep", "aspect"]),
                         ("--keep size,aspect", ["--keep", "size,aspect"]),
                         ("--keep aspect, local smoother", ["--keep", "aspect", "--method", "local"]),
                         ("--keep size,aspect, local smoother", ["--keep", "size,aspect", "--method", "local"])]:
        result_vtk = os.path.join(work, "out.vtk")
        command = [args.paloverde, "improve", poor_vtk, "-o", result_vtk, "--threads", "1"] + flags
        start = time.perf_counter()
        done = subprocess.run(command, check=True, capture_output=True, text=True)
        seconds = time.perf_counter() - start
        worst = re.search(r"worst (\S+) ([-0-9.e]+) -> ([-0-9.e]+), inverted", done.stdout)  # the solver's line
        distance = re.search(r"largest distance from the input's boundary ([-0-9.e]+)", done.stdout)
        result = meshio.read(result_vtk).points
        out.append(measure(label, " ".join(["paloverde improve IN -o OUT"] + flags), result,
                           "%s %s -> %s" % worst.groups(), distance.group(1), round(seconds, 3)))
    with open(args.csv, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(out[0].keys()))
        writer.writeheader()
        writer.writerows(out)
    for row in out:
        print(" | ".join(str(v) for v in row.values()))


if __name__ == "__main__":
    main()
