#pragma once
// Small SVG charts for the comparison report (no scripts, no external resources).

#include <cstddef>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace vsd::report {

/// Round tick positions covering [lo, hi] (about `count` of them, steps of 1, 2 or 5 x 10^n).
std::vector<double> niceTicks(double lo, double hi, int count = 5);

/// Predicted (y) against reference (x) with the diagonal y = x; non-finite pairs are
/// left out. At most `max_points` points are drawn (every k-th); the caption says so.
std::string scatterSvg(const std::vector<double>& reference, const std::vector<double>& predicted,
                       const std::string& title, const std::string& x_label, const std::string& y_label,
                       std::size_t max_points = 2000);

/// Histogram of the finite values in `bins` equal bins, with a marker at `marker`
/// (e.g. 0 for errors) when it lies inside the range.
std::string histogramSvg(const std::vector<double>& values, const std::string& title, const std::string& x_label,
                         int bins = 30, double marker = std::numeric_limits<double>::quiet_NaN());

/// Reliability diagram: observed against nominal coverage of central intervals, one line
/// per named curve (values in [0, 1], one per level; NaN points are skipped), with the
/// diagonal of perfect calibration.
std::string reliabilitySvg(const std::vector<double>& levels,
                           const std::vector<std::pair<std::string, std::vector<double>>>& curves,
                           const std::string& title);

/// Lines through (x, y) points, one per named curve, on axes fitted to the points
/// (y from 0); non-finite points are skipped.
std::string lineChartSvg(const std::vector<std::pair<std::string, std::vector<std::pair<double, double>>>>& curves,
                         const std::string& title, const std::string& x_label, const std::string& y_label);

/// The provenance table of an HTML report (key, value lines).
std::string provenanceSection(const std::vector<std::pair<std::string, std::string>>& provenance);

/// The start of an HTML report up to <body>: "vsd-sumo <kind>: <title>" as its title (title
/// HTML-escaped here) and the inline CSS all reports share.
std::string reportHead(const std::string& kind, const std::string& title);

}  // namespace vsd::report
