#include <iostream>
#include <nlohmann/json.hpp>
#include <memory>
#include <string>

#include "commands.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/mesh/orientation.hpp"
#include "paloverde/mesh/perturb.hpp"

namespace paloverde::cli {

void add_perturb_command(CLI::App& app, int& exit_code) {
    struct Options {
        std::string input, output;
        bool boundary = false, only_boundary = false, quiet = false, ascii = false, json = false;
        PerturbOptions perturb;
        std::string orientation = "auto";
    };
    auto o = std::make_shared<Options>();
    CLI::App* cmd = app.add_subcommand("perturb", "Make a tangled test mesh: move vertices at random (reproducibly) by "
                                                  "up to a multiple of their local edge length");
    cmd->add_option("input", o->input, "Mesh to perturb")->required();
    cmd->add_option("-o,--output", o->output, "Where to write the perturbed mesh")->required();
    cmd->add_option("--fraction", o->perturb.fraction, "Fraction of the eligible vertices to move, in [0, 1]")
        ->capture_default_str();
    cmd->add_option("--amount", o->perturb.amount, "Largest move, in local edge lengths")->capture_default_str();
    cmd->add_option("--seed", o->perturb.seed, "Random seed")->capture_default_str();
    cmd->add_flag("--boundary", o->boundary, "Also move fixed (boundary) vertices");
    cmd->add_flag("--only-boundary", o->only_boundary, "Move only fixed (boundary) vertices, as the seed paper did");
    cmd->add_flag("--ascii", o->ascii, "Write text where the format has a binary form");
    add_orientation_option(*cmd, o->orientation);
    cmd->add_flag("--json", o->json, "Print what was done as JSON (moved, elements, inverted, degenerate)");
    cmd->add_flag("-q,--quiet", o->quiet, "Print nothing but errors");
    cmd->callback([o, &exit_code] {
        PerturbOptions options = o->perturb;
        options.boundary = o->boundary || o->only_boundary;
        options.interior = !o->only_boundary;
        options.validate();
        ReadOptions read;
        read.orientation = orientation_mode(o->orientation);
        MeshFile file = read_mesh(o->input, read);
        const VertexId moved = perturb(file.mesh, options);
        WriteOptions write;
        write.encoding = o->ascii ? Encoding::Ascii : Encoding::Binary;
        // The fixed flags travel with the mesh, so the boundary stays what it was.
        write_mesh(o->output, file.mesh, write, file.point_fields, file.cell_fields);
        const auto counts = count_orientations(file.mesh);
        if (o->json) {
            std::cout << nlohmann::json{{"output", o->output}, {"moved", moved}, {"elements", file.mesh.num_cells()},
                                        {"inverted", counts.inverted}, {"degenerate", counts.degenerate}}
                             .dump(2)
                      << "\n";
        } else if (!o->quiet) {
            std::cout << "moved " << moved << " vertices; " << counts.inverted << " of " << file.mesh.num_cells()
                      << " elements inverted, " << counts.degenerate << " degenerate\n";
        }
        exit_code = kDone;
    });
}

}  // namespace paloverde::cli
