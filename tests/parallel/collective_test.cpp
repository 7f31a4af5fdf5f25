// parallel::together, the one way a distributed run fails: a failure on any rank is a failure on
// every rank, of the same kind (the exit code depends on it) and with the same message. Run on
// 1, 2 and 4 ranks (CTest entries parallel, parallel_np2, parallel_np4).
#include <mpi.h>

#include <boost/test/unit_test.hpp>
#include <string>

#include "paloverde/core/error.hpp"
#include "parallel/collective.hpp"
#include "world.hpp"

namespace pv = paloverde;

namespace {

// What `together` throws on this rank when `fail` throws on the ranks it picks: the message and
// which kind was caught ("option", "mesh", "error"), or "none".
template <class Fail>
std::pair<std::string, std::string> outcome(bool here, Fail&& fail) {
    try {
        pv::parallel::together(MPI_COMM_WORLD, here, fail);
    } catch (const pv::OptionError& e) {
        return {"option", e.what()};
    } catch (const pv::MeshError& e) {
        return {"mesh", e.what()};
    } catch (const pv::Error& e) {
        return {"error", e.what()};
    }
    return {"none", ""};
}

}  // namespace

BOOST_AUTO_TEST_SUITE(collective)

BOOST_AUTO_TEST_CASE(a_failure_anywhere_is_the_same_failure_everywhere) {
    const int rank = pv::test::rank(), last = pv::test::ranks() - 1;
    // Nothing fails: nothing is thrown, and work runs only where asked.
    int ran = 0;
    BOOST_TEST(outcome(rank == 0, [&] { ++ran; }).first == "none");
    BOOST_TEST(ran == (rank == 0 ? 1 : 0));
    // Rank 0 alone works and fails: every rank gets its kind and message.
    const auto usage = outcome(rank == 0, [] { throw pv::OptionError("bad option on rank 0"); });
    BOOST_TEST(usage.first == "option");
    BOOST_TEST(usage.second == "bad option on rank 0");
    const auto mesh = outcome(rank == 0, [] { throw pv::MeshError("bad mesh"); });
    BOOST_TEST(mesh.first == "mesh");
    // Every rank works; the last one and rank 0 fail differently: rank 0's failure wins (the
    // lowest failing rank), with the file error's own text; other kinds come through as Error.
    const auto lowest = outcome(true, [&] {
        if (rank == 0) throw pv::FileError("in.vtk", 3, "broken line");
        if (rank == last) throw pv::OptionError("not this one");
    });
    BOOST_TEST(lowest.first == "error");
    BOOST_TEST(lowest.second.find("in.vtk") != std::string::npos, lowest.second);
    BOOST_TEST(lowest.second.find("broken line") != std::string::npos, lowest.second);
    // Only the last rank fails.
    const auto alone = outcome(true, [&] {
        if (rank == last) throw pv::OptionError("rank " + std::to_string(last) + " disagrees");
    });
    BOOST_TEST(alone.first == "option");
    BOOST_TEST(alone.second == "rank " + std::to_string(last) + " disagrees");
}

BOOST_AUTO_TEST_SUITE_END()
