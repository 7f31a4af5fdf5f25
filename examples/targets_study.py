#!/usr/bin/python3
"""The targets' study (docs/targets.md): meshes whose elements are meant to be stretched or graded,
improved with and without targets, and the measures their users read.

    /usr/bin/python3 examples/targets_study.py [--paloverde build/bin/paloverde] [--work DIR]
        [--csv docs/data/targets.csv]

Makes the cases (a graded block of hexahedra and the same cut into tetrahedra; a Gmsh wall with a
boundary layer of wedges under tetrahedra; a Gmsh tetrahedral mesh graded by a size field, whose
size function the study also gives as a point field for --size-field), runs
`paloverde improve` on each with the command line the table names, and writes one CSV row per run:
the largest change of a layer's mean height and of one vertical edge's (layered cases), the first
layer's thickness after over before, the median relative change of the elements' volumes, the
minimum corner scaled Jacobian before and after, the inverted elements after, and the seconds.

The block: 8 x 8 columns over 16 layers on [0, 1]^2, graded from the wall z = 0 (first layer
1.45e-3 thick, each next 1.35 times thicker, 0.5 in all); its interior vertices are moved
sideways (x, y only) so that the angles need fixing and the heights do not. The Gmsh cases come
from examples/targets/*.geo; the boundary layer's interior vertices are moved sideways the same
way, the graded mesh's every interior vertex by `paloverde perturb`.

Needs numpy and meshio (Debian's python3-numpy, python3-meshio) and gmsh.
"""
import argparse
import csv
import json
import os
import subprocess
import sys
import time

import meshio
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))

HEX_CORNERS = [(0, 1, 3, 4), (1, 2, 0, 5), (2, 3, 1, 6), (3, 0, 2, 7),
               (4, 7, 5, 0), (5, 4, 6, 1), (6, 5, 7, 2), (7, 6, 4, 3)]
WEDGE_CORNERS = [(0, 2, 1, 3), (1, 0, 2, 4), (2, 1, 0, 5), (3, 4, 5, 0), (4, 5, 3, 1), (5, 3, 4, 2)]
TET_CORNERS = [(0, 1, 2, 3), (1, 2, 0, 3), (2, 0, 1, 3), (3, 0, 2, 1)]
# Each cell type's corners and the scaled Jacobian of its ideal corner (1 for right angles).
CORNERS = {"hexahedron": (HEX_CORNERS, 1.0), "wedge": (WEDGE_CORNERS, np.sqrt(3) / 2),
           "tetra": (TET_CORNERS, 1 / np.sqrt(2))}


def make_block(path, tets, columns=8, layers=16, first=1.45e-3, growth=1.35, shift=0.5, seed=1):
    z = np.concatenate([[0.0], np.cumsum(first * growth ** np.arange(layers))])
    i, j, k = np.meshgrid(np.arange(columns + 1), np.arange(columns + 1), np.arange(layers + 1), indexing="ij")
    i, j, k = i.T.ravel(), j.T.ravel(), k.T.ravel()  # vertex id = (k (n + 1) + j) (n + 1) + i
    points = np.stack([i / columns, j / columns, z[k]], axis=1)
    # Each interior vertex moves sideways by up to `shift` times the thinner of its two layers: the
    # columns wobble, every layer's angles need fixing, no height does.
    rng = np.random.default_rng(seed)
    interior = (i > 0) & (i < columns) & (j > 0) & (j < columns) & (k > 0) & (k < layers)
    local = np.minimum(z[np.minimum(k + 1, layers)] - z[k], z[k] - z[np.maximum(k - 1, 0)])
    points[interior, :2] += rng.uniform(-shift, shift, (interior.sum(), 2)) * local[interior, None]
    vid = lambda a, b, c: (c * (columns + 1) + b) * (columns + 1) + a
    hexes = []
    for c in range(layers):
        for b in range(columns):
            for a in range(columns):
                hexes.append([vid(a, b, c), vid(a + 1, b, c), vid(a + 1, b + 1, c), vid(a, b + 1, c),
                              vid(a, b, c + 1), vid(a + 1, b, c + 1), vid(a + 1, b + 1, c + 1), vid(a, b + 1, c + 1)])
    hexes = np.array(hexes)
    if tets:
        # Six tetrahedra around the diagonal 0-6, every hexahedron cut alike: neighbours share
        # their faces' diagonals.
        cut = np.array([(0, 1, 2, 6), (0, 2, 3, 6), (0, 3, 7, 6), (0, 7, 4, 6), (0, 4, 5, 6), (0, 5, 1, 6)])
        cells = [("tetra", hexes[:, cut].reshape(-1, 4))]
    else:
        cells = [("hexahedron", hexes)]
    # The point field `metric`: the spacing the block was made with, as a metric (xx, yy, zz, xy,
    # yz, xz): edges of 1 / columns across, of the layers' height (the geometric mean of a vertex's
    # two layers) up.
    heights = np.diff(z)
    up = np.sqrt(heights[np.maximum(k - 1, 0)] * heights[np.minimum(k, layers - 1)])
    metric = np.zeros((len(points), 6))
    metric[:, 0] = metric[:, 1] = columns ** 2
    metric[:, 2] = 1.0 / up ** 2
    meshio.write(path, meshio.Mesh(points, cells, point_data={"metric": metric}), file_format="vtk", binary=False)


def volume_cells(mesh):
    """The volume cells in VTK's vertex order (meshio holds a wedge's triangles the other way)."""
    order = {"wedge": [0, 2, 1, 3, 5, 4]}
    return [(c.type, c.data[:, order[c.type]] if c.type in order else c.data) for c in mesh.cells if c.type in CORNERS]


def shift_sideways(source, path, low, high, amount=0.5, seed=2):
    """Moves every vertex strictly inside the box [low, high] in x and y by up to `amount` of its
    shortest edge (in the boundary layer, the layer's height); z stays."""
    mesh = meshio.read(source)
    p = mesh.points.copy()
    cells = volume_cells(mesh)
    shortest = np.full(len(p), np.inf)
    for kind, c in cells:
        corners, _ = CORNERS[kind]
        for o, a, b, d in corners:
            for n in (a, b, d):
                np.minimum.at(shortest, c[:, o], np.linalg.norm(p[c[:, n]] - p[c[:, o]], axis=1))
    inside = np.all((p > np.array(low) + 1e-12) & (p < np.array(high) - 1e-12), axis=1) & np.isfinite(shortest)
    rng = np.random.default_rng(seed)
    p[inside, :2] += rng.uniform(-amount, amount, (inside.sum(), 2)) * shortest[inside, None]
    # meshio writes a wedge in its own order: hand it the cells as it read them.
    meshio.write(path, meshio.Mesh(p, [(c.type, c.data) for c in mesh.cells if c.type in CORNERS]),
                 file_format="vtk", binary=False)


def corner_jacobians(points, mesh):
    """Per cell, its minimum corner scaled Jacobian over its ideal corner's."""
    out = []
    for kind, cells in volume_cells(mesh):
        corners, ideal = CORNERS[kind]
        worst = np.full(len(cells), np.inf)
        for c, a, b, d in corners:
            e = [points[cells[:, n]] - points[cells[:, c]] for n in (a, b, d)]
            det = np.einsum("ij,ij->i", e[0], np.cross(e[1], e[2]))
            lengths = np.prod([np.linalg.norm(x, axis=1) for x in e], axis=0)
            worst = np.minimum(worst, det / lengths / ideal)
        out.append(worst)
    return np.concatenate(out)


def volumes(points, mesh):
    """Per cell, the sum of its corners' determinants (a volume measure the same cell keeps)."""
    out = []
    for kind, cells in volume_cells(mesh):
        corners, _ = CORNERS[kind]
        total = np.zeros(len(cells))
        for c, a, b, d in corners:
            e = [points[cells[:, n]] - points[cells[:, c]] for n in (a, b, d)]
            total += np.einsum("ij,ij->i", e[0], np.cross(e[1], e[2]))
        out.append(total)
    return np.concatenate(out)


def layer_heights(points, columns=8, layers=16):
    """Per layer of the block and per column, the height of its vertical edge."""
    n = columns + 1
    z = points[:, 2].reshape(layers + 1, n * n)
    return z[1:] - z[:-1]


def wall_layers(points, mesh, top):
    """The boundary layer's vertical edges (wedges' edges 0-3, 1-4, 2-5 below `top`) with their
    heights, and per edge its layer (by its lower end's height rank)."""
    edges = set()
    for kind, cells in volume_cells(mesh):
        if kind != "wedge":
            continue
        for a, b in ((0, 3), (1, 4), (2, 5)):
            for lo, hi in zip(cells[:, a], cells[:, b]):
                edges.add((lo, hi) if points[lo, 2] < points[hi, 2] else (hi, lo))
    return np.array(sorted(edges))


def add_size_field(unperturbed, path):
    """The point field `size`: the edge length size_graded.geo's Threshold field asks for at each
    vertex's unperturbed position (0.02 within 0.05 of the edge x = y = 0, 0.15 beyond 0.6, linear
    between): the sizes the mesh was made with."""
    p = meshio.read(unperturbed).points
    d = np.hypot(p[:, 0], p[:, 1])
    size = 0.02 + (0.15 - 0.02) * np.clip((d - 0.05) / (0.6 - 0.05), 0.0, 1.0)
    mesh = meshio.read(path)
    mesh.point_data["size"] = size
    meshio.write(path, mesh, binary=False)


def run(paloverde, mesh, out, extra):
    command = [paloverde, "improve", mesh, "-o", out, "-q", "--threads", "1", "--summary", out + ".json"] + extra
    start = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True)
    seconds = time.perf_counter() - start
    if done.returncode not in (0, 3):
        sys.exit(f"{' '.join(command)} failed ({done.returncode}):\n{done.stderr}")
    summary = json.load(open(out + ".json"))
    return seconds, summary


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--paloverde", default=os.path.join(HERE, "..", "build", "bin", "paloverde"))
    parser.add_argument("--work", default="build/targets_study")
    parser.add_argument("--csv", default=os.path.join(HERE, "..", "docs", "data", "targets.csv"))
    args = parser.parse_args()
    os.makedirs(args.work, exist_ok=True)
    w = lambda name: os.path.join(args.work, name)

    make_block(w("block_hex.vtk"), tets=False)
    make_block(w("block_tet.vtk"), tets=True)
    for geo in ("boundary_layer", "size_graded"):
        subprocess.run(["gmsh", os.path.join(HERE, "targets", geo + ".geo"), "-3", "-o", w(geo + ".msh")],
                       check=True, capture_output=True)
        # Through Paloverde's reader: VTK's vertex order for the wedges (Gmsh mirrors them).
        subprocess.run([args.paloverde, "convert", w(geo + ".msh"), w(geo + "_input.vtk"), "--ascii"],
                       check=True, capture_output=True)
    shift_sideways(w("boundary_layer_input.vtk"), w("boundary_layer.vtk"), (0, 0, 0), (1, 1, 0.07), amount=0.25)
    subprocess.run([args.paloverde, "perturb", w("size_graded_input.vtk"), "-o", w("size_graded.vtk"), "--amount",
                    "0.15", "--seed", "3"], check=True, capture_output=True)
    add_size_field(w("size_graded_input.vtk"), w("size_graded.vtk"))

    cases = [
        ("block_hex", "layers", [[], ["--keep", "none"], ["--keep", "size,aspect"], ["--keep", "size,aspect,orientation"],
                                 ["--metric-field", "metric"]]),
        ("block_tet", "layers", [[], ["--keep", "size,aspect"], ["--keep", "size,aspect,orientation"],
                                 ["--keep", "size,aspect", "--set", "queue[0].improve.polish=off"],
                                 ["--metric-field", "metric"]]),
        ("boundary_layer", "wall", [[], ["--keep", "size,aspect"], ["--keep", "size,aspect,orientation"]]),
        ("size_graded", "volumes", [[], ["--keep", "size"], ["--size-field", "size"]]),
    ]
    rows = []
    for name, kind, runs in cases:
        source = w(name + ".vtk")
        before = meshio.read(source)
        for extra in runs:
            out = w(f"{name}_{'_'.join(x.strip('-').replace(',', '-') for x in extra) or 'default'}.vtu")
            seconds, summary = run(args.paloverde, source, out, extra)
            after = meshio.read(out)
            p0, p1 = before.points, after.points
            row = {"mesh": name, "command": "paloverde improve MESH -o OUT " + " ".join(extra),
                   "inverted_after": summary.get("inverted_after"),
                   "scaled_jacobian_before": corner_jacobians(p0, before).min(),
                   "scaled_jacobian_after": corner_jacobians(p1, before).min(),
                   "volume_change_median": np.median(np.abs(volumes(p1, before) / volumes(p0, before) - 1)),
                   "seconds": round(seconds, 3)}
            if kind == "layers":
                h0, h1 = layer_heights(p0), layer_heights(p1)
                row["layer_height_change_max"] = np.abs(h1.mean(axis=1) / h0.mean(axis=1) - 1).max()
                row["edge_height_change_max"] = np.abs(h1 / h0 - 1).max()
                row["first_layer_ratio"] = h1[0].mean() / h0[0].mean()
            elif kind == "wall":
                edges = wall_layers(p0, before, 0.05)
                h0 = p0[edges[:, 1], 2] - p0[edges[:, 0], 2]
                h1 = p1[edges[:, 1], 2] - p1[edges[:, 0], 2]
                # The layers by their lower ends' heights (the extrusion keeps them level).
                levels, layer = np.unique(np.round(p0[edges[:, 0], 2], 9), return_inverse=True)
                means0 = np.bincount(layer, h0) / np.bincount(layer)
                means1 = np.bincount(layer, h1) / np.bincount(layer)
                row["layer_height_change_max"] = np.abs(means1 / means0 - 1).max()
                row["edge_height_change_max"] = np.abs(h1 / h0 - 1).max()
                row["first_layer_ratio"] = means1[0] / means0[0]
            rows.append(row)
            print(", ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}" for k, v in row.items()), flush=True)
    fields = ["mesh", "command", "inverted_after", "scaled_jacobian_before", "scaled_jacobian_after",
              "layer_height_change_max", "edge_height_change_max", "first_layer_ratio", "volume_change_median",
              "seconds"]
    with open(args.csv, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=fields)
        writer.writeheader()
        for r in rows:
            writer.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})
    return 0


if __name__ == "__main__":
    sys.exit(main())
