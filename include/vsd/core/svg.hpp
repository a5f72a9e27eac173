#pragma once
// Minimal SVG drawing in world coordinates (m, y up), for scene drawings and
// report charts that must work offline (no scripts, no external resources).

#include <string>
#include <vector>

#include "vsd/core/geometry.hpp"

namespace vsd {

/// Escapes &, <, >, " and ' for XML text and attributes.
std::string escapeXml(const std::string& text);

class SvgCanvas {
 public:
  /// Maps the world box [lo, hi] into `width` pixels (height follows from the aspect
  /// ratio when `equal_aspect`, else `height`), with `margin` pixels around it. An
  /// equal-aspect canvas is a map in metres: str() adds a scale bar in its bottom margin.
  SvgCanvas(Vec2 lo, Vec2 hi, int width, int height, bool equal_aspect, int margin = 30);

  void polyline(const Polyline& points, const std::string& colour, double width_px, bool dashed = false,
                double opacity = 1.0);
  void line(const Vec2& a, const Vec2& b, const std::string& colour, double width_px, bool dashed = false);
  void arrow(const Vec2& from, const Vec2& to, const std::string& colour, double width_px);
  void circle(const Vec2& centre, double radius_px, const std::string& colour, double opacity = 1.0);
  /// Text anchored at a world point; `anchor` is start, middle or end.
  void text(const Vec2& at, const std::string& content, double size_px, const std::string& colour,
            const std::string& anchor = "start");
  /// Text at pixel coordinates (titles, legends, axis labels).
  void textPx(double x, double y, const std::string& content, double size_px, const std::string& colour,
              const std::string& anchor = "start", bool rotated = false);
  void rectPx(double x, double y, double w, double h, const std::string& fill, const std::string& stroke = "none");
  void linePx(double x0, double y0, double x1, double y1, const std::string& colour, double width_px);

  double toX(double world_x) const;
  double toY(double world_y) const;
  int width() const { return width_; }
  int height() const { return height_; }
  /// The complete <svg> element.
  std::string str() const;

 private:
  std::string scaleBar() const;

  Vec2 lo_;
  Vec2 hi_;
  double scaleX_;
  double scaleY_;
  int width_;
  int height_;
  int margin_;
  bool equalAspect_ = false;
  std::string body_;
};

/// Places complete <svg> elements (as SvgCanvas::str() writes them, with width and
/// height attributes in pixels) side by side in one <svg>, under an optional title.
/// Throws vsd::Error for an element without width/height.
std::string composeSvgRow(const std::vector<std::string>& panels, const std::string& title = "", int gap_px = 10);

}  // namespace vsd
