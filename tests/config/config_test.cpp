// Run configs: every key resolved and written back, errors that name the key and the line, --set,
// runs and studies from a config, and the command line that stands for one.
#include <boost/test/unit_test.hpp>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "paloverde/config/config.hpp"
#include "paloverde/config/run.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/wrappers.hpp"
#include "support/io_checks.hpp"
#include "support/test_support.hpp"

namespace pv = paloverde;
namespace cfg = paloverde::config;
using pv::test::run_cli;

namespace {

std::string quoted(const std::filesystem::path& p) { return "'" + p.string() + "'"; }
bool has(const std::string& text, const std::string& word) { return text.find(word) != std::string::npos; }
std::filesystem::path tangled() { return pv::test::shared_data("mesquite/tets/tet_4_tangled.vtk"); }

// The ConfigError that parsing `yaml` (with overrides) throws; fails the test if none.
cfg::ConfigError error_of(const std::string& yaml, std::vector<cfg::Override> overrides = {}) {
    try {
        cfg::parse_config(yaml, "run.yaml", overrides);
    } catch (const cfg::ConfigError& e) {
        return e;
    }
    BOOST_FAIL("no ConfigError for:\n" << yaml);
    throw;  // not reached
}

// Every key of a config that uses every kind of step, a study and non-default values.
const char* const kRich = R"(input:
  mesh: in.vtk
  fixed: boundary
  fixed_vertices: [3, 7]
threads: 1
study:
  - name: mixed
    queue:
      - assess: {label: start, metrics: [aspect_ratio, min_dihedral_deg], histogram_bins: 4}
      - untangle: {name: global, untangle_termination: {max_iterations: 40}}
      - improve:
          name: global
          direction: steepest_ascent
          objective: {name: p_mean, p: -4}
          metric: {name: mean_ratio, hybrid_sharpness: 12.5}
          termination: {max_iterations: 9, target_worst_quality: 0.25}
      - improve: {name: local, coloring: greedy, improve_below: 0.3}
      - improve: {name: smart_laplace, label: smooth}
      - improve: laplace
      - wrapper: {name: laplace, smart: false}
  - name: wrapped
    queue: untangle_then_improve
output:
  mesh: out_{method}.vtu
  ascii: true
  table: t.csv
  plot: p.svg
  metric: edge_ratio
)";

}  // namespace

BOOST_AUTO_TEST_SUITE(config)

BOOST_AUTO_TEST_CASE(the_resolved_config_reads_back_to_itself) {
    for (const std::string& yaml : {std::string(), std::string(kRich)}) {
        const auto spec = cfg::parse_config(yaml, "run.yaml");
        for (const bool comments : {true, false}) {
            const std::string resolved = cfg::to_yaml(spec, comments);
            BOOST_TEST_CONTEXT(resolved) {
                const auto again = cfg::parse_config(resolved, "resolved.yaml");
                BOOST_TEST(cfg::to_yaml(again, comments) == resolved);
                BOOST_TEST(cfg::to_yaml(again, !comments) == cfg::to_yaml(spec, !comments));
            }
        }
    }
    // The defaults are those of the C++ options structs.
    const auto defaults = cfg::parse_config("", "empty");
    BOOST_REQUIRE(defaults.queue.size() == 1u);
    const auto& global = defaults.queue[0].options.get<pv::GlobalSolverOptions>();
    BOOST_TEST(global.termination.max_iterations == pv::GlobalSolverOptions{}.termination.max_iterations);
    BOOST_TEST(global.objective_options.barrier_shrink == pv::ObjectiveOptions{}.barrier_shrink);
    const std::string text = cfg::to_yaml(defaults, false);
    for (const char* key : {"max_iterations: 500", "progress_window: 25", "barrier_shrink: 0.8", "exchange: colored",
                            "parts: 1", "metric: aspect_ratio", "target_worst_quality: ~"})
        BOOST_TEST(has(text, key), key);
}

BOOST_AUTO_TEST_CASE(a_rich_config_sets_what_it_says) {
    const auto spec = cfg::parse_config(kRich, "run.yaml");
    BOOST_TEST((spec.input.fixed == cfg::FixedVertices::Boundary));
    BOOST_TEST((spec.input.fixed_vertices == std::vector<long long>{3, 7}));
    BOOST_REQUIRE(spec.study.size() == 2u);
    const auto& steps = spec.study[0].queue;
    BOOST_REQUIRE(steps.size() == 7u);
    BOOST_TEST(steps[0].assess.histogram_bins == 4);
    BOOST_TEST(steps[0].label == "start");
    const auto& untangle = steps[1].options.get<pv::GlobalSolverOptions>();
    BOOST_TEST((steps[1].kind == cfg::StepSpec::Kind::Untangle && !untangle.improve_shape));
    BOOST_TEST(untangle.untangle_termination.max_iterations == 40);
    const auto& g = steps[2].options.get<pv::GlobalSolverOptions>();
    BOOST_TEST(g.objective == "p_mean");
    BOOST_TEST(g.objective_options.p == -4.0);
    BOOST_TEST(g.shape_metric == "mean_ratio");
    BOOST_TEST(g.metric_options.hybrid_sharpness == 12.5);
    BOOST_TEST((g.direction == pv::GlobalSolverOptions::Direction::SteepestAscent));
    BOOST_TEST(*g.termination.target_worst_quality == 0.25);
    BOOST_TEST(steps[3].options.get<pv::LocalSolverOptions>().improve_below == 0.3);
    BOOST_TEST((steps[3].options.get<pv::LocalSolverOptions>().coloring == pv::ColoringOrder::Greedy));
    BOOST_TEST(steps[4].label == "smooth");
    BOOST_TEST(steps[4].options.get<pv::LaplaceSolverOptions>().smart);
    BOOST_TEST(!steps[5].options.get<pv::LaplaceSolverOptions>().smart);
    BOOST_TEST((steps[6].kind == cfg::StepSpec::Kind::Wrapper && steps[6].name == "laplace"));
    BOOST_TEST(!steps[6].options.get<pv::LaplaceSolverOptions>().smart);
    BOOST_TEST(spec.study[1].queue[0].name == "untangle_then_improve");
    BOOST_TEST(spec.output.metric == "edge_ratio");
    BOOST_TEST(spec.where("study[0].queue[2].improve.objective.p") == "run.yaml:14:40: study[0].queue[2].improve.objective.p");
}

BOOST_AUTO_TEST_CASE(an_unknown_key_is_named_with_its_line_and_a_suggestion) {
    const auto e = error_of("input:\n  mesh: a.vtk\nqueue:\n  - improve:\n      termination:\n        max_iterationz: 5\n");
    BOOST_TEST(e.key() == "queue[0].improve.termination.max_iterationz");
    BOOST_TEST(e.where() == "run.yaml:6:9");
    BOOST_TEST(has(e.what(), "did you mean 'max_iterations'?"));
    // A misplaced option says whose it is.
    const auto local = error_of("queue:\n  - improve: {name: local, steps_per_mu: 3}\n");
    BOOST_TEST(local.key() == "queue[0].improve.steps_per_mu");
    BOOST_TEST(has(local.what(), "is an option of solver global"));
    const auto objective = error_of("queue:\n  - improve:\n      objective: {name: log_barrier, p: 3}\n");
    BOOST_TEST(objective.where() == "run.yaml:3:38");  // the key
    BOOST_TEST(has(objective.what(), "'p' is an option of objective p_mean"));
    BOOST_TEST(error_of("inptu: {mesh: a.vtk}\n").where() == "run.yaml:1:1");
    BOOST_TEST(has(error_of("queue:\n  - improv: global\n").what(), "did you mean 'improve'?"));
    BOOST_TEST(has(error_of("queue:\n  - improve: globl\n").what(), "unknown solver 'globl'; did you mean 'global'?"));
    BOOST_TEST(has(error_of("queue:\n  - untangle_then_improve: {}\n").what(), "wrapper: untangle_then_improve"));
    // A key that the step decides itself.
    const auto forced = error_of("queue:\n  - wrapper: {name: untangle_then_improve, improve_shape: false}\n");
    BOOST_TEST(forced.key() == "queue[0].wrapper.improve_shape");
    BOOST_TEST(has(forced.what(), "cannot be set here"));
}

BOOST_AUTO_TEST_CASE(a_wrong_type_is_named_with_its_line) {
    struct Case {
        std::string yaml, key, where, words;
    };
    for (const Case& c : {Case{"queue:\n  - improve:\n      termination:\n        max_iterations: lots\n",
                               "queue[0].improve.termination.max_iterations", "run.yaml:4:25", "whole number"},
                          Case{"queue:\n  - improve: {untangle: maybe}\n", "queue[0].improve.untangle", "run.yaml:2:25",
                               "true or false"},
                          Case{"threads: 1.5\n", "threads", "run.yaml:1:10", "whole number"},
                          Case{"input: a.vtk\n", "input", "run.yaml:1:8", "expected a map"},
                          Case{"output:\n  plot: [a, b]\n", "output.plot", "run.yaml:2:9", "expected text"},
                          Case{"queue: {improve: global}\n", "queue", "run.yaml:1:8", "list of steps"},
                          Case{"queue:\n  - improve: global\n    label: x\n", "queue[0]", "run.yaml:2:5", "exactly one key"},
                          Case{"input:\n  fixed: sometimes\n", "input.fixed", "run.yaml:2:10", "boundary"}}) {
        const auto e = error_of(c.yaml);
        BOOST_TEST_CONTEXT(e.what()) {
            BOOST_TEST(e.key() == c.key);
            BOOST_TEST(e.where() == c.where);
            BOOST_TEST(has(e.what(), c.words));
        }
    }
}

BOOST_AUTO_TEST_CASE(an_out_of_range_value_is_named_with_its_line) {
    struct Case {
        std::string yaml, key, where, words;
    };
    for (const Case& c : {Case{"queue:\n  - improve:\n      objective:\n        barrier_shrink: 7\n",
                               "queue[0].improve.objective.barrier_shrink", "run.yaml:4:25", "(0, 1]"},
                          Case{"queue:\n  - improve: {termination: {max_iterations: -1}}\n",
                               "queue[0].improve.termination.max_iterations", "run.yaml:2:45", ">= 0"},
                          Case{"queue:\n  - improve: {name: local, active_tolerance: 1.5}\n",
                               "queue[0].improve.active_tolerance", "run.yaml:2:46", "[0, 1)"},
                          Case{"queue:\n  - improve: {metric: min_dihedral_deg}\n", "queue[0].improve.metric",
                               "run.yaml:2:23", "metric: 'min_dihedral_deg' has no gradient"},
                          Case{"queue:\n  - assess: {histogram_bins: 0}\n", "queue[0].assess.histogram_bins",
                               "run.yaml:2:30", "between 1 and 10000"},
                          Case{"partition: {parts: 0}\n", "partition.parts", "run.yaml:1:20", ">= 1"},
                          Case{"threads: -2\n", "threads", "run.yaml:1:10", ">= 0"},
                          Case{"queue:\n  - improve: {termination: {max_iterations: 99999999999}}\n",
                               "queue[0].improve.termination.max_iterations", "run.yaml:2:45", "out of range"},
                          Case{"output: {plot: p.png}\n", "output.plot", "run.yaml:1:16", ".svg"},
                          Case{"output: {mesh: out.abc}\n", "output.mesh", "run.yaml:1:16", ".vtk, .vtu, .msh or .mesh"},
                          Case{"output: {mesh: out.node}\n", "output.mesh", "run.yaml:1:16", "the format to write"},
                          Case{"queue:\n  - untangle: {name: smart_laplace}\n", "queue[0].untangle.name",
                               "run.yaml:2:22", "does not untangle; these do: global, local"}}) {
        const auto e = error_of(c.yaml);
        BOOST_TEST_CONTEXT(e.what()) {
            BOOST_TEST(e.key() == c.key);
            BOOST_TEST(e.where() == c.where);
            BOOST_TEST(has(e.what(), c.words));
        }
    }
}

BOOST_AUTO_TEST_CASE(yaml_syntax_errors_and_duplicate_keys_name_the_line) {
    BOOST_TEST(error_of("input: {mesh: a.vtk\nqueue: x\n").where() == "run.yaml:2:6");
    const auto duplicate = error_of("threads: 1\ninput: {mesh: a.vtk}\nthreads: 2\n");
    BOOST_TEST(duplicate.where() == "run.yaml:3:1");
    BOOST_TEST(has(duplicate.what(), "first at line 1"));
    // Nesting deep enough to exhaust the stack of a recursive reader is refused with its place.
    const auto deep = error_of("input: " + std::string(300, '[') + std::string(300, ']') + "\n");
    BOOST_TEST(has(deep.what(), "nested more than"));
    BOOST_TEST(deep.where().rfind("run.yaml:1:", 0) == 0);
    const pv::test::ScratchDir dir("config_missing");
    try {
        cfg::read_config(dir / "nope.yaml");
        BOOST_FAIL("no error for a missing config");
    } catch (const cfg::ConfigError& e) {
        BOOST_TEST(has(e.what(), "no such file"));
    }
}

BOOST_AUTO_TEST_CASE(set_overrides_with_the_same_checks) {
    const std::string yaml = "input: {mesh: a.vtk}\nqueue:\n  - improve:\n      objective: log_barrier\n";
    const auto spec = cfg::parse_config(yaml, "run.yaml",
                                        std::vector<cfg::Override>{{"queue[0].improve.objective.barrier_shrink=0.5"},
                                                                   {"queue[0].improve.termination.target_worst_quality=0.3"},
                                                                   {"queue[1].assess=after"},
                                                                   {"output.history=h.csv"},
                                                                   {"input.fixed_vertices=[1, 2]"}});
    const auto& g = spec.queue[0].options.get<pv::GlobalSolverOptions>();
    BOOST_TEST(g.objective_options.barrier_shrink == 0.5);
    BOOST_TEST(*g.termination.target_worst_quality == 0.3);
    BOOST_REQUIRE(spec.queue.size() == 2u);
    BOOST_TEST((spec.queue[1].kind == cfg::StepSpec::Kind::Assess && spec.queue[1].label == "after"));
    BOOST_TEST(spec.output.history == "h.csv");
    BOOST_TEST(spec.input.fixed_vertices.size() == 2u);
    BOOST_TEST(spec.where("output.history") == "--set: output.history");
    // ~ resets; a wrapper given by name can be tuned after.
    const auto reset = cfg::parse_config("queue:\n  - improve: {termination: {target_worst_quality: 0.3}}\n", "run.yaml",
                                         std::vector<cfg::Override>{{"queue[0].improve.termination.target_worst_quality=~"},
                                                                    {"queue=untangle_then_improve"},
                                                                    {"queue[0].wrapper.termination.max_iterations=3"}});
    BOOST_TEST((reset.queue[0].kind == cfg::StepSpec::Kind::Wrapper));
    BOOST_TEST(reset.queue[0].options.get<pv::GlobalSolverOptions>().termination.max_iterations == 3);
    // Errors name --set (or the flag standing for it) and the key.
    const auto bad = error_of(yaml, {{"queue[0].improve.termination.max_iterations=-3"}});
    BOOST_TEST(bad.where() == "--set");
    BOOST_TEST(bad.key() == "queue[0].improve.termination.max_iterations");
    BOOST_TEST(error_of(yaml, {{"queue[0].improve.termination.max_iterations=x", "--iterations"}}).where() == "--iterations");
    BOOST_TEST(has(error_of(yaml, {{"queue[5].improve.name=local"}}).what(), "append one at [1]"));
    // An index past any size_t (found by fuzz_config: it escaped as std::out_of_range).
    BOOST_TEST(has(error_of(yaml, {{"queue[100000000000000000000000000].improve.name=local"}}).what(),
                   "append one at [1]"));
    BOOST_TEST(has(error_of(yaml, {{"no equals sign"}}).what(), "key.path=value"));
    BOOST_TEST(error_of(yaml, {{"output.tabel=t.csv"}}).key() == "output.tabel");
}

BOOST_AUTO_TEST_CASE(a_config_run_untangles_a_shared_mesh) {
    const pv::test::ScratchDir dir("config_run");
    const std::string yaml = "input:\n  mesh: " + tangled().string() +
                             "\nqueue:\n  - assess: before\n  - untangle: global\n  - improve:\n      name: global\n"
                             "      termination: {max_iterations: 40}\n  - assess: after\n"
                             "output:\n  mesh: " + (dir / "out.vtu").string() + "\n  history: " + (dir / "h.csv").string() +
                             "\n  summary: " + (dir / "s.json").string() + "\n  plot: " + (dir / "p.svg").string() + "\n";
    const auto result = cfg::run(cfg::parse_config(yaml, "run.yaml"));
    BOOST_TEST(result.exit_code() == 0);
    BOOST_REQUIRE(result.methods.size() == 1u);
    const auto& m = result.methods[0];
    BOOST_TEST(m.before.inverted == 9);
    BOOST_TEST(m.after.inverted == 0);
    BOOST_TEST(m.queue.steps.size() == 4u);
    BOOST_TEST(m.worst_after > 0.0);
    BOOST_TEST(pv::read_mesh(dir / "out.vtu").mesh.num_elements() == 408);
    const auto summary = nlohmann::json::parse(pv::test::read_text(dir / "s.json"));
    BOOST_TEST(summary["inverted_after"].get<int>() == 0);
    BOOST_TEST(summary["status"].get<std::string>() == "done");
    BOOST_TEST(summary["steps"].size() == 4u);
    BOOST_TEST(has(pv::test::read_text(dir / "h.csv"), "method,improver,iteration,phase,worst_quality"));
    BOOST_TEST(has(pv::test::read_text(dir / "h.csv"), "run,untangle,0,untangle_energy,"));
    BOOST_TEST(has(pv::test::read_text(dir / "p.svg"), "<polyline"));
}

BOOST_AUTO_TEST_CASE(a_wrapper_by_name_runs_the_cpp_wrapper) {
    auto mesh = pv::read_mesh(tangled()).mesh;
    const auto direct = pv::wrappers::untangle_then_improve().run(mesh);
    const pv::test::ScratchDir dir("config_wrapper");
    const auto result = cfg::run(cfg::parse_config(
        "input: {mesh: " + tangled().string() + "}\nqueue: untangle_then_improve\noutput: {mesh: " + (dir / "o.vtk").string() + "}\n",
        "run.yaml"));
    BOOST_REQUIRE(result.methods[0].queue.steps.size() == direct.steps.size());
    const auto out = pv::read_mesh(dir / "o.vtk").mesh;
    BOOST_TEST(std::equal(out.coordinates().begin(), out.coordinates().end(), mesh.coordinates().begin()));
}

BOOST_AUTO_TEST_CASE(a_study_writes_one_row_per_method_each_from_the_same_input) {
    const pv::test::ScratchDir dir("config_study");
    const std::string yaml = "input: {mesh: " + tangled().string() + "}\n"
                             "study:\n"
                             "  - name: global\n    queue: untangle_then_improve\n"
                             "  - name: local\n    queue:\n      - improve: {name: local, termination: {max_iterations: 10}}\n"
                             "  - name: smart_laplace\n    queue: [improve: smart_laplace]\n"
                             "output:\n  table: " + (dir / "t.csv").string() + "\n  summary: " + (dir / "s.json").string() +
                             "\n  history: " + (dir / "h.csv").string() + "\n  mesh: " + (dir / "out_{method}.vtk").string() + "\n";
    const auto result = cfg::run(cfg::parse_config(yaml, "study.yaml"));
    BOOST_REQUIRE(result.methods.size() == 3u);
    for (const auto& m : result.methods) BOOST_TEST(m.before.inverted == 9);  // each starts from the input
    BOOST_TEST(result.methods[0].after.inverted == 0);
    BOOST_TEST(result.methods[1].after.inverted == 0);
    // Smart Laplace does not untangle: that method fails, and so does the run.
    BOOST_TEST((result.methods[2].status == cfg::RunStatus::Failed));
    BOOST_TEST(result.exit_code() == 1);
    std::istringstream table(pv::test::read_text(dir / "t.csv"));
    std::vector<std::string> rows;
    for (std::string line; std::getline(table, line);) rows.push_back(line);
    BOOST_REQUIRE(rows.size() == 4u);  // header + one row per method
    BOOST_TEST(has(rows[0], "method,status,solver,termination,seconds,iterations"));
    BOOST_TEST(rows[1].rfind("global,done,global+global,", 0) == 0);
    BOOST_TEST(rows[2].rfind("local,done,local,", 0) == 0);
    BOOST_TEST(rows[3].rfind("smart_laplace,failed,smart_laplace,cannot_untangle", 0) == 0);
    const auto summary = nlohmann::json::parse(pv::test::read_text(dir / "s.json"));
    BOOST_TEST(summary["methods"].size() == 3u);
    BOOST_TEST(summary["methods"][1]["steps"][0]["summary"]["history"].size() > 0u);
    std::set<std::string> methods_in_history;
    std::istringstream history(pv::test::read_text(dir / "h.csv"));
    std::string line;
    std::getline(history, line);
    while (std::getline(history, line)) methods_in_history.insert(line.substr(0, line.find(',')));
    BOOST_TEST(methods_in_history.size() == 3u);
    for (const char* name : {"out_global.vtk", "out_local.vtk", "out_smart_laplace.vtk"})
        BOOST_TEST(std::filesystem::exists(dir / name), name);
    // One mesh name for several methods would overwrite itself.
    BOOST_CHECK_THROW(cfg::run(cfg::parse_config(yaml, "study.yaml", std::vector<cfg::Override>{{"output.mesh=o.vtk"}})),
                      cfg::ConfigError);
}

BOOST_AUTO_TEST_CASE(a_target_not_reached_with_a_valid_mesh_is_status_three) {
    const std::string yaml = "input: {mesh: " + pv::test::shared_data("mesquite/tets/tire.vtk").string() + "}\n"
                             "queue:\n  - improve:\n      termination: {max_iterations: 3, target_worst_quality: 0.99}\n";
    const auto result = cfg::run(cfg::parse_config(yaml, "run.yaml"));
    BOOST_TEST((result.status == cfg::RunStatus::TargetNotReached));
    BOOST_TEST(result.exit_code() == 3);
    BOOST_TEST(result.methods[0].after.inverted == 0);
    BOOST_TEST(has(result.methods[0].message, "below its target 0.99"));
    // A target the run reaches is not a miss.
    const auto reached = cfg::run(cfg::parse_config(yaml, "run.yaml", std::vector<cfg::Override>{
                                                                         {"queue[0].improve.termination.target_worst_quality=0.001"}}));
    BOOST_TEST(reached.exit_code() == 0);
}

BOOST_AUTO_TEST_CASE(which_vertices_are_fixed) {
    const pv::test::ScratchDir dir("config_fixed");
    auto file = pv::read_mesh(tangled());
    pv::WriteOptions no_field;
    no_field.write_fixed = false;
    pv::write_mesh(dir / "plain.vtk", file.mesh, no_field);
    const std::string base = "input: {mesh: " + (dir / "plain.vtk").string() + "}\nqueue: []\n";
    const auto missing = [&] {
        try {
            cfg::run(cfg::parse_config(base, "run.yaml", std::vector<cfg::Override>{{"input.fixed=file"}}));
        } catch (const cfg::ConfigError& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    }();
    BOOST_TEST(has(missing, "input.fixed"));
    BOOST_TEST(has(missing, "no `fixed` point field"));
    try {
        cfg::run(cfg::parse_config(base, "run.yaml", std::vector<cfg::Override>{{"input.fixed_vertices=[5000]"}}));
        BOOST_FAIL("vertex 5000 accepted");
    } catch (const cfg::ConfigError& e) {
        BOOST_TEST(e.key() == "input.fixed_vertices");
        BOOST_TEST(has(e.what(), "has 129 vertices"));
    }
    const auto none = cfg::run(cfg::parse_config(base, "run.yaml", std::vector<cfg::Override>{{"input.fixed=none"}}));
    BOOST_TEST(none.methods[0].before.free_vertices == 129);
    const auto extra = cfg::run(cfg::parse_config(base, "run.yaml", std::vector<cfg::Override>{{"input.fixed_vertices=[0, 1, 2]"}}));
    BOOST_TEST(extra.methods[0].before.free_vertices <= file.mesh.num_free_vertices());
}

// Partitioned runs (which start MPI) are tested in partitioned_run_test.cpp, in suites of their own.

BOOST_AUTO_TEST_CASE(every_key_of_the_registry_is_documented) {
    const std::string docs = pv::test::read_text(std::filesystem::path(PALOVERDE_SOURCE_DIR) / "docs/config.md");
    for (const auto& object : cfg::registry()) {
        BOOST_TEST(has(docs, "`" + object.name + "`"), object.kind << " " << object.name << " is not in docs/config.md");
        for (const auto& option : object.options)
            BOOST_TEST(has(docs, "`" + option.key + "`"), object.name << "." << option.key << " is not in docs/config.md");
    }
    // The reference part of the page is `paloverde run --describe`, verbatim.
    BOOST_TEST(has(docs, cfg::registry_markdown()), "docs/config.md: paste the output of `paloverde run --describe`");
}

BOOST_AUTO_TEST_CASE(registry_names_build_the_objects) {
    for (const auto& name : cfg::names_of("solver")) BOOST_TEST(cfg::make_solver(name)->name() == name);
    for (const auto& name : cfg::names_of("wrapper")) BOOST_TEST(cfg::make_wrapper(name, cfg::default_options(name)).size() >= 3u);
    BOOST_CHECK_THROW(cfg::make_solver("global", pv::LocalSolverOptions{}), pv::OptionError);
    try {
        cfg::describe("solver", "lokal");
        BOOST_FAIL("no error");
    } catch (const pv::OptionError& e) {
        BOOST_TEST(has(e.what(), "did you mean 'local'?"));
    }
}

BOOST_AUTO_TEST_CASE(a_mesh_in_pieces_refuses_what_only_a_whole_mesh_carries) {
    struct Case {
        std::string set, key, words;
    };
    for (const Case& c : {Case{"input.displacement=d", "input.displacement", "carries no reference"},
                          Case{"targets.reference=ref.vtk", "targets.reference", "carries no reference"},
                          Case{"targets.size_field=h", "targets.size_field", "carries no size field"}}) {
        const cfg::RunSpec spec = cfg::parse_config("input: {pieces: in.pvtu}\n", "run.yaml", std::vector<cfg::Override>{{c.set}});
        BOOST_CHECK_EXCEPTION(spec.check_runnable(), cfg::ConfigError, [&](const cfg::ConfigError& e) {
            BOOST_TEST_CONTEXT(e.what()) {
                BOOST_TEST(e.key() == c.key);
                BOOST_TEST(has(e.what(), c.words));
                BOOST_TEST(has(e.what(), "partition.parts"));
            }
            return true;
        });
    }
}

BOOST_AUTO_TEST_CASE(a_run_on_a_mesh_in_memory_is_the_run_on_its_file) {
    const cfg::RunSpec spec = cfg::parse_config("input: {mesh: " + quoted(tangled()) + "}\nthreads: 1\n", "run.yaml");
    const cfg::RunResult from_file = cfg::run(spec);
    pv::Mesh mesh = pv::read_mesh(tangled()).mesh;
    const std::vector<double> input(mesh.coordinates().begin(), mesh.coordinates().end());
    const cfg::RunResult in_memory = cfg::run(mesh, cfg::parse_config("threads: 1\n", "improve()"));
    BOOST_TEST(in_memory.exit_code() == 0);
    BOOST_TEST(in_memory.methods.front().before.inverted == 9);
    BOOST_TEST(in_memory.methods.front().after.inverted == 0);
    BOOST_TEST(in_memory.methods.front().worst_after == from_file.methods.front().worst_after);
    for (pv::VertexId v = 0; v < mesh.num_vertices(); ++v)
        if (mesh.fixed()[v])
            for (int d = 0; d < 3; ++d) BOOST_TEST(mesh.coordinates()[3 * v + d] == input[3 * v + d]);
    BOOST_TEST(!mesh.has_targets());
    // A partitioned spec needs files.
    BOOST_CHECK_EXCEPTION(cfg::run(mesh, cfg::parse_config("partition: {parts: 2}\n", "improve()")), cfg::ConfigError,
                          [](const cfg::ConfigError& e) { return has(e.what(), "serially"); });
}

BOOST_AUTO_TEST_SUITE_END()

BOOST_AUTO_TEST_SUITE(config_cli)

BOOST_AUTO_TEST_CASE(print_config_of_the_flags_runs_the_same) {
    const pv::test::ScratchDir dir("config_cli_same");
    for (const std::string& flags : {std::string("--iterations 20 --metric mean_ratio --barrier-shrink 0.7"),
                                    std::string("--method local --iterations 8 --improve-below 0.5"),
                                    std::string("--untangle --steepest")}) {
        BOOST_TEST_CONTEXT(flags) {
            const std::string common = "improve " + quoted(tangled()) + " " + flags;
            const auto direct = run_cli(common + " -q -o " + quoted(dir / "a.vtu") + " --summary " + quoted(dir / "a.json"));
            BOOST_TEST_REQUIRE(direct.exit_code == 0);
            const auto printed = run_cli(common + " -o " + quoted(dir / "a.vtu") + " --print-config");
            BOOST_TEST_REQUIRE(printed.exit_code == 0);
            pv::test::write_file(dir / "run.yaml", printed.output);
            const auto config = run_cli("run -q " + quoted(dir / "run.yaml") + " --set output.mesh=" + quoted(dir / "b.vtu") +
                                        " --set output.summary=" + quoted(dir / "b.json"));
            BOOST_TEST_INFO(config.output);
            BOOST_TEST_REQUIRE(config.exit_code == 0);
            BOOST_TEST(pv::test::read_text(dir / "a.vtu") == pv::test::read_text(dir / "b.vtu"));
            const auto a = nlohmann::json::parse(pv::test::read_text(dir / "a.json"));
            const auto b = nlohmann::json::parse(pv::test::read_text(dir / "b.json"));
            BOOST_TEST(a["iterations"] == b["iterations"]);
            BOOST_TEST(a["worst_after"] == b["worst_after"]);
        }
    }
}

BOOST_AUTO_TEST_CASE(run_exit_codes_and_messages) {
    const pv::test::ScratchDir dir("config_cli_codes");
    const auto tire = pv::test::shared_data("mesquite/tets/tire.vtk");
    pv::test::write_file(dir / "target.yaml", "input: {mesh: " + tire.string() +
                                                  "}\nqueue:\n  - improve:\n      termination:\n"
                                                  "        max_iterations: 3\n        target_worst_quality: 0.99\n");
    auto r = run_cli("run -q " + quoted(dir / "target.yaml"));
    BOOST_TEST(r.exit_code == 3);
    r = run_cli("run --json " + quoted(dir / "target.yaml") + " --set queue[0].improve.termination.target_worst_quality=~");
    BOOST_TEST(r.exit_code == 0);
    BOOST_TEST(nlohmann::json::parse(r.output)["status"].get<std::string>() == "done");
    // Smart Laplace cannot untangle: exit 1, with the reason.
    r = run_cli("run -q --set input.mesh=" + quoted(tangled()) + " --set 'queue=[improve: smart_laplace]'");
    BOOST_TEST(r.exit_code == 1);
    BOOST_TEST(has(r.output, "smart_laplace"));
    // Bad config: exit 2, naming file, line and key.
    pv::test::write_file(dir / "bad.yaml", "input: {mesh: x.vtk}\nqueue:\n  - improve:\n      termination: {max_iterations: -1}\n");
    r = run_cli("run " + quoted(dir / "bad.yaml"));
    BOOST_TEST(r.exit_code == 2);
    BOOST_TEST(has(r.output, "bad.yaml:4:37: queue[0].improve.termination.max_iterations: must be >= 0"));
    r = run_cli("run " + quoted(dir / "target.yaml") + " --set queue[0].improve.termination.max_iterations=x");
    BOOST_TEST(r.exit_code == 2);
    BOOST_TEST(has(r.output, "--set: queue[0].improve.termination.max_iterations: expected a whole number, got 'x'"));
    r = run_cli("improve " + quoted(tangled()) + " -o " + quoted(dir / "o.vtk") + " --iterations -4");
    BOOST_TEST(r.exit_code == 2);
    BOOST_TEST(has(r.output, "--iterations: queue[0].improve.termination.max_iterations: must be >= 0"));
    // The file name that earlier versions took after --json.
    r = run_cli("improve " + quoted(tangled()) + " -o " + quoted(dir / "o.vtk") + " --json s.json");
    BOOST_TEST(r.exit_code == 2);
    BOOST_TEST(has(r.output, "--summary s.json"));
    r = run_cli("run");
    BOOST_TEST(r.exit_code == 2);
    BOOST_TEST(has(r.output, "input.mesh"));
    // An unreadable mesh is an error, not bad usage.
    r = run_cli("run --set input.mesh=" + quoted(dir / "missing.vtk"));
    BOOST_TEST(r.exit_code == 1);
    BOOST_TEST(has(r.output, "missing.vtk"));
}

BOOST_AUTO_TEST_CASE(print_config_and_describe_need_no_mesh) {
    auto r = run_cli("run --print-config");
    BOOST_TEST(r.exit_code == 0);
    BOOST_TEST(has(r.output, "max_iterations: 500"));
    r = run_cli("run --describe");
    BOOST_TEST(r.exit_code == 0);
    BOOST_TEST(has(r.output, "| `untangle_then_improve` |"));
    const auto examples = std::filesystem::path(PALOVERDE_SOURCE_DIR) / "examples";
    for (const char* name : {"untangle_then_improve.yaml", "global_vs_local.yaml", "parallel_run.yaml"}) {
        r = run_cli("run --print-config " + quoted(examples / name));
        BOOST_TEST(r.exit_code == 0, name << ": " << r.output);
    }
}

BOOST_AUTO_TEST_CASE(progress_only_on_a_terminal) {
    const pv::test::ScratchDir dir("config_cli_progress");
    const std::string command = std::string(PALOVERDE_CLI) + " improve " + quoted(tangled()) + " -o " + quoted(dir / "o.vtk");
    // Through a pipe: no progress line.
    auto r = run_cli("improve " + quoted(tangled()) + " -o " + quoted(dir / "o.vtk"));
    BOOST_TEST(r.exit_code == 0);
    BOOST_TEST(!has(r.output, "\r"));
    // On a pseudo-terminal (util-linux `script`): one line rewritten in place, unless --quiet.
    if (std::system("command -v script > /dev/null 2>&1") != 0) return;
    const auto terminal = [&](const std::string& extra) {
        const std::string line = "script -qec \"" + command + extra + "\" /dev/null";
        FILE* pipe = ::popen(line.c_str(), "r");
        std::string out;
        char buffer[4096];
        while (std::size_t n = std::fread(buffer, 1, sizeof buffer, pipe)) out.append(buffer, n);
        ::pclose(pipe);
        return out;
    };
    const std::string shown = terminal("");
    BOOST_TEST(has(shown, "\rglobal [untangle_energy]  iteration 0  worst "));
    BOOST_TEST(has(shown, "inverted "));
    BOOST_TEST(!has(terminal(" --quiet"), "\r"));
}

BOOST_AUTO_TEST_SUITE_END()
