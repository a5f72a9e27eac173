#include "vsd/vector/scene_svg.hpp"

#include <fmt/format.h>

#include <cmath>

#include "vsd/core/svg.hpp"

namespace vsd::vector {

namespace {
constexpr const char* kLaneColour = "#9a9a9a";
constexpr const char* kVehicleColour = "#7b3294";
constexpr const char* kEgoColour = "#1f78b4";

/// Clips segment a-b to the box [lo, hi] (Liang-Barsky); false if nothing is inside.
bool clipSegment(Vec2& a, Vec2& b, const Vec2& lo, const Vec2& hi) {
  const Vec2 d = b - a;
  double t0 = 0.0;
  double t1 = 1.0;
  for (int axis = 0; axis < 2; ++axis) {
    for (const auto& [p, q] : {std::pair{-d[axis], a[axis] - lo[axis]}, std::pair{d[axis], hi[axis] - a[axis]}}) {
      if (std::abs(p) < 1e-12) {
        if (q < 0.0) return false;
        continue;
      }
      const double t = q / p;
      if (p < 0.0) {
        t0 = std::max(t0, t);
      } else {
        t1 = std::min(t1, t);
      }
      if (t0 > t1) return false;
    }
  }
  const Vec2 start = a + t0 * d;
  b = a + t1 * d;
  a = start;
  return true;
}

/// The drawn region: everything in the scene (only its road users and futures when focused).
struct View {
  Vec2 lo = Vec2::Zero();
  Vec2 hi = Vec2::Zero();
  Vec2 pad = Vec2::Zero();
};

View viewOf(const VectorizedScene& scene, const std::vector<TrajectoryOverlay>& overlays, double focus_margin_m) {
  const bool focus = focus_margin_m > 0.0;
  Vec2 lo(std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity());
  Vec2 hi = -lo;
  auto extend = [&](const Vec2& p) {
    if (!p.allFinite()) return;
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  };
  for (const auto& polyline : scene.polylines) {
    if (focus && polyline.type == ObjectType::LaneBoundary) continue;
    for (std::size_t v = 0; v < polyline.vectors.size(); ++v) {
      if (!polyline.valid[v]) continue;
      extend({polyline.vectors[v][0], polyline.vectors[v][1]});
      extend({polyline.vectors[v][2], polyline.vectors[v][3]});
    }
  }
  for (std::size_t k = 0; k < scene.target.size(); ++k) {
    if (scene.targetValid[k]) extend(scene.target[k]);
  }
  for (const auto& overlay : overlays) {
    for (const auto& p : overlay.points) extend(p);
  }
  if (!lo.allFinite()) lo = hi = Vec2::Zero();
  if (focus) {
    lo -= Vec2(focus_margin_m, focus_margin_m);
    hi += Vec2(focus_margin_m, focus_margin_m);
  }
  const Vec2 pad = ((hi - lo) * 0.03).cwiseMax(Vec2(2.0, 2.0));
  // Very elongated scenes would be a few pixels high: keep at least 1/6 of the width.
  Vec2 span = hi - lo + 2.0 * pad;
  if (span.y() < span.x() / 6.0) {
    const double grow = (span.x() / 6.0 - span.y()) / 2.0;
    lo.y() -= grow;
    hi.y() += grow;
  }
  return {lo, hi, pad};
}

struct LegendEntry {
  std::string colour;
  std::string text;
};

/// The legend's entries with their offsets from its top left (px); it wraps to further
/// rows on narrow drawings.
struct Legend {
  std::vector<std::pair<Vec2, LegendEntry>> layout;
  double height = 0.0;  ///< px beyond the first row
};

Legend layoutLegend(const std::vector<TrajectoryOverlay>& overlays, const std::string& target_label, int width_px) {
  std::vector<LegendEntry> entries = {{kLaneColour, "lane boundaries"},
                                      {kVehicleColour, "other vehicles (timestamps in s)"},
                                      {kEgoColour, "Ego: initial vector and " + target_label}};
  for (const auto& overlay : overlays) {
    if (!overlay.label.empty()) entries.push_back({overlay.colour, overlay.label});  // "": drawn, not listed (a second part of one overlay)
  }
  Legend legend;
  double x = 10.0;
  for (const auto& entry : entries) {
    const double entry_width = 28.0 + 6.2 * static_cast<double>(entry.text.size());
    if (x > 10.0 && x + entry_width > width_px) {
      x = 10.0;
      legend.height += 16.0;
    }
    legend.layout.push_back({Vec2(x, legend.height), entry});
    x += entry_width;
  }
  return legend;
}

/// Lane boundaries (clipped to the view when focused) and the other road users' vectors.
void drawContext(SvgCanvas& canvas, const VectorizedScene& scene, const View& view, bool focus) {
  const Vec2 view_lo = view.lo - view.pad;
  const Vec2 view_hi = view.hi + view.pad;
  for (const auto& polyline : scene.polylines) {
    if (polyline.type != ObjectType::LaneBoundary) continue;
    for (std::size_t v = 0; v < polyline.vectors.size(); ++v) {
      const auto& f = polyline.vectors[v];
      Vec2 a(f[0], f[1]);
      Vec2 b(f[2], f[3]);
      if (focus && !clipSegment(a, b, view_lo, view_hi)) continue;
      canvas.line(a, b, kLaneColour, 1.2);
    }
  }
  for (const auto& polyline : scene.polylines) {
    if (polyline.type != ObjectType::Vehicle) continue;
    for (std::size_t v = 0; v < polyline.vectors.size(); ++v) {
      if (!polyline.valid[v]) continue;
      const auto& f = polyline.vectors[v];
      canvas.arrow({f[0], f[1]}, {f[2], f[3]}, kVehicleColour, 1.4);
      // Timestamps every second, as in the paper's figure of the ACC&LK data.
      const double t = f[6];
      if (std::abs(t - std::round(t)) < 1e-3) canvas.text({f[2], f[3]}, fmt::format("{:.0f} s", t), 10, kVehicleColour);
    }
  }
}

/// The Ego's vectors, its true future and the overlays (predictions).
void drawEgo(SvgCanvas& canvas, const VectorizedScene& scene, const std::vector<TrajectoryOverlay>& overlays) {
  const auto& ego = scene.polylines.at(scene.egoPolyline);
  for (std::size_t v = 0; v < ego.vectors.size(); ++v) {
    const auto& f = ego.vectors[v];
    canvas.arrow({f[0], f[1]}, {f[2], f[3]}, kEgoColour, v + 1 == ego.vectors.size() ? 3.0 : 1.4);
  }
  Polyline truth;
  truth.emplace_back(ego.vectors.back()[0], ego.vectors.back()[1]);
  for (std::size_t k = 0; k < scene.target.size(); ++k) {
    if (scene.targetValid[k]) truth.push_back(scene.target[k]);
  }
  canvas.polyline(truth, kEgoColour, 1.5, false, 0.6);
  for (std::size_t k = 1; k < truth.size(); ++k) canvas.circle(truth[k], 2.5, kEgoColour);
  for (const auto& overlay : overlays) {
    canvas.polyline(overlay.points, overlay.colour, 2.0, overlay.dashed);
    for (const auto& p : overlay.points) canvas.circle(p, 2.0, overlay.colour);
  }
}

/// Title and legend, laid out above the drawing.
void drawHeading(SvgCanvas& canvas, const std::string& title, const Legend& legend) {
  double y = 18.0;
  if (!title.empty()) {
    canvas.textPx(10, y, title, 13, "#222222");
    y += 18.0;
  }
  for (const auto& [at, entry] : legend.layout) {
    canvas.rectPx(at.x(), y + at.y() - 9, 12, 4, entry.colour);
    canvas.textPx(at.x() + 16, y + at.y() - 4, entry.text, 11, "#333333");
  }
}

}  // namespace

std::string renderSceneSvg(const VectorizedScene& scene, const std::vector<TrajectoryOverlay>& overlays,
                           const std::string& title, int width_px, const std::string& target_label,
                           double focus_margin_m) {
  const bool focus = focus_margin_m > 0.0;
  const View view = viewOf(scene, overlays, focus_margin_m);
  const Legend legend = layoutLegend(overlays, target_label, width_px);
  const int margin = 40 + static_cast<int>(legend.height);
  SvgCanvas canvas(view.lo - view.pad, view.hi + view.pad, width_px, 0, /*equal_aspect=*/true, margin);
  drawContext(canvas, scene, view, focus);
  drawEgo(canvas, scene, overlays);
  drawHeading(canvas, title, legend);
  return canvas.str();
}

}  // namespace vsd::vector
