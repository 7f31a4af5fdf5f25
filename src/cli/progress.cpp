#include "progress.hpp"

#include <cstdio>
#include <sstream>
#include <unistd.h>

namespace paloverde::cli {

ProgressLine::ProgressLine(bool enabled) : enabled_(enabled), start_(std::chrono::steady_clock::now()) {}

ProgressLine::~ProgressLine() { finish(); }

bool ProgressLine::terminal() { return ::isatty(STDERR_FILENO) == 1; }

config::RunHooks ProgressLine::hooks() {
    config::RunHooks hooks;
    if (!enabled_) return hooks;
    hooks.on_iteration = [this](std::string_view method, std::string_view step, const IterationRecord& r) {
        draw(method, step, r);
    };
    hooks.on_method_done = [this](const config::MethodResult&) { finish(); };
    return hooks;
}

void ProgressLine::draw(std::string_view method, std::string_view step, const IterationRecord& r) {
    const auto now = std::chrono::steady_clock::now();
    std::string where(method == "run" ? std::string(step) : std::string(method) + "/" + std::string(step));
    std::ostringstream line;
    line.precision(5);
    line << where << " [" << r.phase << "]  iteration " << r.iteration << "  worst " << r.worst_quality
         << "  inverted " << r.inverted;
    line.precision(3);
    line << "  " << std::chrono::duration<double>(now - start_).count() << " s";
    latest_ = line.str();
    // At most ten redraws a second, but always the first iteration of a step.
    if (where == last_step_ && now - last_draw_ < std::chrono::milliseconds(100)) return;
    last_step_ = where;
    last_draw_ = now;
    show();
}

void ProgressLine::show() {
    std::string text = latest_;
    if (text.size() < width_) text.append(width_ - text.size(), ' ');
    width_ = latest_.size();
    latest_.clear();
    std::fprintf(stderr, "\r%s", text.c_str());
    std::fflush(stderr);
}

void ProgressLine::finish() {
    if (!enabled_) return;
    if (!latest_.empty()) show();  // the last iteration, if the rate limit held it back
    if (width_ == 0) return;
    std::fputc('\n', stderr);
    std::fflush(stderr);
    width_ = 0;
    last_step_.clear();
}

}  // namespace paloverde::cli
