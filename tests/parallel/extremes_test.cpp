// The extremes of the barrier's terms, taken in lanes: the same numbers as std::min and std::max
// folded in order (which every process and the serial run take alike), NaN passed over.
#include <boost/test/unit_test.hpp>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "core/extremes.hpp"

namespace pv = paloverde;

namespace {

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

pv::detail::Extremes folded(const std::vector<double>& values) {
    pv::detail::Extremes e;
    for (double v : values) {
        e.least = std::min(e.least, v);
        e.greatest = std::max(e.greatest, v);
    }
    return e;
}

}  // namespace

BOOST_AUTO_TEST_SUITE(extremes)

BOOST_AUTO_TEST_CASE(the_same_numbers_as_min_and_max_in_order) {
    std::mt19937_64 random(23);
    std::uniform_real_distribution<double> value(-1e3, 1e3);
    constexpr double kInfinity = std::numeric_limits<double>::infinity();
    long mismatches = 0, cases = 0;
    // Lengths around the lanes' width, with NaNs and infinities in any lane or in the tail.
    for (std::size_t n : {0, 1, 2, 7, 8, 9, 15, 16, 17, 31, 64, 100, 1001})
        for (int trial = 0; trial < 40; ++trial) {
            std::vector<double> x(n);
            for (double& v : x) v = value(random);
            if (n > 0 && trial % 3 == 1) x[random() % n] = std::numeric_limits<double>::quiet_NaN();
            if (n > 0 && trial % 4 == 2) x[random() % n] = -kInfinity;
            if (n > 0 && trial % 5 == 3) x[random() % n] = kInfinity;
            if (n > 0 && trial == 7) std::fill(x.begin(), x.end(), std::numeric_limits<double>::quiet_NaN());
            const pv::detail::Extremes lanes = pv::detail::extremes(x), expected = folded(x);
            mismatches += !same_bits(lanes.least, expected.least) || !same_bits(lanes.greatest, expected.greatest);
            ++cases;
        }
    BOOST_TEST(cases == 13 * 40);
    BOOST_TEST(mismatches == 0);
}

BOOST_AUTO_TEST_CASE(nothing_but_nan_leaves_the_empty_extremes) {
    const std::vector<double> x(13, std::numeric_limits<double>::quiet_NaN());
    const pv::detail::Extremes e = pv::detail::extremes(x);
    BOOST_TEST(e.least == std::numeric_limits<double>::infinity());
    BOOST_TEST(e.greatest == -std::numeric_limits<double>::infinity());
}

BOOST_AUTO_TEST_CASE(the_least_and_greatest_of_a_long_run) {
    // The greatest in the last lane of the last group (10,000 numbers), or in the tail after it.
    for (std::size_t n : {10000, 10003}) {
        std::vector<double> x(n);
        for (std::size_t i = 0; i < n; ++i) x[i] = std::sin(static_cast<double>(i));
        x[4321] = -2.5;
        x[n - 1] = 3.5;
        const pv::detail::Extremes e = pv::detail::extremes(x);
        BOOST_TEST(e.least == -2.5);
        BOOST_TEST(e.greatest == 3.5);
    }
}

BOOST_AUTO_TEST_SUITE_END()
