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
  std::string label;   ///< legend text ("": not listed, e.g. further parts of one overlay)
  Polyline points;     ///< scene frame, one point per instant
  std::string colour;  ///< CSS colour
  bool dashed = true;
};

/// A self-contained <svg> element; `title` is printed at the top. `target_label` names
/// the scene's target in the legend ("simulated future", "recorded future").
/// `focus_margin_m` > 0 zooms to the vehicles (Ego, its target, overlays, other vehicles)
/// plus that margin in metres, with lanes clipped to the view; 0 draws the whole scene.
std::string renderSceneSvg(const VectorizedScene& scene, const std::vector<TrajectoryOverlay>& overlays = {},
                           const std::string& title = "", int width_px = 900,
                           const std::string& target_label = "simulated future", double focus_margin_m = 0.0);

}  // namespace vsd::vector
