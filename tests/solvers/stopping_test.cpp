// The stopping rules every solver shares (src/solvers/stopping.hpp): the best iterate, the budget,
// the target and the stall window with its pace.
#include <boost/test/unit_test.hpp>
#include <vector>

#include "paloverde/parallel/reducer.hpp"
#include "solvers/stopping.hpp"

namespace pv = paloverde;
namespace detail = paloverde::detail;

BOOST_AUTO_TEST_SUITE(stopping)

BOOST_AUTO_TEST_CASE(fewer_inverted_elements_then_a_higher_worst_make_the_best_iterate) {
    BOOST_TEST(detail::better_iterate(2, -0.5, 3, 0.1));
    BOOST_TEST(!detail::better_iterate(3, 0.9, 2, -0.5));
    BOOST_TEST(detail::better_iterate(0, 0.31, 0, 0.30));
    BOOST_TEST(!detail::better_iterate(0, 0.30, 0, 0.30));  // a tie keeps the earlier iterate
}

BOOST_AUTO_TEST_CASE(the_budget_and_the_target) {
    pv::TerminationCriterion c;
    c.max_iterations = 5;
    const pv::Reducer serial;
    const auto start = detail::Clock::now();
    BOOST_TEST(!detail::budget_spent(c, 5, serial, start).has_value());
    BOOST_TEST((detail::budget_spent(c, 6, serial, start) == pv::TerminationReason::IterationLimit));
    BOOST_TEST(detail::budget_message(pv::TerminationReason::IterationLimit, c, "sweeps") == "stopped after 5 sweeps");
    BOOST_TEST(!detail::target_reached(c, 1.0));  // no target
    c.target_worst_quality = 0.4;
    BOOST_TEST(!detail::target_reached(c, 0.39));
    BOOST_TEST(detail::target_reached(c, 0.4));
}

BOOST_AUTO_TEST_CASE(the_stall_window_looks_back_progress_window_entries) {
    pv::TerminationCriterion c;
    c.progress_window = 4;
    c.min_progress = 1e-2;
    const detail::StallWindow window(c, 0.5);  // tolerance 1e-2 * 0.5
    BOOST_TEST(window.tolerance() == 5e-3);
    BOOST_TEST(window.window() == 4u);

    const std::vector<double> short_history{0.1, 0.1, 0.1, 0.1};
    BOOST_TEST(!window.spans(short_history));  // nothing stalls before a whole window
    BOOST_TEST(!window.rose_too_little(short_history));

    const std::vector<double> worst{0.10, 0.20, 0.30, 0.40, 0.50, 0.502};
    BOOST_TEST(window.spans(worst));
    BOOST_TEST(!window.rose_too_little(worst));  // 0.502 - 0.20 over the window
    BOOST_TEST(window.pace(worst) == (0.502 - 0.20) / 4.0);
    const std::vector<double> flat{0.10, 0.500, 0.501, 0.502, 0.503, 0.504};
    BOOST_TEST(window.rose_too_little(flat));  // 0.504 - 0.500 <= 5e-3

    const std::vector<double> inverted{7, 5, 5, 5, 5, 5};
    BOOST_TEST(window.did_not_fall(inverted));
    BOOST_TEST(!window.rose(inverted));
    const std::vector<double> falling{7, 6, 5, 5, 5, 5};
    BOOST_TEST(!window.did_not_fall(falling));
    const std::vector<double> rising{5, 5, 5, 5, 5, 6};
    BOOST_TEST(window.rose(rising));
}

BOOST_AUTO_TEST_CASE(a_worst_near_zero_is_judged_at_least_at_a_thousandth) {
    pv::TerminationCriterion c;
    c.progress_window = 1;
    c.min_progress = 0.1;
    BOOST_TEST(detail::StallWindow(c, 0.0).tolerance() == 1e-4);
    BOOST_TEST(detail::StallWindow(c, -2.0).tolerance() == 0.2);
}

BOOST_AUTO_TEST_SUITE_END()
