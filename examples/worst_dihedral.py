#!/usr/bin/env python3
"""Where a dihedral-angle run stopped: the worst tetrahedron with a free vertex (boundary vertices
fixed, as `paloverde improve` fixes them), its six dihedral angles, whether its two smallest sines
tie, and for each free corner the two terms' gradients (finite differences) and the cosine between
them. Two tied terms whose gradients are not opposite mean the corner could raise both: the run
stopped at a kink of the minimum, not at a max-min point (docs/metrics.md, "The dihedral quality").

    paloverde improve MESH -o out.vtk --ascii --metric dihedral_sine
    /usr/bin/python3 examples/worst_dihedral.py out.vtk [--ascend]

With --ascend, each free corner of that tetrahedron is then moved alone, its neighbours held, by a
plain search (random directions, seed 1, the step shrinking fourfold while none pays) that accepts
a move only when the smallest sine over every term of the corner's tetrahedra rises: how far the
corner could go if each angle were a term of its own. A diagnostic, not a solver.

Reads legacy ASCII VTK files of tetrahedra (what `--ascii` writes for .vtk). Needs numpy (Debian:
python3-numpy).
"""
import collections
import sys

import numpy as np

EDGES = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]


def read_vtk(path):
    tokens = open(path).read().split()
    at = tokens.index("POINTS")
    n = int(tokens[at + 1])
    points = np.array(tokens[at + 3:at + 3 + 3 * n], float).reshape(n, 3)
    at = tokens.index("CELLS")
    m = int(tokens[at + 1])
    cells = np.array(tokens[at + 3:at + 3 + 5 * m], int).reshape(m, 5)
    if not (cells[:, 0] == 4).all():
        raise SystemExit("%s: only tetrahedra are read" % path)
    return points, cells[:, 1:]


def dihedral_angles(points, tets):
    """Degrees, one column per edge of EDGES: the angle between the two faces at that edge."""
    x = points[tets]
    out = np.empty((len(tets), 6))
    for k, (i, j) in enumerate(EDGES):
        a, b = [c for c in range(4) if c not in (i, j)]
        edge = x[:, j] - x[:, i]
        n1 = np.cross(edge, x[:, a] - x[:, i])
        n2 = np.cross(edge, x[:, b] - x[:, i])
        cos = np.sum(n1 * n2, 1) / (np.linalg.norm(n1, axis=1) * np.linalg.norm(n2, axis=1))
        out[:, k] = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))
    return out


def ascend(points, tets, v, rounds=40, directions=400):
    """Smallest sine over the tetrahedra around v after the search of --ascend moves v alone."""
    around = tets[[e for e in range(len(tets)) if v in tets[e]]]

    def smallest(p):
        return np.sin(np.radians(dihedral_angles(p, around))).min()

    rng = np.random.default_rng(1)
    length = np.ptp(points, axis=0).max()
    here, value = points.copy(), smallest(points)
    for _ in range(rounds):
        trial = rng.normal(size=(directions, 3))
        trial /= np.linalg.norm(trial, axis=1)[:, None]
        best = None
        for step in [length * 1e-2 * 4.0 ** -k for k in range(8)]:
            for d in trial:
                moved = here.copy()
                moved[v] += step * d
                if (q := smallest(moved)) > value:
                    value, best = q, moved
            if best is not None:
                break
        if best is None:
            break
        here = best
    return value


def main(path, climb):
    points, tets = read_vtk(path)
    faces = collections.Counter(tuple(sorted(np.delete(t, s))) for t in tets for s in range(4))
    boundary = {v for face, count in faces.items() if count == 1 for v in face}
    sines = np.sin(np.radians(dihedral_angles(points, tets)))
    free = np.array([any(v not in boundary for v in t) for t in tets])
    if not free.any():
        raise SystemExit("%s: no tetrahedron has a free vertex" % path)
    worst = int(np.argmin(np.where(free, sines.min(1), np.inf)))
    angles = dihedral_angles(points, tets[worst:worst + 1])[0]
    order = np.argsort(sines[worst])
    print("worst tetrahedron with a free vertex: %d, corners %s" % (worst, list(tets[worst])))
    print("  smallest dihedral angle %.4f deg; angles %s" % (angles.min(), np.round(np.sort(angles), 3)))
    first, second = order[0], order[1]
    print("  two smallest sines %.9f (edge %s, %.4f deg) and %.9f (edge %s, %.4f deg)" % (
        sines[worst][first], EDGES[first], angles[first], sines[worst][second], EDGES[second], angles[second]))
    step = 1e-7 * np.ptp(points, axis=0).max()
    for v in tets[worst]:
        if v in boundary:
            continue
        around = [e for e in range(len(tets)) if v in tets[e]]
        others = sorted(sines[e].min() for e in around if e != worst)
        gradients = []
        for d in range(3):
            moved = points.copy()
            moved[v, d] += step
            after = np.sin(np.radians(dihedral_angles(moved, tets[worst:worst + 1])[0]))
            gradients.append((after - sines[worst]) / step)
        g = np.array(gradients).T
        cos = g[first] @ g[second] / (np.linalg.norm(g[first]) * np.linalg.norm(g[second]))
        print("  free corner %d: gradients of the two terms %s and %s, cosine %.3f; its %d other "
              "tetrahedra's smallest sines from %.6f" % (v, np.round(g[first], 4), np.round(g[second], 4), cos,
                                                          len(others), others[0] if others else float("nan")))
        if climb:
            q = ascend(points, tets, v)
            print("    moved alone over every term: smallest sine around it %.6f (%.4f deg)" % (
                q, np.degrees(np.arcsin(min(q, 1.0)))))


if __name__ == "__main__":
    arguments = [a for a in sys.argv[1:] if a != "--ascend"]
    if len(arguments) != 1:
        raise SystemExit(__doc__)
    main(arguments[0], "--ascend" in sys.argv[1:])
