#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "commands.hpp"
#include "paloverde/core/error.hpp"
#include "paloverde/io/mesh_io.hpp"

namespace paloverde::cli {

void add_convert_command(CLI::App& app, int& exit_code) {
    struct Options {
        std::string input, output;
        bool ascii = false, json = false;
    };
    auto options = std::make_shared<Options>();
    CLI::App* cmd = app.add_subcommand("convert", "Convert a mesh between formats (chosen by extension), keeping "
                                                  "its fields and fixed flags where the format can hold them");
    cmd->add_option("input", options->input, "Mesh to read")->required();
    cmd->add_option("output", options->output, "Mesh to write (.vtk .vtu .msh .mesh)")->required();
    cmd->add_flag("--ascii", options->ascii, "Write text instead of binary where the format has both");
    cmd->add_flag("--json", options->json, "Print what was written as JSON (vertices, elements, format, fields)");
    cmd->callback([options, &exit_code] {
        const MeshFile file = read_mesh(options->input);
        WriteOptions write;
        write.encoding = options->ascii ? Encoding::Ascii : Encoding::Binary;
        write_mesh(options->output, file.mesh, write, file.point_fields, file.cell_fields);
        if (options->json) {
            nlohmann::json fields = nlohmann::json::array();
            for (const auto& f : file.point_fields) fields.push_back(f.name);
            for (const auto& f : file.cell_fields) fields.push_back(f.name);
            std::cout << nlohmann::json{{"input", options->input},
                                        {"output", options->output},
                                        {"format", std::string(to_string(format_from_extension(options->output)))},
                                        {"vertices", file.mesh.num_vertices()},
                                        {"elements", file.mesh.num_cells()},
                                        {"fields", fields}}
                             .dump(2)
                      << "\n";
        }
        exit_code = kDone;
    });
}

}  // namespace paloverde::cli
