// Distributed meshes and solvers: run by CTest on 1, 2 and 4 ranks. Every check compares with
// the serial computation on the whole mesh, which every rank can do for itself.
#include <mpi.h>

#include <boost/test/data/test_case.hpp>
#include <boost/test/unit_test.hpp>
#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "paloverde/assess/quality_assessor.hpp"
#include "paloverde/config/run.hpp"
#include "paloverde/core/error.hpp"
#include "paloverde/mesh/orientation.hpp"
#include "paloverde/mesh/renumber.hpp"
#include "paloverde/parallel/distributed_mesh.hpp"
#include "paloverde/parallel/mesh_part.hpp"
#include "paloverde/parallel/partition.hpp"
#include "paloverde/solvers/global_solver.hpp"
#include "paloverde/solvers/local_solver.hpp"
#include "paloverde/solvers/stop.hpp"
#include "paloverde/wrappers.hpp"
#include "support/io_checks.hpp"
#include "support/sliding_checks.hpp"
#include "support/surface_meshes.hpp"
#include "support/solver_checks.hpp"
#include "distributed_checks.hpp"

namespace pv = paloverde;
namespace cfg = paloverde::config;

namespace {

struct MpiSession {
    MpiSession() { MPI_Init(nullptr, nullptr); }
    ~MpiSession() { MPI_Finalize(); }
};

using paloverde::test::rank;
using paloverde::test::ranks;
using paloverde::test::relative_difference;
using paloverde::test::scatter;
using paloverde::test::serial_and_distributed;

}  // namespace

BOOST_TEST_GLOBAL_FIXTURE(MpiSession);

BOOST_AUTO_TEST_SUITE(distributed)

BOOST_AUTO_TEST_CASE(every_vertex_owned_once_every_element_counted_once) {
    const auto whole = pv::test::shared_mesh("mesquite/tets/tire.vtk");
    auto part = scatter(whole);
    long owned = 0, counted = 0;
    for (int owner : part.vertex_owner()) owned += owner == rank();
    for (auto c : part.counted()) counted += c;
    BOOST_TEST(part.reducer().total(static_cast<double>(owned)) == whole.num_vertices());
    BOOST_TEST(part.reducer().total(static_cast<double>(counted)) == whole.num_elements());
    // A rank holds every element of the vertices it owns.
    for (pv::VertexId v = 0; v < part.mesh().num_vertices(); ++v)
        if (part.vertex_owner()[v] == rank()) {
            const auto global = part.mesh().global_ids()[v];
            (void)global;
            BOOST_TEST(!part.mesh().elements_of(v).empty());
        }
    // No two partners share a color at this rank.
    for (std::size_t i = 1; i < part.schedule().partners.size(); ++i)
        BOOST_TEST(part.schedule().partners[i].color != part.schedule().partners[i - 1].color);
    if (ranks() == 1) BOOST_TEST(part.schedule().partners.empty());
}

// The view solvers and queues take: a part owns and counts what its DistributedMesh says; the
// whole mesh of a serial run owns and counts everything, with reductions that do nothing.
BOOST_AUTO_TEST_CASE(a_mesh_part_owns_and_counts_as_its_mesh_says) {
    auto whole = pv::test::shared_mesh("mesquite/tets/tire.vtk");
    auto distributed = scatter(whole);
    const pv::MeshPart part(distributed);
    BOOST_TEST(&part.mesh() == &distributed.mesh());
    BOOST_TEST(!part.whole());
    BOOST_TEST(part.rank() == distributed.rank());
    BOOST_TEST(part.ranks() == distributed.ranks());
    BOOST_TEST(part.global_vertices() == whole.num_vertices());
    BOOST_TEST(part.global_elements() == whole.num_elements());
    BOOST_TEST(part.element_positions().size() == static_cast<std::size_t>(distributed.mesh().num_elements()));
    long owned = 0, counted = 0;
    for (pv::VertexId v = 0; v < part.mesh().num_vertices(); ++v) owned += part.owns(v);
    for (pv::ElementId e = 0; e < part.mesh().num_elements(); ++e) counted += part.counts(e);
    BOOST_TEST(part.reducer().total(static_cast<double>(owned)) == whole.num_vertices());
    BOOST_TEST(part.reducer().total(static_cast<double>(counted)) == whole.num_elements());

    // Rank 0 gets the owners' values in global id order, as the gathered whole mesh has them.
    const std::vector<double> gathered = part.gather_to_root(distributed.mesh().coordinates(), 3);
    const pv::Mesh all = distributed.gather_whole();
    if (part.root()) {
        const auto xyz = all.coordinates();
        BOOST_TEST(gathered == std::vector<double>(xyz.begin(), xyz.end()));
    } else {
        BOOST_TEST(gathered.empty());
    }
    std::string bytes = part.root() ? std::string("rank 0's") : std::string();
    part.broadcast(bytes);
    BOOST_TEST(bytes == "rank 0's");

    const pv::MeshPart serial(whole);
    BOOST_TEST(serial.whole());
    BOOST_TEST(serial.ranks() == 1);
    BOOST_TEST(serial.element_positions().empty());
    BOOST_TEST(serial.owns(whole.num_vertices() - 1));
    BOOST_TEST(serial.counts(whole.num_elements() - 1));
    BOOST_TEST(serial.reducer().total(2.5) == 2.5);
}

BOOST_AUTO_TEST_CASE(ghosts_receive_their_owners_values_both_ways) {
    const auto whole = pv::test::shared_mesh("mesquite/tets/tire.vtk");
    for (auto mode : {pv::ExchangeMode::Colored, pv::ExchangeMode::RootRelayed}) {
        pv::DistributedMesh part;
        part = scatter(whole, mode);  // moved in: the halo must follow
        const pv::VertexId n = part.mesh().num_vertices();
        std::vector<double> values(2 * static_cast<std::size_t>(n));
        for (pv::VertexId v = 0; v < n; ++v) {
            const bool mine = part.vertex_owner()[v] == rank();
            values[2 * v] = mine ? static_cast<double>(part.mesh().global_ids()[v]) : -1.0;
            values[2 * v + 1] = mine ? 0.5 * rank() : -1.0;
        }
        part.halo().update(values, 2);
        long wrong = 0;
        for (pv::VertexId v = 0; v < n; ++v)
            wrong += values[2 * v] != static_cast<double>(part.mesh().global_ids()[v]) ||
                     values[2 * v + 1] != 0.5 * part.vertex_owner()[v];
        BOOST_TEST(part.reducer().total(static_cast<double>(wrong)) == 0.0);
    }
}

BOOST_AUTO_TEST_CASE(gather_returns_the_mesh_and_the_report_equals_the_serial_one) {
    const auto whole = pv::test::perturbed_shared_mesh("mesquite/tets/tire.vtk", 0.3, 1);
    auto part = scatter(whole);
    const pv::QualityAssessor assessor;
    const auto serial = assessor.assess(whole);
    const auto distributed = assessor.assess(part);
    BOOST_TEST(distributed.elements == serial.elements);
    BOOST_TEST(distributed.vertices == serial.vertices);
    BOOST_TEST(distributed.free_vertices == serial.free_vertices);
    BOOST_TEST(distributed.inverted == serial.inverted);
    BOOST_TEST(distributed.frozen_elements == serial.frozen_elements);
    for (std::size_t i = 0; i < serial.metrics.size(); ++i) {
        BOOST_TEST(distributed.metrics[i].movable.min == serial.metrics[i].movable.min);
        BOOST_TEST(distributed.metrics[i].all.mean == serial.metrics[i].all.mean);
        BOOST_TEST(distributed.metrics[i].all.histogram == serial.metrics[i].all.histogram);
    }
    pv::Mesh copy = whole;
    for (double& c : copy.coordinates()) c = 0.0;
    part.gather_coordinates(rank() == 0 ? &copy : nullptr);
    if (rank() == 0) BOOST_TEST(relative_difference(copy, whole) == 0.0);
}

// The paper's claim made exact: any number of ranks, the same mesh as the serial run.
BOOST_AUTO_TEST_CASE(global_solver_gives_the_serial_answer) {
    for (auto mode : {pv::ExchangeMode::Colored, pv::ExchangeMode::RootRelayed}) {
        const auto input = pv::test::perturbed_shared_mesh("mesquite/tets/tire.vtk", 0.05, 2);
        pv::GlobalSolverOptions options;
        options.termination.max_iterations = 12;
        options.untangle_termination.max_iterations = 150;
        pv::Mesh serial = input;
        const auto serial_summary = pv::GlobalSolver(options).improve(serial);

        pv::Mesh gathered = input;
        auto part = scatter(input, mode);
        const auto summary = pv::GlobalSolver(options).improve(part);
        part.gather_coordinates(rank() == 0 ? &gathered : nullptr);
        BOOST_TEST(summary.iterations == serial_summary.iterations);
        BOOST_TEST(pv::to_string(summary.reason) == pv::to_string(serial_summary.reason));
        BOOST_TEST(summary.after.inverted == serial_summary.after.inverted);
        BOOST_TEST(summary.worst_after == serial_summary.worst_after, boost::test_tools::tolerance(1e-12));
        BOOST_TEST(summary.after.inverted == 0);
        if (rank() == 0) {
            const double difference = relative_difference(gathered, serial);
            BOOST_TEST_MESSAGE(ranks() << " ranks: " << summary.brief_report() << "; relative difference " << difference);
            BOOST_TEST(difference <= 1e-10);
        }
    }
}

// The dihedral quality (dihedral_sine: each element's smallest angle sine, a nonsmooth minimum)
// moves every vertex the same on any number of ranks as serially.
BOOST_AUTO_TEST_CASE(the_dihedral_quality_gives_the_serial_answer) {
    pv::GlobalSolverOptions options;
    options.shape_metric = "dihedral_sine";
    options.termination.max_iterations = 15;
    const auto [serial, distributed] =
        serial_and_distributed(pv::test::perturbed_shared_mesh("mesquite/tets/tire.vtk", 0.05, 2), options);
    BOOST_TEST(serial.after.inverted == 0);
    BOOST_TEST(serial.quality_metric == "dihedral_sine");
}

// A planar mesh in a tilted plane: the serial run rates its triangles about the plane the input
// has, as every rank does (the whole mesh's), so both end on the same mesh.
BOOST_AUTO_TEST_CASE(a_tilted_planar_mesh_gives_the_serial_answer) {
    const pv::Mesh flat = pv::test::shared_mesh("mesquite/tris/tri_20258.vtk");
    const double a = 0.7, b = 0.4;  // turned about x, then about y
    std::vector<double> xyz(flat.coordinates().begin(), flat.coordinates().end());
    for (std::size_t i = 0; i < xyz.size(); i += 3) {
        const double x = xyz[i], y = std::cos(a) * xyz[i + 1] - std::sin(a) * xyz[i + 2],
                     z = std::sin(a) * xyz[i + 1] + std::cos(a) * xyz[i + 2];
        xyz[i] = std::cos(b) * x + std::sin(b) * z;
        xyz[i + 1] = y;
        xyz[i + 2] = -std::sin(b) * x + std::cos(b) * z;
    }
    pv::Mesh tilted(flat.kind(), std::move(xyz), {flat.connectivity().begin(), flat.connectivity().end()});
    tilted.set_fixed({flat.fixed().begin(), flat.fixed().end()});
    BOOST_REQUIRE(tilted.is_planar());
    pv::GlobalSolverOptions options;
    options.termination.max_iterations = 15;
    const auto [serial, distributed] = serial_and_distributed(tilted, options);
    BOOST_TEST(serial.iterations > 0);
}

// A focused shape phase: which vertices move is decided by their owners from the whole mesh's
// qualities, so the focus, its refocusing and every step are the serial run's.
BOOST_AUTO_TEST_CASE(a_focused_shape_phase_gives_the_serial_answer) {
    pv::GlobalSolverOptions options;
    options.focus_band = 0.1;
    options.termination.max_iterations = 40;
    const auto [serial, distributed] =
        serial_and_distributed(pv::test::perturbed_shared_mesh("mesquite/tets/tire.vtk", 0.05, 2), options);
    BOOST_TEST(serial.after.inverted == 0);
    BOOST_TEST(serial.history.back().moved > 0);
    for (std::size_t i = 0; i < serial.history.size(); ++i) BOOST_TEST(distributed.history[i].moved == serial.history[i].moved);
}

// The Newton finish (Newton steps where conjugate gradients stalled, on their barrier and then on
// a fresh one: on tire with min_progress a hundred times smaller than the default, which hands
// over later) takes the serial steps on any number of ranks. The shape phase before
// it damps vertices again where their own barrier terms fall (damped_vertex_ascent): decided by
// each vertex's owner, it takes the serial steps too. Slow (tests/CMakeLists.txt): the sanitizers
// see the finish's two parts on the ranks in the next case.
BOOST_AUTO_TEST_CASE(the_newton_finish_gives_the_serial_answer, *boost::unit_test::label("slow")) {
    pv::GlobalSolverOptions options;
    options.termination.min_progress = 1e-8;
    const auto [serial, distributed] = serial_and_distributed(pv::test::shared_mesh("mesquite/tets/tire.vtk"), options);
    const auto& history = serial.history;
    auto in = [&history](const char* phase) {
        return std::count_if(history.begin(), history.end(), [&](const pv::IterationRecord& r) { return r.phase == phase; });
    };
    BOOST_TEST(in("finish") > 5);
    BOOST_TEST(in("finish_fresh") > 5);
    BOOST_TEST(serial.gradient_passes > serial.iterations + 2 * (in("finish") + in("finish_fresh")));  // the products are counted
    for (std::size_t i = 0; i < serial.history.size(); ++i) BOOST_TEST(distributed.history[i].moved == serial.history[i].moved);
}

// A finish that hands over to a fresh barrier because its worst element rose far above t (tire
// with min_progress 0.1: the shape phase ends early and the finish climbs faster than t follows)
// takes the serial steps too, and so does the fresh barrier after it.
BOOST_AUTO_TEST_CASE(a_fresh_barrier_after_the_worst_rose_far_above_t_gives_the_serial_answer) {
    pv::GlobalSolverOptions options;
    options.termination.min_progress = 0.1;
    const auto [serial, distributed] = serial_and_distributed(pv::test::shared_mesh("mesquite/tets/tire.vtk"), options);
    const auto& h = serial.history;
    const auto finish = std::find_if(h.begin(), h.end(), [](const pv::IterationRecord& r) { return r.phase == "finish"; });
    const auto fresh = std::find_if(h.begin(), h.end(), [](const pv::IterationRecord& r) { return r.phase == "finish_fresh"; });
    BOOST_TEST_REQUIRE((fresh != h.end()));
    BOOST_TEST((fresh - finish) < 51);  // not after the first part's 50 steps
    BOOST_TEST(distributed.history.size() == h.size());
}

// The mean's polish (here always, after the finish): which vertices stand still is decided by
// their owners from the whole mesh's qualities, and its steps are the serial ones, bit for bit.
// Slow (tests/CMakeLists.txt): the sanitizers see the polish on the ranks in the queues of
// distributed_run and in partitioned_run_test's runs under the launcher (config_mpirun_np2).
BOOST_AUTO_TEST_CASE(the_means_polish_gives_the_serial_answer, *boost::unit_test::label("slow")) {
    pv::GlobalSolverOptions options;
    options.polish = pv::GlobalSolverOptions::Polish::Always;
    const auto [serial, distributed] = serial_and_distributed(pv::test::shared_mesh("mesquite/tets/tire.vtk"), options);
    const auto& h = serial.history;
    const auto polish = std::count_if(h.begin(), h.end(), [](const pv::IterationRecord& r) { return r.phase == "polish"; });
    BOOST_TEST(polish > 20);
    BOOST_TEST_REQUIRE(distributed.history.size() == h.size());
    for (std::size_t i = 0; i < h.size(); ++i)
        BOOST_TEST((distributed.history[i].moved == h[i].moved && distributed.history[i].mean_quality == h[i].mean_quality));
}

// Newton directions (each a truncated CG solve over Hessian products through the halo) take the
// same steps on any number of ranks as serially, on a mesh that is untangled first.
BOOST_AUTO_TEST_CASE(newton_directions_give_the_serial_answer) {
    pv::GlobalSolverOptions options;
    options.direction = pv::GlobalSolverOptions::Direction::Newton;
    options.newton_cg_iterations = 30;  // as many exchanges as needed to tell, at a fraction of the time
    options.termination.max_iterations = 8;
    options.untangle_termination.max_iterations = 150;
    const auto [serial, distributed] =
        serial_and_distributed(pv::test::perturbed_shared_mesh("mesquite/tets/tire.vtk", 0.05, 2), options);
    BOOST_TEST(serial.after.inverted == 0);
    BOOST_TEST(serial.worst_after > serial.worst_before);
    BOOST_TEST(serial.gradient_passes > 2 * serial.iterations);  // the products are counted
}

// A heavy tangle (every interior vertex moved by up to 1.5 local edge lengths), which the barrier
// ascent alone leaves tangled: the regularized energy frees it, and takes the same steps on any
// number of ranks as serially.
BOOST_AUTO_TEST_CASE(energy_untangling_gives_the_serial_answer) {
    pv::GlobalSolverOptions options;
    options.termination.max_iterations = 5;
    const auto [serial, distributed] =
        serial_and_distributed(pv::test::perturbed_shared_mesh("mesquite/tets/tire.vtk", 1.0, 21, 1.5), options);
    BOOST_TEST(serial.after.inverted == 0);
    BOOST_TEST(std::any_of(serial.history.begin(), serial.history.end(),
                           [](const auto& r) { return r.phase == "untangle_energy"; }));
}

// Where the barrier ascent stalls with elements still inverted, sweeps of local untangling take
// over. A distributed run sweeps color by color, its colors from the global ids, so it makes the
// same moves on any number of ranks: the run on all ranks ends as the run of each rank alone.
// (A serial run sweeps in id order: the same outcome, not the same mesh.)
BOOST_AUTO_TEST_CASE(local_untangling_where_the_ascent_stalls_gives_the_same_answer_on_any_rank_count) {
    const auto input = pv::test::perturbed_shared_mesh("mesquite/tets/tire.vtk", 0.3, 2);
    pv::GlobalSolverOptions options;
    options.untangling = pv::GlobalSolverOptions::Untangling::Barrier;  // the ascent, whose stalls need local rounds
    options.untangle_termination.progress_window = 5;  // call the ascent stalled early
    options.untangle_termination.min_progress = 0.01;
    options.termination.max_iterations = 5;
    auto local_rounds = [](const pv::Summary& s) {
        return std::count_if(s.history.begin(), s.history.end(), [](const auto& r) { return r.phase == "untangle_local"; });
    };
    pv::Mesh alone = input;
    auto alone_part = pv::DistributedMesh::scatter(MPI_COMM_SELF, &input, {});
    const auto alone_summary = pv::GlobalSolver(options).improve(alone_part);
    alone_part.gather_coordinates(&alone);
    BOOST_TEST_REQUIRE(local_rounds(alone_summary) > 0);

    pv::Mesh gathered = input;
    auto part = scatter(input);
    const auto summary = pv::GlobalSolver(options).improve(part);
    part.gather_coordinates(rank() == 0 ? &gathered : nullptr);
    BOOST_TEST_MESSAGE(ranks() << " ranks: " << summary.brief_report());
    BOOST_TEST(local_rounds(summary) == local_rounds(alone_summary));
    BOOST_TEST(summary.iterations == alone_summary.iterations);
    BOOST_TEST(pv::to_string(summary.reason) == pv::to_string(alone_summary.reason));
    BOOST_TEST(summary.after.inverted == 0);
    BOOST_TEST(summary.worst_after == alone_summary.worst_after, boost::test_tools::tolerance(1e-12));
    if (rank() == 0) BOOST_TEST(relative_difference(gathered, alone) <= 1e-10);
    pv::test::check_never_worse(summary);

    // The serial run untangles too.
    pv::Mesh serial = input;
    const auto serial_summary = pv::GlobalSolver(options).improve(serial);
    BOOST_TEST(serial_summary.after.inverted == 0);
}

BOOST_AUTO_TEST_CASE(shape_improvement_on_a_valid_mesh_matches_too) {
    const auto input = pv::test::shared_mesh("stellar/house2.node");
    pv::GlobalSolverOptions options;
    options.termination.max_iterations = 15;
    pv::Mesh serial = input;
    const auto serial_summary = pv::GlobalSolver(options).improve(serial);
    pv::Mesh gathered = input;
    auto part = scatter(input);
    const auto summary = pv::GlobalSolver(options).improve(part);
    part.gather_coordinates(rank() == 0 ? &gathered : nullptr);
    BOOST_TEST(summary.worst_after > summary.worst_before);
    BOOST_TEST(summary.after.inverted == 0);
    BOOST_TEST(summary.iterations == serial_summary.iterations);
    if (rank() == 0) BOOST_TEST(relative_difference(gathered, serial) <= 1e-10);
}

// The global solver reorders the part's elements in place while it runs (rather than holding a
// reordered copy); the local smoother's sums follow the part's order, so it must come back.
BOOST_AUTO_TEST_CASE(global_solver_hands_the_part_back_in_its_element_order) {
    pv::GlobalSolverOptions options;
    options.termination.max_iterations = 3;
    auto part = scatter(pv::test::shared_mesh("stellar/house2.node"));
    const std::vector<pv::VertexId> connectivity(part.mesh().connectivity().begin(), part.mesh().connectivity().end());
    const std::vector<pv::GlobalId> element_order(part.element_order().begin(), part.element_order().end());
    const std::vector<std::uint8_t> counted(part.counted().begin(), part.counted().end());
    pv::GlobalSolver(options).improve(part);
    BOOST_TEST((std::vector<pv::VertexId>(part.mesh().connectivity().begin(), part.mesh().connectivity().end()) == connectivity));
    BOOST_TEST(std::ranges::equal(part.element_order(), element_order));
    BOOST_TEST(std::ranges::equal(part.counted(), counted));
}

// gather_whole() builds on rank 0 the mesh no rank holds in a run from pieces: every vertex once,
// at its global id, with its owner's coordinates and flag; every element once.
BOOST_AUTO_TEST_CASE(gather_whole_builds_the_whole_mesh_in_the_canonical_order) {
    pv::Mesh input = pv::test::shared_mesh("mesquite/tets/tire.vtk");
    const pv::Mesh whole = pv::test::gathered_whole(input);
    if (rank() != 0) return;
    const auto order = pv::locality_order(input);
    BOOST_REQUIRE(whole.num_elements() == input.num_elements());
    std::vector<std::array<pv::VertexId, 4>> a, b;
    for (pv::ElementId e = 0; e < input.num_elements(); ++e) {
        std::array<pv::VertexId, 4> x{}, y{};
        for (int c = 0; c < 4; ++c) x[c] = order.old_vertex[whole.element(e)[c]], y[c] = input.element(e)[c];
        std::sort(x.begin(), x.end()), std::sort(y.begin(), y.end());
        a.push_back(x), b.push_back(y);
    }
    std::sort(a.begin(), a.end()), std::sort(b.begin(), b.end());
    BOOST_TEST((a == b));
}

BOOST_AUTO_TEST_CASE(more_ranks_than_vertices_is_an_error_on_every_rank) {
    if (ranks() < 2) return;
    // ranks - 1 vertices (at least one element needs 3; fewer vertices make a mesh of none).
    std::vector<double> xyz;
    for (int i = 0; i < ranks() - 1; ++i) xyz.insert(xyz.end(), {double(i), 0.0, 0.0});
    const pv::Mesh tiny(pv::ElementKind::Triangle, xyz, {});
    BOOST_CHECK_THROW(scatter(tiny), pv::OptionError);
}

BOOST_AUTO_TEST_CASE(partition_statistics_count_the_exchange) {
    const auto whole = pv::test::shared_mesh("mesquite/tets/tire.vtk");
    const auto part = pv::partition_vertices(whole, 4);
    const auto stats = pv::partition_statistics(whole, part, 4);
    BOOST_TEST(stats.ghost_copies > 0);
    BOOST_TEST(stats.shared_vertices > 0);
    BOOST_TEST(stats.shared_vertices <= stats.ghost_copies);
    BOOST_TEST(stats.colors >= stats.max_neighbours);  // a color per partner at the busiest part
    BOOST_TEST(stats.process_edges <= 6);
    BOOST_CHECK_THROW(pv::partition_vertices(whole, 0), pv::OptionError);
    BOOST_CHECK_THROW(pv::partition_vertices(whole, whole.num_vertices() + 1), pv::OptionError);
    const auto one = pv::partition_statistics(whole, pv::partition_vertices(whole, 1), 1);
    BOOST_TEST(one.ghost_copies == 0);
    BOOST_TEST(one.colors == 0);
}

BOOST_AUTO_TEST_SUITE_END()

BOOST_AUTO_TEST_SUITE(pieces)

using paloverde::test::scratch;

BOOST_AUTO_TEST_CASE(pieces_written_then_read_give_the_serial_answer) {
    const auto input = pv::test::shared_mesh("stellar/house2.node");
    for (const char* name : {"house.pvtu", "house.vtk"}) {
        const auto path = scratch(name);
        if (rank() == 0) pv::DistributedMesh::write_partitioned(input, ranks(), path);
        MPI_Barrier(MPI_COMM_WORLD);
        auto part = pv::DistributedMesh::read_pieces(MPI_COMM_WORLD, path);
        BOOST_TEST(part.global_vertices() == input.num_vertices());
        BOOST_TEST(part.global_elements() == input.num_elements());
        pv::GlobalSolverOptions options;
        options.termination.max_iterations = 10;
        const auto summary = pv::GlobalSolver(options).improve(part);
        pv::Mesh serial = input;
        const auto serial_summary = pv::GlobalSolver(options).improve(serial);
        BOOST_TEST(summary.worst_after == serial_summary.worst_after);
        BOOST_TEST(summary.iterations == serial_summary.iterations);
        // Written back as pieces and read again: the same coordinates.
        const auto again_path = scratch(std::string("again_") + name);
        part.write_pieces(again_path);
        auto again = pv::DistributedMesh::read_pieces(MPI_COMM_WORLD, again_path);
        BOOST_TEST(again.mesh().num_vertices() == part.mesh().num_vertices());
        BOOST_TEST(std::equal(again.mesh().coordinates().begin(), again.mesh().coordinates().end(),
                              part.mesh().coordinates().begin()));
    }
}

// Pieces of a mirrored tangled mesh: the decision is taken over all pieces together, so every
// rank flips; the count and the solve are those of the original, and pieces written back keep
// the mirror's order.
BOOST_AUTO_TEST_CASE(mirrored_pieces_are_flipped_alike_on_every_rank) {
    const auto tangled = pv::test::perturbed_shared_mesh("mesquite/tets/tire.vtk", 0.2, 7);
    const auto mirror = pv::test::mirrored(tangled);
    const auto path = scratch("mirror.pvtu");
    if (rank() == 0) pv::DistributedMesh::write_partitioned(mirror, ranks(), path);
    MPI_Barrier(MPI_COMM_WORLD);
    auto part = pv::DistributedMesh::read_pieces(MPI_COMM_WORLD, path);
    BOOST_TEST(part.orientation().flipped);
    BOOST_TEST(part.orientation().sign == -1);
    BOOST_TEST(part.mesh().elements_flipped());
    const pv::QualityAssessor assessor;
    BOOST_TEST(assessor.assess(part).inverted == pv::count_orientations(tangled).inverted);
    // The same solve as on the pieces of the original, to the bit.
    const auto original_path = scratch("original.pvtu");
    if (rank() == 0) pv::DistributedMesh::write_partitioned(tangled, ranks(), original_path);
    MPI_Barrier(MPI_COMM_WORLD);
    auto original = pv::DistributedMesh::read_pieces(MPI_COMM_WORLD, original_path);
    BOOST_TEST(!original.orientation().flipped);
    pv::GlobalSolverOptions options;
    options.termination.max_iterations = 5;
    const auto summary = pv::GlobalSolver(options).improve(part);
    const auto original_summary = pv::GlobalSolver(options).improve(original);
    BOOST_TEST(summary.after.inverted == original_summary.after.inverted);
    BOOST_TEST(summary.worst_after == original_summary.worst_after);
    BOOST_TEST(std::equal(part.mesh().coordinates().begin(), part.mesh().coordinates().end(),
                          original.mesh().coordinates().begin(), original.mesh().coordinates().end()));
    const auto again_path = scratch("mirror_again.pvtu");
    part.write_pieces(again_path);
    pv::DistributeOptions as_is;
    as_is.orientation = pv::OrientationMode::AsIs;
    auto again = pv::DistributedMesh::read_pieces(MPI_COMM_WORLD, again_path, as_is);
    BOOST_TEST(!again.orientation().flipped);
    BOOST_TEST(again.orientation().sign == -1);
    const auto now = assessor.assess(original);
    BOOST_TEST(assessor.assess(again).inverted == tangled.num_elements() - now.inverted - now.degenerate);
}

// A usage error (run it on as many processes as pieces): OptionError, exit code 2, on every rank.
BOOST_AUTO_TEST_CASE(the_wrong_number_of_pieces_is_an_error_on_every_rank) {
    const auto input = pv::test::shared_mesh("stellar/house2.node");
    const auto path = scratch("wrong_count.pvtu");
    if (rank() == 0) pv::DistributedMesh::write_partitioned(input, ranks() + 1, path);
    MPI_Barrier(MPI_COMM_WORLD);
    BOOST_CHECK_EXCEPTION(pv::DistributedMesh::read_pieces(MPI_COMM_WORLD, path), pv::OptionError,
                          [](const pv::OptionError& e) { return std::string(e.what()).find("pieces") != std::string::npos; });
}

BOOST_AUTO_TEST_CASE(a_vertex_owned_twice_is_an_error_on_every_rank) {
    if (ranks() < 2) return;
    const auto input = pv::test::shared_mesh("stellar/house2.node");
    const auto path = scratch("owned_twice.pvtu");
    if (rank() == 0) {
        pv::DistributedMesh::write_partitioned(input, ranks(), path);
        // Piece 1 claims one of its ghosts (owned by another piece) as its own.
        const auto piece = path.parent_path() / "owned_twice" / "owned_twice_1.vtu";
        auto file = pv::read_mesh(piece, {.format = pv::MeshFormat::FromExtension, .fix_boundary = false});
        auto points = file.point_fields;
        for (auto& f : points)
            if (f.name == "OwnerRank")
                for (double& owner : f.values)
                    if (owner != 1.0) {
                        owner = 1.0;
                        break;
                    }
        std::vector<pv::Field> without_fixed;
        for (auto& f : points)
            if (f.name != "fixed") without_fixed.push_back(f);
        pv::write_mesh(piece, file.mesh, {}, without_fixed, file.cell_fields);
    }
    MPI_Barrier(MPI_COMM_WORLD);
    BOOST_CHECK_EXCEPTION(pv::DistributedMesh::read_pieces(MPI_COMM_WORLD, path), pv::MeshError,
                          [](const pv::MeshError& e) { return std::string(e.what()).find("more than one") != std::string::npos; });
}

BOOST_AUTO_TEST_SUITE_END()

BOOST_AUTO_TEST_SUITE(distributed_local)

BOOST_AUTO_TEST_CASE(coloring_is_proper_and_independent_of_the_rank_count) {
    const auto whole = pv::test::shared_mesh("mesquite/tets/tire.vtk");
    auto part = scatter(whole);
    const auto coloring = pv::color_vertices(part);
    // Proper on every local element (ghosts carry their owners' colors).
    long clashes = 0;
    for (pv::ElementId e = 0; e < part.mesh().num_elements(); ++e) {
        const auto corners = part.mesh().element(e);
        for (std::size_t i = 0; i < corners.size(); ++i)
            for (std::size_t j = i + 1; j < corners.size(); ++j)
                clashes += coloring.color[corners[i]] >= 0 && coloring.color[corners[i]] == coloring.color[corners[j]];
    }
    BOOST_TEST(part.reducer().total(static_cast<double>(clashes)) == 0.0);
    // The same colors as a one-rank run, vertex by vertex.
    auto alone = pv::DistributedMesh::scatter(MPI_COMM_SELF, &whole);
    const auto reference = pv::color_vertices(alone);
    long different = 0;
    for (pv::VertexId v = 0; v < part.mesh().num_vertices(); ++v) {
        const auto id = part.mesh().global_ids()[v];
        const auto ids = alone.mesh().global_ids();
        const auto at = std::lower_bound(ids.begin(), ids.end(), id) - ids.begin();
        different += coloring.color[v] != reference.color[static_cast<std::size_t>(at)];
    }
    BOOST_TEST(part.reducer().total(static_cast<double>(different)) == 0.0);
    BOOST_TEST(coloring.count == reference.count);
}

BOOST_AUTO_TEST_CASE(untangles_and_never_makes_the_worst_element_worse) {
    const auto input = pv::test::perturbed_shared_mesh("mesquite/tets/tire.vtk", 0.05, 3);
    auto part = scatter(input);
    pv::LocalSolverOptions options;
    options.termination.max_iterations = 5;
    const auto summary = pv::LocalSolver(options).improve(part);
    BOOST_TEST_MESSAGE(ranks() << " ranks: " << summary.brief_report());
    BOOST_TEST(summary.before.inverted > 0);
    BOOST_TEST(summary.after.inverted == 0);
    pv::Mesh gathered = input;
    part.gather_coordinates(rank() == 0 ? &gathered : nullptr);
    if (rank() == 0) {
        BOOST_TEST(pv::count_orientations(gathered).inverted == 0);
        const auto after = pv::QualityAssessor().assess(gathered);
        BOOST_TEST(after.metric("aspect_ratio")->movable.min == summary.worst_after);
    }
    // Ghosts sit where their owners put them.
    std::vector<double> xyz(part.mesh().coordinates().begin(), part.mesh().coordinates().end());
    part.halo().update(xyz, 3);
    BOOST_TEST(std::equal(xyz.begin(), xyz.end(), part.mesh().coordinates().begin()));
}

// A heavy tangle (every interior vertex moved by up to 1.5 local edge lengths): the energy
// sweeps free it with the same moves on any number of ranks (colors from global ids, exact sums
// for the schedule's epsilon).
BOOST_AUTO_TEST_CASE(energy_untangling_gives_the_one_rank_answer) {
    const auto input = pv::test::perturbed_shared_mesh("mesquite/tets/tire.vtk", 1.0, 21, 1.5);
    pv::LocalSolverOptions options;
    options.improve_shape = false;
    auto part = scatter(input);
    const auto summary = pv::LocalSolver(options).improve(part);
    BOOST_TEST_MESSAGE(ranks() << " ranks: " << summary.brief_report());
    BOOST_TEST(summary.before.inverted > 0);
    BOOST_TEST(summary.after.inverted == 0);
    pv::test::check_never_worse(summary);
    auto alone = pv::DistributedMesh::scatter(MPI_COMM_SELF, &input);
    const auto alone_summary = pv::LocalSolver(options).improve(alone);
    BOOST_TEST(summary.iterations == alone_summary.iterations);
    pv::Mesh from_one = input, from_all = input;
    alone.gather_coordinates(&from_one);
    part.gather_coordinates(rank() == 0 ? &from_all : nullptr);
    if (rank() == 0) {
        BOOST_TEST(pv::count_orientations(from_all).inverted == 0);
        BOOST_TEST(relative_difference(from_all, from_one) == 0.0);
    }
}

BOOST_AUTO_TEST_CASE(improves_a_valid_mesh_like_the_serial_smoother) {
    const auto input = pv::test::shared_mesh("stellar/house2.node");
    pv::LocalSolverOptions options;
    options.termination.max_iterations = 8;
    auto part = scatter(input);
    const auto summary = pv::LocalSolver(options).improve(part);
    pv::Mesh serial = input;
    const auto serial_summary = pv::LocalSolver(options).improve(serial);
    BOOST_TEST(summary.worst_after > summary.worst_before);
    BOOST_TEST(summary.after.inverted == 0);
    // A different (global) coloring visits vertices in another order: close, not equal.
    BOOST_TEST(summary.worst_after >= 0.8 * serial_summary.worst_after);
    BOOST_TEST_MESSAGE(ranks() << " ranks: local " << summary.worst_after << " vs serial " << serial_summary.worst_after);
    // Colors and updates do not depend on the split: the same mesh as on one rank.
    auto alone = pv::DistributedMesh::scatter(MPI_COMM_SELF, &input);
    pv::LocalSolver(options).improve(alone);
    pv::Mesh from_one = input, from_all = input;
    alone.gather_coordinates(&from_one);
    part.gather_coordinates(rank() == 0 ? &from_all : nullptr);
    if (rank() == 0) BOOST_TEST(relative_difference(from_all, from_one) == 0.0);
}

BOOST_AUTO_TEST_SUITE_END()

BOOST_AUTO_TEST_SUITE(distributed_run)

// One queue, one path: the wrapper a serial run uses, run on the part, ends on the serial mesh
// with the same steps.
BOOST_AUTO_TEST_CASE(a_queue_runs_on_a_part_as_on_the_whole_mesh) {
    const auto input = pv::test::perturbed_shared_mesh("mesquite/tets/tire.vtk", 0.05, 2);
    pv::GlobalSolverOptions options;
    options.termination.max_iterations = 8;
    options.untangle_termination.max_iterations = 150;
    pv::Mesh serial = input;
    const pv::QueueResult serial_result = pv::wrappers::untangle_then_improve(options).run(serial);

    pv::Mesh gathered = input;
    auto part = scatter(input);
    const pv::QueueResult result = pv::wrappers::untangle_then_improve(options).run(part);
    part.gather_coordinates(rank() == 0 ? &gathered : nullptr);
    BOOST_TEST(result.success == serial_result.success);
    BOOST_REQUIRE(result.steps.size() == serial_result.steps.size());
    for (std::size_t i = 0; i < result.steps.size(); ++i) {
        BOOST_TEST(result.steps[i].label == serial_result.steps[i].label);
        if (const auto* summary = std::get_if<pv::Summary>(&result.steps[i].outcome))
            BOOST_TEST(summary->iterations == std::get<pv::Summary>(serial_result.steps[i].outcome).iterations);
        else
            BOOST_TEST(std::get<pv::QualityReport>(result.steps[i].outcome).inverted ==
                       std::get<pv::QualityReport>(serial_result.steps[i].outcome).inverted);
    }
    if (rank() == 0) BOOST_TEST(relative_difference(gathered, serial) <= 1e-10);
}

// The command line's path (config::run): read on rank 0, solve on all, gather and write one file.
// On one rank the run is the serial one, the one-part case of the same path.
BOOST_AUTO_TEST_CASE(a_whole_run_writes_the_serial_answer) {
    const auto input_path = pv::test::shared_data("stellar/house2.node");
    const auto input = pv::read_mesh(input_path).mesh;
    const auto output = std::filesystem::temp_directory_path() / ("paloverde_run_" + std::to_string(ranks()) + ".vtk");
    const std::vector<cfg::Override> set{{"input.mesh=" + input_path.string(), "test", true},
                                         {"output.mesh=" + output.string(), "test", true},
                                         {"partition.parts=" + std::to_string(ranks())},
                                         {"queue[0].improve.name=global"},
                                         {"queue[0].improve.termination.max_iterations=10"}};
    const cfg::RunResult result = cfg::run(cfg::parse_config("", "test", set));
    BOOST_TEST(result.methods.at(0).after.inverted == 0);
    if (ranks() == 1) {
        BOOST_TEST(!result.parallel.has_value());
    } else {
        BOOST_REQUIRE(result.parallel.has_value());
        BOOST_TEST(result.parallel->ranks == ranks());
        BOOST_TEST(result.parallel->ghost_copies > 0);
    }
    if (rank() == 0) {
        pv::GlobalSolverOptions solver_options;
        solver_options.termination.max_iterations = 10;
        pv::Mesh serial = input;
        pv::GlobalSolver(solver_options).improve(serial);
        const auto written = pv::read_mesh(output).mesh;
        BOOST_TEST(relative_difference(written, serial) <= 1e-10);
    }
}

BOOST_AUTO_TEST_SUITE_END()

// Sliding boundary vertices (boundary: slide, issue 17): every rank slides on the whole mesh's
// boundary (the faces where the parts were cut are not boundary), and an owner and its ghosts
// project the same point alike.
BOOST_AUTO_TEST_SUITE(distributed_sliding)

// `Solver` with `options` but the boundary fixed, on the ranks, with the budget the sliding run
// gives its own boundary-fixed run (half): the sliding run `slid` ends with the worst element of
// all no lower. (A fixed run on the whole budget can end higher: tri_20258 after 30 iterations,
// or where the global solver's Newton finish uses the second half.)
template <class Solver, class Options>
void check_no_worse_than_fixed(const pv::Mesh& input, Options options, const pv::Summary& slid) {
    options.boundary = Options::Boundary::Fixed;
    options.termination.max_iterations = (options.termination.max_iterations + 1) / 2;
    auto part = scatter(input);
    const auto fixed = Solver(options).improve(part);
    BOOST_TEST(pv::test::worst_of_all(slid, "aspect_ratio") >= pv::test::worst_of_all(fixed, "aspect_ratio"));
}

// The checks of the_global_solver_slides_to_the_serial_mesh, on `name`.
void check_slides_to_the_serial_mesh(const char* name) {
    const auto input = pv::test::shared_mesh(name);
    pv::GlobalSolverOptions options;
    options.boundary = pv::GlobalSolverOptions::Boundary::Slide;
    options.termination.max_iterations = 100;  // enough for both runs (check_no_worse_than_fixed)
    pv::Mesh gathered = input;
    const auto [serial, slid] = serial_and_distributed(input, options, &gathered);
    BOOST_REQUIRE(slid.boundary.has_value());
    BOOST_TEST(slid.boundary->moved > 0);
    BOOST_TEST(slid.boundary->sliding == serial.boundary->sliding);
    BOOST_TEST(slid.boundary->moved == serial.boundary->moved);
    BOOST_TEST(slid.boundary->largest_distance == serial.boundary->largest_distance);
    BOOST_TEST(slid.boundary->volume_after == serial.boundary->volume_after);
    check_no_worse_than_fixed<pv::GlobalSolver>(input, options, slid);
    if (rank() == 0) pv::test::check_on_the_input_boundary(input, gathered, slid);
}

// The global solver's sliding run takes the serial steps to the serial mesh, bit for bit, on any
// number of ranks; every boundary vertex ends on the input's boundary, corners in place. Curved
// faces with creases (tire), a mesh whose elements are flipped on reading (house2), planar
// triangles (tri_20258); flat faces (cube-clip-5) in the next case.
BOOST_DATA_TEST_CASE(the_global_solver_slides_to_the_serial_mesh,
                     boost::unit_test::data::make({"mesquite/tets/tire.vtk", "stellar/house2.node",
                                                   "mesquite/tris/tri_20258.vtk"}),
                     name) {
    check_slides_to_the_serial_mesh(name);
}

// Slow (tests/CMakeLists.txt): the sanitizers see the other meshes slide on the ranks, above.
BOOST_AUTO_TEST_CASE(the_global_solver_slides_cube_clip_5_to_the_serial_mesh,
                     *boost::unit_test::label("slow")) {
    check_slides_to_the_serial_mesh("mesquite/tets/cube-clip-5.vtk");
}

// A sliding run stopped in its sliding run (three records after rank 0 saw the second checkpoint
// of the pair, written before that run) resumes on as many ranks to the serial mesh, bit for bit.
BOOST_AUTO_TEST_CASE(a_sliding_run_stopped_while_sliding_resumes_on_the_parts_to_the_serial_mesh) {
    const auto input = pv::test::shared_mesh("mesquite/tets/tire.vtk");
    pv::GlobalSolverOptions options;
    options.boundary = pv::GlobalSolverOptions::Boundary::Slide;
    options.termination.max_iterations = 24;
    pv::Mesh serial = input;
    const pv::Summary uninterrupted = pv::GlobalSolver(options).improve(serial);
    BOOST_TEST_REQUIRE(uninterrupted.message.find("then sliding") != std::string::npos);

    const std::filesystem::path file = pv::test::scratch("sliding.ckpt");
    if (rank() == 0) std::filesystem::remove(file);
    auto writing = options;
    writing.checkpoint.file = file.string();
    // Rank 0 watches the file: a stop requested on one rank stops them all at once.
    std::string last;
    int written = 0, records = 0;
    auto stopped_part = scatter(input);
    pv::GlobalSolver stopping(writing);
    stopping.set_observer([&](const pv::IterationRecord&) {
        if (rank() != 0 || !std::filesystem::exists(file)) return;
        const std::string bytes = pv::test::read_text(file);
        if (bytes != last) last = bytes, ++written;
        if (written >= 2 && ++records == 3) pv::request_stop();
    });
    pv::clear_stop_request();
    const pv::Summary stopped = stopping.improve(stopped_part);
    pv::clear_stop_request();
    BOOST_TEST_REQUIRE(to_string(stopped.reason) == "interrupted");

    auto resuming = options;
    resuming.checkpoint.resume = file.string();
    auto part = scatter(input);
    const pv::Summary resumed = pv::GlobalSolver(resuming).improve(part);
    BOOST_TEST(resumed.message == uninterrupted.message);
    BOOST_TEST(resumed.iterations == uninterrupted.iterations);
    BOOST_TEST(resumed.history.size() == uninterrupted.history.size());
    BOOST_TEST(resumed.worst_after == uninterrupted.worst_after);
    pv::Mesh gathered = input;
    part.gather_coordinates(rank() == 0 ? &gathered : nullptr);
    if (rank() == 0) BOOST_TEST(relative_difference(gathered, serial) == 0.0);
    MPI_Barrier(MPI_COMM_WORLD);
    if (rank() == 0) std::filesystem::remove(file), std::filesystem::remove(file.string() + ".run");
}

// A surface mesh slides on itself, on every rank the whole surface (gathered, ordered by
// coordinates; each element's normal found by its corners' global ids): the serial mesh bit for
// bit, for a torus of triangles, for Mesquite's sphere patch of quadrilaterals, its outline
// sliding along itself, for a sphere of triangles on the sphere as its domain, and for a tangled
// torus, untangled sliding (energy, then shape).
BOOST_DATA_TEST_CASE(a_surface_mesh_slides_to_the_serial_mesh, boost::unit_test::data::make({0, 1, 2, 3}), which) {
    const auto input = which == 0   ? pv::test::torus(32, 16, 0.3)
                       : which == 1 ? pv::test::shared_mesh("mesquite/hexes/sph-10-zsquare.vtk")
                       : which == 2 ? pv::test::sphere(16, 10, 0.3)
                                    : pv::test::tangled_torus(32, 16);
    pv::GlobalSolverOptions options;
    options.boundary = pv::GlobalSolverOptions::Boundary::Slide;
    if (which == 2) options.surface.domain.shape = pv::SurfaceDomain::Shape::Sphere;
    options.termination.max_iterations = 60;
    const auto [serial, slid] = serial_and_distributed(input, options);
    if (which == 3) {
        BOOST_TEST(serial.before.inverted == 8);
        BOOST_TEST(serial.after.inverted == 0);
        BOOST_TEST(serial.untangle_iterations > 0);
    }
    BOOST_REQUIRE(slid.boundary.has_value());
    BOOST_TEST(slid.boundary->moved > 0);
    BOOST_TEST(slid.boundary->moved == serial.boundary->moved);
    BOOST_TEST(slid.boundary->largest_distance == serial.boundary->largest_distance);
    BOOST_TEST(slid.boundary->volume_after == serial.boundary->volume_after);
}

// The local smoother sweeps a part by colors from the global ids: sliding, it makes the same
// moves on any number of ranks as on one, and keeps the boundary on the input's.
BOOST_AUTO_TEST_CASE(the_local_smoother_slides_to_the_one_rank_mesh) {
    const auto input = pv::test::shared_mesh("mesquite/tets/tire.vtk");
    pv::LocalSolverOptions options;
    options.boundary = pv::LocalSolverOptions::Boundary::Slide;
    options.termination.max_iterations = 8;
    auto part = scatter(input);
    const auto slid = pv::LocalSolver(options).improve(part);
    BOOST_TEST_MESSAGE(ranks() << " ranks: " << slid.brief_report());
    auto alone = pv::DistributedMesh::scatter(MPI_COMM_SELF, &input);
    const auto alone_summary = pv::LocalSolver(options).improve(alone);
    BOOST_TEST(slid.iterations == alone_summary.iterations);
    BOOST_TEST(slid.worst_after == alone_summary.worst_after);
    BOOST_REQUIRE(slid.boundary.has_value());
    BOOST_TEST(slid.boundary->moved > 0);
    BOOST_TEST(slid.boundary->moved == alone_summary.boundary->moved);
    check_no_worse_than_fixed<pv::LocalSolver>(input, options, slid);
    pv::Mesh from_one = input, from_all = input;
    alone.gather_coordinates(&from_one);
    part.gather_coordinates(rank() == 0 ? &from_all : nullptr);
    if (rank() == 0) {
        BOOST_TEST(relative_difference(from_all, from_one) == 0.0);
        pv::test::check_on_the_input_boundary(input, from_all, slid);
    }
}

BOOST_AUTO_TEST_SUITE_END()
