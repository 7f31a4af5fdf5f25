// ExactSum: the sum must not depend on the order of the terms or on how partial sums were split
// and merged, and must be exact where rounding would lose everything.
#include <boost/test/unit_test.hpp>
#include <omp.h>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "core/exact_sums.hpp"
#include "paloverde/core/exact_sum.hpp"

namespace pv = paloverde;

namespace {

// x added to a BoundedSum under `bound` in runs of random lengths below 300, each with add_all, or
// with add_all_exact where `exact`; that sum, exactly.
pv::ExactSum summed_in_runs(const std::vector<double>& x, double bound, bool exact, pv::detail::BoundedSum::Simd simd,
                            std::mt19937_64& random) {
    pv::detail::BoundedSum s(bound);
    for (std::size_t begin = 0; begin < x.size();) {
        const std::size_t length = std::min<std::size_t>(x.size() - begin, random() % 300);
        if (exact) s.add_all_exact(x.data() + begin, length, simd);
        else s.add_all(x.data() + begin, length, simd);
        begin += length;
    }
    pv::ExactSum e;
    s.add_to(e);
    return e;
}

}  // namespace

BOOST_AUTO_TEST_SUITE(exact_sum)

BOOST_AUTO_TEST_CASE(keeps_what_rounding_loses) {
    pv::ExactSum s;
    for (double x : {1e100, 1.0, -1e100, 1e-300, -1.0}) s.add(x);
    BOOST_TEST(s.value() == 1e-300);
    pv::ExactSum tiny;
    tiny.add(std::numeric_limits<double>::denorm_min());
    tiny.add(std::numeric_limits<double>::denorm_min());
    BOOST_TEST(tiny.value() == 2 * std::numeric_limits<double>::denorm_min());
    pv::ExactSum huge;
    huge.add(std::numeric_limits<double>::max());
    huge.add(std::numeric_limits<double>::max());
    huge.add(-std::numeric_limits<double>::max());
    BOOST_TEST(huge.value() == std::numeric_limits<double>::max());  // no overflow in between
    pv::ExactSum negative;
    negative.add(-3.5);
    negative.add(1.25);
    BOOST_TEST(negative.value() == -2.25);
    BOOST_TEST(pv::ExactSum{}.value() == 0.0);
}

BOOST_AUTO_TEST_CASE(does_not_depend_on_order_or_split) {
    std::mt19937_64 random(7);
    std::uniform_real_distribution<double> mantissa(-1.0, 1.0);
    std::uniform_int_distribution<int> exponent(-40, 40);
    std::vector<double> terms(20000);
    for (double& t : terms) t = std::ldexp(mantissa(random), exponent(random));
    pv::ExactSum forward;
    for (double t : terms) forward.add(t);
    for (int trial = 0; trial < 5; ++trial) {
        std::shuffle(terms.begin(), terms.end(), random);
        // Split among "processes" of random sizes, normalized and merged as a reduction does.
        pv::ExactSum total;
        std::size_t begin = 0;
        while (begin < terms.size()) {
            const std::size_t end = std::min(terms.size(), begin + 1 + random() % 3000);
            pv::ExactSum part;
            for (std::size_t i = begin; i < end; ++i) part.add(terms[i]);
            part.normalize();
            total += part;
            begin = end;
        }
        BOOST_TEST(total.value() == forward.value());  // bit for bit
    }
    // And close to a careful floating-point sum.
    long double reference = 0.0L;
    for (double t : terms) reference += t;
    BOOST_TEST(std::abs(forward.value() - static_cast<double>(reference)) <= 1e-9 * std::abs(static_cast<double>(reference)));
}

BOOST_AUTO_TEST_CASE(special_values) {
    pv::ExactSum s;
    s.add(1.0);
    s.add(std::numeric_limits<double>::infinity());
    BOOST_TEST(s.value() == std::numeric_limits<double>::infinity());
    s.add(-std::numeric_limits<double>::infinity());
    BOOST_TEST(std::isnan(s.value()));
    pv::ExactSum n;
    n.add(std::nan(""));
    BOOST_TEST(std::isnan(n.value()));
}

// BoundedSum rounds each term the same way wherever it is added, so its sums must not depend on
// order or split either, and must stay within n 2^(e - 84) of the true sum.
BOOST_AUTO_TEST_CASE(bounded_sums_do_not_depend_on_order_or_split) {
    std::mt19937_64 random(11);
    std::uniform_real_distribution<double> mantissa(-1.0, 1.0);
    std::uniform_int_distribution<int> exponent(-60, 0);
    std::vector<double> terms(50000);
    double bound = 0.0;
    for (double& t : terms) {
        t = 3.0 * std::ldexp(mantissa(random), exponent(random));
        bound = std::max(bound, std::abs(t));
    }
    auto sum_in_parts = [&](std::size_t largest_part) {
        pv::ExactSum total;
        std::size_t begin = 0;
        while (begin < terms.size()) {
            const std::size_t end = std::min(terms.size(), begin + 1 + random() % largest_part);
            pv::detail::BoundedSum part(bound);
            for (std::size_t i = begin; i < end; ++i) part.add(terms[i]);
            pv::ExactSum exact;
            part.add_to(exact);
            exact.normalize();
            total += exact;
            begin = end;
        }
        return total.value();
    };
    const double whole = sum_in_parts(terms.size());
    for (int trial = 0; trial < 5; ++trial) {
        std::shuffle(terms.begin(), terms.end(), random);
        BOOST_TEST(sum_in_parts(3000) == whole);  // bit for bit
    }
    pv::ExactSum exact;
    for (double t : terms) exact.add(t);
    BOOST_TEST(std::abs(whole - exact.value()) <= terms.size() * std::ldexp(4.0, -84));
    // The threaded helper agrees with the single accumulator.
    const auto threaded = pv::detail::bounded_sums<1>(terms.size(), {bound}, [&](std::size_t i, auto& acc) { acc[0].add(terms[i]); });
    BOOST_TEST(threaded[0].value() == whole);
}

// add_exact() must give exactly ExactSum's sum, digit for digit, whatever the terms' sizes: near
// the bound, far below it (down to subnormals), zero, past it, with a few cancelling ones, and
// well past kFlush terms; and an unusable bound sends every term to the ExactSum.
BOOST_AUTO_TEST_CASE(bounded_sums_added_exactly_equal_exact_sums) {
    std::mt19937_64 random(7);
    std::uniform_real_distribution<double> mantissa(-1.0, 1.0);
    std::uniform_int_distribution<int> exponent(-1080, 1);
    std::vector<double> terms(30000);
    for (std::size_t i = 0; i < terms.size(); ++i) {
        const double m = mantissa(random);
        terms[i] = i % 3 == 0 ? std::ldexp(m, exponent(random)) : 1.5 * m;  // a third spread over every scale
    }
    terms[10] = 0.0, terms[11] = -0.0, terms[12] = std::numeric_limits<double>::denorm_min(), terms[13] = 1.5;
    terms[14] = 1e-300, terms[15] = -1.5, terms[16] = 3.0;  // 3.0: past the bound
    auto digits_of = [](pv::ExactSum s) {
        s.normalize();
        return std::vector<std::int64_t>(s.digits().begin(), s.digits().end());
    };
    pv::ExactSum exact;
    for (double t : terms) exact.add(t);
    for (const double bound : {1.5, 2.0, 1e10, -1.0, std::numeric_limits<double>::infinity()}) {
        pv::detail::BoundedSum s(bound);
        for (double t : terms) s.add_exact(t);
        pv::ExactSum total;
        s.add_to(total);
        BOOST_TEST_CONTEXT("bound " << bound) {
            BOOST_TEST(digits_of(total) == digits_of(exact));
            BOOST_TEST(total.value() == exact.value());
        }
    }
    pv::detail::BoundedSum with_nan(1.5);
    with_nan.add_exact(1.0);
    with_nan.add_exact(std::nan(""));
    pv::ExactSum nan_total;
    with_nan.add_to(nan_total);
    BOOST_TEST(std::isnan(nan_total.value()));
}

// add_all_exact() is add_exact() in SIMD instructions: the exact sum, bit for bit, with terms far
// below the bound (bits under the finer grid: the exact path), past it, infinite or NaN, for any
// run length and wherever the flushes fall.
BOOST_AUTO_TEST_CASE(exact_bounded_sums_of_whole_buffers_are_the_exact_sums) {
    std::mt19937_64 random(11);
    std::uniform_real_distribution<double> mantissa(-1.0, 1.0);
    std::uniform_int_distribution<int> exponent(-90, 2);
    const double bound = 2.5;
    std::vector<double> terms(20000);
    for (double& t : terms) t = std::ldexp(mantissa(random), exponent(random));  // up to 4: some past the bound
    using Simd = pv::detail::BoundedSum::Simd;
    auto exact = [](const std::vector<double>& x) {
        pv::ExactSum e;
        for (double t : x) e.add(t);
        return e.value();
    };
    auto one_by_one = [&](const std::vector<double>& x) {
        pv::detail::BoundedSum s(bound);
        for (double t : x) s.add_exact(t);
        pv::ExactSum e;
        s.add_to(e);
        return e.value();
    };
    auto in_runs = [&](const std::vector<double>& x, Simd simd) {
        return summed_in_runs(x, bound, true, simd, random).value();
    };
    for (int trial = 0; trial < 4; ++trial) {
        for (const Simd simd : {Simd::best, Simd::sse2}) {
            const double sum = exact(terms);
            BOOST_TEST(one_by_one(terms) == sum);  // bit for bit
            BOOST_TEST(in_runs(terms, simd) == sum);
            std::vector<double> special(terms);
            special[7] = std::numeric_limits<double>::infinity();
            BOOST_TEST(in_runs(special, simd) == std::numeric_limits<double>::infinity());
            special[9000] = std::nan("");
            BOOST_TEST(std::isnan(in_runs(special, simd)));
        }
        std::shuffle(terms.begin(), terms.end(), random);
    }
}

// exact_sum(x): the exact sum in lanes under x's largest magnitude, ExactSum's bits, on any number
// of threads; empty, all zero, infinite and NaN too.
BOOST_AUTO_TEST_CASE(an_exact_sum_of_an_array_is_exact) {
    std::mt19937_64 random(13);
    std::uniform_real_distribution<double> mantissa(-1.0, 1.0);
    std::uniform_int_distribution<int> exponent(-80, 20);
    std::vector<double> x(100000);
    for (double& t : x) t = std::ldexp(mantissa(random), exponent(random));
    auto one_by_one = [](const std::vector<double>& terms) {
        pv::ExactSum e;
        for (double t : terms) e.add(t);
        return e.value();
    };
    const int threads_before = omp_get_max_threads();
    for (const int threads : {1, 2}) {
        omp_set_num_threads(threads);
        BOOST_TEST(pv::detail::exact_sum(x).value() == one_by_one(x));  // bit for bit
        BOOST_TEST(pv::detail::exact_sum(std::vector<double>{}).value() == 0.0);
        BOOST_TEST(pv::detail::exact_sum(std::vector<double>(5000, 0.0)).value() == 0.0);
        std::vector<double> special(x);
        special[99] = -std::numeric_limits<double>::infinity();
        BOOST_TEST(pv::detail::exact_sum(special).value() == -std::numeric_limits<double>::infinity());
        special[4321] = std::nan("");
        BOOST_TEST(std::isnan(pv::detail::exact_sum(special).value()));
    }
    omp_set_num_threads(threads_before);
}

// add_all() splits many terms per SIMD instruction: it must give add()'s bits, with terms past
// the bound, infinities and NaN among them, for any run length and wherever the flushes fall.
BOOST_AUTO_TEST_CASE(bounded_sums_of_whole_buffers_equal_those_of_single_terms) {
    std::mt19937_64 random(5);
    std::uniform_real_distribution<double> mantissa(-1.0, 1.0);
    std::uniform_int_distribution<int> exponent(-70, 2);
    const double bound = 2.5;
    std::vector<double> terms(20000);
    for (double& t : terms) t = std::ldexp(mantissa(random), exponent(random));  // up to 4: some past the bound
    terms[7] = std::numeric_limits<double>::infinity();
    terms[9000] = -std::numeric_limits<double>::infinity();
    auto one_by_one = [&](const std::vector<double>& x) {
        pv::detail::BoundedSum s(bound);
        for (double t : x) s.add(t);
        pv::ExactSum e;
        s.add_to(e);
        return e;
    };
    using Simd = pv::detail::BoundedSum::Simd;
    auto in_runs = [&](const std::vector<double>& x, Simd simd) { return summed_in_runs(x, bound, false, simd, random); };
    for (int trial = 0; trial < 4; ++trial) {
        for (const Simd simd : {Simd::best, Simd::sse2}) {
            BOOST_TEST(std::isnan(one_by_one(terms).value()));  // +inf and -inf
            BOOST_TEST(std::isnan(in_runs(terms, simd).value()));
            std::vector<double> finite(terms);
            for (double& t : finite)
                if (!std::isfinite(t)) t = -3.0;
            BOOST_TEST(one_by_one(finite).value() == in_runs(finite, simd).value());  // bit for bit
            finite[123] = std::nan("");
            BOOST_TEST(std::isnan(in_runs(finite, simd).value()));
        }
        std::shuffle(terms.begin(), terms.end(), random);
    }
}

// Terms made a block at a time give bounded_sums' sums bit for bit: any length (blocks of 256
// and a partial last one), two sums at once, terms past the bound, and NaN.
BOOST_AUTO_TEST_CASE(bounded_block_sums_equal_bounded_sums) {
    std::mt19937_64 random(13);
    std::uniform_real_distribution<double> mantissa(-1.0, 1.0);
    std::uniform_int_distribution<int> exponent(-70, 2);
    const std::array<double, 2> bounds{2.5, 6.25};
    for (std::size_t n : {0, 1, 255, 256, 257, 5000, 100003}) {
        std::vector<double> x(n);
        for (double& t : x) t = std::ldexp(mantissa(random), exponent(random));  // some past the bound
        auto single = [&] {
            return pv::detail::bounded_sums<2>(n, bounds, [&](std::size_t i, auto& acc) {
                acc[0].add(x[i]);
                acc[1].add(x[i] * x[i]);
            });
        };
        auto blocks = [&] {
            return pv::detail::bounded_block_sums<2>(n, bounds, [&](std::size_t first, std::size_t count, const auto& terms) {
                BOOST_TEST(count <= 256u);
                for (std::size_t i = 0; i < count; ++i) {
                    terms[0][i] = x[first + i];
                    terms[1][i] = x[first + i] * x[first + i];
                }
            });
        };
        const auto a = single(), b = blocks();
        BOOST_TEST(a[0].value() == b[0].value());
        BOOST_TEST(a[1].value() == b[1].value());
        if (n > 300) {
            x[n / 2] = std::nan("");
            BOOST_TEST(std::isnan(blocks()[0].value()));
        }
    }
}

BOOST_AUTO_TEST_CASE(bounded_sums_take_terms_past_the_bound_exactly) {
    pv::detail::BoundedSum s(1.0);
    s.add(0.5);
    s.add(1e20);  // past the bound: summed exactly, not lost
    s.add(-1e20);
    s.add(0.25);
    pv::ExactSum total;
    s.add_to(total);
    BOOST_TEST(total.value() == 0.75);

    pv::detail::BoundedSum no_bound(std::numeric_limits<double>::quiet_NaN());
    no_bound.add(1e-300);
    no_bound.add(2.0);
    pv::ExactSum other;
    no_bound.add_to(other);
    BOOST_TEST(other.value() == 2.0 + 1e-300);

    pv::detail::BoundedSum nan(1.0);
    nan.add(std::nan(""));
    pv::ExactSum with_nan;
    nan.add_to(with_nan);
    BOOST_TEST(std::isnan(with_nan.value()));
}

BOOST_AUTO_TEST_SUITE_END()
