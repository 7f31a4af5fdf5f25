#include "paloverde/assess/quality_assessor.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <iomanip>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/exact_sums.hpp"
#include "metrics/evaluate_together.hpp"
#include "paloverde/core/error.hpp"
#include "paloverde/mesh/cell_types.hpp"
#include "paloverde/mesh/orientation.hpp"

namespace paloverde {

namespace {

// Below this many elements an assessment stays on one thread.
constexpr std::ptrdiff_t kParallelElements = 32768;

// One metric's statistics over the elements this process counts, in three groups: all, movable
// (group 1: a free vertex) and frozen (group 2). Two passes: the ranges, then the sums and the
// histograms. Sums are exact, so the result depends on nothing but the mesh, however it is split:
// those of "all" are the two groups' added exactly, and the histograms count in integers.
void statistics(std::span<const double> q, std::span<const std::uint8_t> group, int bins, const Reducer& reducer,
                bool distributed, MetricReport& report) {
    QualityStatistics* s[3] = {&report.all, &report.movable, &report.frozen};
    // Pass 1, by thread: each group's range and its first element of least quality (the serial
    // scan's: the smallest index among the least), then combined.
    struct Range {
        double low = std::numeric_limits<double>::infinity(), high = -std::numeric_limits<double>::infinity();
        long count = 0;
        ElementId worst = -1;
        void add(double qe, std::ptrdiff_t e) {
            ++count;
            if (qe < low) low = qe, worst = static_cast<ElementId>(e);
            high = std::max(high, qe);
        }
    };
    Range range[3];
    const auto n = static_cast<std::ptrdiff_t>(q.size());
#pragma omp parallel if (n >= kParallelElements)
    {
        // Named, not an array indexed by the group: the compiler keeps them in registers.
        Range all, movable, frozen;
#pragma omp for schedule(static) nowait
        for (std::ptrdiff_t e = 0; e < n; ++e) {
            const int g = group[static_cast<std::size_t>(e)];
            if (!g) continue;
            const double qe = q[static_cast<std::size_t>(e)];
            all.add(qe, e);
            if (g == 1) movable.add(qe, e);
            else frozen.add(qe, e);
        }
        const Range mine[3] = {all, movable, frozen};
#pragma omp critical(paloverde_assess_range)
        for (int k = 0; k < 3; ++k) {
            Range& r = range[k];
            r.count += mine[k].count;
            if (mine[k].worst >= 0 && (mine[k].low < r.low || (mine[k].low == r.low && mine[k].worst < r.worst) || r.worst < 0))
                r.low = mine[k].low, r.worst = mine[k].worst;
            r.high = std::max(r.high, mine[k].high);
        }
    }
    double width[3] = {0.0, 0.0, 0.0};
    for (int k = 0; k < 3; ++k) {
        s[k]->count = static_cast<ElementId>(reducer.total(static_cast<double>(range[k].count)));
        s[k]->worst_element = distributed ? -1 : range[k].worst;  // a local index means nothing to the caller
        if (s[k]->count == 0) continue;
        s[k]->min = reducer.min(range[k].low);
        s[k]->max = reducer.max(range[k].high);
        width[k] = (s[k]->max - s[k]->min) / bins;
    }
    // Pass 2, by thread, a block at a time: exact sums and integer counts, added together (exactly:
    // in any order). The terms are bounded by this process's range, so they sum exactly in pieces
    // on two grids; only those far below the bound (or not finite) take the slower digit-by-digit
    // sum. The movable elements' terms go several to an instruction, the frozen ones' (usually
    // few) one by one.
    const auto b = static_cast<std::size_t>(bins);
    const double bound = std::max(std::abs(range[0].low), std::abs(range[0].high));
    std::vector<std::int64_t> counts(3 * b, 0);
    std::vector<ExactSum> sums(4 + 3 * b);  // sum and squares of movable, then of frozen; the histograms
    // A movable element's bin is its bin among all where the two ranges agree (the usual case: the
    // frozen elements lie within the movable ones' range). A bin is (qe - min) / width, divided:
    // a product with the width's inverse could round an element into the next bin.
    const bool movable_bins_as_all = s[1]->min == s[0]->min && width[1] == width[0];
    const auto bin_of = [&](int k, double qe) {
        const int bin = width[k] > 0.0 ? static_cast<int>((qe - s[k]->min) / width[k]) : 0;
        return static_cast<std::size_t>(k) * b + static_cast<std::size_t>(std::clamp(bin, 0, bins - 1));
    };
    constexpr std::ptrdiff_t kBlock = 256;
#pragma omp parallel if (n >= kParallelElements)
    {
        std::vector<std::int64_t> my_counts(3 * b, 0);
        std::array<detail::BoundedSum, 4> my_sums{detail::BoundedSum(bound), detail::BoundedSum(bound * bound),
                                                  detail::BoundedSum(bound), detail::BoundedSum(bound * bound)};
        alignas(32) double terms[2][kBlock];
        int bin[2][kBlock];
        const auto bins_of = [&](const double* x, std::ptrdiff_t count, int k, int* out) {
            if (!(width[k] > 0.0)) return std::fill(out, out + count, 0);
            const double low = s[k]->min, w = width[k];
            for (std::ptrdiff_t i = 0; i < count; ++i) out[i] = static_cast<int>((x[i] - low) / w);
            for (std::ptrdiff_t i = 0; i < count; ++i) out[i] = std::clamp(out[i], 0, bins - 1);
        };
#pragma omp for schedule(static) nowait
        for (std::ptrdiff_t first = 0; first < n; first += kBlock) {
            const std::ptrdiff_t count = std::min(kBlock, n - first);
            const double* x = q.data() + first;
            const std::uint8_t* g = group.data() + first;
            // A term of an element that is not movable is +0: its bits masked off (0 * x would be
            // NaN for an infinite x).
            for (std::ptrdiff_t i = 0; i < count; ++i) {
                const std::uint64_t movable = 0 - std::uint64_t{g[i] == 1};
                terms[0][i] = std::bit_cast<double>(std::bit_cast<std::uint64_t>(x[i]) & movable);
                terms[1][i] = std::bit_cast<double>(std::bit_cast<std::uint64_t>(x[i] * x[i]) & movable);
            }
            my_sums[0].add_all_exact(terms[0], static_cast<std::size_t>(count));
            my_sums[1].add_all_exact(terms[1], static_cast<std::size_t>(count));
            bins_of(x, count, 0, bin[0]);
            if (!movable_bins_as_all) bins_of(x, count, 1, bin[1]);
            for (std::ptrdiff_t i = 0; i < count; ++i) {
                if (!g[i]) continue;
                ++my_counts[static_cast<std::size_t>(bin[0][i])];
                if (g[i] == 1) {
                    ++my_counts[b + static_cast<std::size_t>(bin[movable_bins_as_all ? 0 : 1][i])];
                    continue;
                }
                ++my_counts[bin_of(2, x[i])];
                my_sums[2].add_exact(x[i]);
                my_sums[3].add_exact(x[i] * x[i]);
            }
        }
#pragma omp critical(paloverde_assess_sums)
        {
            for (std::size_t i = 0; i < 4; ++i) my_sums[i].add_to(sums[i]);
            for (std::size_t i = 0; i < counts.size(); ++i) counts[i] += my_counts[i];
        }
    }
    for (std::size_t i = 0; i < counts.size(); ++i) sums[4 + i].add(static_cast<double>(counts[i]));
    reducer.sum(sums);
    ExactSum total = sums[0], squares = sums[1];
    total += sums[2];
    squares += sums[3];
    const ExactSum* sum_of[3] = {&total, &sums[0], &sums[2]};
    const ExactSum* squares_of[3] = {&squares, &sums[1], &sums[3]};
    for (int k = 0; k < 3; ++k) {
        if (s[k]->count == 0) continue;
        s[k]->mean = sum_of[k]->value() / s[k]->count;
        s[k]->rms = std::sqrt(squares_of[k]->value() / s[k]->count);
        for (std::size_t i = 0; i < b; ++i)
            s[k]->histogram.push_back(static_cast<ElementId>(sums[4 + static_cast<std::size_t>(k) * b + i].value()));
    }
}

// The element passes go chunk by chunk over the threads, and every metric rates a chunk before
// the next: the chunk's corners, scattered over memory in a mesh's file order, are fetched once
// and then read from the cache (one pass per metric over the whole mesh fetched them each time).
constexpr ElementId kChunk = 4096;
template <class RateChunk>
void for_each_chunk(ElementId elements, RateChunk rate_chunk) {
#pragma omp parallel for schedule(static) if (elements >= kParallelElements)
    for (ElementId first = 0; first < elements; first += kChunk) rate_chunk(first, std::min(elements, first + kChunk));
}

}  // namespace

const std::vector<std::string>& QualityAssessor::default_metrics() {
    static const std::vector<std::string> names{"aspect_ratio",     "mean_ratio",    "inverse_condition",
                                                "edge_ratio",       "scaled_volume", "scaled_jacobian",
                                                "min_dihedral_deg", "min_angle_deg"};
    return names;
}

QualityAssessor::QualityAssessor() : QualityAssessor(default_metrics()) {}

QualityAssessor::QualityAssessor(const std::vector<std::string>& metric_names, int histogram_bins)
    : names_(metric_names), bins_(histogram_bins) {
    if (bins_ < 1 || bins_ > 10000) throw OptionError("histogram bins must be between 1 and 10000");
    for (const auto& name : names_) make_metric(name);  // unknown names fail here, not mid-run
}

QualityReport QualityAssessor::assess(const Mesh& mesh, std::span<const double> xyz) const {
    const Reducer serial;
    return assess(mesh, xyz, {}, {}, serial, mesh.plane_normal());
}

QualityReport QualityAssessor::assess(const MeshPart& whole_or_part) const {
    const Mesh& mesh = whole_or_part.mesh();
    // Empty flags: every element counted, every vertex owned.
    std::vector<std::uint8_t> owned;
    if (!whole_or_part.counted().empty()) {
        owned.resize(static_cast<std::size_t>(mesh.num_vertices()));
        for (VertexId v = 0; v < mesh.num_vertices(); ++v) owned[v] = whole_or_part.owns(v);
    }
    return assess(mesh, mesh.coordinates(), whole_or_part.counted(), owned, whole_or_part.reducer(),
                  whole_or_part.plane_normal());
}

QualityReport QualityAssessor::assess(const Mesh& mesh, std::span<const double> xyz,
                                      std::span<const std::uint8_t> counted, std::span<const std::uint8_t> owned,
                                      const Reducer& reducer, const Vec3& plane_normal) const {
    const bool distributed = !counted.empty();
    // Far from unit scale, volumes overflow or underflow: assess an exactly rescaled copy (every
    // metric is scale-free and orientation survives a power-of-two scaling).
    double largest = 0.0;
    for (double c : xyz) largest = std::max(largest, std::abs(c));
    largest = reducer.max(largest);
    if (const int exponent = unit_scale_exponent(std::span<const double>(&largest, 1)); std::abs(exponent) > 64) {
        if (mesh.has_targets()) {  // their volumes scale with the coordinates
            Mesh scaled = mesh;
            std::copy(xyz.begin(), xyz.end(), scaled.coordinates().begin());
            scaled.scale(exponent);
            return assess(scaled, scaled.coordinates(), counted, owned, reducer, plane_normal);
        }
        std::vector<double> scaled(xyz.begin(), xyz.end());
        scale_coordinates(scaled, exponent);
        return assess(mesh, scaled, counted, owned, reducer, plane_normal);
    }
    const auto m = static_cast<std::size_t>(mesh.num_elements());
    auto is_counted = [&](std::size_t e) { return counted.empty() || counted[e]; };
    auto is_owned = [&](VertexId v) { return owned.empty() || owned[v]; };
    QualityReport report;
    long vertices = 0, free_vertices = 0;
    for (VertexId v = 0; v < mesh.num_vertices(); ++v)
        if (is_owned(v)) ++vertices, free_vertices += mesh.can_move(v);

    // Per element: 1 = counted here and movable (a free vertex), 2 = counted here and frozen; its
    // exact orientation; and its unsigned volume, whose mean over the counted elements is the
    // metrics' scale.
    std::vector<std::uint8_t> group(m, 0);
    std::vector<std::int8_t> orientation(m, 1);
    std::vector<double> q(m);
    MetricScale scale;
    scale.oriented_triangles = mesh.kind() == ElementKind::Tetrahedron || mesh.is_planar() || mesh.has_surface_normals();
    scale.plane_normal = plane_normal;
    const auto unit_volume = make_metric("scaled_volume");
    unit_volume->set_scale(scale);
    for_each_chunk(mesh.num_elements(), [&](ElementId first, ElementId last) {
        unit_volume->evaluate(mesh, xyz, first, last, q.data() + first);
        element_orientations(mesh, xyz, first, last, orientation.data() + first);
        for (ElementId e = first; e < last; ++e) {
            if (!is_counted(static_cast<std::size_t>(e))) {
                orientation[e] = 1;  // another process's to count
                continue;
            }
            group[e] = mesh.element_can_move(e) ? 1 : 2;
        }
    });
    // A mesh with cells is reported by cell: a cell is movable when any corner is, inverted when
    // any corner is, degenerate when none is and one is flat, and as good as its worst corner. A
    // cell's corners are counted together (by the process that counts the cell).
    std::vector<std::uint8_t> cell_group;
    std::vector<std::int8_t> cell_orientation;
    if (mesh.has_cells()) {
        cell_group.assign(static_cast<std::size_t>(mesh.num_cells()), 0);
        cell_orientation.assign(static_cast<std::size_t>(mesh.num_cells()), 1);
        for (std::size_t e = 0; e < m; ++e) {
            const auto c = static_cast<std::size_t>(mesh.cell_of(static_cast<ElementId>(e)));
            if (group[e] != 0 && cell_group[c] != 1) cell_group[c] = group[e];
            cell_orientation[c] = std::min(cell_orientation[c], orientation[e]);
        }
    }
    const std::vector<std::uint8_t>& unit_group = mesh.has_cells() ? cell_group : group;
    const std::vector<std::int8_t>& unit_orientation = mesh.has_cells() ? cell_orientation : orientation;
    long counts[5] = {0, 0, 0, 0, 0};  // elements, frozen, inverted, inverted frozen, degenerate
    for (std::size_t u = 0; u < unit_group.size(); ++u) {
        if (!unit_group[u]) continue;
        const int o = unit_orientation[u];
        counts[0] += 1;
        counts[1] += unit_group[u] == 2;
        counts[2] += o < 0;
        counts[3] += o < 0 && unit_group[u] == 2;
        counts[4] += o == 0;
    }
    // Whether the mesh has cells, asked of every process (a part's can hold none).
    const bool cells = reducer.max(mesh.has_cells() ? 1.0 : 0.0) > 0.0;
    if (cells) {
        std::vector<ExactSum> by_type(2 * kCellTypeCount);  // count and inverted of each type
        for (std::size_t c = 0; c < cell_group.size(); ++c)
            if (cell_group[c]) {
                const auto t = static_cast<std::size_t>(mesh.cell_types()[c]);
                by_type[2 * t].add(1.0);
                if (cell_orientation[c] < 0) by_type[2 * t + 1].add(1.0);
            }
        reducer.sum(by_type);
        for (int t = 0; t < kCellTypeCount; ++t)
            if (by_type[2 * static_cast<std::size_t>(t)].value() > 0.0)
                report.by_type.push_back({std::string(cell_info(static_cast<CellType>(t)).name),
                                          static_cast<ElementId>(by_type[2 * static_cast<std::size_t>(t)].value()),
                                          static_cast<ElementId>(by_type[2 * static_cast<std::size_t>(t) + 1].value()), {}});
    }
    std::vector<ExactSum> totals(7);
    for (int i = 0; i < 5; ++i) totals[i].add(static_cast<double>(counts[i]));
    totals[5].add(static_cast<double>(vertices));
    totals[6].add(static_cast<double>(free_vertices));
    // Metrics rate elements (a cell's corners): their mean volume is the scale.
    totals.emplace_back().add(static_cast<double>(std::count_if(group.begin(), group.end(), [](std::uint8_t g) { return g != 0; })));

    // The metric scale: the mean absolute element volume, summed exactly. The volumes are not
    // needed after it: q holds the terms (0 for an element not counted here).
    for (std::size_t e = 0; e < m; ++e) q[e] = group[e] ? std::abs(q[e]) : 0.0;
    totals.push_back(detail::exact_sum(q));
    reducer.sum(totals);
    report.elements = static_cast<ElementId>(totals[0].value());
    report.frozen_elements = static_cast<ElementId>(totals[1].value());
    report.inverted = static_cast<ElementId>(totals[2].value());
    report.inverted_frozen = static_cast<ElementId>(totals[3].value());
    report.degenerate = static_cast<ElementId>(totals[4].value());
    report.vertices = static_cast<VertexId>(totals[5].value());
    report.free_vertices = static_cast<VertexId>(totals[6].value());
    // A mesh of only degenerate elements keeps 1: there is no size to measure against.
    const double volume = totals[8].value(), rated = totals[7].value();
    if (volume > 0.0 && std::isfinite(volume) && rated > 0) scale.reference_volume = volume / rated;

    std::vector<std::unique_ptr<QualityMetric>> metrics;
    std::vector<std::string_view> names;
    for (const auto& name : names_) {
        auto metric = make_metric(name);
        if (!metric->supports(mesh.kind()) || (cells && !metric->supports_cells())) continue;
        metric->set_scale(scale);
        metrics.push_back(std::move(metric));
        names.push_back(name);
    }
    std::vector<std::vector<double>> qualities(metrics.size());
    if (!qualities.empty()) qualities.front() = std::move(q);
    for (std::size_t i = 1; i < qualities.size(); ++i) qualities[i].resize(m);
    std::vector<const QualityMetric*> together;
    for (const auto& metric : metrics) together.push_back(metric.get());
    for_each_chunk(mesh.num_elements(), [&](ElementId first, ElementId last) {
        std::vector<double*> out;
        for (auto& q : qualities) out.push_back(q.data() + first);
        metrics::evaluate_together(together, mesh, xyz, first, last, out);
    });
    for (std::size_t i = 0; i < metrics.size(); ++i) {
        const std::vector<double>& q = qualities[i];
        const std::string name(names[i]);
        const std::vector<double> per_cell = mesh.has_cells() ? mesh.cell_minimum(q) : std::vector<double>{};
        const std::vector<double>& unit_q = mesh.has_cells() ? per_cell : q;
        MetricReport r;
        r.name = name;
        statistics(unit_q, unit_group, bins_, reducer, distributed, r);
        for (auto& t : report.by_type) {
            double worst = INFINITY;
            for (std::size_t c = 0; c < per_cell.size(); ++c)
                if (unit_group[c] && cell_info(mesh.cell_types()[c]).name == t.type) worst = std::min(worst, per_cell[c]);
            t.worst.emplace_back(name, reducer.min(worst));
        }
        report.metrics.push_back(std::move(r));
    }
    return report;
}

std::optional<QualityReport> QualityAssessor::taken_from(const QualityReport& report, const QualityAssessor& other) const {
    if (bins_ != other.bins_) return std::nullopt;
    for (const auto& name : names_)
        if (std::find(other.names_.begin(), other.names_.end(), name) == other.names_.end()) return std::nullopt;
    // A metric `other` rates but the report lacks does not support the mesh: assess() leaves it
    // out too. Metrics and each type's worst values go in this assessor's order.
    QualityReport out = report;
    out.metrics.clear();
    for (const auto& name : names_)
        if (const MetricReport* m = report.metric(name)) out.metrics.push_back(*m);
    for (std::size_t t = 0; t < out.by_type.size(); ++t) {
        out.by_type[t].worst.clear();
        for (const auto& name : names_)
            for (const auto& entry : report.by_type[t].worst)
                if (entry.first == name) out.by_type[t].worst.push_back(entry);
    }
    return out;
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
    for (const auto& t : by_type) {
        out << std::left << std::setw(20) << t.type << std::right << t.count << " cells, " << t.inverted << " inverted";
        for (const auto& [name, worst] : t.worst) out << ", worst " << name << " " << std::setprecision(5) << worst;
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
    if (!by_type.empty()) {
        json types = json::object();
        for (const auto& t : by_type) {
            json tj{{"count", t.count}, {"inverted", t.inverted}};
            for (const auto& [name, worst] : t.worst) tj["worst"][name] = worst;
            types[t.type] = std::move(tj);
        }
        j["cell_types"] = std::move(types);
    }
    return j.dump(2);
}

}  // namespace paloverde
