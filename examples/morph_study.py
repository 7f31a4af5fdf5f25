#!/usr/bin/env python3
"""Morphing cases of docs/morphing.md: meshes made with Gmsh from examples/morph/*.geo, a
displacement field on their boundary, and `paloverde morph` on each; one CSV row per case.

    /usr/bin/python3 examples/morph_study.py [--paloverde build/bin/paloverde] [--csv docs/data/morph.csv]
                                             [--threads 1] [--work DIR] [--args "..."] [--witness] [CASE ...]

--args adds flags to every `paloverde morph` (docs/morphing.md's shape-only rows:
--args "--set targets.from_reference=[aspect,skew] --iterations 800"
--csv docs/data/morph_shape_only.csv hole-30 hole-60 hole-90).

Cases: hole-30, hole-60, hole-90 (a block-shaped hole in a box of tetrahedra, turned about z),
torus-30, torus-60, torus-90 (a torus-shaped hole in a box of tetrahedra, turned about its axis),
beam-45, beam-90 (a beam of tetrahedra bent in an arc, one end held), hexbeam-90 (the same beam of
hexahedra), ellipse-30, ellipse-60 (a planar elliptic hole of triangles, pitched). Quality is
relative to the undeformed mesh: the mean ratio of A W^-1, W the element in the input (1: the same
shape; orientation and size ignored).

--witness: for the torus cases, also every vertex turned about z by the angle times a weight of
(rho, z) alone, falling linearly from 1 on the torus to 0 at the box (a map of determinant 1, so
the continuum stays valid), written to WORK/CASE_witness.vtu; its inverted elements are the
witness_inverted column (0: a valid mesh exists for the case).
"""
import argparse
import csv
import json
import math
import os
import re
import subprocess
import tempfile

import meshio
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def gmsh(geo, dim, out):
    subprocess.run(["gmsh", f"-{dim}", os.path.join(HERE, "morph", geo), "-o", out, "-format", "msh22"],
                   check=True, capture_output=True)
    return meshio.read(out)


def turned(p, mask, degrees):
    a = math.radians(degrees)
    d = np.zeros_like(p)
    x, y = p[mask, 0], p[mask, 1]
    d[mask, 0] = math.cos(a) * x - math.sin(a) * y - x
    d[mask, 1] = math.sin(a) * x + math.cos(a) * y - y
    return d


def bent(p, degrees, length=4.0):
    """The beam's axis (y = z = 0, x in [0, length]) bent into a circular arc turning by `degrees`
    in the x-z plane, each cross-section kept normal to the axis: a smooth map, valid everywhere."""
    phi = math.radians(degrees)
    r = length / phi
    alpha = phi * p[:, 0] / length
    q = p.copy()
    q[:, 0] = (r - p[:, 2]) * np.sin(alpha)
    q[:, 2] = r - (r - p[:, 2]) * np.cos(alpha)
    return q - p


# examples/morph/torus.geo: the torus's major and minor radii, the box's half width and half height.
TORUS_RADII = (1.8, 0.6)
BOX_HALF = (3.0, 1.5)


def to_torus(p):
    """Each point's distance from the torus surface (negative inside it)."""
    major, minor = TORUS_RADII
    return np.hypot(np.hypot(p[:, 0], p[:, 1]) - major, p[:, 2]) - minor


def torus_witness(p, degrees):
    """Every point turned about z by `degrees` times a weight of its (rho, z): 1 on the torus,
    0 on and beyond the box's nearest wall (rho = its half width, or |z| = its half height)."""
    rho = np.hypot(p[:, 0], p[:, 1])
    torus = np.maximum(to_torus(p), 0.0)
    box = np.maximum(np.minimum(BOX_HALF[0] - rho, BOX_HALF[1] - np.abs(p[:, 2])), 0.0)
    weight = np.where(torus + box > 0.0, box / np.maximum(torus + box, 1e-300), 1.0)
    a = np.radians(degrees) * weight
    q = p.copy()
    q[:, 0] = np.cos(a) * p[:, 0] - np.sin(a) * p[:, 1]
    q[:, 1] = np.sin(a) * p[:, 0] + np.cos(a) * p[:, 1]
    return q


def case(name, work):
    shape, degrees = name.split("-")
    degrees = float(degrees)
    if shape == "hole":
        m = gmsh("hole.geo", 3, os.path.join(work, "hole.msh"))
        p = m.points
        wall = (np.abs(p[:, 0]) <= 0.5 + 1e-9) & (np.abs(p[:, 1]) <= 0.08 + 1e-9) & (np.abs(p[:, 2]) <= 0.5 + 1e-9)
        cells, d = [c for c in m.cells if c.type == "tetra"], turned(p, wall, degrees)
    elif shape == "torus":
        m = gmsh("torus.geo", 3, os.path.join(work, "torus.msh"))
        p = m.points
        on_torus = np.abs(to_torus(p)) <= 1e-6
        cells, d = [c for c in m.cells if c.type == "tetra"], turned(p, on_torus, degrees)
    elif shape == "beam":
        m = gmsh("beam.geo", 3, os.path.join(work, "beam.msh"))
        cells, d = [c for c in m.cells if c.type == "tetra"], bent(m.points, degrees)
    elif shape == "hexbeam":
        m = gmsh("hexbeam.geo", 3, os.path.join(work, "hexbeam.msh"))
        cells, d = [c for c in m.cells if c.type == "hexahedron"], bent(m.points, degrees)
    elif shape == "ellipse":
        m = gmsh("ellipse.geo", 2, os.path.join(work, "ellipse.msh"))
        p = m.points
        hole = (p[:, 0] / 0.6) ** 2 + (p[:, 1] / 0.08) ** 2 <= 1.0 + 1e-6
        cells, d = [c for c in m.cells if c.type == "triangle"], turned(p, hole, degrees)
    else:
        raise SystemExit(f"unknown case {name}")
    path = os.path.join(work, name + ".vtu")
    # Only the boundary's displacement matters: paloverde moves the fixed (boundary) vertices.
    meshio.write(path, meshio.Mesh(m.points, cells, point_data={"displacement": d}))
    return path, sum(len(c.data) for c in cells)


def witness_inverted(paloverde, mesh, name, work):
    """The inverted elements of the case's smooth turn (torus cases; "" for the others)."""
    shape, degrees = name.split("-")
    if shape != "torus":
        return ""
    m = meshio.read(mesh)
    path = os.path.join(work, name + "_witness.vtu")
    meshio.write(path, meshio.Mesh(torus_witness(m.points, float(degrees)), [(c.type, c.data) for c in m.cells]))
    report = subprocess.run([paloverde, "quality", path], check=True, capture_output=True, text=True).stdout
    return int(re.search(r"^inverted (\d+)", report, re.M).group(1))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("cases", nargs="*",
                        default=["hole-30", "hole-60", "hole-90", "torus-30", "torus-60", "torus-90", "beam-45", "beam-90", "hexbeam-90", "ellipse-30", "ellipse-60"])
    parser.add_argument("--paloverde", default="build/bin/paloverde")
    parser.add_argument("--csv", default=os.path.join(HERE, "..", "docs", "data", "morph.csv"))
    parser.add_argument("--threads", default="1")
    parser.add_argument("--work", default=None)
    parser.add_argument("--args", default="", help="more flags for paloverde morph, split on spaces")
    parser.add_argument("--witness", action="store_true", help="the torus cases' smooth turn and its inverted count")
    args = parser.parse_args()
    work = args.work or tempfile.mkdtemp(prefix="morph_")
    os.makedirs(work, exist_ok=True)
    rows = []
    for name in args.cases:
        mesh, elements = case(name, work)
        summary = os.path.join(work, name + ".json")
        run = subprocess.run([args.paloverde, "morph", "-q", mesh, "-o", os.path.join(work, name + "_out.vtu"),
                              "--displacement", "displacement", "--threads", args.threads, "--summary", summary] + args.args.split(),
                             capture_output=True, text=True)
        s = json.load(open(summary))
        m = s["methods"][0]
        shape = m["after"]["metrics"]["mean_ratio"]
        message = [st["summary"]["message"] for st in m["steps"] if st["kind"] == "improve"][-1]
        steps = re.search(r"followed in (\d+) step", message)
        # A motion that cannot be followed says how far it was: the furthest valid step.
        furthest = re.search(r"furthest valid mesh is at ([0-9.]+)%", message)
        rows.append({"case": name, "elements": elements, "exit_code": run.returncode,
                     "inverted_before": m["inverted_before"], "inverted_after": m["inverted_after"],
                     "steps": int(steps.group(1)) if steps else "" if furthest else 1,
                     "followed_percent": float(furthest.group(1)) if furthest else 100.0,
                     "worst_shape": round(shape["min"], 4), "mean_shape": round(shape["mean"], 4),
                     "iterations": m["iterations"], "seconds": round(m["seconds"], 2)})
        if args.witness:
            rows[-1]["witness_inverted"] = witness_inverted(args.paloverde, mesh, name, work)
        print(",".join(str(v) for v in rows[-1].values()), flush=True)
    with open(args.csv, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)


if __name__ == "__main__":
    main()
