#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "commands.hpp"
#include "paloverde/assess/quality_assessor.hpp"
#include "paloverde/config/run.hpp"
#include "paloverde/io/atomic_file.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/mesh/boundary_surface.hpp"

namespace paloverde::cli {

void add_quality_command(CLI::App& app, int& exit_code) {
    struct Options {
        std::string mesh;
        bool json = false;
        std::string json_file;
        bool free_all = false;
        std::string orientation = "auto";
    };
    auto options = std::make_shared<Options>();
    CLI::App* cmd = app.add_subcommand("quality", "Report the quality of a mesh: min/max/mean/rms of each metric, "
                                                  "inverted elements, and the elements no smoother can move");
    cmd->add_option("mesh", options->mesh, "Mesh file (.vtk .vtu .msh .mesh .node/.ele)")->required();
    cmd->add_flag("--json", options->json, "Print the report as JSON instead of a table");
    cmd->add_option("--json-file", options->json_file, "Also write the JSON report to this file");
    cmd->add_flag("--no-fixed-boundary", options->free_all,
                  "Without a `fixed` field in the file, treat every vertex as free (default: boundary fixed)");
    add_orientation_option(*cmd, options->orientation);
    cmd->callback([options, &exit_code] {
        ReadOptions read;
        read.fix_boundary = !options->free_all;
        read.orientation = orientation_mode(options->orientation);
        MeshFile file = read_mesh(options->mesh, read);
        // A surface mesh's triangles are rated as the solvers rate them: about the surface's normal
        // at each (docs/surfaces.md).
        const bool surface = is_surface_mesh(file.mesh);
        if (surface) file.mesh.set_surface_normals(BoundarySurface(file.mesh).normals_of(file.mesh));
        const QualityReport report = QualityAssessor().assess(file.mesh);
        const OrientationDecision& o = file.orientation;
        nlohmann::json json = nlohmann::json::parse(report.to_json());
        json["input_orientation"] = nlohmann::json::parse(config::to_json(o));
        if (options->json) std::cout << json.dump(2) << "\n";
        else
            std::cout << options->mesh << ": " << describe_cells(file.mesh) << "; "
                      << o.describe(file.mesh.kind())
                      << (surface ? "; a surface: each triangle rated about the surface's normal at it" : "")
                      << "\n" << report.to_text();
        if (!options->json_file.empty()) write_text_file(options->json_file, json.dump(2) + "\n");
        exit_code = kDone;
    });
}

}  // namespace paloverde::cli
