#include <memory>
#include <string>

#include "commands.hpp"
#include "paloverde/core/error.hpp"
#include "paloverde/io/mesh_io.hpp"

namespace paloverde::cli {

void add_convert_command(CLI::App& app, int& exit_code) {
    struct Options {
        std::string input, output;
        bool ascii = false;
    };
    auto options = std::make_shared<Options>();
    CLI::App* cmd = app.add_subcommand("convert", "Convert a mesh between formats (chosen by extension), keeping "
                                                  "its fields and fixed flags where the format can hold them");
    cmd->add_option("input", options->input, "Mesh to read")->required();
    cmd->add_option("output", options->output, "Mesh to write (.vtk .vtu .msh .mesh)")->required();
    cmd->add_flag("--ascii", options->ascii, "Write text instead of binary where the format has both");
    cmd->callback([options, &exit_code] {
        const MeshFile file = read_mesh(options->input);
        WriteOptions write;
        write.encoding = options->ascii ? Encoding::Ascii : Encoding::Binary;
        write_mesh(options->output, file.mesh, write, file.point_fields, file.cell_fields);
        exit_code = kDone;
    });
}

}  // namespace paloverde::cli
