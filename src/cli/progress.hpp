#pragma once
// The progress line: while a terminal watches stderr, one line rewritten in place per recorded
// iteration (method/step, phase, iteration, worst quality, inverted elements left, elapsed
// time). Off when stderr is not a terminal or with --quiet. In a partitioned run only rank 0
// should draw it.
#include <chrono>
#include <cstddef>
#include <string>
#include <string_view>

#include "paloverde/config/run.hpp"

namespace paloverde::cli {

class ProgressLine {
public:
    explicit ProgressLine(bool enabled);
    ~ProgressLine();
    ProgressLine(const ProgressLine&) = delete;
    ProgressLine& operator=(const ProgressLine&) = delete;

    // Whether stderr is a terminal.
    static bool terminal();
    // Hooks that draw the line (none when disabled).
    config::RunHooks hooks();
    // Ends the current line, leaving it on the screen.
    void finish();

private:
    void draw(std::string_view method, std::string_view step, const IterationRecord& r);
    void show();  // prints latest_ over the current line

    bool enabled_;
    std::chrono::steady_clock::time_point start_, last_draw_{};
    std::string last_step_;
    std::string latest_;  // the newest line, not yet shown
    std::size_t width_ = 0;
};

}  // namespace paloverde::cli
