#pragma once
// The checks every solver passes: never worse than its input, and a history that shows it.
#include <boost/test/unit_test.hpp>

#include "paloverde/solvers/summary.hpp"

namespace paloverde::test {

// Within a phase: the count of non-positive elements never rises; at an equal count the best
// worst quality never falls; every accepted global step raised its objective. Overall: no more
// inverted elements than the input, and no lower worst quality for a valid input.
inline void check_never_worse(const Summary& summary) {
    BOOST_TEST(summary.after.inverted <= summary.before.inverted);
    if (summary.before.inverted == 0) BOOST_TEST(summary.worst_after >= summary.worst_before);
    const auto& h = summary.history;
    for (std::size_t i = 1; i < h.size(); ++i) {
        if (h[i].phase != h[i - 1].phase) continue;
        BOOST_TEST(h[i].inverted <= h[i - 1].inverted);
        if (h[i].inverted == h[i - 1].inverted) BOOST_TEST(h[i].best_worst_quality >= h[i - 1].best_worst_quality);
        if (h[i].step > 0.0) BOOST_TEST(h[i].gain > 0.0);
    }
}

}  // namespace paloverde::test
