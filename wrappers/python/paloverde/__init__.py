"""Paloverde: untangling and quality improvement of meshes, from Python.

    import paloverde
    mesh = paloverde.read("tangled.vtk")
    paloverde.quality(mesh)["inverted"]          # the report of `paloverde quality --json`
    summary = paloverde.improve(mesh, iterations=200)   # in place; the keys of `--summary`
    paloverde.write("improved.vtu", mesh)

Meshes come from files (`read`), from numpy arrays (`Mesh(points, cells)`, cells keyed by meshio's
type names) or from meshio (`Mesh.from_meshio`). `improve` takes the config keys of an improve
step as keywords (docs/config.md), and `run` a whole config. Errors are `paloverde.Error`s:
`MeshError` for a mesh that cannot be used, `OptionError` for an option, `FileError` for a file.
See docs/python.md.
"""
import json as _json

import numpy as _np

from ._paloverde import Error, FileError, Mesh, MeshError, OptionError, read, write
from . import _paloverde

__all__ = ["Error", "FileError", "Mesh", "MeshError", "OptionError", "read", "write", "quality", "improve", "run"]

# Keywords that stand for a key outside the improve step, or for a longer key path (as the
# command line's flags do: docs/cli.md).
_KEYS = {
    "iterations": "queue[0].improve.termination.max_iterations",
    "target": "queue[0].improve.termination.target_worst_quality",
    "time_limit": "queue[0].improve.termination.max_seconds",
    "threads": "threads",
    "keep": "targets.keep",
    "reference": "targets.reference",
}


def _yaml(value):
    """A Python value as the YAML text of a config value."""
    if value is None:
        return "~"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_yaml(v) for v in value) + "]"
    if isinstance(value, dict):
        return _json.dumps(value)
    return _json.dumps(str(value))  # quoted: a name is never read as a number or a flag


def quality(mesh):
    """The quality report of `paloverde quality --json`: counts (vertices, elements, inverted, ...),
    and per metric its min, max, mean and rms over all elements and over those with a free vertex."""
    return _json.loads(_paloverde._quality(mesh))


def improve(mesh, method="global", observer=None, **options):
    """Untangles (if needed) and raises the worst element's quality of `mesh`, in place.

    method: "global" (the log-barrier solver), "local", "smart_laplace" or "laplace".
    options: the keys of an improve step (docs/config.md), e.g. untangle=False, metric="mean_ratio",
    boundary="slide", improve_shape=False, or a key path as a string ("termination.max_seconds");
    also iterations=, target=, time_limit= (the termination's), threads=, keep= (a list of factors or
    "auto"/"none") and reference= (a mesh file) as on the command line.
    observer: called with a dict (method, step, phase, iteration, worst, best_worst, mean,
    inverted, seconds) at each recorded iteration; an exception it raises stops the run.

    Returns the run's summary, the keys of `paloverde improve --summary` (success, status,
    inverted_before, inverted_after, worst_before, worst_after, iterations, ...). Ctrl-C stops the
    run on its best mesh so far (status "interrupted"). The GIL is released while it runs.
    """
    sets = ["queue[0].improve.name=" + _yaml(method)]
    for key, value in options.items():
        path = _KEYS.get(key, "queue[0].improve." + key)
        if key == "keep" and isinstance(value, str):
            value = [v.strip() for v in value.split(",")]
        sets.append(path + "=" + _yaml(value))
    return _json.loads(_paloverde._run_on(mesh, "", sets, observer))


def run(config):
    """Runs a config as `paloverde run` does: a path to a config file, or the config as a dict.
    Returns the run's summary (the keys of `output.summary`)."""
    if isinstance(config, dict):
        return _json.loads(_paloverde._run(_json.dumps(config), "run()"))
    return _json.loads(_paloverde._run_file(str(config)))


def _from_meshio(mesh):
    """A Paloverde mesh from a meshio.Mesh: its points and its cells of the types Paloverde
    knows (blocks of one type joined); other blocks (lines, vertices) are left out."""
    known = {"triangle", "quad", "tetra", "hexahedron", "wedge", "pyramid"}
    cells = {}
    for block in mesh.cells:
        if block.type in known:
            cells.setdefault(block.type, []).append(_np.asarray(block.data))
    return Mesh(_np.asarray(mesh.points, dtype=float), {k: _np.concatenate(v) for k, v in cells.items()})


def _to_meshio(self):
    """A meshio.Mesh with a copy of the points, the cells and the fixed flags as point data."""
    import meshio

    return meshio.Mesh(self.points.copy(), list(self.cells.items()),
                       point_data={"fixed": self.fixed.astype(_np.uint8)})


Mesh.from_meshio = staticmethod(_from_meshio)
Mesh.to_meshio = _to_meshio
