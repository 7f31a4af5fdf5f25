"""The Python package: meshes from files, numpy and meshio; quality; improve; run; errors; threads.

Run by CTest (entry `python`) with PYTHONPATH=build/python and PALOVERDE_SHARED_DATA set.
"""
import math
import os
import threading
import time

import meshio
import numpy as np
import pytest

import paloverde

DATA = os.environ.get("PALOVERDE_SHARED_DATA", os.path.join(os.path.dirname(__file__), "..", "..", "..", "shared", "data"))
TANGLED = os.path.join(DATA, "mesquite", "tets", "tet_4_tangled.vtk")
TIRE = os.path.join(DATA, "mesquite", "tets", "tire.vtk")


def test_a_tangled_mesh_is_read_reported_and_untangled_in_place():
    mesh = paloverde.read(TANGLED)
    assert paloverde.quality(mesh)["inverted"] == 9
    before = mesh.points.copy()
    summary = paloverde.improve(mesh)
    assert summary["success"] and summary["inverted_before"] == 9 and summary["inverted_after"] == 0
    assert paloverde.quality(mesh)["inverted"] == 0
    assert not np.array_equal(before, mesh.points)
    # Fixed vertices (the boundary) stay where they were.
    assert np.array_equal(before[mesh.fixed], mesh.points[mesh.fixed])


def test_the_same_mesh_from_numpy_and_from_meshio_gives_the_same_result():
    from_file = paloverde.read(TANGLED)
    from_arrays = paloverde.Mesh(from_file.points.copy(), from_file.cells)
    # meshio keeps the file's single-precision points as float32; Paloverde reads them as doubles.
    read_by_meshio = meshio.read(TANGLED)
    assert np.abs(read_by_meshio.points - from_file.points).max() < 1e-6
    read_by_meshio.points = from_file.points.copy()
    from_meshio = paloverde.Mesh.from_meshio(read_by_meshio)
    assert np.array_equal(from_file.fixed, from_arrays.fixed) and np.array_equal(from_file.fixed, from_meshio.fixed)
    for mesh in (from_file, from_arrays, from_meshio):
        paloverde.improve(mesh, threads=1)
    assert np.array_equal(from_file.points, from_arrays.points)
    assert np.array_equal(from_file.points, from_meshio.points)
    back = from_meshio.to_meshio()
    assert back.points.shape == from_file.points.shape and back.cells[0].type == "tetra"
    assert np.array_equal(back.point_data["fixed"].astype(bool), from_file.fixed)


def test_points_are_a_view_and_fixed_flags_can_be_set():
    mesh = paloverde.read(TANGLED)
    view = mesh.points
    view[0, 0] += 0.25
    assert mesh.points[0, 0] == view[0, 0]
    mesh.fixed = np.zeros(mesh.num_vertices, dtype=bool)
    assert not mesh.fixed.any()
    with pytest.raises(paloverde.OptionError, match="one flag per vertex"):
        mesh.fixed = np.zeros(3, dtype=bool)


def test_the_local_smoother_untangles_with_keywords_as_config_keys():
    mesh = paloverde.read(TANGLED)
    summary = paloverde.improve(mesh, method="local", untangle=True, iterations=200)
    assert summary["solver"] == "local" and summary["inverted_after"] == 0


def test_a_planar_triangle_mesh_from_two_columns():
    points = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0.9, 0.8]], dtype=float)
    cells = {"triangle": np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]])}
    mesh = paloverde.Mesh(points, cells)
    assert mesh.points.shape == (5, 3) and mesh.fixed.tolist() == [True, True, True, True, False]
    worst = paloverde.quality(mesh)["metrics"]["aspect_ratio"]["min"]
    summary = paloverde.improve(mesh)
    assert summary["worst_after"] > worst
    assert np.allclose(mesh.points[4], [0.5, 0.5, 0.0], atol=1e-2)


def test_files_round_trip_and_a_config_runs_as_a_dict(tmp_path):
    mesh = paloverde.read(TANGLED)
    paloverde.write(str(tmp_path / "copy.vtu"), mesh)
    again = paloverde.read(str(tmp_path / "copy.vtu"))
    assert np.array_equal(again.points, mesh.points) and np.array_equal(again.fixed, mesh.fixed)
    summary = paloverde.run({"input": {"mesh": TANGLED}, "output": {"mesh": str(tmp_path / "out.vtu")}})
    assert summary["success"] and summary["inverted_after"] == 0
    assert paloverde.quality(paloverde.read(str(tmp_path / "out.vtu")))["inverted"] == 0


def test_bad_input_raises_the_command_lines_messages():
    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, math.nan]])
    with pytest.raises(paloverde.MeshError, match="non-finite"):
        paloverde.Mesh(points, {"tetra": np.array([[0, 1, 2, 3]])})
    with pytest.raises(paloverde.MeshError, match="out of range"):
        paloverde.Mesh(points[:3], {"tetra": np.array([[0, 1, 2, 3]])})
    with pytest.raises(paloverde.OptionError, match="unknown cell type 'tet'"):
        paloverde.Mesh(points, {"tet": np.array([[0, 1, 2, 3]])})
    mesh = paloverde.read(TANGLED)
    with pytest.raises(paloverde.OptionError, match="colour"):
        paloverde.improve(mesh, colour="red")
    with pytest.raises(paloverde.OptionError, match="lokal"):
        paloverde.improve(mesh, method="lokal")
    with pytest.raises(paloverde.FileError, match="no-such-file"):
        paloverde.read("no-such-file.vtk")
    # Every one of them is a paloverde.Error.
    assert issubclass(paloverde.MeshError, paloverde.Error) and issubclass(paloverde.OptionError, paloverde.Error)


def test_the_observer_sees_the_iterations_and_can_stop_the_run():
    mesh = paloverde.read(TANGLED)
    seen = []
    paloverde.improve(mesh, observer=seen.append)
    assert seen and {"iteration", "worst", "inverted", "seconds"} <= set(seen[0])

    def stop(record):
        raise RuntimeError("enough")

    mesh = paloverde.read(TIRE)
    summary = paloverde.improve(mesh, observer=stop)
    assert summary["status"] == "interrupted"


def test_a_solve_runs_in_a_thread_while_the_main_thread_goes_on():
    mesh = paloverde.read(TIRE)
    result = {}
    worker = threading.Thread(target=lambda: result.update(paloverde.improve(mesh, threads=1, iterations=400)))
    start = time.perf_counter()
    worker.start()
    ticks = 0
    while worker.is_alive():  # the GIL is free while the solver runs
        ticks += 1
        time.sleep(0.001)
    worker.join()
    assert result["success"]
    assert ticks >= 10, f"the main thread ran {ticks} times in {time.perf_counter() - start:.2f} s"


def test_ctrl_c_stops_a_run_on_its_best_mesh():
    import signal

    mesh = paloverde.read(os.path.join(DATA, "mesquite", "tets", "cub_wedge_like.vtk"))
    before = paloverde.quality(mesh)
    sent = []

    def press_ctrl_c(record):  # SIGINT at the first iteration, whatever the machine's speed
        if not sent:
            sent.append(record["iteration"])
            os.kill(os.getpid(), signal.SIGINT)

    summary = paloverde.improve(mesh, threads=1, iterations=100000, target=1.0, observer=press_ctrl_c)
    assert sent and summary["status"] == "interrupted"
    assert summary["worst_after"] >= summary["worst_before"]
    assert paloverde.quality(mesh)["inverted"] <= before["inverted"]


@pytest.mark.parametrize("script, arguments", [
    ("improve_and_plot.py", ["--out", "{tmp}/improved.vtu", "--plot", "{tmp}/worst.png"]),
    ("global_vs_local.py", [TANGLED, "--csv", "{tmp}/methods.csv"]),
])
def test_the_python_examples_run(tmp_path, script, arguments):
    import subprocess
    import sys

    examples = os.path.join(os.path.dirname(__file__), "..", "..", "examples", "python")
    done = subprocess.run([sys.executable, os.path.join(examples, script)] + [a.format(tmp=tmp_path) for a in arguments],
                          capture_output=True, text=True, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert any(tmp_path.iterdir())
