#pragma once
// Drawings of vectorized scenes in the style of the paper's figures: lanes
// grey, other vehicles purple with timestamps, the Ego's initial vector blue,
// its future (target) blue dots, extra trajectories (e.g. predictions) on top.

#include <string>
#include <vector>

#include "vsd/core/geometry.hpp"
#include "vsd/vector/scene.hpp"

namespace vsd::vector {

struct TrajectoryOverlay {
  std::string label;   ///< legend text
  Polyline points;     ///< scene frame, one point per instant
  std::string colour;  ///< CSS colour
  bool dashed = true;
};

/// A self-contained <svg> element; `title` is printed at the top.
std::string renderSceneSvg(const VectorizedScene& scene, const std::vector<TrajectoryOverlay>& overlays = {},
                           const std::string& title = "", int width_px = 900);

}  // namespace vsd::vector
