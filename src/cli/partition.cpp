#include <chrono>
#include <iomanip>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "commands.hpp"
#include "mpi_session.hpp"
#include "paloverde/core/error.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/parallel/partition.hpp"

namespace paloverde::cli {

void add_partition_command(CLI::App& app, int& exit_code) {
    struct Options {
        std::string mesh, output;
        std::vector<int> parts;
        bool json = false;
        bool free_all = false;
    };
    auto options = std::make_shared<Options>();
    CLI::App* cmd = app.add_subcommand(
        "partition", "Split a mesh into pieces for a distributed run (METIS k-way on the vertices), or count what a "
                     "split would communicate for several part counts (the paper's Table 2)");
    cmd->add_option("mesh", options->mesh, "Mesh file (.vtk .vtu .msh .mesh .node/.ele)")->required();
    cmd->add_option("-n,--parts", options->parts, "Number of parts; several numbers print the statistics of each")
        ->required()
        ->check(CLI::PositiveNumber);
    cmd->add_option("-o,--output", options->output,
                    "Write the pieces: OUT.pvtu (with OUT/OUT_<rank>.vtu) or Mesquite-style OUT.vtk (OUT_<rank>.vtk); "
                    "run them with `mpirun -n K paloverde improve OUT.pvtu ...`");
    cmd->add_flag("--json", options->json, "Print the statistics as JSON");
    cmd->add_flag("--no-fixed-boundary", options->free_all,
                  "Without a `fixed` field in the file, treat every vertex as free (default: boundary fixed)");
    cmd->callback([options, &exit_code] {
        if (!options->output.empty() && options->parts.size() != 1)
            throw OptionError("--output writes one partition: give a single --parts count");
        if (!options->output.empty()) MpiSession::require("paloverde partition --output (pieces for a distributed run)");
        ReadOptions read;
        read.fix_boundary = !options->free_all;
        const MeshFile file = read_mesh(options->mesh, read);
        nlohmann::json rows = nlohmann::json::array();
        if (!options->json)
            std::cout << std::setw(6) << "parts" << std::setw(16) << "ghost copies" << std::setw(16) << "shared vertices"
                      << std::setw(10) << "edges" << std::setw(8) << "colors" << std::setw(12) << "neighbours"
                      << std::setw(18) << "largest (elems)" << std::setw(12) << "seconds" << "\n";
        for (int k : options->parts) {
            const auto start = std::chrono::steady_clock::now();
            const auto part = partition_vertices(file.mesh, k);
            const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            const auto s = partition_statistics(file.mesh, part, k);
            rows.push_back({{"parts", k},
                            {"ghost_copies", s.ghost_copies},
                            {"shared_vertices", s.shared_vertices},
                            {"process_edges", s.process_edges},
                            {"colors", s.colors},
                            {"max_neighbours", s.max_neighbours},
                            {"largest_part_elements", s.largest_part_elements},
                            {"metis_seconds", seconds}});
            if (!options->json)
                std::cout << std::setw(6) << k << std::setw(16) << s.ghost_copies << std::setw(16) << s.shared_vertices
                          << std::setw(10) << s.process_edges << std::setw(8) << s.colors << std::setw(12)
                          << s.max_neighbours << std::setw(18) << s.largest_part_elements << std::setw(12)
                          << std::setprecision(3) << seconds << "\n";
        }
        if (options->json) std::cout << nlohmann::json{{"mesh", options->mesh}, {"partitions", rows}}.dump(2) << "\n";
        if (!options->output.empty()) {
            MpiSession::write_pieces(file.mesh, options->parts.front(), options->output);
            if (!options->json) std::cout << "wrote " << options->parts.front() << " pieces: " << options->output << "\n";
        }
        exit_code = kDone;
    });
}

}  // namespace paloverde::cli
