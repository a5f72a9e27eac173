#include "vsd/core/svg.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <regex>
#include <stdexcept>

#include "vsd/core/error.hpp"

namespace vsd {

std::string escapeXml(const std::string& text) {
  std::string escaped;
  escaped.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '&': escaped += "&amp;"; break;
      case '<': escaped += "&lt;"; break;
      case '>': escaped += "&gt;"; break;
      case '"': escaped += "&quot;"; break;
      case '\'': escaped += "&#39;"; break;
      default: escaped += c;
    }
  }
  return escaped;
}

SvgCanvas::SvgCanvas(Vec2 lo, Vec2 hi, int width, int height, bool equal_aspect, int margin)
    : lo_(lo), width_(width), height_(height), margin_(margin), equalAspect_(equal_aspect) {
  const Vec2 span = (hi - lo).cwiseMax(Vec2(1e-9, 1e-9));
  const double inner_width = width - 2.0 * margin;
  scaleX_ = inner_width / span.x();
  if (equal_aspect) {
    scaleY_ = scaleX_;
    height_ = static_cast<int>(std::ceil(span.y() * scaleY_ + 2.0 * margin));
  } else {
    scaleY_ = (height - 2.0 * margin) / span.y();
  }
  lo_ = lo;
  hi_ = lo + span;
}

double SvgCanvas::toX(double world_x) const { return margin_ + (world_x - lo_.x()) * scaleX_; }
double SvgCanvas::toY(double world_y) const { return height_ - margin_ - (world_y - lo_.y()) * scaleY_; }

void SvgCanvas::polyline(const Polyline& points, const std::string& colour, double width_px, bool dashed,
                         double opacity) {
  if (points.size() < 2) return;
  std::string coordinates;
  for (const auto& p : points) coordinates += fmt::format("{:.1f},{:.1f} ", toX(p.x()), toY(p.y()));
  body_ += fmt::format(
      "<polyline points=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"{:.2f}\" stroke-opacity=\"{:.2f}\""
      " stroke-linejoin=\"round\"{}/>\n",
      coordinates, colour, width_px, opacity, dashed ? " stroke-dasharray=\"6,4\"" : "");
}

void SvgCanvas::line(const Vec2& a, const Vec2& b, const std::string& colour, double width_px, bool dashed) {
  polyline({a, b}, colour, width_px, dashed);
}

void SvgCanvas::arrow(const Vec2& from, const Vec2& to, const std::string& colour, double width_px) {
  const double x0 = toX(from.x());
  const double y0 = toY(from.y());
  double x1 = toX(to.x());
  double y1 = toY(to.y());
  double dx = x1 - x0;
  double dy = y1 - y0;
  double length = std::hypot(dx, dy);
  if (length < 8.0) {  // too short to see: draw at a minimum size in the same direction
    if (length < 1e-9) {
      dx = 1.0;
      dy = 0.0;
      length = 1.0;
    }
    x1 = x0 + dx / length * 8.0;
    y1 = y0 + dy / length * 8.0;
    dx = x1 - x0;
    dy = y1 - y0;
    length = 8.0;
  }
  const double ux = dx / length;
  const double uy = dy / length;
  const double head = 3.0 * width_px + 4.0;
  body_ += fmt::format("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"{}\" stroke-width=\"{:.2f}\"/>\n",
                       x0, y0, x1, y1, colour, width_px);
  body_ += fmt::format("<polygon points=\"{:.1f},{:.1f} {:.1f},{:.1f} {:.1f},{:.1f}\" fill=\"{}\"/>\n", x1, y1,
                       x1 - head * ux + 0.5 * head * uy, y1 - head * uy - 0.5 * head * ux,
                       x1 - head * ux - 0.5 * head * uy, y1 - head * uy + 0.5 * head * ux, colour);
}

void SvgCanvas::circle(const Vec2& centre, double radius_px, const std::string& colour, double opacity) {
  body_ += fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"{:.1f}\" fill=\"{}\" fill-opacity=\"{:.2f}\"/>\n",
                       toX(centre.x()), toY(centre.y()), radius_px, colour, opacity);
}

void SvgCanvas::text(const Vec2& at, const std::string& content, double size_px, const std::string& colour,
                     const std::string& anchor) {
  textPx(toX(at.x()), toY(at.y()), content, size_px, colour, anchor);
}

void SvgCanvas::textPx(double x, double y, const std::string& content, double size_px, const std::string& colour,
                       const std::string& anchor, bool rotated) {
  body_ += fmt::format(
      "<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"{:.1f}\" font-family=\"sans-serif\" fill=\"{}\" "
      "text-anchor=\"{}\"{}>{}</text>\n",
      x, y, size_px, colour, anchor,
      rotated ? fmt::format(" transform=\"rotate(-90 {:.1f} {:.1f})\"", x, y) : std::string(), escapeXml(content));
}

void SvgCanvas::rectPx(double x, double y, double w, double h, const std::string& fill, const std::string& stroke) {
  body_ += fmt::format("<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"{}\" stroke=\"{}\"/>\n",
                       x, y, w, h, fill, stroke);
}

void SvgCanvas::linePx(double x0, double y0, double x1, double y1, const std::string& colour, double width_px) {
  body_ += fmt::format("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"{}\" stroke-width=\"{:.2f}\"/>\n",
                       x0, y0, x1, y1, colour, width_px);
}

/// A bar of a round length (1, 2 or 5 times a power of ten metres, at most about a quarter
/// of the drawing's width) at the bottom right, inside the margin.
std::string SvgCanvas::scaleBar() const {
  const double longest = std::min(140.0, 0.25 * (width_ - 2.0 * margin_)) / scaleX_;
  if (!(longest > 0.0) || !std::isfinite(longest)) return {};
  const double magnitude = std::pow(10.0, std::floor(std::log10(longest)));
  double metres = magnitude;
  for (const double factor : {2.0, 5.0}) {
    if (factor * magnitude <= longest) metres = factor * magnitude;
  }
  const double px = metres * scaleX_;
  const double x1 = width_ - margin_;
  const double x0 = x1 - px;
  const double y = height_ - 10.0;
  const std::string label = metres >= 1.0 ? fmt::format("{:g} m", metres) : fmt::format("{:g} cm", 100.0 * metres);
  return fmt::format(
      "<g class=\"scale-bar\" stroke=\"#333333\" stroke-width=\"1.5\">"
      "<line x1=\"{0:.1f}\" y1=\"{2:.1f}\" x2=\"{1:.1f}\" y2=\"{2:.1f}\"/>"
      "<line x1=\"{0:.1f}\" y1=\"{3:.1f}\" x2=\"{0:.1f}\" y2=\"{2:.1f}\"/>"
      "<line x1=\"{1:.1f}\" y1=\"{3:.1f}\" x2=\"{1:.1f}\" y2=\"{2:.1f}\"/></g>\n"
      "<text x=\"{4:.1f}\" y=\"{5:.1f}\" font-size=\"10.0\" font-family=\"sans-serif\" fill=\"#333333\" "
      "text-anchor=\"middle\">{6}</text>\n",
      x0, x1, y, y - 4.0, 0.5 * (x0 + x1), y - 6.0, label);
}

std::string SvgCanvas::str() const {
  return fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{0}\" height=\"{1}\" viewBox=\"0 0 {0} {1}\">\n"
      "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n{2}{3}</svg>\n",
      width_, height_, body_, equalAspect_ ? scaleBar() : std::string());
}

std::string composeSvgRow(const std::vector<std::string>& panels, const std::string& title, int gap_px) {
  static const std::regex size_pattern(R"re(<svg[^>]*?\swidth="([0-9.]+)"\s+height="([0-9.]+)")re");
  const double title_height = title.empty() ? 0.0 : 34.0;
  double width = 0.0;
  double height = 0.0;
  std::string body;
  for (const auto& panel : panels) {
    std::smatch match;
    if (!std::regex_search(panel, match, size_pattern)) {
      throw Error("internal: composeSvgRow: a panel is not an <svg> element with width and height");
    }
    const double panel_width = std::stod(match[1].str());
    const double panel_height = std::stod(match[2].str());
    const auto open = panel.find("<svg");
    body += panel.substr(0, open + 4) + fmt::format(" x=\"{:.0f}\" y=\"{:.0f}\"", width, title_height) +
            panel.substr(open + 4);
    width += panel_width + gap_px;
    height = std::max(height, panel_height);
  }
  width = std::max(0.0, width - gap_px);
  std::string header;
  if (!title.empty()) {
    header = fmt::format("<text x=\"10\" y=\"22\" font-size=\"18\" font-family=\"sans-serif\" fill=\"black\">{}</text>\n",
                         escapeXml(title));
  }
  return fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{0:.0f}\" height=\"{1:.0f}\" viewBox=\"0 0 {0:.0f} {1:.0f}\">\n"
      "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n{2}{3}</svg>\n",
      width, height + title_height, header, body);
}

}  // namespace vsd
