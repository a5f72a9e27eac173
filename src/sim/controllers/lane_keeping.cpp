// PurePursuitLateral: lane keeping by pure pursuit on the lane-centre preview (every built-in
// controller's lateral part, and the scripted road users' lane keeping).

#include <algorithm>
#include <cmath>

#include "vsd/sim/builtin_controllers.hpp"

namespace vsd::sim {

void PurePursuitLateral::init(const ControllerParams& params) {
  lookaheadTime_ = params.get("lookahead_time", lookaheadTime_, 0.1, 10.0);
  minLookahead_ = params.get("min_lookahead", minLookahead_, 1.0, 100.0);
}

double PurePursuitLateral::curvature(const Observation& observation) const {
  if (!observation.lane) return 0.0;
  const auto& lane = *observation.lane;
  const double max_distance = lane.previewSpacing * kPreviewPoints;
  const double lookahead = std::clamp(lookaheadTime_ * observation.ego.speed, minLookahead_, max_distance);
  // Interpolate the lane-centre point at `lookahead` m ahead along the preview.
  const double position = lookahead / lane.previewSpacing - 1.0;
  Vec2 target;
  if (position <= 0.0) {
    target = lane.preview[0] * (lookahead / lane.previewSpacing);
  } else {
    const auto lower = std::min(static_cast<std::size_t>(position), static_cast<std::size_t>(kPreviewPoints - 2));
    const double fraction = std::min(position - static_cast<double>(lower), 1.0);
    target = lane.preview[lower] + fraction * (lane.preview[lower + 1] - lane.preview[lower]);
  }
  const double distance = target.norm();
  if (distance < 1e-6) return 0.0;
  const double sin_alpha = target.y() / distance;
  return 2.0 * sin_alpha / distance;
}

}  // namespace vsd::sim
