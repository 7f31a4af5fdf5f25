// The Python extension `paloverde._paloverde`: meshes as numpy arrays, the readers and writers,
// the quality report and runs of the config layer. The package's __init__.py adds the
// meshio conversions and the keyword options of improve().
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "paloverde/assess/quality_assessor.hpp"
#include "paloverde/config/run.hpp"
#include "paloverde/core/error.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/mesh/cell_types.hpp"
#include "paloverde/mesh/mesh.hpp"
#include "paloverde/solvers/stop.hpp"

namespace py = pybind11;
using namespace paloverde;

namespace {

// meshio's names of the cell types.
constexpr std::array<std::pair<const char*, CellType>, 6> kCellNames = {{{"triangle", CellType::Triangle},
                                                                        {"quad", CellType::Quadrilateral},
                                                                        {"tetra", CellType::Tetrahedron},
                                                                        {"hexahedron", CellType::Hexahedron},
                                                                        {"wedge", CellType::Wedge},
                                                                        {"pyramid", CellType::Pyramid}}};

CellType cell_type_named(const std::string& name) {
    std::string known;
    for (const auto& [n, type] : kCellNames) {
        if (name == n) return type;
        known += (known.empty() ? "" : ", ") + std::string(n);
    }
    throw OptionError("unknown cell type '" + name + "' (known: " + known + ")");
}

const char* name_of(CellType type) {
    for (const auto& [n, t] : kCellNames)
        if (t == type) return n;
    return "";
}

// A mesh from points (n x 2 or n x 3) and cells (type name -> (m x k) vertex indices).
Mesh mesh_from_arrays(const py::array_t<double, py::array::c_style | py::array::forcecast>& points,
                      const std::map<std::string, py::array_t<long long, py::array::c_style | py::array::forcecast>>& cells) {
    if (points.ndim() != 2 || (points.shape(1) != 2 && points.shape(1) != 3))
        throw OptionError("points must be an (n, 2) or (n, 3) array, got one of shape " +
                          std::to_string(points.ndim() == 2 ? points.shape(0) : points.size()) +
                          (points.ndim() == 2 ? " x " + std::to_string(points.shape(1)) : std::string()));
    const auto n = static_cast<std::size_t>(points.shape(0));
    const auto width = static_cast<std::size_t>(points.shape(1));
    std::vector<double> xyz(3 * n, 0.0);
    const double* p = points.data();
    for (std::size_t v = 0; v < n; ++v)
        for (std::size_t d = 0; d < width; ++d) xyz[3 * v + d] = p[width * v + d];
    std::vector<CellType> types;
    std::vector<VertexId> connectivity;
    for (const auto& [name, block] : cells) {
        const CellType type = cell_type_named(name);
        const auto corners = static_cast<py::ssize_t>(cell_info(type).corners);
        if (block.ndim() != 2 || block.shape(1) != corners)
            throw OptionError("cells['" + name + "'] must be an (m, " + std::to_string(corners) + ") array of vertex indices");
        const long long* c = block.data();
        for (py::ssize_t i = 0; i < block.shape(0); ++i) {
            types.push_back(type);
            for (py::ssize_t k = 0; k < corners; ++k) {
                const long long v = c[i * corners + k];
                if (v < 0 || v >= static_cast<long long>(n))
                    throw MeshError("cells['" + name + "'] row " + std::to_string(i) + ": vertex " + std::to_string(v) +
                                    " is out of range (the mesh has " + std::to_string(n) + " points)");
                connectivity.push_back(static_cast<VertexId>(v));
            }
        }
    }
    if (types.empty()) throw MeshError("the mesh has no cells");
    Mesh mesh = Mesh::from_cells(std::move(xyz), types, std::move(connectivity));
    mesh.fix_boundary();
    return mesh;
}

// The cells by type name, in the order a file holds them (a mesh flipped on reading is given
// back in its file's order).
py::dict cells_of(const Mesh& mesh) {
    std::map<CellType, std::vector<long long>> blocks;
    for (ElementId c = 0; c < mesh.num_cells(); ++c) {
        const CellType type = mesh.cell_type(c);
        const auto corners = mesh.cell(c);
        auto& block = blocks[type];
        const auto& mirror = cell_info(type).mirror;
        for (std::size_t k = 0; k < corners.size(); ++k)
            block.push_back(corners[mesh.elements_flipped() ? static_cast<std::size_t>(mirror[k]) : k]);
    }
    py::dict out;
    for (auto& [type, block] : blocks) {
        const auto corners = static_cast<py::ssize_t>(cell_info(type).corners);
        py::array_t<long long> array({static_cast<py::ssize_t>(block.size()) / corners, corners});
        std::copy(block.begin(), block.end(), array.mutable_data());
        out[name_of(type)] = std::move(array);
    }
    return out;
}

// Runs the config layer on the mesh with the GIL released; the observer (if any) and Ctrl-C are
// looked at each recorded iteration, with the GIL held.
py::str run_on(Mesh& mesh, const std::string& yaml, const std::vector<std::string>& sets, const py::object& observer) {
    std::vector<config::Override> overrides;
    for (const std::string& s : sets) overrides.push_back({s, "improve()"});
    const config::RunSpec spec = config::parse_config(yaml, "improve()", overrides);
    config::RunHooks hooks;
    bool interrupted = false;
    hooks.on_iteration = [&](std::string_view method, std::string_view step, const IterationRecord& r) {
        py::gil_scoped_acquire hold;
        if (PyErr_CheckSignals() != 0) {  // Ctrl-C: stop on the best iterate
            PyErr_Clear();
            interrupted = true;
            request_stop();
        }
        if (observer.is_none() || interrupted) return;
        try {
            observer(py::dict(py::arg("method") = std::string(method), py::arg("step") = std::string(step),
                              py::arg("iteration") = r.iteration, py::arg("phase") = r.phase,
                              py::arg("worst") = r.worst_quality, py::arg("best_worst") = r.best_worst_quality,
                              py::arg("mean") = r.mean_quality, py::arg("inverted") = r.inverted,
                              py::arg("seconds") = r.seconds));
        } catch (py::error_already_set& e) {
            // An observer that raises stops the run; its exception is not lost, only reported.
            PyErr_WriteUnraisable(e.value().ptr());
            request_stop();
        }
    };
    config::RunResult result;
    {
        py::gil_scoped_release free;
        clear_stop_request();
        try {
            result = config::run(mesh, spec, hooks);
        } catch (...) {
            clear_stop_request();
            throw;
        }
        clear_stop_request();
    }
    return result.to_json();
}

}  // namespace

PYBIND11_MODULE(_paloverde, m) {
    m.doc() = "Paloverde: untangling and quality improvement of meshes (the C++ library's Python bindings)";

    // One exception family; the messages are the command line's. Translators registered later
    // are tried first, so each subclass is registered after Error.
    auto& error = py::register_exception<Error>(m, "Error");
    py::register_exception<MeshError>(m, "MeshError", error.ptr());
    py::register_exception<OptionError>(m, "OptionError", error.ptr());
    py::register_exception<FileError>(m, "FileError", error.ptr());

    py::class_<Mesh>(m, "Mesh", "A mesh: points, cells and which vertices are fixed")
        .def(py::init(&mesh_from_arrays), py::arg("points"), py::arg("cells"),
             "A mesh from an (n, 2) or (n, 3) array of points and a dict of cell type (meshio's names: triangle, "
             "quad, tetra, hexahedron, wedge, pyramid) -> (m, k) array of vertex indices. Boundary vertices start "
             "fixed.")
        .def_property_readonly(
            "points",
            [](py::object self) {
                Mesh& mesh = self.cast<Mesh&>();
                // A view of the mesh's own coordinates: writing to it moves the vertices.
                return py::array_t<double>({static_cast<py::ssize_t>(mesh.num_vertices()), py::ssize_t{3}},
                                           mesh.coordinates().data(), self);
            },
            "The (n, 3) coordinates, a view without a copy: writing to it moves the vertices")
        .def_property_readonly("cells", &cells_of, "A dict of cell type -> (m, k) array of vertex indices (a copy)")
        .def_property(
            "fixed",
            [](const Mesh& mesh) {
                py::array_t<bool> out(static_cast<py::ssize_t>(mesh.num_vertices()));
                std::copy(mesh.fixed().begin(), mesh.fixed().end(), out.mutable_data());
                return out;
            },
            [](Mesh& mesh, const py::array_t<bool, py::array::c_style | py::array::forcecast>& flags) {
                if (flags.ndim() != 1 || flags.shape(0) != static_cast<py::ssize_t>(mesh.num_vertices()))
                    throw OptionError("fixed must be one flag per vertex (" + std::to_string(mesh.num_vertices()) + ")");
                mesh.set_fixed(std::vector<std::uint8_t>(flags.data(), flags.data() + flags.shape(0)));
            },
            "One flag per vertex: True where the vertex stays put")
        .def_property_readonly("num_vertices", &Mesh::num_vertices)
        .def_property_readonly("num_cells", &Mesh::num_cells)
        .def("copy", [](const Mesh& mesh) { return Mesh(mesh); }, "An independent copy")
        .def("__repr__", [](const Mesh& mesh) { return "<paloverde.Mesh: " + describe_cells(mesh) + ", " +
                                                       std::to_string(mesh.num_vertices()) + " vertices>"; });

    m.def(
        "read",
        [](const std::string& path, bool fix_boundary) {
            ReadOptions options;
            options.fix_boundary = fix_boundary;
            return read_mesh(path, options).mesh;
        },
        py::arg("path"), py::arg("fix_boundary") = true,
        "Reads a mesh (.vtk, .vtu, .msh, .mesh, .node/.ele); without a `fixed` point field in the file the boundary "
        "vertices are fixed (fix_boundary=False: none)");
    m.def(
        "write",
        [](const std::string& path, const Mesh& mesh, bool ascii) {
            WriteOptions options;
            options.encoding = ascii ? Encoding::Ascii : Encoding::Binary;
            write_mesh(path, mesh, options);
        },
        py::arg("path"), py::arg("mesh"), py::arg("ascii") = false,
        "Writes a mesh (format from the extension) through a temporary file renamed over the path");
    m.def(
        "_quality",
        [](const Mesh& mesh) {
            std::string json;
            {
                py::gil_scoped_release free;
                json = QualityAssessor().assess(mesh).to_json();
            }
            return json;
        },
        py::arg("mesh"));
    m.def("_run_on", &run_on, py::arg("mesh"), py::arg("yaml"), py::arg("sets"), py::arg("observer"));
    m.def(
        "_run",
        [](const std::string& yaml, const std::string& source) {
            const config::RunSpec spec = config::parse_config(yaml, source);
            std::string json;
            {
                py::gil_scoped_release free;
                json = config::run(spec).to_json();
            }
            return json;
        },
        py::arg("yaml"), py::arg("source"));
    m.def(
        "_run_file",
        [](const std::string& path) {
            const config::RunSpec spec = config::read_config(path);
            std::string json;
            {
                py::gil_scoped_release free;
                json = config::run(spec).to_json();
            }
            return json;
        },
        py::arg("path"));
}
