#pragma once
// The coordinate frame a model works in, per scene (internal to the model module).
// README "Representations":
//   ego  - the scene translated to the Ego's initial position and rotated by its heading;
//   lane - a lane-relative (Frenet) frame: x = arc length along a reference line that
//          follows the lane the Ego starts on (0 at the Ego's foot point), y = signed
//          offset from it (> 0 left). Straight and curved roads look alike in it.
// Positions the model predicts in its frame are mapped back to the scene's frame.

#include <Eigen/Core>
#include <memory>
#include <string>

#include "vsd/core/geometry.hpp"
#include "vsd/vector/scene.hpp"

namespace vsd::model {

class SceneFrame {
 public:
  virtual ~SceneFrame() = default;
  virtual Vec2 toModel(const Vec2& scene_point) const = 0;
  virtual Vec2 toScene(const Vec2& model_point) const = 0;
  /// Scene-frame heading of a direction `model_heading` at `model_point`.
  virtual double headingToScene(const Vec2& model_point, double model_heading) const = 0;
  /// Model-frame heading of a scene-frame direction at `scene_point`.
  virtual double headingToModel(const Vec2& scene_point, double scene_heading) const = 0;
  /// d scene / d model at `model_point` (maps model-frame covariances and speeds).
  virtual Eigen::Matrix2d jacobian(const Vec2& model_point) const = 0;
};

/// The frame `name` (one of availableFrames()) for a scene; `lane_smoothing_m`: the lane
/// frame's smoothing half-width (VectorNetConfig::laneSmoothing).
std::unique_ptr<SceneFrame> makeFrame(const std::string& name, const vector::VectorizedScene& scene,
                                      double lane_smoothing_m);

}  // namespace vsd::model
