#pragma once
// The vectorized scenario description (VectorNet polylines): one uniform
// representation for every scenario, whatever its parameters.
//
// A vector is [x_start, y_start, x_end, y_end, object_type, polyline_id, timestamp]
// (feature version 1, 7 features):
//   - lane boundaries (object_type 1): left and right boundary of every lane, from
//     SUMO's lane geometry and width; timestamp 0;
//   - other vehicles (object_type 2): one vector per step from the vehicle's
//     centre at t_{k-1} to t_k, timestamp t_k (s, relative to the scene's t0);
//   - the Ego (object_type 3): its initial vector from p(t0) to
//     p(t0) + max(v dt, 1 cm) * heading, so it holds position, heading and speed
//     (the 1 cm keeps the heading at standstill); timestamp 0. With a history,
//     its past steps come first (timestamps -H+dt .. 0), then the initial vector.
// polyline_id is the polyline's position in the scene. Vehicle and Ego polylines
// also carry the road user's length and width (m), which gaps between vehicles need, and
// its kind (car, truck, pedestrian, stationary object, ...; core/road_user.hpp) - outside
// the 7 features, so the feature layout, and models trained on it, stay as they are. Coordinates are in the
// scene's frame (scenario frame for generated scenarios, network frame for maps),
// metres. The target is the Ego's centre at t_1 .. t_F.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "vsd/core/geometry.hpp"
#include "vsd/core/trace.hpp"

namespace vsd::vector {

inline constexpr int kFeatureVersion = 1;
inline constexpr std::size_t kFeatures = 7;
inline constexpr const char* kFeatureNames[kFeatures] = {"x_start", "y_start",     "x_end",    "y_end",
                                                         "object_type", "polyline_id", "timestamp"};
/// Length of the Ego's initial vector at standstill (m).
inline constexpr double kStandstillVectorLength = 0.01;

enum class ObjectType : int { LaneBoundary = 1, Vehicle = 2, Ego = 3 };

/// In memory features are double; datasets store them as float32 relative to the
/// sample's origin (the Ego's initial position, stored as float64), so map
/// coordinates kilometres from the origin keep millimetre precision.
using Feature = std::array<double, kFeatures>;

struct ScenePolyline {
  ObjectType type = ObjectType::LaneBoundary;
  std::vector<Feature> vectors;
  std::vector<std::uint8_t> valid;  ///< per vector: 1 = real, 0 = masked (vehicle absent or out of range)
  /// For lane polylines of a map: index of the first vector in the map's shared
  /// lane-vector pool (the vectors are consecutive there); -1 otherwise. Lets a
  /// dataset store a map's lanes once instead of once per sample.
  std::int64_t sharedStart = -1;
  /// Vehicles and the Ego: the vehicle's bounding box (m, > 0); lane boundaries: 0.
  double length = 0.0;
  double width = 0.0;
  /// Vehicles and the Ego: what kind of road user it is (a pedestrian, a stationary object
  /// are "vehicle" polylines too, object_type 2); lane boundaries: unused.
  RoadUserType roadUser = RoadUserType::Car;
};

/// Where a sample came from.
struct Provenance {
  std::string source;        ///< scenario file (generated) or map file (export)
  std::string sourceSha256;  ///< SHA-256 of that file
  std::string egoId;         ///< the Ego's vehicle id
  double t0 = 0.0;           ///< s, simulation time of the scene's t = 0
};

struct VectorizedScene {
  std::string label;          ///< functional scenario (acc, lk, acc_lk) or map label
  std::uint64_t sample = 0;   ///< sample index of the run / window number of the export
  double step = 0.0;          ///< s between instants; no default: from the trace or the dataset header
  std::vector<ScenePolyline> polylines;
  std::size_t egoPolyline = 0;        ///< index of the Ego's polyline
  std::vector<Vec2> target;           ///< Ego centre at t_1 .. t_F (scene frame)
  std::vector<std::uint8_t> targetValid;
  std::vector<double> inputs;         ///< concrete inputs (generated scenarios; names in the dataset)
  std::vector<double> metrics;        ///< metrics of the simulated run (generated scenarios)
  Provenance provenance;

  std::size_t vectorCount() const;
  /// Position, heading and speed encoded in the Ego's initial vector.
  VehicleState egoInitialState() const;
};

/// The Ego's initial vector for a state (see the file comment).
Feature egoInitialVector(const VehicleState& state, double step, int polyline_id);

/// Sets every vector's polyline_id feature to its polyline's position.
void numberPolylines(VectorizedScene& scene);

}  // namespace vsd::vector
