#include "vsd/vector/scene.hpp"

#include <cmath>

namespace vsd::vector {

std::size_t VectorizedScene::vectorCount() const {
  std::size_t count = 0;
  for (const auto& polyline : polylines) count += polyline.vectors.size();
  return count;
}

VehicleState VectorizedScene::egoInitialState() const {
  const Feature& initial = polylines.at(egoPolyline).vectors.back();
  const Vec2 start(initial[0], initial[1]);
  const Vec2 delta = Vec2(initial[2], initial[3]) - start;
  VehicleState state;
  state.x = start.x();
  state.y = start.y();
  state.heading = headingOf(delta);
  const double length = delta.norm();
  state.speed = length <= 1.5 * kStandstillVectorLength ? 0.0 : length / step;
  return state;
}

Feature egoInitialVector(const VehicleState& state, double step, int polyline_id) {
  const double length = std::max(state.speed * step, kStandstillVectorLength);
  const Vec2 end = state.position() + length * headingVector(state.heading);
  return {state.x, state.y, end.x(), end.y(), static_cast<double>(ObjectType::Ego), static_cast<double>(polyline_id), 0.0};
}

void numberPolylines(VectorizedScene& scene) {
  for (std::size_t p = 0; p < scene.polylines.size(); ++p) {
    for (auto& vector : scene.polylines[p].vectors) vector[5] = static_cast<double>(p);
  }
}

}  // namespace vsd::vector
