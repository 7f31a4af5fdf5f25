#!/usr/bin/python3
"""The surface study: surface meshes in 3D made poorer by sliding their vertices along the surface,
then smoothed by `paloverde improve` and (triangles) by CGAL's surface smoothers, measured alike.

    /usr/bin/python3 examples/surface_study.py [--paloverde build/bin/paloverde]
        [--tool build/bin/paloverde_surface_tool] [--work DIR] [--csv docs/data/surfaces.csv]

The cases: the Gmsh meshes examples/surfaces/{torus,cad_part,open_surface}.geo (a closed smooth
surface, a part with sharp edges and corners, a saddle with an open boundary); and of
quadrilaterals, the shared sphere patch mesquite/hexes/sph-10-zsquare.vtk and the Gmsh sphere
examples/surfaces/sphere_quads.geo (quad_rows(): measured by corners, Paloverde only).

Each mesh is made poorer: every vertex that is on no feature curve (an edge whose two triangles'
normals are more than --feature-angle apart) and on no open boundary takes a random step in its
tangent plane, up to --shift times its shortest edge, and is snapped back onto the surface: onto
the exact torus or sphere, else onto the unperturbed triangles (the tool's `project`). A step that
turns a triangle over (its normal against the unperturbed one) is halved until it does not.

Rows per case: the unperturbed mesh, the poorer one (the input of the rest), `paloverde improve`
with the global solver and with the local smoother, CGAL's angle_and_area_smoothing and its
tangential_relaxation (all with the same feature angle; CGAL's with the feature curves and
boundary held, and the vertices projected onto the input: paloverde_surface_tool). Columns:
the worst and the mean triangle mean ratio (4 sqrt(3) area / sum of squared edges, negative for a
triangle turned over against the poorer input), the worst smallest angle (degrees), the triangles
turned over, the largest distance of a vertex to its input surface (the poorer mesh's triangles for
the smoothed rows, the unperturbed triangles for the two inputs), the largest move of a
feature or boundary vertex and its largest distance to the unperturbed feature and boundary edges
(the three over the unperturbed bounding box's diagonal), and the seconds of the smoothing call.
A method that fails gets its row with the error and the measures left empty.

With --tangle K (triangle cases only, its own CSV: docs/data/surfaces_tangled.csv), K free vertices
of the poorer mesh, far apart, are then each slid past one of their free neighbours (to 1.5 times the
edge towards it, snapped onto the surface), which turns the triangles between them over; every row's
turned-over count is then against the unperturbed triangles, and a Paloverde run that exits with 1
(a tangle it could not undo) keeps its row, with a note.

Needs numpy and meshio (Debian's python3-numpy, python3-meshio), gmsh and the two programs.
"""
import argparse
import csv
import json
import os
import re
import subprocess
import sys
import tempfile
import time

import meshio
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
SHARED = os.path.join(HERE, "..", "..", "shared", "data")

TORUS_R, TORUS_r = 1.0, 0.35  # examples/surfaces/torus.geo


def torus_snap(q):
    """Closest points on the torus around z of torus.geo."""
    rho = np.maximum(np.hypot(q[:, 0], q[:, 1]), 1e-300)
    center = np.stack([TORUS_R * q[:, 0] / rho, TORUS_R * q[:, 1] / rho, np.zeros(len(q))], axis=1)
    away = q - center
    return center + TORUS_r * away / np.linalg.norm(away, axis=1)[:, None]


def sphere_snap(points):
    """Closest points on the sphere through `points` (a least-squares fit: |p|^2 = 2 c.p + k)."""
    a = np.hstack([2 * points, np.ones((len(points), 1))])
    solution = np.linalg.lstsq(a, (points ** 2).sum(1), rcond=None)[0]
    center = solution[:3]
    radius = np.sqrt(solution[3] + center @ center)
    return lambda q: center + radius * (q - center) / np.linalg.norm(q - center, axis=1)[:, None]


# (name, source, how to snap onto the surface: "torus", "sphere" or "triangles")
CASES = [
    ("torus", os.path.join(HERE, "surfaces", "torus.geo"), "torus"),
    ("cad_part", os.path.join(HERE, "surfaces", "cad_part.geo"), "triangles"),
    ("open_surface", os.path.join(HERE, "surfaces", "open_surface.geo"), "triangles"),
]
# Quadrilateral surfaces, both on spheres: Mesquite's patch (its outline open) and a Gmsh sphere.
QUAD_CASES = [
    ("sphere_patch", os.path.join(SHARED, "mesquite", "hexes", "sph-10-zsquare.vtk")),
    ("sphere_quads", os.path.join(HERE, "surfaces", "sphere_quads.geo")),
]

FIELDS = ["case", "method", "vertices", "triangles", "worst_mean_ratio", "mean_mean_ratio", "worst_scaled_jacobian",
          "worst_min_angle_deg",
          "turned_over", "max_distance_rel", "max_feature_move_rel", "max_feature_off_curve_rel", "seconds", "note",
          "error"]


def run(command, **kwargs):
    return subprocess.run([str(c) for c in command], capture_output=True, text=True, **kwargs)


def write_off(path, points, triangles):
    with open(path, "w") as f:
        f.write(f"OFF\n{len(points)} {len(triangles)} 0\n")
        np.savetxt(f, points, fmt="%.17g")
        np.savetxt(f, np.hstack([np.full((len(triangles), 1), 3), triangles]), fmt="%d")


def read_points(path):
    """The vertices of an OFF or any meshio mesh, in file order."""
    if path.endswith(".off"):
        with open(path) as f:
            words = [w for line in f for w in line.split("#")[0].split()]
        count = int(words[1])
        return np.array(words[4:4 + 3 * count], dtype=float).reshape(count, 3)
    return meshio.read(path).points[:, :3]


def normals(points, triangles):
    """Each triangle's normal, twice its area long."""
    p = points[triangles]
    return np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])


def feature_edges(points, triangles, feature_angle):
    """The edges of the feature curves and of the open boundary: their vertices are not moved to make
    the mesh poorer, and CGAL's smoothers hold them."""
    edges = np.sort(triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    face = np.repeat(np.arange(len(triangles)), 3)
    order = np.lexsort((edges[:, 1], edges[:, 0]))
    edges, face = edges[order], face[order]
    unique, start, count = np.unique(edges, axis=0, return_index=True, return_counts=True)
    n = normals(points, triangles)
    n /= np.linalg.norm(n, axis=1)[:, None]
    two = count == 2
    cosine = (n[face[start[two]]] * n[face[start[two] + 1]]).sum(1)
    return np.vstack([unique[~two],  # boundary (and non-manifold) edges
                      unique[two][cosine < np.cos(np.radians(feature_angle))]])


def off_curves(q, a, b):
    """Each point's distance to the nearest of the segments a[i] b[i]."""
    nearest = np.full(len(q), np.inf)
    for start in range(0, len(q), 256):  # chunks keep the points-by-segments arrays small
        p = q[start:start + 256, None, :]
        t = np.clip(((p - a) * (b - a)).sum(2) / np.maximum(((b - a) ** 2).sum(1), 1e-300), 0, 1)
        nearest[start:start + 256] = np.linalg.norm(p - (a + t[:, :, None] * (b - a)), axis=2).min(1)
    return nearest


def poorer(points, triangles, frozen, snap, shift, seed):
    """The mesh with its free vertices slid along the surface (see the module's comment)."""
    rng = np.random.default_rng(seed)
    n = normals(points, triangles)
    vertex_normal = np.zeros_like(points)
    for corner in range(3):
        np.add.at(vertex_normal, triangles[:, corner], n)
    vertex_normal /= np.linalg.norm(vertex_normal, axis=1)[:, None]
    edges = triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    length = np.linalg.norm(points[edges[:, 0]] - points[edges[:, 1]], axis=1)
    shortest = np.full(len(points), np.inf)
    np.minimum.at(shortest, edges.ravel(), np.repeat(length, 2))

    direction = rng.normal(size=points.shape)
    direction -= (direction * vertex_normal).sum(1)[:, None] * vertex_normal
    direction /= np.linalg.norm(direction, axis=1)[:, None]
    step = direction * (rng.uniform(0, shift, len(points)) * shortest)[:, None]
    step[frozen] = 0.0

    def place(step):
        moved = snap(points + step)
        still = ~step.any(1)
        moved[still] = points[still]  # a projection's rounding must not move them either
        return moved

    for _ in range(12):
        moved = place(step)
        turned = (normals(moved, triangles) * n).sum(1) <= 0
        if not turned.any():
            return moved
        step[np.unique(triangles[turned])] *= 0.5
    step[np.unique(triangles[turned])] = 0.0
    return place(step)


def tangle(points, triangles, frozen, snap, count, seed):
    """The mesh with `count` free vertices slid past a free neighbour each (see the module's comment);
    vertices within two rings of a slid one are not slid, so each tangle is its own."""
    rng = np.random.default_rng(seed + 1)
    edges = np.unique(np.sort(triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1), axis=0)
    neighbours = [[] for _ in range(len(points))]
    for a, b in edges:
        neighbours[a].append(b)
        neighbours[b].append(a)
    blocked = frozen.copy()
    moved = points.copy()
    slid = []
    for v in rng.permutation(len(points)):
        if len(slid) == count:
            break
        if blocked[v] or any(frozen[w] for w in neighbours[v]):
            continue
        w = neighbours[v][rng.integers(len(neighbours[v]))]
        moved[v] = points[w] + 0.5 * (points[w] - points[v])
        slid.append(v)
        for a in [v] + neighbours[v]:
            blocked[a] = True
            blocked[neighbours[a]] = True
    snapped = snap(moved)
    out = points.copy()
    out[slid] = snapped[slid]
    return out


def measure(points, triangles, reference_normals, unperturbed, features, distance):
    frozen = np.unique(features)
    a, b = unperturbed[features[:, 0]], unperturbed[features[:, 1]]
    diagonal = np.linalg.norm(unperturbed.max(0) - unperturbed.min(0))
    p = points[triangles]
    edges = np.stack([p[:, 1] - p[:, 0], p[:, 2] - p[:, 1], p[:, 0] - p[:, 2]], axis=1)
    squared = (edges ** 2).sum(2)
    n = np.cross(edges[:, 0], -edges[:, 2])
    area = 0.5 * np.linalg.norm(n, axis=1)
    turned = (n * reference_normals).sum(1) <= 0
    ratio = np.where(turned, -1, 1) * 4 * np.sqrt(3) * area / squared.sum(1)
    # The angle at corner k lies between the edges into and out of it.
    cosines = [-(edges[:, k] * edges[:, k - 1]).sum(1) / np.sqrt(squared[:, k] * squared[:, k - 1]) for k in range(3)]
    min_angle = np.degrees(np.arccos(np.clip(np.max(cosines, axis=0), -1, 1)))
    # Moved at all, and moved off the feature curves: sliding along them keeps the shape.
    moved = np.linalg.norm(points[frozen] - unperturbed[frozen], axis=1)
    return {"worst_mean_ratio": f"{ratio.min():.4f}", "mean_mean_ratio": f"{ratio.mean():.4f}",
            "worst_min_angle_deg": f"{min_angle.min():.2f}", "turned_over": int(turned.sum()),
            "max_distance_rel": f"{distance:.2e}",
            "max_feature_move_rel": f"{moved.max(initial=0) / diagonal:.1e}",
            "max_feature_off_curve_rel": f"{off_curves(points[frozen], a, b).max(initial=0) / diagonal:.1e}"}


def tool_distance(tool, surface_off, points, triangles, path):
    write_off(path, points, triangles)
    result = run([tool, "distance", surface_off, path])
    if result.returncode != 0:
        raise RuntimeError(result.stderr.strip())
    return float(re.search(r"^relative (\S+)", result.stdout, re.M).group(1))


def mesh_file(name, source, work, paloverde):
    """The case's mesh file: a .geo meshed by Gmsh and written by paloverde's own reader and writer
    (the files its users will hand it), anything else as it is."""
    if not source.endswith(".geo"):
        return source
    msh = os.path.join(work, name + ".msh")
    result = run(["gmsh", "-2", source, "-o", msh])
    if result.returncode != 0:
        raise RuntimeError(f"gmsh: {result.stdout[-500:]}{result.stderr[-500:]}")
    vtk = os.path.join(work, name + ".vtk")
    result = run([paloverde, "convert", msh, vtk])
    if result.returncode != 0:
        raise RuntimeError(f"paloverde convert: {result.stderr.strip()}")
    return vtk


def load_case(name, source, work, paloverde):
    """The case's points and triangles, or the reason it is skipped."""
    source = mesh_file(name, source, work, paloverde)
    mesh = meshio.read(source)
    types = sorted({block.type for block in mesh.cells if block.type not in ("vertex", "line")})
    if "triangle" not in types:
        return None, f"{', '.join(types)} cells only: surface smoothing of those comes later"
    triangles = np.vstack([block.data for block in mesh.cells if block.type == "triangle"])
    used = np.unique(triangles)
    renumber = np.full(len(mesh.points), -1)
    renumber[used] = np.arange(len(used))
    return (mesh.points[used, :3].astype(float), renumber[triangles]), None


def smooth_paloverde(paloverde, poor_vtk, work, name, feature_angle, method, tangled=False):
    out = os.path.join(work, f"{name}_paloverde_{method}.vtk")
    summary = os.path.join(work, f"{name}_paloverde_{method}.json")
    start = time.perf_counter()
    result = run([paloverde, "improve", poor_vtk, "-o", out, "--method", method, "--threads", "1",
                  "--feature-angle", feature_angle, "--summary", summary, "-q"])
    seconds = time.perf_counter() - start
    # A tangle it could not undo: exit 1, the mesh with the fewest turned over written.
    note = "exit 1: could not untangle" if tangled and result.returncode == 1 and os.path.exists(out) else ""
    if result.returncode != 0 and not note:
        raise RuntimeError(f"exit {result.returncode}: {(result.stderr or result.stdout).strip()}")
    try:
        with open(summary) as f:
            seconds = json.load(f)["seconds"]  # the solver's own time, like CGAL's below
    except (OSError, KeyError, ValueError):
        pass
    return read_points(out), seconds, note


def smooth_cgal(tool, poor_off, work, name, method, iterations, feature_angle):
    out = os.path.join(work, f"{name}_cgal_{method}.off")
    result = run([tool, "smooth", poor_off, out, "--method", method, "--iterations", iterations,
                  "--feature-angle", feature_angle])
    if result.returncode != 0:
        raise RuntimeError(f"exit {result.returncode}: {result.stderr.strip()}")
    note = "angle smoothing only (CGAL without Ceres)" if "area smoothing off" in result.stdout else ""
    return read_points(out), float(re.search(r"^seconds (\S+)", result.stdout, re.M).group(1)), note


def read_quads(source, name, work, paloverde):
    source = mesh_file(name, source, work, paloverde)
    mesh = meshio.read(source)
    quads = np.vstack([block.data for block in mesh.cells if block.type == "quad"])
    used = np.unique(quads)
    renumber = np.full(len(mesh.points), -1)
    renumber[used] = np.arange(len(used))
    return mesh.points[used, :3].astype(float), renumber[quads]


def quad_normals(points, quads):
    """Each quadrilateral's normal: the sum of its corners' cross products."""
    p = points[quads]
    return sum(np.cross(p[:, (k + 1) % 4] - p[:, k], p[:, (k + 3) % 4] - p[:, k]) for k in range(4))


def measure_quads(points, quads, reference_normals):
    """Worst and mean corner-triangle mean ratio, worst corner scaled Jacobian (about each
    quadrilateral's own normal), and the quadrilaterals with a corner turned against the reference."""
    p = points[quads]
    n = quad_normals(points, quads)
    n /= np.linalg.norm(n, axis=1)[:, None]
    ratios, jacobians, turned = [], [], np.zeros(len(quads), bool)
    for k in range(4):
        a, b, c = p[:, (k + 3) % 4], p[:, k], p[:, (k + 1) % 4]
        e1, e2 = c - b, a - b
        cross = np.cross(e1, e2)
        turned |= (cross * reference_normals).sum(1) <= 0
        jacobians.append((cross * n).sum(1) / (np.linalg.norm(e1, axis=1) * np.linalg.norm(e2, axis=1)))
        squares = (e1 ** 2).sum(1) + (e2 ** 2).sum(1) + ((c - a) ** 2).sum(1)
        ratios.append(2 * np.sqrt(3) * np.linalg.norm(cross, axis=1) / squares)
    ratios = np.array(ratios)
    return {"worst_mean_ratio": f"{ratios.min():.4f}", "mean_mean_ratio": f"{ratios.mean():.4f}",
            "worst_scaled_jacobian": f"{np.min(jacobians):.4f}", "turned_over": int(turned.sum())}


def quad_rows(args, work):
    """The quadrilateral cases: made poorer on their sphere, smoothed by both Paloverde solvers (with
    the outline fixed, and sliding), measured by corners; CGAL's smoothers take triangles only."""
    rows = []
    for name, source in QUAD_CASES:
        try:
            points, quads = read_quads(source, name, work, args.paloverde)
        except (RuntimeError, ValueError) as error:
            print(f"{name}: skipped ({error})")
            continue
        edges = np.sort(quads[:, [0, 1, 1, 2, 2, 3, 3, 0]].reshape(-1, 2), axis=1)
        unique, count = np.unique(edges, axis=0, return_counts=True)
        frozen = np.zeros(len(points), bool)
        frozen[unique[count == 1].ravel()] = True  # the outline
        # The same cut as Paloverde's (first corner to third): the input surface its vertices keep to.
        split = np.vstack([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
        snap = sphere_snap(points)
        poor = poorer(points, split, frozen, snap, args.shift, args.seed)
        # A quadrilateral corner turned by the move is undone: its vertices go back.
        for _ in range(12):
            bad = measure_quads(poor, quads, quad_normals(points, quads))["turned_over"]
            if bad == 0:
                break
            turned = np.zeros(len(quads), bool)
            n0 = quad_normals(points, quads)
            p = poor[quads]
            for k in range(4):
                turned |= (np.cross(p[:, (k + 1) % 4] - p[:, k], p[:, (k + 3) % 4] - p[:, k]) * n0).sum(1) <= 0
            back = np.unique(quads[turned])
            poor[back] = points[back]
        poor_vtk, poor_off = os.path.join(work, name + "_poor.vtk"), os.path.join(work, name + "_poor.off")
        meshio.write(poor_vtk, meshio.Mesh(poor, [("quad", quads)]), file_format="vtk", binary=True)
        write_off(poor_off, poor, split)
        unperturbed_off = os.path.join(work, name + ".off")
        write_off(unperturbed_off, points, split)
        print(f"{name}: {len(points)} vertices, {len(quads)} quadrilaterals, {int(frozen.sum())} on the outline",
              flush=True)
        poor_normals = quad_normals(poor, quads)
        methods = [("unperturbed", None, []), ("poorer", None, [])]
        for method in ("global", "local"):
            methods.append((f"paloverde_{method}", method, []))
            if frozen.any():
                methods.append((f"paloverde_{method}_slide", method, ["--boundary", "slide"]))
        for label, method, extra in methods:
            row = {"case": name, "method": label, "vertices": len(points), "triangles": f"{len(quads)} quads"}
            try:
                if method is None:
                    result, seconds = (points if label == "unperturbed" else poor), None
                else:
                    out = os.path.join(work, f"{name}_{label}.vtk")
                    summary = os.path.join(work, f"{name}_{label}.json")
                    done = run([args.paloverde, "improve", poor_vtk, "-o", out, "--method", method, "--threads", "1",
                                "--summary", summary, "-q"] + extra)
                    if done.returncode != 0:
                        raise RuntimeError(f"exit {done.returncode}: {(done.stderr or done.stdout).strip()}")
                    result = read_points(out)
                    with open(summary) as f:
                        seconds = json.load(f)["seconds"]
                reference = quad_normals(points, quads) if seconds is None else poor_normals
                row.update(measure_quads(result, quads, reference))
                surface_off = unperturbed_off if seconds is None else poor_off
                row["max_distance_rel"] = f"{tool_distance(args.tool, surface_off, result, split, os.path.join(work, f'{name}_{label}_measured.off')):.2e}"
                moved = np.linalg.norm(result[frozen] - poor[frozen], axis=1) if frozen.any() else np.zeros(1)
                row["max_feature_move_rel"] = f"{moved.max() / np.linalg.norm(points.max(0) - points.min(0)):.1e}"
                row["seconds"] = "" if seconds is None else f"{seconds:.3f}"
            except RuntimeError as error:
                row["error"] = " ".join(str(error).split())[:300] or "failed"
            rows.append(row)
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--paloverde", default="build/bin/paloverde")
    parser.add_argument("--tool", default="build/bin/paloverde_surface_tool")
    parser.add_argument("--work", default=None, help="where the meshes go (default: a temporary directory)")
    parser.add_argument("--csv", default=os.path.join(HERE, "..", "docs", "data", "surfaces.csv"))
    parser.add_argument("--feature-angle", type=float, default=60.0,
                        help="degrees between two triangles' normals that make their edge a feature")
    parser.add_argument("--shift", type=float, default=0.35, help="largest step, times the vertex's shortest edge")
    parser.add_argument("--cgal-iterations", type=int, default=10)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--tangle", type=int, default=0,
                        help="vertices of the poorer mesh to slide past a neighbour (triangle cases only)")
    args = parser.parse_args()
    if args.tangle and args.csv == parser.get_default("csv"):
        args.csv = os.path.join(HERE, "..", "docs", "data", "surfaces_tangled.csv")
    for program in (args.paloverde, args.tool):
        if not os.access(program, os.X_OK):
            sys.exit(f"{program}: not found (build it, or pass its path)")
    temporary = None if args.work else tempfile.TemporaryDirectory(prefix="surface_study_")
    work = args.work or temporary.name
    os.makedirs(work, exist_ok=True)

    rows = []
    for name, source, surface in CASES:
        try:
            loaded, skipped = load_case(name, source, work, args.paloverde)
        except RuntimeError as error:
            loaded, skipped = None, f"could not be made: {error}"
        if skipped:
            print(f"{name}: skipped ({os.path.relpath(source)}: {skipped})")
            continue
        points, triangles = loaded
        features = feature_edges(points, triangles, args.feature_angle)
        frozen = np.zeros(len(points), bool)
        frozen[features.ravel()] = True
        unperturbed_off = os.path.join(work, name + ".off")
        write_off(unperturbed_off, points, triangles)
        if surface == "torus":
            snap = torus_snap
        elif surface == "sphere":
            snap = sphere_snap(points)
        else:
            def snap(q, points=points):
                moved_off = os.path.join(work, name + "_moved.off")
                snapped_off = os.path.join(work, name + "_snapped.off")
                write_off(moved_off, q, triangles)
                result = run([args.tool, "project", unperturbed_off, moved_off, snapped_off])
                if result.returncode != 0:
                    raise RuntimeError(result.stderr.strip())
                return read_points(snapped_off)
        poor = poorer(points, triangles, frozen, snap, args.shift, args.seed)
        if args.tangle:
            poor = tangle(poor, triangles, frozen, snap, args.tangle, args.seed)
        poor_off, poor_vtk = os.path.join(work, name + "_poor.off"), os.path.join(work, name + "_poor.vtk")
        write_off(poor_off, poor, triangles)
        meshio.write(poor_vtk, meshio.Mesh(poor, [("triangle", triangles)]), file_format="vtk", binary=True)
        print(f"{name}: {len(points)} vertices, {len(triangles)} triangles, {int(frozen.sum())} on features "
              f"or the boundary", flush=True)

        poor_normals = normals(poor, triangles)
        methods = [("unperturbed", lambda: (points, None, "")), ("poorer", lambda: (poor, None, ""))]
        for method in ("global", "local"):
            methods.append((f"paloverde_{method}", lambda method=method: smooth_paloverde(
                args.paloverde, poor_vtk, work, name, args.feature_angle, method, args.tangle > 0)))
        for method in ("angle_area", "tangential"):
            methods.append((f"cgal_{method}", lambda method=method: smooth_cgal(
                args.tool, poor_off, work, name, method, args.cgal_iterations, args.feature_angle)))
        for method, smooth in methods:
            row = {"case": name, "method": method, "vertices": len(points), "triangles": len(triangles)}
            try:
                result, seconds, row["note"] = smooth()
                if result.shape != points.shape:
                    raise RuntimeError(f"{len(result)} vertices came back, not {len(points)}")
                # The unperturbed and poorer meshes are judged against the unperturbed triangles'
                # orientation, the results against their input's.
                # (A tangled input's own orientation is what is judged: against the unperturbed.)
                reference = normals(points, triangles) if seconds is None or args.tangle else poor_normals
                # Smoothed meshes are measured against their input surface (the poorer mesh), the
                # two inputs against the unperturbed triangles.
                surface_off = unperturbed_off if seconds is None else poor_off
                distance = tool_distance(args.tool, surface_off, result, triangles,
                                         os.path.join(work, f"{name}_{method}_measured.off"))
                row.update(measure(result, triangles, reference, points, features, distance))
                row["seconds"] = "" if seconds is None else f"{seconds:.3f}"
            except RuntimeError as error:
                row["error"] = " ".join(str(error).split())[:300] or "failed"
            rows.append(row)

    if not args.tangle:
        rows += quad_rows(args, work)

    if args.csv:
        os.makedirs(os.path.dirname(os.path.abspath(args.csv)), exist_ok=True)
        with open(args.csv, "w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=FIELDS)
            writer.writeheader()
            writer.writerows(rows)
    shown = ["case", "method", "worst_mean_ratio", "mean_mean_ratio", "worst_scaled_jacobian", "worst_min_angle_deg",
             "turned_over",
             "max_distance_rel", "max_feature_move_rel", "max_feature_off_curve_rel", "seconds", "note", "error"]
    print("\n| " + " | ".join(shown) + " |\n|" + "---|" * len(shown))
    for row in rows:
        print("| " + " | ".join(str(row.get(key, "")) for key in shown) + " |")


if __name__ == "__main__":
    main()
