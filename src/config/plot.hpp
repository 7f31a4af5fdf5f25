#pragma once
// A small SVG line plot (no plotting library needed): two panels sharing the y axis, one line per
// series in each.
#include <string>
#include <utility>
#include <vector>

namespace paloverde::config::detail {

struct PlotSeries {
    std::string name;
    std::vector<std::pair<double, double>> left, right;  // (x, y) points of each panel
};

struct PlotLabels {
    std::string title, y, left_x, right_x;
};

std::string svg_plot(const std::vector<PlotSeries>& series, const PlotLabels& labels);

}  // namespace paloverde::config::detail
