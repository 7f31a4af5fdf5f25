// A build without MPI (PALOVERDE_MPI=OFF; this file is built only there): whatever asks for a
// distributed run is refused with a clear error and a non-zero exit code, and nothing is written:
// 2 (bad usage) for a config or flags that ask for one, as for any config error; 1 otherwise.
#include <boost/test/unit_test.hpp>
#include <cstdlib>
#include <filesystem>

#include "paloverde/config/run.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "support/test_support.hpp"

namespace pv = paloverde;
namespace cfg = paloverde::config;
namespace fs = std::filesystem;
using pv::test::run_cli;

namespace {
const std::string kCube = PALOVERDE_SOURCE_DIR "/examples/data/tangled_cube.vtk";
std::string in_quotes(const fs::path& p) { return "'" + p.string() + "'"; }
bool has(const std::string& text, const std::string& word) { return text.find(word) != std::string::npos; }

// Refused as a build without MPI does, naming what asked for it.
void check_refused(const pv::test::CommandResult& result, const std::string& asked_by, int exit_code) {
    BOOST_TEST_INFO(result.output);
    BOOST_TEST(result.exit_code == exit_code);
    BOOST_TEST(has(result.output, "this build has no MPI"));
    BOOST_TEST(has(result.output, "PALOVERDE_MPI=ON"));
    BOOST_TEST(has(result.output, asked_by));
}
}  // namespace

BOOST_AUTO_TEST_SUITE(no_mpi)

BOOST_AUTO_TEST_CASE(a_partitioned_config_is_refused_naming_its_key) {
    const pv::test::ScratchDir dir("no_mpi_config");
    pv::test::write_file(dir / "run.yaml", "input: {mesh: " + in_quotes(kCube) + "}\npartition: {parts: 2}\n"
                                           "output: {mesh: " + in_quotes(dir / "out.vtk") + "}\n");
    check_refused(run_cli("run " + in_quotes(dir / "run.yaml")), "run.yaml:2:", 2);
    BOOST_TEST(!fs::exists(dir / "out.vtk"));
    // Serially the same config runs.
    const auto serial = run_cli("run -q " + in_quotes(dir / "run.yaml") + " --set partition.parts=1");
    BOOST_TEST_INFO(serial.output);
    BOOST_TEST(serial.exit_code == 0);
    BOOST_TEST(fs::exists(dir / "out.vtk"));
}

BOOST_AUTO_TEST_CASE(improve_refuses_pieces_in_and_out) {
    const pv::test::ScratchDir dir("no_mpi_improve");
    check_refused(run_cli("improve " + in_quotes(kCube) + " -o " + in_quotes(dir / "out.pvtu")), "output.mesh", 2);
    BOOST_TEST(!fs::exists(dir / "out.pvtu"));
    pv::test::write_file(dir / "in.pvtu", "<VTKFile type=\"PUnstructuredGrid\"/>\n");
    check_refused(run_cli("improve " + in_quotes(dir / "in.pvtu") + " -o " + in_quotes(dir / "out.vtk")), "input.mesh", 2);
    BOOST_TEST(!fs::exists(dir / "out.vtk"));
}

BOOST_AUTO_TEST_CASE(partition_writes_no_pieces_but_still_counts) {
    const pv::test::ScratchDir dir("no_mpi_partition");
    check_refused(run_cli("partition " + in_quotes(kCube) + " -n 2 -o " + in_quotes(dir / "pieces.pvtu")), "--output", 1);
    BOOST_TEST(fs::is_empty(dir.path()));
    // The statistics need METIS only.
    const auto counted = run_cli("partition --json " + in_quotes(kCube) + " -n 2 4");
    BOOST_TEST_INFO(counted.output);
    BOOST_TEST(counted.exit_code == 0);
    BOOST_TEST(has(counted.output, "ghost_copies"));
}

BOOST_AUTO_TEST_CASE(under_an_mpi_launcher_every_command_is_refused) {
    // What mpirun sets in each process it starts.
    ::setenv("OMPI_COMM_WORLD_SIZE", "2", 1);
    const auto result = run_cli("quality " + in_quotes(kCube));
    ::unsetenv("OMPI_COMM_WORLD_SIZE");
    check_refused(result, "mpirun", 1);
}

BOOST_AUTO_TEST_CASE(the_library_refuses_a_partitioned_spec) {
    BOOST_TEST(!cfg::runs_distributed(cfg::parse_config("input: {mesh: in.vtk}\n", "run.yaml")));
    const cfg::RunSpec spec = cfg::parse_config("input: {mesh: in.vtk}\npartition: {parts: 3}\n", "run.yaml");
    BOOST_TEST(cfg::runs_distributed(spec));
    BOOST_CHECK_EXCEPTION(cfg::run(spec), cfg::ConfigError, [](const cfg::ConfigError& e) {
        return has(e.what(), "this build has no MPI") && has(e.what(), "run.yaml:2:") && has(e.what(), "partition.parts");
    });
}

BOOST_AUTO_TEST_SUITE_END()
