#include "config/plot.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include "io/xml_reader.hpp"

namespace paloverde::config::detail {

namespace {

struct Range {
    double lo = std::numeric_limits<double>::infinity(), hi = -std::numeric_limits<double>::infinity();
    void add(double v) {
        if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
    }
    void settle() {
        if (!(lo <= hi)) lo = 0.0, hi = 1.0;
        if (hi - lo < 1e-12 * std::max(1.0, std::abs(hi))) lo -= 0.5, hi += 0.5;
    }
};

// Tick positions at 1, 2 or 5 times a power of ten, about `count` of them.
std::vector<double> ticks(Range& r, int count) {
    const double raw = (r.hi - r.lo) / count;
    const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
    double step = magnitude;
    for (double m : {1.0, 2.0, 5.0, 10.0})
        if (m * magnitude >= raw) {
            step = m * magnitude;
            break;
        }
    r.lo = std::floor(r.lo / step) * step;
    r.hi = std::ceil(r.hi / step) * step;
    std::vector<double> out;
    for (double t = r.lo; t <= r.hi + step * 1e-9; t += step) out.push_back(std::abs(t) < step * 1e-9 ? 0.0 : t);
    return out;
}

std::string number(double v) {
    std::ostringstream s;
    s << std::setprecision(4) << v;
    return s.str();
}

const char* const kColors[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf"};

}  // namespace

std::string svg_plot(const std::vector<PlotSeries>& series, const PlotLabels& labels) {
    const double width = 1000, height = 420, top = 50, bottom = 60, panel_width = 400, gap = 90, left0 = 80;
    Range y, x_left, x_right;
    for (const auto& s : series) {
        for (const auto& [x, v] : s.left) x_left.add(x), y.add(v);
        for (const auto& [x, v] : s.right) x_right.add(x), y.add(v);
    }
    // Untangling metrics can fall far below -1 (scaled volumes); the shape range [-1, 1] is what
    // matters, and lines below it are clipped.
    y.lo = std::max(y.lo, -1.0);
    y.settle();
    x_left.settle();
    x_right.settle();
    const auto y_ticks = ticks(y, 6);
    const auto left_ticks = ticks(x_left, 6);
    const auto right_ticks = ticks(x_right, 6);
    const double plot_height = height - top - bottom;
    auto y_pos = [&](double v) { return top + plot_height * (1.0 - (v - y.lo) / (y.hi - y.lo)); };

    std::ostringstream out;
    out << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
        << "\" viewBox=\"0 0 " << width << ' ' << height << "\" font-family=\"sans-serif\" font-size=\"12\">\n"
        << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
        << "<text x=\"" << width / 2 << "\" y=\"24\" text-anchor=\"middle\" font-size=\"15\">" << io::xml_escaped(labels.title)
        << "</text>\n";
    auto panel = [&](double left, const Range& xr, const std::vector<double>& xt, const std::string& xlabel, bool use_left) {
        auto x_pos = [&](double v) { return left + panel_width * (v - xr.lo) / (xr.hi - xr.lo); };
        for (double t : y_ticks)
            out << "<line x1=\"" << left << "\" x2=\"" << left + panel_width << "\" y1=\"" << y_pos(t) << "\" y2=\""
                << y_pos(t) << "\" stroke=\"#e0e0e0\"/>\n<text x=\"" << left - 6 << "\" y=\"" << y_pos(t) + 4
                << "\" text-anchor=\"end\">" << number(t) << "</text>\n";
        for (double t : xt)
            out << "<line x1=\"" << x_pos(t) << "\" x2=\"" << x_pos(t) << "\" y1=\"" << top << "\" y2=\""
                << top + plot_height << "\" stroke=\"#e0e0e0\"/>\n<text x=\"" << x_pos(t) << "\" y=\""
                << top + plot_height + 16 << "\" text-anchor=\"middle\">" << number(t) << "</text>\n";
        out << "<rect x=\"" << left << "\" y=\"" << top << "\" width=\"" << panel_width << "\" height=\"" << plot_height
            << "\" fill=\"none\" stroke=\"black\"/>\n<text x=\"" << left + panel_width / 2 << "\" y=\""
            << top + plot_height + 38 << "\" text-anchor=\"middle\">" << io::xml_escaped(xlabel) << "</text>\n"
            << "<text transform=\"translate(" << left - 52 << ' ' << top + plot_height / 2
            << ") rotate(-90)\" text-anchor=\"middle\">" << io::xml_escaped(labels.y) << "</text>\n";
        const std::string clip = use_left ? "left" : "right";
        out << "<clipPath id=\"" << clip << "\"><rect x=\"" << left << "\" y=\"" << top << "\" width=\"" << panel_width
            << "\" height=\"" << plot_height << "\"/></clipPath>\n";
        for (std::size_t i = 0; i < series.size(); ++i) {
            const auto& points = use_left ? series[i].left : series[i].right;
            if (points.empty()) continue;
            out << "<polyline clip-path=\"url(#" << clip << ")\" fill=\"none\" stroke-width=\"1.5\" stroke=\""
                << kColors[i % std::size(kColors)] << "\" points=\"";
            for (const auto& [x, v] : points)
                if (std::isfinite(x) && std::isfinite(v)) out << number(x_pos(x)) << ',' << number(y_pos(v)) << ' ';
            out << "\"/>\n";
        }
    };
    panel(left0, x_left, left_ticks, labels.left_x, true);
    panel(left0 + panel_width + gap, x_right, right_ticks, labels.right_x, false);
    for (std::size_t i = 0; i < series.size(); ++i) {
        const double ly = top + 14 + 18 * static_cast<double>(i), lx = left0 + panel_width - 150;
        out << "<line x1=\"" << lx << "\" x2=\"" << lx + 24 << "\" y1=\"" << ly << "\" y2=\"" << ly
            << "\" stroke-width=\"2\" stroke=\"" << kColors[i % std::size(kColors)] << "\"/>\n<text x=\"" << lx + 30
            << "\" y=\"" << ly + 4 << "\">" << io::xml_escaped(series[i].name) << "</text>\n";
    }
    out << "</svg>\n";
    return out.str();
}

}  // namespace paloverde::config::detail
