// Runs as separate processes, as a user or a batch system stops them: `paloverde improve` stopped
// by SIGTERM; `paloverde improve` and a 2-rank MPI run killed by SIGKILL once their checkpoint
// appears, then resumed with --resume and compared, bit for bit, with uninterrupted runs.
#include <boost/test/data/test_case.hpp>
#include <boost/test/unit_test.hpp>
#include <cerrno>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "paloverde/io/mesh_io.hpp"
#include "process.hpp"
#include "robustness_support.hpp"

namespace pv = paloverde;
namespace fs = std::filesystem;
namespace bdata = boost::unit_test::data;
using json = nlohmann::json;
using pv::test::ChildProcess;

namespace {

const std::string kCli = PALOVERDE_CLI;
const std::string kTire = pv::test::shared_data("mesquite/tets/tire.vtk").string();

std::vector<std::string> split(const std::string& text) {
    std::vector<std::string> out;
    std::string word;
    for (char c : text + " ")
        if (c == ' ') {
            if (!word.empty()) out.push_back(word);
            word.clear();
        } else {
            word += c;
        }
    return out;
}

std::vector<std::string> operator+(std::vector<std::string> a, const std::vector<std::string>& b) {
    a.insert(a.end(), b.begin(), b.end());
    return a;
}

// The launcher and its flags as CMake found them (MPIEXEC_EXECUTABLE, MPIEXEC_PREFLAGS).
std::vector<std::string> mpirun(int ranks) {
    return std::vector<std::string>{PALOVERDE_MPIEXEC, PALOVERDE_MPIEXEC_NUMPROC_FLAG, std::to_string(ranks)} +
           split(PALOVERDE_MPIEXEC_PREFLAGS) + std::vector<std::string>{PALOVERDE_MPI_IMPROVE};
}

// Runs to its end (a minute at most) and returns the exit code.
int run_to_end(const std::vector<std::string>& argv, const fs::path& log) {
    ChildProcess child(argv, log);
    BOOST_TEST_REQUIRE(child.wait(60.0), "still running after a minute: " << child.output());
    BOOST_TEST_INFO(child.output());
    return child.exit_code();
}

json read_json(const fs::path& p) { return json::parse(pv::test::read_text(p)); }

// Whether process `pid` has ended (gone, or a zombie waiting for its parent).
bool ended(pid_t pid) {
    std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
    if (!stat) return true;
    std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
    const auto close = text.rfind(')');
    return close == std::string::npos || close + 2 >= text.size() || text[close + 2] == 'Z';
}

// The processes whose parent is `parent` (the ranks mpirun started on this machine).
std::vector<pid_t> children_of(pid_t parent) {
    std::vector<pid_t> children;
    for (const auto& entry : fs::directory_iterator("/proc")) {
        const std::string name = entry.path().filename().string();
        if (name.find_first_not_of("0123456789") != std::string::npos) continue;
        std::ifstream stat(entry.path() / "stat");
        std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
        const auto close = text.rfind(')');  // the fields after the command's name: state, ppid, ...
        if (close == std::string::npos) continue;
        std::istringstream fields(text.substr(close + 1));
        std::string state;
        pid_t ppid = 0;
        if (fields >> state >> ppid && ppid == parent) children.push_back(std::stoi(name));
    }
    return children;
}

// The same final mesh, bit for bit, and the same iterations and outcome.
void check_same_result(const fs::path& a_mesh, const json& a, const fs::path& b_mesh, const json& b) {
    BOOST_TEST(pv::test::same_coordinates(pv::read_mesh(a_mesh).mesh, pv::read_mesh(b_mesh).mesh));
    BOOST_TEST(a["iterations"].get<int>() == b["iterations"].get<int>());
    BOOST_TEST(a["termination"].get<std::string>() == b["termination"].get<std::string>());
    BOOST_TEST(a["worst_after"].get<double>() == b["worst_after"].get<double>());
}

// `paloverde improve` arguments for a run that would go on for a long time (no convergence test,
// many iterations), with a checkpoint every 5 iterations to show that it is iterating.
std::vector<std::string> long_improve(const fs::path& dir) {
    return {"improve", kTire, "-o", (dir / "out.vtu").string(), "--summary", (dir / "s.json").string(),
            "--iterations", "100000", "--set", "queue[0].improve.termination.min_progress=0", "--checkpoint",
            (dir / "run.ckpt").string(), "--checkpoint-every", "5", "-q"};
}

// What a stopped long_improve() run must have done: exit with 4 after writing the best iterate it
// saw and a summary that says it was interrupted.
void check_stopped_improve(ChildProcess& child, const fs::path& dir) {
    BOOST_TEST_REQUIRE(child.wait(60.0));
    BOOST_TEST_INFO(child.output());
    BOOST_TEST(child.exit_code() == 4);
    BOOST_TEST_REQUIRE(fs::exists(dir / "out.vtu"));
    const json s = read_json(dir / "s.json");
    BOOST_TEST(s["status"].get<std::string>() == "interrupted");
    BOOST_TEST(s["termination"].get<std::string>() == "interrupted");
    BOOST_TEST(s["inverted_after"].get<int>() == 0);
    BOOST_TEST(s["worst_after"].get<double>() >= s["worst_before"].get<double>());
    double best = -1.0;
    for (const auto& r : s["steps"][0]["summary"]["history"]) best = std::max(best, r["worst_quality"].get<double>());
    BOOST_TEST(s["steps"][0]["summary"]["worst_after"].get<double>() == best, boost::test_tools::tolerance(1e-12));
    const auto written = pv::read_mesh(dir / "out.vtu").mesh;
    BOOST_TEST(pv::count_orientations(written).inverted == 0);
    BOOST_TEST(written.num_vertices() == pv::read_mesh(kTire).mesh.num_vertices());
}

}  // namespace

// Run by the CTest entry `robustness_killed` (--run_test=killed), not by `robustness`.
BOOST_AUTO_TEST_SUITE(killed, *boost::unit_test::disabled())

// SIGTERM to `paloverde improve`: it stops at the next iteration, writes its best mesh and the
// summary, and exits with 4.
BOOST_AUTO_TEST_CASE(sigterm_stops_improve_which_writes_its_best_mesh_and_exits_four) {
    const pv::test::ScratchDir dir("kill_sigterm");
    ChildProcess child(std::vector<std::string>{kCli} + long_improve(dir.path()), dir / "log.txt");
    BOOST_TEST_REQUIRE(pv::test::wait_for_file(dir / "run.ckpt", child, 60.0), child.output());
    child.signal(SIGTERM);
    check_stopped_improve(child, dir.path());
}

// `paloverde improve` on 2 ranks under mpirun, stopped the way a batch system stops a job (SIGTERM
// to every rank, as Slurm's scancel does): the ranks stop at the same iteration, rank 0 writes the
// gathered best mesh and the summary, and mpirun passes on the ranks' exit code 4. (SIGTERM to
// mpirun itself is Open MPI's business: docs/robustness.md.)
BOOST_AUTO_TEST_CASE(sigterm_to_the_ranks_of_an_mpirun_improve_writes_its_best_mesh_and_exits_four) {
    const pv::test::ScratchDir dir("kill_sigterm_np2");
    auto launcher = mpirun(2);
    launcher.back() = kCli;  // the command line itself, not the test program
    ChildProcess child(launcher + long_improve(dir.path()), dir / "log.txt");
    BOOST_TEST_REQUIRE(pv::test::wait_for_file(dir / "run.ckpt", child, 60.0), child.output());
    const std::vector<pid_t> ranks = children_of(child.pid());
    BOOST_TEST_REQUIRE(ranks.size() == 2u, child.output());
    for (pid_t pid : ranks) ::kill(pid, SIGTERM);
    check_stopped_improve(child, dir.path());
}

// The same for `paloverde run` with a config: a study stopped in its first method skips the
// second, and the run exits with 4 after writing its outputs.
BOOST_AUTO_TEST_CASE(sigterm_stops_a_config_run_which_writes_its_outputs_and_exits_four) {
    const pv::test::ScratchDir dir("kill_sigterm_run");
    pv::test::write_file(dir / "run.yaml",
                         "input: {mesh: '" + kTire + "'}\n"
                         "study:\n"
                         "  - name: long\n"
                         "    queue:\n"
                         "      - improve: {name: global, termination: {max_iterations: 100000, min_progress: 0},\n"
                         "                  checkpoint: {file: '" + (dir / "run.ckpt").string() + "', every_iterations: 5}}\n"
                         "  - name: never\n"
                         "    queue: [improve: local]\n"
                         "output: {mesh: '" + (dir / "{method}.vtu").string() + "', summary: '" +
                             (dir / "s.json").string() + "'}\n");
    ChildProcess child({kCli, "run", (dir / "run.yaml").string(), "-q"}, dir / "log.txt");
    BOOST_TEST_REQUIRE(pv::test::wait_for_file(dir / "run.ckpt", child, 60.0), child.output());
    child.signal(SIGTERM);
    BOOST_TEST_REQUIRE(child.wait(60.0));
    BOOST_TEST_INFO(child.output());
    BOOST_TEST(child.exit_code() == 4);
    BOOST_TEST(fs::exists(dir / "long.vtu"));
    BOOST_TEST(!fs::exists(dir / "never.vtu"));
    const json s = read_json(dir / "s.json");
    BOOST_TEST(s["status"].get<std::string>() == "interrupted");
    BOOST_TEST(s["methods"].size() == 1u);
}

// SIGKILL after the first checkpoint, then --resume: the mesh and the summary of an uninterrupted
// run.
// With the boundary fixed, and sliding (two runs: killed in the first, which writes run.ckpt.run).
BOOST_DATA_TEST_CASE(improve_killed_and_resumed_ends_as_the_uninterrupted_run, bdata::make({"fixed", "slide"}), boundary) {
    const pv::test::ScratchDir dir(std::string("kill_serial_") + boundary);
    const std::vector<std::string> run{kCli, "improve", kTire, "--iterations", "150", "-q", "--boundary", boundary};
    BOOST_TEST_REQUIRE(run_to_end(run + std::vector<std::string>{"-o", (dir / "a.vtu").string(), "--summary",
                                                                 (dir / "a.json").string()},
                                  dir / "a.log") == 0);

    const std::vector<std::string> checkpoint{"--checkpoint", (dir / "run.ckpt").string(), "--checkpoint-every", "20"};
    {
        ChildProcess child(run + checkpoint + std::vector<std::string>{"-o", (dir / "b.vtu").string()}, dir / "b.log");
        const fs::path written = dir / (std::string(boundary) == "slide" ? "run.ckpt.run" : "run.ckpt");
        BOOST_TEST_REQUIRE(pv::test::wait_for_file(written, child, 60.0),
                           "the run ended before its first checkpoint: " << child.output());
        child.signal_group(SIGKILL);
        BOOST_TEST_REQUIRE(child.wait(60.0));
        BOOST_TEST(child.killed_by() == SIGKILL);
        BOOST_TEST(!fs::exists(dir / "b.vtu"));
    }
    BOOST_TEST_REQUIRE(run_to_end(run + checkpoint +
                                      std::vector<std::string>{"--resume", (dir / "run.ckpt").string(), "-o",
                                                               (dir / "c.vtu").string(), "--summary",
                                                               (dir / "c.json").string()},
                                  dir / "c.log") == 0);
    const json a = read_json(dir / "a.json"), c = read_json(dir / "c.json");
    check_same_result(dir / "a.vtu", a, dir / "c.vtu", c);
    BOOST_TEST(a["steps"][0]["summary"]["history"].size() == c["steps"][0]["summary"]["history"].size());
}

// The same on 2 ranks: every rank and the launcher are killed at once.
BOOST_AUTO_TEST_CASE(two_rank_run_killed_and_resumed_ends_as_the_uninterrupted_run) {
    const pv::test::ScratchDir dir("kill_np2");
    const auto run = mpirun(2) + std::vector<std::string>{kTire};
    const std::vector<std::string> limit{"--iterations", "150"};
    BOOST_TEST_REQUIRE(run_to_end(run + std::vector<std::string>{(dir / "a.vtu").string(), "--summary",
                                                                 (dir / "a.json").string()} + limit,
                                  dir / "a.log") == 0);

    const std::vector<std::string> checkpoint{"--checkpoint", (dir / "run.ckpt").string(), "--every", "20"};
    {
        ChildProcess child(run + std::vector<std::string>{(dir / "b.vtu").string(), "--pids", (dir / "pid").string()} +
                               limit + checkpoint,
                           dir / "b.log");
        BOOST_TEST_REQUIRE(pv::test::wait_for_file(dir / "run.ckpt", child, 60.0),
                           "the run ended before its first checkpoint: " << child.output());
        std::vector<pid_t> ranks;
        for (int r = 0; r < 2; ++r) {
            std::ifstream in(dir / ("pid" + std::to_string(r)));
            pid_t pid = 0;
            in >> pid;
            BOOST_TEST_REQUIRE(pid > 0);
            ranks.push_back(pid);
        }
        for (pid_t pid : ranks) ::kill(pid, SIGKILL);
        child.signal_group(SIGKILL);
        BOOST_TEST_REQUIRE(child.wait(60.0));
        for (int i = 0; i < 6000 && !(ended(ranks[0]) && ended(ranks[1])); ++i) ::usleep(10000);
        BOOST_TEST_REQUIRE((ended(ranks[0]) && ended(ranks[1])));
        BOOST_TEST(!fs::exists(dir / "b.vtu"));
    }
    BOOST_TEST_REQUIRE(run_to_end(run + std::vector<std::string>{(dir / "c.vtu").string(), "--summary",
                                                                 (dir / "c.json").string(), "--resume",
                                                                 (dir / "run.ckpt").string()} + limit + checkpoint,
                                  dir / "c.log") == 0);
    const json a = read_json(dir / "a.json"), c = read_json(dir / "c.json");
    check_same_result(dir / "a.vtu", a, dir / "c.vtu", c);
    BOOST_TEST(a["history"].size() == c["history"].size());

    // A 2-rank checkpoint is refused by a serial run, which says why.
    const auto serial = pv::test::run_cli("improve '" + kTire + "' -o '" + (dir / "d.vtu").string() +
                                          "' --iterations 150 --resume '" + (dir / "run.ckpt").string() + "'");
    BOOST_TEST(serial.exit_code == 1);
    BOOST_TEST(serial.output.find("2 rank(s)") != std::string::npos, serial.output);
}

// The local smoother on 2 ranks resumed from its last checkpoint (it sweeps too fast on this mesh
// to be killed reliably between checkpoints; in-process tests cover the rest).
BOOST_AUTO_TEST_CASE(two_rank_local_run_resumed_from_its_last_checkpoint_ends_as_the_uninterrupted_run) {
    const pv::test::ScratchDir dir("resume_local_np2");
    const auto run = mpirun(2) + std::vector<std::string>{kTire};
    const std::vector<std::string> options{"--method", "local", "--iterations", "8"};
    BOOST_TEST_REQUIRE(run_to_end(run + std::vector<std::string>{(dir / "a.vtu").string(), "--summary",
                                                                 (dir / "a.json").string()} + options,
                                  dir / "a.log") == 0);
    const std::vector<std::string> checkpoint{"--checkpoint", (dir / "run.ckpt").string(), "--every", "3"};
    BOOST_TEST_REQUIRE(run_to_end(run + std::vector<std::string>{(dir / "b.vtu").string()} + options + checkpoint,
                                  dir / "b.log") == 0);
    BOOST_TEST_REQUIRE(run_to_end(run + std::vector<std::string>{(dir / "c.vtu").string(), "--summary",
                                                                 (dir / "c.json").string(), "--resume",
                                                                 (dir / "run.ckpt").string()} + options,
                                  dir / "c.log") == 0);
    const json a = read_json(dir / "a.json"), c = read_json(dir / "c.json");
    BOOST_TEST_REQUIRE(a["iterations"].get<int>() > 6);
    check_same_result(dir / "a.vtu", a, dir / "c.vtu", c);
}

// Through the command line: a damaged or foreign checkpoint is an error (exit code 1) that names
// the file and says what is wrong; nothing is written.
BOOST_AUTO_TEST_CASE(improve_refuses_damaged_and_foreign_checkpoints) {
    const pv::test::ScratchDir dir("kill_refused");
    const std::string run = "improve '" + kTire + "' --iterations 12";
    const auto written = pv::test::run_cli(run + " -q --checkpoint '" + (dir / "run.ckpt").string() +
                                           "' --checkpoint-every 10 -o '" + (dir / "first.vtu").string() + "'");
    const std::string base = run + " -o '" + (dir / "out.vtu").string() + "'";
    BOOST_TEST_REQUIRE(written.exit_code == 0, written.output);
    std::string bytes = pv::test::read_text(dir / "run.ckpt");
    bytes[bytes.size() - 5] ^= 0x01;
    pv::test::write_bytes(dir / "bad.ckpt", bytes);
    const auto damaged = pv::test::run_cli(base + " --resume '" + (dir / "bad.ckpt").string() + "'");
    BOOST_TEST(damaged.exit_code == 1);
    BOOST_TEST(damaged.output.find("bad.ckpt") != std::string::npos, damaged.output);
    BOOST_TEST(damaged.output.find("checksum") != std::string::npos, damaged.output);
    const auto other = pv::test::run_cli(base + " --steepest --resume '" + (dir / "run.ckpt").string() + "'");
    BOOST_TEST(other.exit_code == 1);
    BOOST_TEST(other.output.find("other global solver options") != std::string::npos, other.output);
    const auto local = pv::test::run_cli(base + " --method local --resume '" + (dir / "run.ckpt").string() + "'");
    BOOST_TEST(local.exit_code == 1);
    BOOST_TEST(local.output.find("written by the global solver") != std::string::npos, local.output);
    BOOST_TEST(!fs::exists(dir / "out.vtu"));
    // A checkpoint option of a solver that has none.
    const auto laplace = pv::test::run_cli(base + " --method laplace --checkpoint '" + (dir / "x.ckpt").string() + "'");
    BOOST_TEST(laplace.exit_code == 2, laplace.output);
}

BOOST_AUTO_TEST_SUITE_END()
