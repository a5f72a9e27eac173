#include "charts.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>

#include "vsd/core/svg.hpp"

namespace vsd::report {

namespace {
constexpr int kWidth = 340;
constexpr int kHeight = 300;
constexpr int kMargin = 46;
constexpr const char* kAxisColour = "#555555";
constexpr const char* kGridColour = "#e4e4e4";
constexpr const char* kPointColour = "#1f78b4";

std::string tickLabel(double value, double step) {
  const int decimals = std::max(0, static_cast<int>(std::ceil(-std::log10(step) - 1e-9)));
  return fmt::format("{:.{}f}", std::abs(value) < 1e-12 ? 0.0 : value, decimals);
}

/// Axes, grid and labels of a chart whose data box is [lo, hi].
void drawAxes(SvgCanvas& canvas, const Vec2& lo, const Vec2& hi, const std::string& title, const std::string& x_label,
              const std::string& y_label, bool y_ticks = true) {
  const auto x_ticks = niceTicks(lo.x(), hi.x());
  for (double x : x_ticks) {
    canvas.linePx(canvas.toX(x), canvas.toY(lo.y()), canvas.toX(x), canvas.toY(hi.y()), kGridColour, 1.0);
    canvas.textPx(canvas.toX(x), canvas.toY(lo.y()) + 14, tickLabel(x, x_ticks.size() > 1 ? x_ticks[1] - x_ticks[0] : 1.0),
                  10, kAxisColour, "middle");
  }
  if (y_ticks) {
    const auto ticks = niceTicks(lo.y(), hi.y());
    for (double y : ticks) {
      canvas.linePx(canvas.toX(lo.x()), canvas.toY(y), canvas.toX(hi.x()), canvas.toY(y), kGridColour, 1.0);
      canvas.textPx(canvas.toX(lo.x()) - 4, canvas.toY(y) + 3, tickLabel(y, ticks.size() > 1 ? ticks[1] - ticks[0] : 1.0),
                    10, kAxisColour, "end");
    }
  }
  canvas.linePx(canvas.toX(lo.x()), canvas.toY(lo.y()), canvas.toX(hi.x()), canvas.toY(lo.y()), kAxisColour, 1.0);
  canvas.linePx(canvas.toX(lo.x()), canvas.toY(lo.y()), canvas.toX(lo.x()), canvas.toY(hi.y()), kAxisColour, 1.0);
  canvas.textPx(kWidth / 2.0, 16, title, 12, "#222222", "middle");
  canvas.textPx((canvas.toX(lo.x()) + canvas.toX(hi.x())) / 2.0, kHeight - 8, x_label, 11, kAxisColour, "middle");
  canvas.textPx(12, (canvas.toY(lo.y()) + canvas.toY(hi.y())) / 2.0, y_label, 11, kAxisColour, "middle", /*rotated=*/true);
}

/// One named curve in the c-th colour, its name in the legend's c-th line.
void drawCurve(SvgCanvas& canvas, std::size_t c, const std::string& name, const Polyline& points, bool markers) {
  // Twelve colours told apart at a glance (a report compares up to ten metrics); the grey
  // of the dashed reference diagonal is not among them. Beyond twelve, curves are dashed.
  static const char* const kColours[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b",
                                         "#e377c2", "#17becf", "#bcbd22", "#222222", "#6b6ecf", "#b5cf6b"};
  const std::string colour = kColours[c % std::size(kColours)];
  canvas.polyline(points, colour, 1.6, /*dashed=*/c >= std::size(kColours));
  if (markers) {
    for (const auto& p : points) canvas.circle(p, 2.5, colour);
  }
  canvas.textPx(kMargin + 8, 34 + 12.0 * static_cast<double>(c), name, 10, colour, "start");
}

std::string emptyChart(const std::string& title, const std::string& message) {
  SvgCanvas canvas(Vec2(0, 0), Vec2(1, 1), kWidth, kHeight, false, kMargin);
  canvas.textPx(kWidth / 2.0, 16, title, 12, "#222222", "middle");
  canvas.textPx(kWidth / 2.0, kHeight / 2.0, message, 11, kAxisColour, "middle");
  return canvas.str();
}
}  // namespace

std::vector<double> niceTicks(double lo, double hi, int count) {
  if (!(hi > lo) || !std::isfinite(lo) || !std::isfinite(hi)) return {lo};
  const double raw = (hi - lo) / std::max(1, count);
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  double step = magnitude;
  for (double factor : {1.0, 2.0, 5.0, 10.0}) {
    step = factor * magnitude;
    if (step >= raw) break;
  }
  std::vector<double> ticks;
  for (double t = std::ceil(lo / step - 1e-9) * step; t <= hi + 1e-9 * step; t += step) ticks.push_back(t);
  return ticks;
}

std::string scatterSvg(const std::vector<double>& reference, const std::vector<double>& predicted,
                       const std::string& title, const std::string& x_label, const std::string& y_label,
                       std::size_t max_points) {
  std::vector<Vec2> points;
  for (std::size_t i = 0; i < std::min(reference.size(), predicted.size()); ++i) {
    if (std::isfinite(reference[i]) && std::isfinite(predicted[i])) points.emplace_back(reference[i], predicted[i]);
  }
  if (points.empty()) return emptyChart(title, "no scenario with both values finite");
  double lo = points.front().x();
  double hi = lo;
  for (const auto& p : points) {
    lo = std::min({lo, p.x(), p.y()});
    hi = std::max({hi, p.x(), p.y()});
  }
  const double pad = std::max(1e-3, 0.05 * (hi - lo));
  lo -= pad;
  hi += pad;
  // Same range on both axes, so the diagonal is the line of perfect prediction.
  SvgCanvas canvas(Vec2(lo, lo), Vec2(hi, hi), kWidth, kHeight, false, kMargin);
  drawAxes(canvas, Vec2(lo, lo), Vec2(hi, hi), title, x_label, y_label);
  canvas.line(Vec2(lo, lo), Vec2(hi, hi), "#d62728", 1.0, /*dashed=*/true);
  const std::size_t stride = std::max<std::size_t>(1, (points.size() + max_points - 1) / max_points);
  for (std::size_t i = 0; i < points.size(); i += stride) canvas.circle(points[i], 2.0, kPointColour, 0.55);
  if (stride > 1) {
    canvas.textPx(kWidth - 6, 30, fmt::format("every {}th of {} shown", stride, points.size()), 9, kAxisColour, "end");
  }
  return canvas.str();
}

std::string histogramSvg(const std::vector<double>& values, const std::string& title, const std::string& x_label,
                         int bins, double marker) {
  std::vector<double> finite;
  for (double v : values) {
    if (std::isfinite(v)) finite.push_back(v);
  }
  if (finite.empty()) return emptyChart(title, "no finite value");
  std::sort(finite.begin(), finite.end());
  double lo = finite.front();
  double hi = finite.back();
  // A few far outliers (e.g. time-to-collision errors of hundreds of seconds when the
  // closing speed is near zero) would squeeze everything else into one bar: show the
  // 1st..99th percentile and count the rest in the edge bins.
  std::size_t beyond = 0;
  if (finite.size() >= 50) {
    const double q01 = finite[finite.size() / 100];
    const double q99 = finite[finite.size() - 1 - finite.size() / 100];
    if (hi - lo > 4.0 * (q99 - q01) && q99 > q01) {
      lo = q01;
      hi = q99;
      for (double v : finite) beyond += v < lo || v > hi;
    }
  }
  if (hi - lo < 1e-9) {
    lo -= 0.5;
    hi += 0.5;
  }
  const double width = (hi - lo) / bins;
  std::vector<std::size_t> counts(static_cast<std::size_t>(bins), 0);
  for (double v : finite) {
    const double position = std::clamp((v - lo) / width, 0.0, static_cast<double>(bins) - 0.5);
    const auto bin = std::min<std::size_t>(static_cast<std::size_t>(bins) - 1, static_cast<std::size_t>(position));
    ++counts[bin];
  }
  const double top = static_cast<double>(*std::max_element(counts.begin(), counts.end())) * 1.08;
  SvgCanvas canvas(Vec2(lo, 0.0), Vec2(hi, top), kWidth, kHeight, false, kMargin);
  drawAxes(canvas, Vec2(lo, 0.0), Vec2(hi, top), title, x_label, "scenarios");
  for (std::size_t b = 0; b < counts.size(); ++b) {
    if (counts[b] == 0) continue;
    const double x0 = canvas.toX(lo + static_cast<double>(b) * width);
    const double x1 = canvas.toX(lo + static_cast<double>(b + 1) * width);
    const double y = canvas.toY(static_cast<double>(counts[b]));
    canvas.rectPx(x0 + 0.5, y, std::max(0.5, x1 - x0 - 1.0), canvas.toY(0.0) - y, kPointColour);
  }
  if (std::isfinite(marker) && marker > lo && marker < hi) {
    canvas.linePx(canvas.toX(marker), canvas.toY(0.0), canvas.toX(marker), canvas.toY(top), "#d62728", 1.2);
  }
  canvas.textPx(kWidth - 6, 30, fmt::format("n = {}", finite.size()), 9, kAxisColour, "end");
  if (beyond > 0) {
    canvas.textPx(kWidth - 6, 41, fmt::format("{} beyond the 1st..99th percentile, in the edge bins", beyond), 9,
                  kAxisColour, "end");
  }
  return canvas.str();
}

std::string reliabilitySvg(const std::vector<double>& levels,
                           const std::vector<std::pair<std::string, std::vector<double>>>& curves,
                           const std::string& title) {
  if (curves.empty()) return emptyChart(title, "no interval to score");
  SvgCanvas canvas(Vec2(0.0, 0.0), Vec2(1.0, 1.0), kWidth, kHeight, false, kMargin);
  drawAxes(canvas, Vec2(0.0, 0.0), Vec2(1.0, 1.0), title, "nominal coverage of the central interval",
           "observed coverage");
  canvas.line(Vec2(0.0, 0.0), Vec2(1.0, 1.0), "#888888", 1.0, /*dashed=*/true);
  for (std::size_t c = 0; c < curves.size(); ++c) {
    Polyline points;
    for (std::size_t l = 0; l < levels.size() && l < curves[c].second.size(); ++l) {
      if (std::isfinite(curves[c].second[l])) points.emplace_back(levels[l], curves[c].second[l]);
    }
    drawCurve(canvas, c, curves[c].first, points, /*markers=*/true);
  }
  return canvas.str();
}

std::string lineChartSvg(const std::vector<std::pair<std::string, std::vector<std::pair<double, double>>>>& curves,
                         const std::string& title, const std::string& x_label, const std::string& y_label) {
  std::vector<Polyline> lines;
  Vec2 lo(std::numeric_limits<double>::infinity(), 0.0);
  Vec2 hi(-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity());
  for (const auto& curve : curves) {
    Polyline points;
    for (const auto& [x, y] : curve.second) {
      if (!std::isfinite(x) || !std::isfinite(y)) continue;
      points.emplace_back(x, y);
      lo = Vec2(std::min(lo.x(), x), std::min(lo.y(), y));
      hi = Vec2(std::max(hi.x(), x), std::max(hi.y(), y));
    }
    lines.push_back(std::move(points));
  }
  if (!(hi.x() > lo.x())) return emptyChart(title, "fewer than two points");
  if (!(hi.y() > lo.y())) hi = Vec2(hi.x(), lo.y() + 1.0);
  SvgCanvas canvas(lo, hi, kWidth, kHeight, false, kMargin);
  drawAxes(canvas, lo, hi, title, x_label, y_label);
  for (std::size_t c = 0; c < curves.size(); ++c) drawCurve(canvas, c, curves[c].first, lines[c], /*markers=*/false);
  return canvas.str();
}

}  // namespace vsd::report
