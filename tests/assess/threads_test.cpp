// An assessment spreads over the threads on large meshes (quality_assessor.cpp): its report must
// not depend on how many there are, to the bit, nor on where the worst element falls among them.
#include <omp.h>

#include <boost/test/unit_test.hpp>

#include "paloverde/assess/quality_assessor.hpp"
#include "support/solver_checks.hpp"

namespace pv = paloverde;

BOOST_AUTO_TEST_SUITE(assessor_threads)

BOOST_AUTO_TEST_CASE(the_report_is_the_same_on_one_two_and_three_threads) {
    // 112,393 tets: above the size where the assessment goes parallel. Tangled, so that the
    // inverted counts and the negative qualities are exercised too.
    const auto mesh = pv::test::perturbed_shared_mesh("mesquite/tets/cub_wedge_like.vtk", 0.3, 5);
    const int saved = omp_get_max_threads();
    std::string reports[3];
    for (int threads = 1; threads <= 3; ++threads) {
        omp_set_num_threads(threads);
        const auto report = pv::QualityAssessor().assess(mesh);
        reports[threads - 1] = report.to_json();
        if (threads == 1) {
            BOOST_TEST(report.inverted > 0);
            const auto* aspect = report.metric("aspect_ratio");
            BOOST_TEST_REQUIRE(aspect);
            BOOST_TEST(aspect->all.worst_element >= 0);
        }
    }
    omp_set_num_threads(saved);
    BOOST_TEST(reports[0] == reports[1]);
    BOOST_TEST(reports[0] == reports[2]);
}

BOOST_AUTO_TEST_SUITE_END()
