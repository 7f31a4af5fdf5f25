// Partitioned (MPI) runs from a config. Two suites, both disabled in the plain `config` run so
// that it never starts MPI (LeakSanitizer cannot run with Open MPI, see tests/CMakeLists.txt):
//   partitioned          in this process, one rank (CTest `config_partitioned`);
//   partitioned_mpirun   `paloverde run` under mpirun, compared with the serial run (CTest
//                        `config_mpirun_np2`, `config_mpirun_np4`), with the ranks and the
//                        launcher after `--`: test_config --run_test=partitioned_mpirun -- N MPIEXEC ARGS...
#include <mpi.h>

#include <algorithm>
#include <array>
#include <boost/test/unit_test.hpp>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <sys/wait.h>

#include "paloverde/config/config.hpp"
#include "paloverde/config/run.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/mesh/renumber.hpp"
#include "paloverde/parallel/distributed_mesh.hpp"
#include "support/cell_meshes.hpp"
#include "support/io_checks.hpp"
#include "support/solver_checks.hpp"
#include "support/test_support.hpp"

namespace pv = paloverde;
namespace cfg = paloverde::config;
namespace utf = boost::unit_test;
using pv::test::run_cli;

namespace {

// MPI is started by the first test that needs it and finalized at the end of the program.
struct FinalizeMpi {
    ~FinalizeMpi() {
        int initialized = 0, finalized = 0;
        MPI_Initialized(&initialized);
        MPI_Finalized(&finalized);
        if (initialized && !finalized) MPI_Finalize();
    }
};
struct StartMpi {
    StartMpi() {
        int initialized = 0, provided = 0;
        MPI_Initialized(&initialized);
        if (!initialized) MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
    }
};

bool has(const std::string& text, const std::string& word) { return text.find(word) != std::string::npos; }
std::string quoted(const std::filesystem::path& p) { return "'" + p.string() + "'"; }
std::filesystem::path tangled() { return pv::test::shared_data("mesquite/tets/tet_4_tangled.vtk"); }

// The largest coordinate difference, relative to the largest coordinate.
double relative_difference(const std::filesystem::path& a, const std::filesystem::path& b) {
    const auto x = pv::read_mesh(a).mesh, y = pv::read_mesh(b).mesh;
    BOOST_REQUIRE(x.coordinates().size() == y.coordinates().size());
    double extent = 0.0, difference = 0.0;
    for (std::size_t i = 0; i < x.coordinates().size(); ++i) {
        extent = std::max(extent, std::abs(x.coordinates()[i]));
        difference = std::max(difference, std::abs(x.coordinates()[i] - y.coordinates()[i]));
    }
    return difference / extent;
}

// A queue that untangles and improves with the global solver, and its outputs in `dir`.
std::string global_config(const std::filesystem::path& mesh, const std::filesystem::path& dir) {
    return "input: {mesh: " + mesh.string() + "}\nthreads: 1\n"
           "queue:\n  - assess: before\n  - untangle: global\n"
           "  - improve: {name: global, termination: {max_iterations: 25}}\n  - assess: after\n"
           "output:\n  mesh: " + (dir / "out.vtu").string() + "\n  summary: " + (dir / "s.json").string() +
           "\n  history: " + (dir / "h.csv").string() + "\n";
}

std::vector<std::string> step_labels(const cfg::MethodResult& m) {
    std::vector<std::string> labels;
    for (const auto& s : m.queue.steps)
        labels.push_back(s.label + (std::holds_alternative<pv::QualityReport>(s.outcome) ? ":assess" : ":improve"));
    return labels;
}

// A mesh gathered from pieces against the serial result: the pieces number the vertices in the
// canonical order (reverse Cuthill-McKee of the input), so gathered vertex i is the serial mesh's
// vertex old_vertex[i]. The largest coordinate difference; every element must match too.
double gathered_difference(const std::filesystem::path& input, const std::filesystem::path& serial,
                           const std::filesystem::path& gathered) {
    const auto order = pv::locality_order(pv::read_mesh(input).mesh);
    const auto s = pv::read_mesh(serial).mesh, g = pv::read_mesh(gathered).mesh;
    BOOST_REQUIRE(g.num_vertices() == s.num_vertices());
    BOOST_REQUIRE(g.num_elements() == s.num_elements());
    double difference = 0.0;
    for (pv::VertexId v = 0; v < g.num_vertices(); ++v) {
        const auto o = static_cast<std::size_t>(order.old_vertex[static_cast<std::size_t>(v)]);
        BOOST_TEST(g.fixed()[v] == s.fixed()[o]);
        for (std::size_t c = 0; c < 3; ++c)
            difference = std::max(difference, std::abs(g.coordinates()[3 * static_cast<std::size_t>(v) + c] - s.coordinates()[3 * o + c]));
    }
    const auto elements = [](const pv::Mesh& m, std::span<const pv::VertexId> map) {
        std::vector<std::array<pv::VertexId, 4>> keys;
        for (pv::ElementId e = 0; e < m.num_elements(); ++e) {
            std::array<pv::VertexId, 4> key{-1, -1, -1, -1};
            for (int c = 0; c < m.corners(); ++c) key[c] = map.empty() ? m.element(e)[c] : map[m.element(e)[c]];
            keys.push_back(key);
        }
        std::sort(keys.begin(), keys.end());
        return keys;
    };
    BOOST_TEST((elements(g, order.old_vertex) == elements(s, {})));
    return difference;
}

std::size_t lines_of(const std::string& text) { return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n')); }

}  // namespace

BOOST_TEST_GLOBAL_FIXTURE(FinalizeMpi);

BOOST_AUTO_TEST_SUITE(partitioned, *utf::disabled() * utf::fixture<StartMpi>())

BOOST_AUTO_TEST_CASE(a_partitioned_config_runs_on_one_rank_as_the_serial_run) {
    const pv::test::ScratchDir serial("partitioned_serial"), split("partitioned_split");
    const auto serial_result = cfg::run(cfg::parse_config(global_config(tangled(), serial.path()), "run.yaml"));
    // output.pieces makes it a partitioned run; without mpirun it has one rank.
    const auto spec = cfg::parse_config(global_config(tangled(), split.path()) + "  pieces: " +
                                            (split / "p.pvtu").string() + "\n", "run.yaml");
    BOOST_TEST(spec.partitioned());
    int iterations_seen = 0, methods_done = 0;
    cfg::RunHooks hooks;
    hooks.on_iteration = [&](std::string_view method, std::string_view step, const pv::IterationRecord&) {
        BOOST_TEST(method == "run");
        BOOST_TEST((step == "untangle" || step == "global"));
        ++iterations_seen;
    };
    hooks.on_method_done = [&](const cfg::MethodResult&) { ++methods_done; };
    const auto result = cfg::run(spec, hooks);
    BOOST_TEST(methods_done == 1);
    BOOST_TEST(result.exit_code() == 0);
    BOOST_REQUIRE(result.parallel.has_value());
    BOOST_TEST(result.parallel->ranks == 1);
    BOOST_TEST(result.parallel->vertices == 129);
    BOOST_TEST(result.parallel->elements == 408);
    BOOST_TEST(result.parallel->ghost_copies == 0);
    BOOST_TEST(!serial_result.parallel.has_value());
    BOOST_REQUIRE(result.methods.size() == 1u);
    const auto& m = result.methods[0];
    BOOST_TEST(m.before.inverted == 9);
    BOOST_TEST(m.after.inverted == 0);
    BOOST_TEST(step_labels(m) == step_labels(serial_result.methods[0]));
    BOOST_TEST(m.iterations == serial_result.methods[0].iterations);
    BOOST_TEST(iterations_seen >= m.iterations);
    BOOST_TEST(m.worst_after == serial_result.methods[0].worst_after, boost::test_tools::tolerance(1e-10));
    BOOST_TEST(relative_difference(serial / "out.vtu", split / "out.vtu") <= 1e-10);
    BOOST_TEST(std::filesystem::exists(split / "p.pvtu"));
    BOOST_TEST(std::filesystem::exists(split / "p" / "p_0.vtu"));
    // The summary has the serial keys and the distributed numbers; the history the same rows.
    const auto summary = nlohmann::json::parse(pv::test::read_text(split / "s.json"));
    BOOST_TEST(summary["inverted_after"].get<int>() == 0);
    BOOST_TEST(summary["parallel"]["ranks"].get<int>() == 1);
    BOOST_TEST(summary["parallel"]["exchange"].get<std::string>() == "colored");
    for (const char* stage : {"read", "partition", "distribute", "schedule", "solve", "write"})
        BOOST_TEST(summary["parallel"]["seconds"][stage].get<double>() >= 0.0, stage);
    BOOST_TEST(summary["parallel"]["seconds"]["solve"].get<double>() > 0.0);
    BOOST_TEST(lines_of(pv::test::read_text(split / "h.csv")) == lines_of(pv::test::read_text(serial / "h.csv")));
    BOOST_TEST(has(result.report(), "parallel: 1 rank, 129 vertices, 408 elements"));
}

BOOST_AUTO_TEST_CASE(a_study_runs_every_method_from_the_input) {
    const pv::test::ScratchDir dir("partitioned_study");
    const std::string yaml = "input: {mesh: " + tangled().string() + "}\nthreads: 1\nparallel: {exchange: root}\n"
                             "study:\n  - name: global\n    queue: untangle_then_improve\n"
                             "  - name: local\n    queue: [improve: {name: local, termination: {max_iterations: 8}}]\n"
                             "output:\n  mesh: " + (dir / "m_{method}.vtk").string() + "\n  pieces: " +
                             (dir / "p_{method}.pvtu").string() + "\n  table: " + (dir / "t.csv").string() + "\n";
    const auto result = cfg::run(cfg::parse_config(yaml, "study.yaml"));
    BOOST_REQUIRE(result.methods.size() == 2u);
    BOOST_TEST(result.parallel->exchange == "root_relayed");
    for (const auto& m : result.methods) {
        BOOST_TEST(m.before.inverted == 9);
        BOOST_TEST(m.after.inverted == 0);
    }
    for (const char* name : {"m_global.vtk", "m_local.vtk", "p_global.pvtu", "p_local.pvtu"})
        BOOST_TEST(std::filesystem::exists(dir / name), name);
    BOOST_TEST(lines_of(pv::test::read_text(dir / "t.csv")) == 3u);
}

BOOST_AUTO_TEST_CASE(wrappers_run_the_same_steps_on_a_distributed_mesh) {
    const pv::test::ScratchDir dir("partitioned_wrappers");
    const auto tire = pv::test::shared_data("mesquite/tets/tire.vtk");
    for (const std::string name : {"untangle", "shape_improvement", "local_shape_improvement", "untangle_then_improve"}) {
        BOOST_TEST_CONTEXT(name) {
            const auto& mesh = name == "shape_improvement" || name == "local_shape_improvement" ? tire : tangled();
            const std::string limit = name == "untangle" ? "untangle_termination" : "termination";
            const std::string yaml = "input: {mesh: " + mesh.string() + "}\nthreads: 1\nqueue:\n  - wrapper: {name: " +
                                     name + ", " + limit + ": {max_iterations: 6}}\noutput: {mesh: " +
                                     (dir / "serial.vtu").string() + "}\n";
            const auto serial = cfg::run(cfg::parse_config(yaml, "run.yaml"));
            const auto split = cfg::run(cfg::parse_config(
                yaml, "run.yaml",
                std::vector<cfg::Override>{{"output.mesh=" + (dir / "split.vtu").string()},
                                           {"output.pieces=" + (dir / "split.pvtu").string()}}));
            BOOST_REQUIRE(split.parallel.has_value());
            BOOST_TEST(step_labels(split.methods[0]) == step_labels(serial.methods[0]), boost::test_tools::per_element());
            BOOST_TEST(split.exit_code() == serial.exit_code());
            // The local smoother colors differently over MPI (docs/parallel.md); the global solver
            // gives the serial mesh.
            if (name != "local_shape_improvement")
                BOOST_TEST(relative_difference(dir / "serial.vtu", dir / "split.vtu") <= 1e-10);
        }
    }
}

BOOST_AUTO_TEST_CASE(a_run_from_pieces) {
    const pv::test::ScratchDir dir("partitioned_pieces");
    pv::DistributedMesh::write_partitioned(pv::read_mesh(tangled()).mesh, 1, dir / "in.pvtu");
    const std::string queue = "threads: 1\nqueue: untangle_then_improve\noutput: {pieces: " + (dir / "out.pvtu").string() + "}\n";
    const auto reference = cfg::run(cfg::parse_config("input: {mesh: " + tangled().string() + "}\n" + queue, "run.yaml"));
    for (const std::string& input : {"input: {pieces: [" + (dir / "in.pvtu").string() + "]}\n",
                                    "input: {mesh: " + (dir / "in.pvtu").string() + "}\n",
                                    "input: {pieces: [" + (dir / "in" / "in_0.vtu").string() + "]}\n"}) {
        BOOST_TEST_CONTEXT(input) {
            const auto result = cfg::run(cfg::parse_config(input + queue, "run.yaml"));
            BOOST_TEST(result.exit_code() == 0);
            BOOST_TEST(result.parallel->from_pieces);
            BOOST_TEST(result.methods[0].after.inverted == 0);
            BOOST_TEST(result.methods[0].iterations == reference.methods[0].iterations);
            BOOST_TEST(result.methods[0].worst_after == reference.methods[0].worst_after, boost::test_tools::tolerance(1e-10));
            BOOST_TEST(pv::read_mesh(dir / "out" / "out_0.vtu").mesh.num_elements() == 408);
        }
    }
}

// Rank 0 holds the whole mesh only to write output.mesh as one file: kept from the input, or,
// from pieces, gathered for the write (the serial mesh, in the pieces' numbering).
BOOST_AUTO_TEST_CASE(rank_0_holds_the_whole_mesh_only_to_write_it) {
    const pv::test::ScratchDir dir("partitioned_whole");
    const std::string queue = "threads: 1\nqueue: untangle_then_improve\n";
    const auto serial = cfg::run(cfg::parse_config("input: {mesh: " + tangled().string() + "}\n" + queue +
                                                       "output: {mesh: " + (dir / "serial.vtu").string() + "}\n", "run.yaml"));
    BOOST_TEST_REQUIRE(serial.exit_code() == 0);
    pv::DistributedMesh::write_partitioned(pv::read_mesh(tangled()).mesh, 1, dir / "in.pvtu");
    struct Case {
        std::string input, output, holds;
    };
    for (const Case& c : {Case{"mesh: " + tangled().string(), "mesh: " + (dir / "kept.vtu").string(), "kept"},
                          Case{"mesh: " + tangled().string(), "mesh: " + (dir / "dropped.pvtu").string(), "dropped"},
                          Case{"mesh: " + tangled().string(), "summary: " + (dir / "s.json").string(), "dropped"},
                          Case{"pieces: [" + (dir / "in.pvtu").string() + "]", "mesh: " + (dir / "gathered.vtk").string(), "gathered"},
                          Case{"mesh: " + (dir / "in.pvtu").string(), "history: " + (dir / "h.csv").string(), "never"}}) {
        BOOST_TEST_CONTEXT(c.input << ", " << c.output) {
            // output.pieces makes each a partitioned run (of one rank, in this process).
            const auto result = cfg::run(cfg::parse_config("input: {" + c.input + "}\n" + queue + "output: {" + c.output +
                                                               ", pieces: " + (dir / "p.pvtu").string() + "}\n", "run.yaml"));
            BOOST_TEST(result.exit_code() == 0);
            BOOST_REQUIRE(result.parallel.has_value());
            BOOST_TEST(result.parallel->whole_mesh_on_rank_0 == c.holds);
            BOOST_TEST(has(result.to_json(), "\"whole_mesh_on_rank_0\": \"" + c.holds + "\""));
            BOOST_TEST(result.methods[0].worst_after == serial.methods[0].worst_after, boost::test_tools::tolerance(1e-10));
        }
    }
    BOOST_TEST(relative_difference(dir / "serial.vtu", dir / "kept.vtu") <= 1e-10);
    BOOST_TEST(gathered_difference(tangled(), dir / "serial.vtu", dir / "gathered.vtk") <= 1e-10);
}

BOOST_AUTO_TEST_CASE(what_a_partitioned_run_cannot_do_is_named_before_reading) {
    struct Case {
        std::string yaml, key, where, words;
    };
    // input.mesh does not exist: each error must come before anything is read.
    for (const Case& c :
         {Case{"input: {mesh: missing.vtk}\npartition:\n  parts: 2\n", "partition.parts", "run.yaml:3:10", "mpirun -n 2"},
          Case{"input: {mesh: missing.vtk}\noutput: {pieces: p.pvtu}\nqueue:\n  - improve: smart_laplace\n",
               "queue[0].improve.name", "run.yaml:4:14", "no distributed version"},
          Case{"input: {mesh: missing.vtk}\noutput: {pieces: p.pvtu}\nqueue: laplace\n", "queue[0].wrapper.name",
               "run.yaml:3:8", "no distributed version"},
          Case{"input: {mesh: missing.vtk}\noutput: {pieces: p.pvtu}\nstudy:\n  - name: a\n    queue: [improve: global]\n"
               "  - name: b\n    queue: [improve: local]\n",
               "output.pieces", "run.yaml:2:18", "{method}"},
          Case{"input:\n  pieces: [a.vtu, b.vtu]\n", "input.pieces", "run.yaml:2:11", "mpirun -n 2"},
          Case{"input:\n  pieces: [a.pvtu, b.vtu]\n", "input.pieces", "run.yaml:2:11", "lists its pieces itself"},
          Case{"input:\n  pieces: [a.vtu]\n  fixed: boundary\n", "input.fixed", "run.yaml:3:10", "own `fixed` field"},
          Case{"input:\n  pieces: [a.vtu]\n  fixed_vertices: [3]\n", "input.fixed_vertices", "run.yaml:3:19", "pieces"}}) {
        BOOST_TEST_CONTEXT(c.yaml) {
            try {
                cfg::run(cfg::parse_config(c.yaml, "run.yaml"));
                BOOST_FAIL("no error");
            } catch (const cfg::ConfigError& e) {
                BOOST_TEST_CONTEXT(e.what()) {
                    BOOST_TEST(e.key() == c.key);
                    BOOST_TEST(e.where() == c.where);
                    BOOST_TEST(has(e.what(), c.words));
                }
            }
        }
    }
    // A piece that is not there is an input error, naming the file.
    try {
        cfg::run(cfg::parse_config("input: {pieces: [missing_piece.vtu]}\n", "run.yaml"));
        BOOST_FAIL("no error");
    } catch (const cfg::ConfigError& e) {
        BOOST_FAIL("a usage error for a missing piece: " << e.what());
    } catch (const pv::Error& e) {
        BOOST_TEST(has(e.what(), "missing_piece.vtu"), e.what());
    }
}

BOOST_AUTO_TEST_SUITE_END()

// ---------------------------------------------------------------------------------------------
// `paloverde run` under mpirun.

namespace {

struct Launch {
    int ranks = 0;
    std::string prefix;  // the launcher with its flags, shell-quoted
};

// The ranks and the launcher given after `--` (tests/CMakeLists.txt).
Launch launch() {
    const auto& suite = utf::framework::master_test_suite();
    if (suite.argc < 3)
        BOOST_FAIL("give the ranks and the MPI launcher after --: test_config --run_test=partitioned_mpirun -- 2 "
                   "mpiexec -n 2 [flags]");
    Launch l;
    l.ranks = std::stoi(suite.argv[1]);
    for (int i = 2; i < suite.argc; ++i) l.prefix += quoted(suite.argv[i]) + " ";
    return l;
}

struct RankedRun {
    std::vector<int> exit_codes;  // one per rank that finished
    std::string out, err;
};

// `paloverde ARGUMENTS` on every rank of the launcher; each rank's exit code recorded apart (the
// launcher reports only one).
RankedRun mpirun_cli(const pv::test::ScratchDir& dir, const std::string& arguments, const std::filesystem::path& cwd = {}) {
    const Launch l = launch();
    const auto codes = dir / "codes";
    std::filesystem::remove_all(codes);
    std::filesystem::create_directories(codes);
    // Each rank's shell records the exit code of its paloverde under the rank's number.
    const std::string record =
        "codes=$1; shift; \"$@\"; echo $? > \"$codes/rank_${OMPI_COMM_WORLD_RANK:-${PMIX_RANK:-${PMI_RANK:-x}}}\"";
    const std::string command = (cwd.empty() ? std::string() : "cd " + quoted(cwd) + " && ") + l.prefix + "sh -c '" + record + "' sh " + quoted(codes) + " " + quoted(PALOVERDE_CLI) +
                                " " + arguments + " > " + quoted(dir / "out.txt") + " 2> " + quoted(dir / "err.txt");
    const int status = std::system(command.c_str());
    BOOST_TEST_INFO(command);
    BOOST_TEST(WIFEXITED(status));
    RankedRun r;
    for (const auto& entry : std::filesystem::directory_iterator(codes))
        r.exit_codes.push_back(std::stoi(pv::test::read_text(entry.path())));
    r.out = pv::test::read_text(dir / "out.txt");
    r.err = pv::test::read_text(dir / "err.txt");
    return r;
}

std::size_t count_of(const std::string& text, const std::string& word) {
    std::size_t n = 0;
    for (std::size_t at = text.find(word); at != std::string::npos; at = text.find(word, at + 1)) ++n;
    return n;
}

}  // namespace

BOOST_AUTO_TEST_SUITE(partitioned_mpirun, *utf::disabled())

BOOST_AUTO_TEST_CASE(mpirun_gives_the_serial_mesh) {
    const int ranks = launch().ranks;
    // A folder per rank count: CTest may run config_mpirun_np2 and _np4 at the same time.
    const pv::test::ScratchDir dir("mpirun_same_np" + std::to_string(ranks));
    pv::test::write_file(dir / "run.yaml", global_config(tangled(), dir.path()));
    // The serial run of the same config (no mpirun, partition.parts: 1).
    const auto serial = run_cli("run -q " + quoted(dir / "run.yaml") + " --set output.mesh=" + quoted(dir / "serial.vtu"));
    BOOST_TEST_REQUIRE(serial.exit_code == 0, serial.output);
    const auto r = mpirun_cli(dir, "run " + quoted(dir / "run.yaml") + " --json --set partition.parts=" +
                                       std::to_string(ranks) + " --set output.pieces=" + quoted(dir / "p.pvtu"));
    BOOST_TEST_INFO(r.err);
    BOOST_TEST(r.exit_codes == std::vector<int>(static_cast<std::size_t>(ranks), 0), boost::test_tools::per_element());
    BOOST_TEST(relative_difference(dir / "serial.vtu", dir / "out.vtu") <= 1e-10);
    // --json from rank 0 alone, with the distributed numbers.
    const auto printed = nlohmann::json::parse(r.out);
    BOOST_TEST(printed["parallel"]["ranks"].get<int>() == ranks);
    BOOST_TEST(printed["parallel"]["ghost_copies"].get<long>() > 0);
    BOOST_TEST(printed["parallel"]["messages_per_exchange"].get<long>() >= 2);
    BOOST_TEST(printed["parallel"]["colors"].get<int>() >= 1);
    BOOST_TEST(printed["inverted_after"].get<int>() == 0);
    const auto summary = nlohmann::json::parse(pv::test::read_text(dir / "s.json"));
    BOOST_TEST(summary["parallel"] == printed["parallel"]);
    for (int p = 0; p < ranks; ++p)
        BOOST_TEST(std::filesystem::exists(dir / "p" / ("p_" + std::to_string(p) + ".vtu")), p);
    // The example of docs/config.md, from the repository's root.
    const auto example = mpirun_cli(dir, "run examples/parallel_run.yaml --json --set partition.parts=" + std::to_string(ranks) +
                                             " --set output.mesh=" + quoted(dir / "example.vtu") + " --set output.pieces=" +
                                             quoted(dir / "example.pvtu") + " --set output.summary=~ --set output.history=~",
                                    PALOVERDE_SOURCE_DIR);
    BOOST_TEST_INFO(example.err);
    BOOST_TEST(example.exit_codes == std::vector<int>(static_cast<std::size_t>(ranks), 0), boost::test_tools::per_element());
    BOOST_TEST(nlohmann::json::parse(example.out)["parallel"]["elements"].get<long>() == 11098);
    // `improve` under mpirun splits the mesh over the ranks too.
    const auto improved = mpirun_cli(dir, "improve " + quoted(tangled()) + " -q -o " + quoted(dir / "improved.vtu") +
                                              " --iterations 25 --threads 1");
    BOOST_TEST_INFO(improved.err);
    BOOST_TEST(improved.exit_codes == std::vector<int>(static_cast<std::size_t>(ranks), 0), boost::test_tools::per_element());
    const auto improved_serial = run_cli("improve " + quoted(tangled()) + " -q -o " + quoted(dir / "improved_serial.vtu") +
                                         " --iterations 25 --threads 1");
    BOOST_TEST_REQUIRE(improved_serial.exit_code == 0);
    BOOST_TEST(relative_difference(dir / "improved_serial.vtu", dir / "improved.vtu") <= 1e-10);
}

// Sliding boundary vertices under the launcher: the global solver's mesh is the serial one, from
// the whole mesh or from pieces; the local smoother's boundary slides too and stays on the
// input's (its summary says so).
BOOST_AUTO_TEST_CASE(mpirun_slides_the_boundary) {
    const int ranks = launch().ranks;
    const pv::test::ScratchDir dir("mpirun_slide_np" + std::to_string(ranks));
    const auto tire = pv::test::shared_data("mesquite/tets/tire.vtk");
    const std::string flags = " -q --boundary slide --iterations 40 --threads 1";
    const auto serial = run_cli("improve " + quoted(tire) + " -o " + quoted(dir / "serial.vtu") + flags + " --summary " +
                                quoted(dir / "serial.json"));
    BOOST_TEST_REQUIRE(serial.exit_code == 0, serial.output);
    for (const std::string method : {"global", "local"}) {
        const auto out = dir / (method + ".vtu");
        const auto summary = dir / (method + ".json");
        const auto r = mpirun_cli(dir, "improve " + quoted(tire) + " -o " + quoted(out) + " --method " + method + flags +
                                           " --summary " + quoted(summary));
        BOOST_TEST_INFO(method << ": " << r.err);
        BOOST_TEST(r.exit_codes == std::vector<int>(static_cast<std::size_t>(ranks), 0), boost::test_tools::per_element());
        const auto s = nlohmann::json::parse(pv::test::read_text(summary));
        const auto& motion = s["steps"][0]["summary"]["boundary"];
        BOOST_TEST(motion["moved"].get<long>() > 0, method);
        BOOST_TEST(motion["largest_distance"].get<double>() <= 1e-9, method);
        BOOST_TEST(s["steps"][0]["summary"]["inverted_after"].get<int>() == 0, method);
    }
    BOOST_TEST(relative_difference(dir / "serial.vtu", dir / "global.vtu") <= 1e-10);
    // From pieces, which no rank holds whole: the same run (its mesh comes out in the pieces'
    // global order, so the summaries are compared).
    const auto split = run_cli("partition " + quoted(tire) + " -n " + std::to_string(ranks) + " -o " + quoted(dir / "in.pvtu"));
    BOOST_TEST_REQUIRE(split.exit_code == 0, split.output);
    const auto r = mpirun_cli(dir, "improve " + quoted(dir / "in.pvtu") + " -o " + quoted(dir / "pieces.vtu") + flags +
                                       " --summary " + quoted(dir / "pieces.json"));
    BOOST_TEST_INFO(r.err);
    BOOST_TEST(r.exit_codes == std::vector<int>(static_cast<std::size_t>(ranks), 0), boost::test_tools::per_element());
    const auto a = nlohmann::json::parse(pv::test::read_text(dir / "serial.json"))["steps"][0]["summary"];
    const auto b = nlohmann::json::parse(pv::test::read_text(dir / "pieces.json"))["steps"][0]["summary"];
    BOOST_TEST(b["iterations"].get<int>() == a["iterations"].get<int>());
    BOOST_TEST(b["worst_after"].get<double>() == a["worst_after"].get<double>());
    BOOST_TEST(b["boundary"]["moved"].get<long>() == a["boundary"]["moved"].get<long>());
}

BOOST_AUTO_TEST_CASE(mpirun_local_and_pieces_give_the_one_rank_result) {
    const int ranks = launch().ranks;
    const pv::test::ScratchDir dir("mpirun_local_np" + std::to_string(launch().ranks));
    const auto tire = pv::test::shared_data("mesquite/tets/tire.vtk");
    pv::test::write_file(dir / "local.yaml", "input: {mesh: " + tire.string() + "}\nthreads: 1\n"
                                             "queue: [improve: {name: local, termination: {max_iterations: 4}}]\n"
                                             "output: {mesh: " + (dir / "out.vtu").string() + ", summary: " +
                                             (dir / "s.json").string() + "}\n");
    // One rank without mpirun (a partitioned config: output.pieces) against `ranks` under mpirun.
    const auto one = run_cli("run -q " + quoted(dir / "local.yaml") + " --set output.mesh=" + quoted(dir / "one.vtu") +
                             " --set output.pieces=" + quoted(dir / "one.pvtu") + " --set output.summary=" +
                             quoted(dir / "one.json"));
    BOOST_TEST_REQUIRE(one.exit_code == 0, one.output);
    const auto many = mpirun_cli(dir, "run -q " + quoted(dir / "local.yaml") + " --set partition.parts=" + std::to_string(ranks));
    BOOST_TEST_INFO(many.err);
    BOOST_TEST(many.exit_codes == std::vector<int>(static_cast<std::size_t>(ranks), 0), boost::test_tools::per_element());
    BOOST_TEST(relative_difference(dir / "one.vtu", dir / "out.vtu") <= 1e-10);

    // Pieces written by `paloverde partition`, read one per rank, written back as pieces.
    const auto split = run_cli("partition " + quoted(tire) + " -n " + std::to_string(ranks) + " -o " + quoted(dir / "in.pvtu"));
    BOOST_TEST_REQUIRE(split.exit_code == 0, split.output);
    const auto from_pieces = mpirun_cli(dir, "run -q " + quoted(dir / "local.yaml") + " --set input.mesh=~ --set 'input.pieces=[" +
                                                 (dir / "in.pvtu").string() + "]' --set output.mesh=" + quoted(dir / "out.pvtu") +
                                                 " --set output.summary=" + quoted(dir / "pieces.json"));
    BOOST_TEST_INFO(from_pieces.err);
    BOOST_TEST(from_pieces.exit_codes == std::vector<int>(static_cast<std::size_t>(ranks), 0), boost::test_tools::per_element());
    const auto a = nlohmann::json::parse(pv::test::read_text(dir / "one.json"));
    const auto b = nlohmann::json::parse(pv::test::read_text(dir / "pieces.json"));
    BOOST_TEST(b["parallel"]["from_pieces"].get<bool>());
    BOOST_TEST(b["parallel"]["ranks"].get<int>() == ranks);
    BOOST_TEST(b["iterations"] == a["iterations"]);
    BOOST_TEST(b["worst_after"].get<double>() == a["worst_after"].get<double>(), boost::test_tools::tolerance(1e-10));
    for (int p = 0; p < ranks; ++p)
        BOOST_TEST(std::filesystem::exists(dir / "out" / ("out_" + std::to_string(p) + ".vtu")), p);
}

// `mpirun -n N paloverde improve PIECES.pvtu -o whole.vtk`: rank 0 gathers the improved parts
// into one file, the serial result in the pieces' numbering. A run that splits input.mesh and
// writes pieces drops the whole mesh on rank 0 after the scatter.
BOOST_AUTO_TEST_CASE(mpirun_improve_from_pieces_writes_one_file) {
    const int ranks = launch().ranks;
    const pv::test::ScratchDir dir("mpirun_gather_np" + std::to_string(ranks));
    const auto tire = pv::test::shared_data("mesquite/tets/tire.vtk");
    const auto split = run_cli("partition " + quoted(tire) + " -n " + std::to_string(ranks) + " -o " + quoted(dir / "in.pvtu"));
    BOOST_TEST_REQUIRE(split.exit_code == 0, split.output);
    const std::string options = " -q --iterations 10 --threads 1";
    const auto serial = run_cli("improve " + quoted(tire) + " -o " + quoted(dir / "serial.vtk") + options);
    BOOST_TEST_REQUIRE(serial.exit_code == 0, serial.output);
    const auto gathered = mpirun_cli(dir, "improve " + quoted(dir / "in.pvtu") + " -o " + quoted(dir / "whole.vtk") + options +
                                              " --summary " + quoted(dir / "s.json"));
    BOOST_TEST_INFO(gathered.err);
    BOOST_TEST(gathered.exit_codes == std::vector<int>(static_cast<std::size_t>(ranks), 0), boost::test_tools::per_element());
    // The global solver moves every vertex the same on any number of ranks.
    BOOST_TEST(gathered_difference(tire, dir / "serial.vtk", dir / "whole.vtk") == 0.0);
    const auto summary = nlohmann::json::parse(pv::test::read_text(dir / "s.json"));
    BOOST_TEST(summary["parallel"]["from_pieces"].get<bool>());
    BOOST_TEST(summary["parallel"]["whole_mesh_on_rank_0"].get<std::string>() == "gathered");
    BOOST_TEST(summary["input"].get<std::string>() == (dir / "in.pvtu").string());

    const auto dropped = mpirun_cli(dir, "improve " + quoted(tire) + " -o " + quoted(dir / "out.pvtu") + options + " --json");
    BOOST_TEST(dropped.exit_codes == std::vector<int>(static_cast<std::size_t>(ranks), 0), boost::test_tools::per_element());
    BOOST_TEST(nlohmann::json::parse(dropped.out)["parallel"]["whole_mesh_on_rank_0"].get<std::string>() == "dropped");
}

// A file of the mirror convention under mpirun: split by rank 0 or read as pieces, it is flipped
// (one decision for all ranks), untangled like the original, and written back in its own order.
BOOST_AUTO_TEST_CASE(mpirun_flips_a_mirrored_input_and_writes_it_back_mirrored) {
    const int ranks = launch().ranks;
    const pv::test::ScratchDir dir("mpirun_mirror_np" + std::to_string(ranks));
    const auto mirror = pv::test::mirrored(pv::read_mesh(tangled()).mesh);
    pv::write_mesh(dir / "m.vtk", mirror);
    pv::ReadOptions as_is;
    as_is.orientation = pv::OrientationMode::AsIs;
    const auto whole = mpirun_cli(dir, "improve " + quoted(dir / "m.vtk") + " -q --untangle --threads 1 -o " +
                                           quoted(dir / "out.vtu") + " --summary " + quoted(dir / "whole.json"));
    BOOST_TEST_INFO(whole.err);
    BOOST_TEST(whole.exit_codes == std::vector<int>(static_cast<std::size_t>(ranks), 0), boost::test_tools::per_element());
    const auto split = run_cli("partition " + quoted(dir / "m.vtk") + " -n " + std::to_string(ranks) + " -o " +
                               quoted(dir / "in.pvtu"));
    BOOST_TEST_REQUIRE(split.exit_code == 0, split.output);
    const auto pieces = mpirun_cli(dir, "improve " + quoted(dir / "in.pvtu") + " -q --untangle --threads 1 -o " +
                                            quoted(dir / "out.pvtu") + " --summary " + quoted(dir / "pieces.json"));
    BOOST_TEST_INFO(pieces.err);
    BOOST_TEST(pieces.exit_codes == std::vector<int>(static_cast<std::size_t>(ranks), 0), boost::test_tools::per_element());
    for (const char* name : {"whole.json", "pieces.json"}) {
        const auto s = nlohmann::json::parse(pv::test::read_text(dir / name));
        BOOST_TEST(s["input_orientation"]["flipped"].get<bool>(), name);
        BOOST_TEST(s["inverted_before"].get<int>() == 9, name);
        BOOST_TEST(s["inverted_after"].get<int>() == 0, name);
    }
    // Written in the file's order: read as it is, the untangled mesh has every element inverted.
    const auto out = pv::read_mesh(dir / "out.vtu", as_is).mesh;
    BOOST_TEST(std::equal(out.connectivity().begin(), out.connectivity().end(), mirror.connectivity().begin(),
                          mirror.connectivity().end()));
    BOOST_TEST(pv::count_orientations(out).inverted == out.num_elements());
    for (int p = 0; p < ranks; ++p) {
        const auto piece = pv::read_mesh(dir / "out" / ("out_" + std::to_string(p) + ".vtu"), as_is).mesh;
        BOOST_TEST(pv::count_orientations(piece).inverted == piece.num_elements(), p);
    }
    // From pieces to one file: the mesh rank 0 builds from the parts keeps the convention too.
    const auto gathered = mpirun_cli(dir, "improve " + quoted(dir / "in.pvtu") + " -q --untangle --threads 1 -o " +
                                              quoted(dir / "whole.vtu"));
    BOOST_TEST_INFO(gathered.err);
    BOOST_TEST(gathered.exit_codes == std::vector<int>(static_cast<std::size_t>(ranks), 0), boost::test_tools::per_element());
    const auto whole_out = pv::read_mesh(dir / "whole.vtu", as_is).mesh;
    BOOST_TEST(whole_out.num_elements() == mirror.num_elements());
    BOOST_TEST(pv::count_orientations(whole_out).inverted == whole_out.num_elements());
}

// A tangled mesh of hexahedra under the launcher: the serial mesh, bit for bit, written with its
// cells; and from pieces to one file.
BOOST_AUTO_TEST_CASE(mpirun_improves_a_mesh_of_hexahedra) {
    const int ranks = launch().ranks;
    const pv::test::ScratchDir dir("mpirun_hexahedra_np" + std::to_string(ranks));
    const auto hexahedra = pv::test::tangled(pv::test::cube_grid(4, pv::test::Fill::Hexahedra), 1);
    const auto input = dir / "hexahedra.vtu";
    pv::write_mesh(input, hexahedra);
    const std::string options = " -q --iterations 20 --threads 1";
    const auto serial = run_cli("improve " + quoted(input) + " -o " + quoted(dir / "serial.vtu") + options + " --summary " +
                                quoted(dir / "serial.json"));
    BOOST_TEST_REQUIRE(serial.exit_code == 0, serial.output);
    const auto r = mpirun_cli(dir, "improve " + quoted(input) + " -o " + quoted(dir / "out.vtu") + options + " --summary " +
                                       quoted(dir / "out.json"));
    BOOST_TEST_INFO(r.err);
    BOOST_TEST(r.exit_codes == std::vector<int>(static_cast<std::size_t>(ranks), 0), boost::test_tools::per_element());
    BOOST_TEST(relative_difference(dir / "serial.vtu", dir / "out.vtu") == 0.0);
    const auto out = pv::read_mesh(dir / "out.vtu").mesh;
    BOOST_TEST(out.has_cells());
    BOOST_TEST(out.num_cells() == hexahedra.num_cells());
    const auto a = nlohmann::json::parse(pv::test::read_text(dir / "serial.json"));
    const auto b = nlohmann::json::parse(pv::test::read_text(dir / "out.json"));
    BOOST_TEST(b["parallel"]["elements"].get<long>() == hexahedra.num_cells());  // cells, as the reports count
    BOOST_TEST(b["steps"][0]["summary"]["iterations"] == a["steps"][0]["summary"]["iterations"]);
    BOOST_TEST(b["steps"][0]["summary"]["inverted_after"] == a["steps"][0]["summary"]["inverted_after"]);
    // Pieces of cells, gathered into one file by rank 0: the serial mesh in the canonical numbering.
    const auto split = run_cli("partition " + quoted(input) + " -n " + std::to_string(ranks) + " -o " + quoted(dir / "in.pvtu"));
    BOOST_TEST_REQUIRE(split.exit_code == 0, split.output);
    const auto gathered = mpirun_cli(dir, "improve " + quoted(dir / "in.pvtu") + " -o " + quoted(dir / "whole.vtk") + options);
    BOOST_TEST_INFO(gathered.err);
    BOOST_TEST(gathered.exit_codes == std::vector<int>(static_cast<std::size_t>(ranks), 0), boost::test_tools::per_element());
    BOOST_TEST(gathered_difference(input, dir / "serial.vtu", dir / "whole.vtk") == 0.0);
    BOOST_TEST(pv::read_mesh(dir / "whole.vtk").mesh.num_cells() == hexahedra.num_cells());
}

// Morphing on the ranks (docs/morphing.md): the reference travels with the parts, and `morph`
// under mpirun writes the serial mesh bit for bit.
BOOST_AUTO_TEST_CASE(mpirun_morph_gives_the_serial_mesh) {
    const int ranks = launch().ranks;
    const pv::test::ScratchDir dir("mpirun_morph_np" + std::to_string(ranks));
    const auto source = pv::read_mesh(pv::test::shared_data("mesquite/tets/tire.vtk"));
    const pv::Mesh& mesh = source.mesh;
    // The boundary turned by 15 degrees about the z axis.
    const double a = 15.0 * 3.14159265358979 / 180.0;
    pv::Field turn{"displacement", 3, {}};
    for (pv::VertexId v = 0; v < mesh.num_vertices(); ++v) {
        const double x = mesh.coordinates()[3 * v], y = mesh.coordinates()[3 * v + 1];
        turn.values.insert(turn.values.end(), {std::cos(a) * x - std::sin(a) * y - x, std::sin(a) * x + std::cos(a) * y - y, 0.0});
    }
    pv::write_mesh(dir / "turned.vtu", mesh, pv::WriteOptions{}, std::vector<pv::Field>{turn});
    const std::string options = " --displacement displacement --iterations 20";
    const auto serial = run_cli("morph -q " + quoted(dir / "turned.vtu") + " -o " + quoted(dir / "serial.vtu") + options);
    BOOST_TEST_REQUIRE(serial.exit_code == 0, serial.output);
    const auto r = mpirun_cli(dir, "morph -q " + quoted(dir / "turned.vtu") + " -o " + quoted(dir / "parts.vtu") + options +
                                       " --set partition.parts=" + std::to_string(ranks));
    BOOST_TEST_INFO(r.err);
    BOOST_TEST(r.exit_codes == std::vector<int>(static_cast<std::size_t>(ranks), 0), boost::test_tools::per_element());
    BOOST_TEST(relative_difference(dir / "serial.vtu", dir / "parts.vtu") == 0.0);
    // Pieces carry no reference: refused on every rank, said once.
    const auto pieces = mpirun_cli(dir, "morph -q " + quoted(dir / "turned.vtu") + " -o " + quoted(dir / "x.pvtu") + options +
                                            " --set partition.parts=" + std::to_string(ranks) + " --set input.mesh=" +
                                            quoted(dir / "in.pvtu"));
    BOOST_TEST(pieces.exit_codes == std::vector<int>(static_cast<std::size_t>(ranks), 2), boost::test_tools::per_element());
    BOOST_TEST(count_of(pieces.err, "carries no reference") == 1u, pieces.err);
}

BOOST_AUTO_TEST_CASE(mpirun_bad_input_fails_on_every_rank_and_says_so_once) {
    const int ranks = launch().ranks;
    const pv::test::ScratchDir dir("mpirun_bad_np" + std::to_string(launch().ranks));
    pv::test::write_file(dir / "run.yaml", "input: {mesh: " + tangled().string() + "}\npartition:\n  parts: " +
                                               std::to_string(ranks + 1) + "\n");
    auto r = mpirun_cli(dir, "run " + quoted(dir / "run.yaml"));
    BOOST_TEST(r.exit_codes == std::vector<int>(static_cast<std::size_t>(ranks), 2), boost::test_tools::per_element());
    BOOST_TEST(count_of(r.err, "partition.parts: must equal the number of MPI ranks") == 1u, r.err);
    BOOST_TEST(has(r.err, "run.yaml:3:10: partition.parts"), r.err);
    // Missing pieces: a .pvtu that is not there, and a listed piece that is not there.
    r = mpirun_cli(dir, "run --set 'input.pieces=[" + (dir / "missing.pvtu").string() + "]'");
    BOOST_TEST(r.exit_codes == std::vector<int>(static_cast<std::size_t>(ranks), 1), boost::test_tools::per_element());
    BOOST_TEST(count_of(r.err, "missing.pvtu") == 1u, r.err);
    std::string listed;
    for (int p = 0; p < ranks; ++p) listed += (p ? ", " : "") + (dir / ("piece_" + std::to_string(p) + ".vtu")).string();
    r = mpirun_cli(dir, "run --set 'input.pieces=[" + listed + "]'");
    BOOST_TEST(r.exit_codes == std::vector<int>(static_cast<std::size_t>(ranks), 1), boost::test_tools::per_element());
    BOOST_TEST(count_of(r.err, "paloverde: error:") == 1u, r.err);
    BOOST_TEST(has(r.err, "piece_0.vtu"), r.err);
    // A serial config under mpirun says what to set.
    r = mpirun_cli(dir, "run --set input.mesh=" + quoted(tangled()));
    BOOST_TEST(r.exit_codes == std::vector<int>(static_cast<std::size_t>(ranks), 2), boost::test_tools::per_element());
    BOOST_TEST(count_of(r.err, "partition.parts: " + std::to_string(ranks)) == 1u, r.err);
}

BOOST_AUTO_TEST_SUITE_END()

// In the plain `config` run MPI is never started: a partitioned run says what it needs, after
// the config's own errors.
BOOST_AUTO_TEST_SUITE(partitioned_without_mpi)

BOOST_AUTO_TEST_CASE(a_partitioned_run_asks_for_mpi_init) {
    int initialized = 0;
    MPI_Initialized(&initialized);
    if (initialized) {
        BOOST_TEST_MESSAGE("MPI was started by another suite of this run; nothing to check");
        return;
    }
    const std::string yaml = "input: {mesh: missing.vtk}\noutput: {pieces: p.pvtu}\n";
    BOOST_CHECK_THROW(cfg::run(cfg::parse_config(yaml + "partition: {parts: 3}\n", "run.yaml")), cfg::ConfigError);
    try {
        cfg::run(cfg::parse_config(yaml, "run.yaml"));
        BOOST_FAIL("no error");
    } catch (const cfg::ConfigError& e) {
        BOOST_FAIL("a config error: " << e.what());
    } catch (const pv::Error& e) {
        BOOST_TEST(has(e.what(), "call MPI_Init before config::run"), e.what());
    }
}

BOOST_AUTO_TEST_SUITE_END()
