// The barrier's logarithm: the same bits from its AVX2, SSE2 and scalar paths (so from every
// process of a run), within one unit in the last place of std::log, and std::log's values where
// the input is not a positive normal number.
#include <boost/test/unit_test.hpp>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "core/fast_log.hpp"

namespace pv = paloverde;

namespace {

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0 || (std::isnan(a) && std::isnan(b)); }

// Random positive numbers from 1e-300 to 1e300, a band around 1 (where log is small), and the
// special inputs.
std::vector<double> inputs() {
    std::mt19937_64 random(17);
    std::uniform_real_distribution<double> exponent(-690.0, 690.0), near_one(-1e-3, 1e-3);
    std::vector<double> x;
    for (int i = 0; i < 200000; ++i) x.push_back(std::exp(exponent(random)));
    for (int i = 0; i < 20000; ++i) x.push_back(1.0 + near_one(random));
    for (double v : {0.0, -0.0, -1.0, 1.0, 2.0, 0.5, std::sqrt(2.0), std::numeric_limits<double>::min(),
                     std::numeric_limits<double>::denorm_min(), 1e-310, std::numeric_limits<double>::max(),
                     std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
                     std::numeric_limits<double>::quiet_NaN()})
        x.push_back(v);
    std::shuffle(x.begin(), x.end(), random);
    x.push_back(3.0);  // a length that is no multiple of the vectors' width
    return x;
}

}  // namespace

BOOST_AUTO_TEST_SUITE(fast_log)

BOOST_AUTO_TEST_CASE(every_path_gives_the_same_bits) {
    const std::vector<double> x = inputs();
    std::vector<double> best(x.size()), sse2(x.size()), in_place = x;
    pv::detail::log_all(x.data(), best.data(), x.size());
    pv::detail::log_all(x.data(), sse2.data(), x.size(), pv::detail::LogSimd::sse2);
    pv::detail::log_all(in_place.data(), in_place.data(), x.size());
    long mismatches = 0;
    for (std::size_t i = 0; i < x.size(); ++i) {
        const double one = pv::detail::log_one(x[i]);
        mismatches += !same_bits(best[i], one) || !same_bits(sse2[i], one) || !same_bits(in_place[i], one);
    }
    BOOST_TEST(mismatches == 0);
}

BOOST_AUTO_TEST_CASE(within_one_unit_in_the_last_place_of_std_log) {
    const std::vector<double> x = inputs();
    std::vector<double> y(x.size());
    pv::detail::log_all(x.data(), y.data(), x.size());
    long off = 0, different = 0;
    for (std::size_t i = 0; i < x.size(); ++i) {
        const double exact = std::log(x[i]);
        if (!(x[i] > 0.0) || !std::isfinite(x[i]) || x[i] < std::numeric_limits<double>::min()) {
            off += !same_bits(y[i], exact);  // std::log's own value
            continue;
        }
        const double ulp = std::abs(std::nextafter(exact, 0.0) - exact);
        different += y[i] != exact;
        off += !(std::abs(y[i] - exact) <= (exact == 0.0 ? 0.0 : ulp));
    }
    BOOST_TEST(off == 0);
    BOOST_TEST(different < static_cast<long>(x.size() / 20));  // nearly always the same number
}

BOOST_AUTO_TEST_SUITE_END()
