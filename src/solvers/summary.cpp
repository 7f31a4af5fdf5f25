#include "paloverde/solvers/summary.hpp"

#include <cmath>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <sstream>

#include "paloverde/core/error.hpp"
#include "paloverde/solvers/termination.hpp"

namespace paloverde {

std::string_view to_string(TerminationReason reason) {
    switch (reason) {
        case TerminationReason::TargetReached: return "target_reached";
        case TerminationReason::Converged: return "converged";
        case TerminationReason::GradientVanished: return "gradient_vanished";
        case TerminationReason::NoImprovingStep: return "no_improving_step";
        case TerminationReason::IterationLimit: return "iteration_limit";
        case TerminationReason::TimeLimit: return "time_limit";
        case TerminationReason::CannotUntangle: return "cannot_untangle";
        case TerminationReason::NothingToMove: return "nothing_to_move";
        case TerminationReason::Interrupted: return "interrupted";
        case TerminationReason::NumericalFailure: return "numerical_failure";
    }
    return "unknown";
}

bool Summary::success() const {
    return valid() && reason != TerminationReason::CannotUntangle && reason != TerminationReason::NothingToMove &&
           reason != TerminationReason::Interrupted && reason != TerminationReason::NumericalFailure;
}

std::string Summary::brief_report() const {
    std::ostringstream out;
    out << solver << ": " << to_string(reason) << " after " << iterations << " iterations (" << untangle_iterations
        << " untangling) in " << std::setprecision(3) << seconds << " s; worst " << quality_metric << " "
        << std::setprecision(6) << worst_before << " -> " << worst_after << ", inverted " << before.inverted << " -> "
        << after.inverted;
    if (!message.empty()) out << "\n  " << message;
    if (boundary) {
        const double change = boundary->volume_before != 0.0
                                  ? (boundary->volume_after - boundary->volume_before) / std::abs(boundary->volume_before)
                                  : 0.0;
        out << "\n  boundary: " << boundary->moved << " of " << boundary->sliding
            << " sliding vertices moved; largest distance from the input's boundary " << std::setprecision(3)
            << boundary->largest_distance << " of the bounding box diagonal; volume " << std::setprecision(9)
            << boundary->volume_before << " -> " << boundary->volume_after << " (" << std::setprecision(3) << change << " relative)";
    }
    return out.str();
}

std::string Summary::full_report() const {
    std::ostringstream out;
    out << brief_report() << "\n\nbefore:\n" << before.to_text() << "\nafter:\n" << after.to_text();
    return out.str();
}

std::string Summary::history_csv() const {
    std::ostringstream out;
    out << "iteration,phase,worst_quality,best_worst_quality,mean_quality,inverted,mu,t,objective,step,gain,moved,seconds\n";
    out << std::setprecision(17);
    for (const auto& r : history)
        out << r.iteration << ',' << r.phase << ',' << r.worst_quality << ',' << r.best_worst_quality << ',' << r.mean_quality << ',' << r.inverted
            << ',' << r.mu << ',' << r.t << ',' << r.objective << ',' << r.step << ',' << r.gain << ',' << r.moved << ',' << r.seconds << '\n';
    return out.str();
}

std::string Summary::to_json() const {
    using nlohmann::json;
    json j{{"solver", solver},
           {"termination", std::string(to_string(reason))},
           {"message", message},
           {"success", success()},
           {"valid", valid()},
           {"iterations", iterations},
           {"untangle_iterations", untangle_iterations},
           {"quality_passes", quality_passes},
           {"gradient_passes", gradient_passes},
           {"seconds", seconds},
           {"quality_metric", quality_metric},
           {"worst_before", worst_before},
           {"worst_after", worst_after},
           {"inverted_before", before.inverted},
           {"inverted_after", after.inverted},
           {"before", json::parse(before.to_json())},
           {"after", json::parse(after.to_json())}};
    json h = json::array();
    for (const auto& r : history)
        h.push_back({{"iteration", r.iteration}, {"phase", r.phase}, {"worst_quality", r.worst_quality}, {"best_worst_quality", r.best_worst_quality},
                     {"mean_quality", r.mean_quality}, {"inverted", r.inverted}, {"mu", r.mu}, {"t", r.t},
                     {"objective", r.objective}, {"step", r.step}, {"gain", r.gain}, {"moved", r.moved}, {"seconds", r.seconds}});
    j["history"] = std::move(h);
    if (boundary)
        j["boundary"] = {{"sliding", boundary->sliding},
                         {"moved", boundary->moved},
                         {"largest_distance", boundary->largest_distance},
                         {"volume_before", boundary->volume_before},
                         {"volume_after", boundary->volume_after}};
    return j.dump(2);
}

void TerminationCriterion::validate() const {
    if (max_iterations < 0) throw OptionError("max_iterations must be >= 0 (got " + std::to_string(max_iterations) + ")");
    if (!(max_seconds >= 0.0) || !std::isfinite(max_seconds))
        throw OptionError("max_seconds must be >= 0, 0 meaning no limit");
    if (target_worst_quality && !std::isfinite(*target_worst_quality))
        throw OptionError("target_worst_quality must be a finite number");
    if (!(min_progress >= 0.0) || !std::isfinite(min_progress)) throw OptionError("min_progress must be >= 0");
    if (progress_window < 1) throw OptionError("progress_window must be >= 1");
    if (!(gradient_tolerance >= 0.0 && gradient_tolerance < 1.0)) throw OptionError("gradient_tolerance must lie in [0, 1)");
}

}  // namespace paloverde
