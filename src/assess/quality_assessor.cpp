#include "paloverde/assess/quality_assessor.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

#include "paloverde/core/error.hpp"
#include "paloverde/mesh/orientation.hpp"

namespace paloverde {

namespace {

// Two passes (range, then sums and histogram) over the selected elements, in element order, so
// the result does not depend on anything but the mesh.
QualityStatistics statistics(std::span<const double> q, std::span<const std::uint8_t> selected, std::uint8_t want,
                             int bins) {
    QualityStatistics s;
    s.min = std::numeric_limits<double>::infinity();
    s.max = -s.min;
    for (std::size_t e = 0; e < q.size(); ++e) {
        if (selected[e] != want) continue;
        ++s.count;
        if (q[e] < s.min) s.min = q[e], s.worst_element = static_cast<ElementId>(e);
        s.max = std::max(s.max, q[e]);
    }
    if (s.count == 0) {
        s.min = s.max = 0.0;
        return s;
    }
    s.histogram.assign(static_cast<std::size_t>(bins), 0);
    long double sum = 0.0L, squares = 0.0L;
    const double width = (s.max - s.min) / bins;
    for (std::size_t e = 0; e < q.size(); ++e) {
        if (selected[e] != want) continue;
        sum += q[e];
        squares += static_cast<long double>(q[e]) * q[e];
        int bin = width > 0.0 ? static_cast<int>((q[e] - s.min) / width) : 0;
        s.histogram[static_cast<std::size_t>(std::clamp(bin, 0, bins - 1))]++;
    }
    s.mean = static_cast<double>(sum / s.count);
    s.rms = static_cast<double>(std::sqrt(squares / s.count));
    return s;
}

QualityStatistics merge_all(std::span<const double> q, int bins) {
    const std::vector<std::uint8_t> everything(q.size(), 1);
    return statistics(q, everything, 1, bins);
}

}  // namespace

QualityAssessor::QualityAssessor()
    : QualityAssessor({"aspect_ratio", "mean_ratio", "inverse_condition", "edge_ratio", "scaled_volume",
                       "min_dihedral_deg", "min_angle_deg"}) {}

QualityAssessor::QualityAssessor(const std::vector<std::string>& metric_names, int histogram_bins)
    : names_(metric_names), bins_(histogram_bins) {
    if (bins_ < 1 || bins_ > 10000) throw OptionError("histogram bins must be between 1 and 10000");
    for (const auto& name : names_) make_metric(name);  // unknown names fail here, not mid-run
}

QualityReport QualityAssessor::assess(const SimplexMesh& mesh, std::span<const double> xyz) const {
    // Far from unit scale, volumes overflow or underflow: assess an exactly rescaled copy (every
    // metric is scale-free and orientation survives a power-of-two scaling).
    if (const int exponent = unit_scale_exponent(xyz); std::abs(exponent) > 64) {
        std::vector<double> scaled(xyz.begin(), xyz.end());
        scale_coordinates(scaled, exponent);
        return assess(mesh, scaled);
    }
    QualityReport report;
    report.vertices = mesh.num_vertices();
    report.free_vertices = mesh.num_free_vertices();
    report.elements = mesh.num_elements();
    const auto m = static_cast<std::size_t>(mesh.num_elements());

    // 1 = the element has a free vertex.
    std::vector<std::uint8_t> movable(m, 0);
    const auto fixed = mesh.fixed();
    for (ElementId e = 0; e < mesh.num_elements(); ++e)
        for (VertexId v : mesh.element(e))
            if (!fixed[v]) movable[e] = 1;
    report.frozen_elements = static_cast<ElementId>(std::count(movable.begin(), movable.end(), 0));

    for (ElementId e = 0; e < mesh.num_elements(); ++e) {
        const int o = element_orientation(mesh, xyz, e);
        report.inverted += o < 0;
        report.inverted_frozen += o < 0 && !movable[e];
        report.degenerate += o == 0;
    }

    const MetricScale scale = MetricScale::of(mesh, xyz);
    std::vector<double> q(m);
    for (const auto& name : names_) {
        auto metric = make_metric(name);
        if (!metric->supports(mesh.kind())) continue;
        metric->set_scale(scale);
        metric->evaluate(mesh, xyz, 0, mesh.num_elements(), q.data());
        MetricReport r;
        r.name = name;
        r.all = merge_all(q, bins_);
        r.movable = statistics(q, movable, 1, bins_);
        r.frozen = statistics(q, movable, 0, bins_);
        report.metrics.push_back(std::move(r));
    }
    return report;
}

const MetricReport* QualityReport::metric(std::string_view name) const {
    for (const auto& m : metrics)
        if (m.name == name) return &m;
    return nullptr;
}

std::string QualityReport::to_text() const {
    std::ostringstream out;
    out << "vertices " << vertices << " (" << free_vertices << " free), elements " << elements << " ("
        << frozen_elements << " with all vertices fixed)\n";
    out << "inverted " << inverted << " (" << inverted_frozen << " of them with all vertices fixed), degenerate "
        << degenerate << "\n";
    out << std::left << std::setw(20) << "metric" << std::right << std::setw(12) << "min" << std::setw(12) << "max"
        << std::setw(12) << "mean" << std::setw(12) << "rms" << std::setw(14) << "min movable" << "\n";
    for (const auto& m : metrics) {
        out << std::left << std::setw(20) << m.name << std::right << std::setprecision(5);
        for (double v : {m.all.min, m.all.max, m.all.mean, m.all.rms}) out << std::setw(12) << v;
        out << std::setw(14);
        if (m.movable.count > 0) out << m.movable.min;
        else out << "-";
        out << "\n";
    }
    return out.str();
}

std::string QualityReport::to_json() const {
    using nlohmann::json;
    auto stats = [](const QualityStatistics& s) {
        json j{{"count", s.count}, {"min", s.min}, {"max", s.max}, {"mean", s.mean}, {"rms", s.rms},
               {"worst_element", s.worst_element}, {"histogram", s.histogram}};
        return j;
    };
    json j{{"vertices", vertices},
           {"free_vertices", free_vertices},
           {"elements", elements},
           {"elements_all_fixed", frozen_elements},
           {"inverted", inverted},
           {"inverted_all_fixed", inverted_frozen},
           {"degenerate", degenerate}};
    json metrics_json = json::object();
    for (const auto& m : metrics) {
        json mj = stats(m.all);
        mj["movable"] = stats(m.movable);
        mj["all_fixed"] = stats(m.frozen);
        metrics_json[m.name] = std::move(mj);
    }
    j["metrics"] = std::move(metrics_json);
    return j.dump(2);
}

}  // namespace paloverde
