#include "vsd/road/lane_frame.hpp"

#include <algorithm>
#include <cmath>

#include "vsd/core/path_relation.hpp"

namespace vsd::road {

LaneFrame::LaneFrame(const Polyline& centre) : centre_(centre) {
  const Polyline unit = offsetPolyline(centre, 1.0);
  mitre_.reserve(centre.size());
  cumulative_.reserve(centre.size());
  double s = 0.0;
  for (std::size_t i = 0; i < centre.size(); ++i) {
    mitre_.push_back(unit[i] - centre[i]);
    if (i > 0) s += (centre[i] - centre[i - 1]).norm();
    cumulative_.push_back(s);
  }
}

LaneFrame::Segment LaneFrame::segmentAt(double s) const {
  const auto it = std::upper_bound(cumulative_.begin(), cumulative_.end(), s);
  auto index = static_cast<std::size_t>(std::distance(cumulative_.begin(), it));
  index = index == 0 ? 0 : std::min(index - 1, cumulative_.size() - 2);
  const double length = cumulative_[index + 1] - cumulative_[index];
  return {index, length > 0.0 ? (s - cumulative_[index]) / length : 0.0};
}

Vec2 LaneFrame::point(double s, double d) const {
  const auto [i, f] = segmentAt(s);
  const Polyline& c = centre_.points();
  const Vec2 a = c[i] + d * mitre_[i];
  const Vec2 b = c[i + 1] + d * mitre_[i + 1];
  return a + f * (b - a);
}

Vec2 LaneFrame::alongDerivative(std::size_t segment, double d) const {
  const Polyline& c = centre_.points();
  const double length = cumulative_[segment + 1] - cumulative_[segment];
  const Vec2 delta = c[segment + 1] - c[segment] + d * (mitre_[segment + 1] - mitre_[segment]);
  return length > 0.0 ? Vec2(delta / length) : Vec2(1.0, 0.0);
}

double LaneFrame::sRate(double s, double d, double speed_along) const {
  const double stretch = alongDerivative(segmentAt(s).index, d).norm();
  return stretch > 0.0 ? speed_along / stretch : speed_along;
}

Vec2 LaneFrame::velocity(double s, double d, double speed_along, double lateral_rate) const {
  const auto [i, f] = segmentAt(s);
  const Vec2 along = alongDerivative(i, d);
  const Vec2 across = mitre_[i] + f * (mitre_[i + 1] - mitre_[i]);
  const double stretch = along.norm();
  return (stretch > 0.0 ? Vec2(along / stretch) : Vec2(1.0, 0.0)) * speed_along + across * lateral_rate;
}

double LaneFrame::heading(double s, double d) const { return headingOf(alongDerivative(segmentAt(s).index, d)); }

std::pair<double, double> LaneFrame::coordinates(const Vec2& point) const {
  const PolylineProjection foot = projectExtended(centre_, point);
  return {foot.arcLength, foot.lateralOffset};
}

}  // namespace vsd::road
