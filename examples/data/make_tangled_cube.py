#!/usr/bin/env python3
"""Writes tangled_cube.vtk: the unit cube as a 7x7x7 grid of vertices, each cell split into six
tetrahedra around its main diagonal, with the interior vertices moved at random (fixed seed) by
up to 0.8 of the grid spacing so that some tetrahedra invert. The bundled example of the README."""
import random

N = 7  # vertices per side
h = 1.0 / (N - 1)
rng = random.Random(2026)


def vid(i, j, k):
    return i + N * (j + N * k)


points = []
for k in range(N):
    for j in range(N):
        for i in range(N):
            p = [i * h, j * h, k * h]
            if 0 < i < N - 1 and 0 < j < N - 1 and 0 < k < N - 1:
                p = [c + rng.uniform(-0.8, 0.8) * h for c in p]
            points.append(p)

# Six tetrahedra per cell along the diagonal from corner 0 to corner 7 (Kuhn's subdivision);
# each path 0 -> a -> b -> 7 through the cell's corners gives one tetrahedron.
corner = lambda i, j, k, c: vid(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1))
paths = [(1, 3), (1, 5), (2, 3), (2, 6), (4, 5), (4, 6)]
tets = []
for k in range(N - 1):
    for j in range(N - 1):
        for i in range(N - 1):
            for a, b in paths:
                t = [corner(i, j, k, c) for c in (0, a, b, 7)]
                # Orient positively on the undistorted grid.
                P = [[v % N, (v // N) % N, v // (N * N)] for v in t]  # grid coordinates
                u = [P[1][d] - P[0][d] for d in range(3)]
                v = [P[2][d] - P[0][d] for d in range(3)]
                w = [P[3][d] - P[0][d] for d in range(3)]
                det = (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0])
                       + u[2] * (v[0] * w[1] - v[1] * w[0]))
                if det < 0:
                    t[1], t[2] = t[2], t[1]
                tets.append(t)

with open("tangled_cube.vtk", "w") as out:
    out.write("# vtk DataFile Version 3.0\nPaloverde example: tangled unit cube\nASCII\nDATASET UNSTRUCTURED_GRID\n")
    out.write(f"POINTS {len(points)} double\n")
    for p in points:
        out.write(" ".join(f"{c:.17g}" for c in p) + "\n")
    out.write(f"CELLS {len(tets)} {5 * len(tets)}\n")
    for t in tets:
        out.write("4 " + " ".join(map(str, t)) + "\n")
    out.write(f"CELL_TYPES {len(tets)}\n" + "10\n" * len(tets))
