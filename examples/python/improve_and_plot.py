#!/usr/bin/python3
"""Read a mesh with meshio, improve it with Paloverde, plot the worst quality per iteration.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/improve_and_plot.py \
        [MESH] [--out improved.vtu] [--plot worst.png]

MESH defaults to the bundled examples/data/tangled_cube.vtk. Needs numpy, meshio and matplotlib
(Debian's python3-numpy, python3-meshio, python3-matplotlib).
"""
import argparse
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import meshio

import paloverde

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("mesh", nargs="?", default=os.path.join(HERE, "..", "data", "tangled_cube.vtk"))
    parser.add_argument("--out", default="improved.vtu")
    parser.add_argument("--plot", default="worst.png")
    args = parser.parse_args()

    mesh = paloverde.Mesh.from_meshio(meshio.read(args.mesh))
    report = paloverde.quality(mesh)
    print(f"{args.mesh}: {report['elements']} elements, {report['inverted']} inverted, "
          f"worst aspect ratio {report['metrics']['aspect_ratio']['min']:.4f}")

    history = []  # one record per recorded iteration: phase, iteration, worst, seconds, ...
    summary = paloverde.improve(mesh, observer=history.append)
    print(f"{summary['status']}: inverted {summary['inverted_before']} -> {summary['inverted_after']}, "
          f"worst {summary['worst_before']:.4f} -> {summary['worst_after']:.4f} in {summary['seconds']:.2f} s")

    meshio.write(args.out, mesh.to_meshio())
    for phase in ("untangle", "shape"):
        records = [r for r in history if r["phase"] == phase]
        if records:
            plt.plot([r["seconds"] for r in records], [r["worst"] for r in records], label=phase)
    plt.xlabel("seconds")
    plt.ylabel("worst quality (untangling: the hybrid metric)")
    plt.title(os.path.basename(args.mesh))
    plt.legend()
    plt.savefig(args.plot, dpi=120)
    print(f"wrote {args.out} and {args.plot}")


if __name__ == "__main__":
    main()
