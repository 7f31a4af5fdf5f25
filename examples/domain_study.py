#!/usr/bin/python3
"""The domain study: surface meshes of spheres and a cylinder, made poorer along the exact shape,
smoothed by `paloverde improve` on the input's own triangles and on the analytic shape
(`--domain`), measured alike.

    /usr/bin/python3 examples/domain_study.py [--paloverde build/bin/paloverde] [--work DIR]
        [--csv docs/data/surface_domains.csv]

The cases: Gmsh meshes examples/surfaces/sphere.geo (coarse triangles on the unit sphere),
sphere_quads.geo (quadrilaterals on the unit sphere) and tube.geo (triangles on a cylinder of
radius 1 about z, its rims open and held), and the shared mesquite/hexes/sph-10-zsquare.vtk
(quadrilaterals on a sphere of radius 10, its outline sliding: `--boundary slide`). Each is made
poorer as in examples/surface_study.py: every vertex not on an open edge takes a random step in
its tangent plane, up to --shift times its shortest edge, and is put back onto the exact shape.

Rows per case: the unperturbed mesh, the poorer one (the input of the rest), and the global and
local solvers each on the mesh (no domain) and on the shape. Columns: the worst and mean mean
ratio (triangles; a quadrilateral's corner triangles), the worst corner scaled Jacobian
(quadrilaterals), the elements turned over against the poorer input, the largest distance of a
vertex to the exact shape over its radius, and the solver's seconds.

Needs numpy and meshio, gmsh and the paloverde program.
"""
import argparse
import csv
import json
import os
import sys

import meshio
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from surface_study import SHARED, measure_quads, mesh_file, normals, poorer, quad_normals, run  # noqa: E402


def sphere(radius):
    return {"snap": lambda q: radius * q / np.linalg.norm(q, axis=1)[:, None],
            "off": lambda q: np.abs(np.linalg.norm(q, axis=1) - radius) / radius,
            "domain": f"{{shape: sphere, point: [0, 0, 0], radius: {radius}}}"}


def cylinder(radius):
    def snap(q):
        rho = np.hypot(q[:, 0], q[:, 1])
        return np.stack([radius * q[:, 0] / rho, radius * q[:, 1] / rho, q[:, 2]], axis=1)
    return {"snap": snap, "off": lambda q: np.abs(np.hypot(q[:, 0], q[:, 1]) - radius) / radius,
            "domain": f"{{shape: cylinder, point: [0, 0, 0], direction: [0, 0, 1], radius: {radius}}}"}


# (name, source, shape, extra flags for every run)
CASES = [
    ("sphere", os.path.join(HERE, "surfaces", "sphere.geo"), sphere(1.0), []),
    ("sphere_quads", os.path.join(HERE, "surfaces", "sphere_quads.geo"), sphere(1.0), []),
    ("tube", os.path.join(HERE, "surfaces", "tube.geo"), cylinder(1.0), []),
    ("sph-10-zsquare", os.path.join(SHARED, "mesquite", "hexes", "sph-10-zsquare.vtk"), sphere(10.0),
     ["--boundary", "slide"]),
]
FIELDS = ["case", "method", "domain", "vertices", "elements", "worst_mean_ratio", "mean_mean_ratio",
          "worst_scaled_jacobian", "turned_over", "max_off_shape_rel", "seconds", "error"]


def read_surface(name, source, work, paloverde):
    """Points (those of the elements), and the triangles or quadrilaterals."""
    mesh = meshio.read(mesh_file(name, source, work, paloverde))
    kind = "quad" if any(b.type == "quad" for b in mesh.cells) else "triangle"
    cells = np.vstack([b.data for b in mesh.cells if b.type == kind])
    used = np.unique(cells)
    renumber = np.full(len(mesh.points), -1)
    renumber[used] = np.arange(len(used))
    return mesh.points[used, :3].astype(float), renumber[cells], kind


def measure(points, cells, kind, reference_normals):
    if kind == "quad":
        return measure_quads(points, cells, reference_normals)
    p = points[cells]
    squared = sum(((p[:, (k + 1) % 3] - p[:, k]) ** 2).sum(1) for k in range(3))
    n = normals(points, cells)
    turned = (n * reference_normals).sum(1) <= 0
    ratio = np.where(turned, -1, 1) * 2 * np.sqrt(3) * np.linalg.norm(n, axis=1) / squared
    return {"worst_mean_ratio": f"{ratio.min():.4f}", "mean_mean_ratio": f"{ratio.mean():.4f}",
            "turned_over": int(turned.sum())}


def make_poorer(points, cells, kind, snap, shift, seed):
    """The mesh made poorer along the shape, its open edges held; a quadrilateral corner that the
    moves turn over has its vertices put back."""
    sides = cells.shape[1]
    edges = np.sort(np.stack([cells, np.roll(cells, -1, axis=1)], axis=2).reshape(-1, 2), axis=1)
    unique, count = np.unique(edges, axis=0, return_counts=True)
    frozen = np.zeros(len(points), bool)
    frozen[unique[count == 1].ravel()] = True
    split = cells if sides == 3 else np.vstack([cells[:, [0, 1, 2]], cells[:, [0, 2, 3]]])
    poor = poorer(points, split, frozen, snap, shift, seed)
    if kind == "quad":
        n0 = quad_normals(points, cells)
        for _ in range(12):
            p = poor[cells]
            turned = np.zeros(len(cells), bool)
            for k in range(4):
                turned |= (np.cross(p[:, (k + 1) % 4] - p[:, k], p[:, (k + 3) % 4] - p[:, k]) * n0).sum(1) <= 0
            if not turned.any():
                break
            back = np.unique(cells[turned])
            poor[back] = points[back]
    return poor, frozen


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--paloverde", default="build/bin/paloverde")
    parser.add_argument("--work", default=None, help="where the meshes go (default: a temporary directory)")
    parser.add_argument("--csv", default=os.path.join(HERE, "..", "docs", "data", "surface_domains.csv"))
    parser.add_argument("--shift", type=float, default=0.35, help="largest step, times the vertex's shortest edge")
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    import tempfile
    work = args.work or tempfile.mkdtemp(prefix="paloverde_domains_")
    rows = []
    for name, source, shape, extra in CASES:
        points, cells, kind = read_surface(name, source, work, args.paloverde)
        points = shape["snap"](points)  # the file's rounding aside, on the shape already
        poor, frozen = make_poorer(points, cells, kind, shape["snap"], args.shift, args.seed)
        normal_of = (lambda q: quad_normals(q, cells)) if kind == "quad" else (lambda q: normals(q, cells))
        poor_vtk = os.path.join(work, name + "_poor.vtk")
        meshio.write(poor_vtk, meshio.Mesh(poor, [(kind, cells)]), file_format="vtk", binary=True)
        print(f"{name}: {len(points)} vertices, {len(cells)} {kind}s, {int(frozen.sum())} on open edges", flush=True)
        runs = [("unperturbed", None, ""), ("poorer", None, "")]
        runs += [(m, m, d) for m in ("global", "local") for d in ("mesh", "shape")]
        for label, method, domain in runs:
            row = {"case": name, "method": label, "domain": domain, "vertices": len(points), "elements": len(cells)}
            try:
                if method is None:
                    result, seconds = (points if label == "unperturbed" else poor), None
                else:
                    out = os.path.join(work, f"{name}_{method}_{domain}.vtk")
                    summary = os.path.join(work, f"{name}_{method}_{domain}.json")
                    flags = ["--domain", shape["domain"]] if domain == "shape" else []
                    done = run([args.paloverde, "improve", poor_vtk, "-o", out, "--method", method, "--threads", "1",
                                "--summary", summary, "-q"] + extra + flags)
                    if done.returncode != 0:
                        raise RuntimeError(f"exit {done.returncode}: {(done.stderr or done.stdout).strip()}")
                    result = meshio.read(out).points[:, :3]
                    with open(summary) as f:
                        seconds = json.load(f)["seconds"]
                row.update(measure(result, cells, kind, normal_of(points if seconds is None else poor)))
                row["max_off_shape_rel"] = f"{shape['off'](result).max():.1e}"
                row["seconds"] = "" if seconds is None else f"{seconds:.3f}"
            except RuntimeError as error:
                row["error"] = " ".join(str(error).split())[:300] or "failed"
            print("  " + ", ".join(f"{k} {row[k]}" for k in FIELDS[1:] if row.get(k) not in (None, "")), flush=True)
            rows.append(row)
    os.makedirs(os.path.dirname(os.path.abspath(args.csv)), exist_ok=True)
    with open(args.csv, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=FIELDS)
        writer.writeheader()
        writer.writerows(rows)
    print(f"wrote {args.csv}")


if __name__ == "__main__":
    main()
