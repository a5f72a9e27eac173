#pragma once
// Converters into the vectorized scenario description. One scene builder serves
// generated scenarios and windows of arbitrary maps alike; they differ only in
// how lanes are selected (scenario region vs. radius around the Ego).

#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include "vsd/core/geometry.hpp"
#include "vsd/core/trace.hpp"
#include "vsd/vector/scene.hpp"

namespace vsd::vector {

/// Left and right boundary of a lane: its centre line moved by +-width/2.
std::pair<Polyline, Polyline> laneBoundaries(const Polyline& centre, double width);

/// One vector per segment of `line`, segments longer than `max_length` split
/// into equal parts (max_length <= 0: no splitting).
std::vector<std::pair<Vec2, Vec2>> splitIntoVectors(const Polyline& line, double max_length);

/// A lane-boundary polyline of consecutive vectors (all valid, timestamp 0).
ScenePolyline boundaryPolyline(const std::vector<std::pair<Vec2, Vec2>>& vectors);

/// Builds a scene from a trace and the lane polylines around it.
/// `trace.vehicles[0]` is the Ego; instants 0..K with t0 at `t0_index` (instants
/// before it are history). Other vehicles become polylines of one vector per step
/// (valid when both ends are valid), timestamped with the end instant relative to
/// t0; vehicles without a single valid vector are left out. The Ego polyline holds
/// its history vectors and its initial vector; the target is its centre at
/// t0_index + 1 .. K. Polylines: lanes, other vehicles, Ego (in this order).
VectorizedScene buildScene(const std::string& label, const Trace& trace, std::size_t t0_index,
                           std::vector<ScenePolyline> lane_polylines);

/// Lanes of a generated scenario: every lane's centre clipped to x in [x_min, x_max]
/// (the scenario region), then its two boundaries, one vector per shape segment
/// (24 per boundary for the paper's 25 lane points).
std::vector<ScenePolyline> regionLanePolylines(const std::vector<LaneGeometry>& lanes, double x_min, double x_max);

/// Lane-boundary vectors of a whole network in a uniform grid, for "every lane
/// within a radius" queries on arbitrary maps (junction-internal lanes included).
class LaneIndex {
 public:
  /// `max_vector_length`: longer shape segments are split (m, > 0).
  LaneIndex(const std::vector<LaneGeometry>& lanes, double max_vector_length, double cell_size = 25.0);

  /// The boundary vectors within `radius` of `centre`, as polylines of consecutive
  /// vectors (a boundary that leaves and re-enters the circle gives two), in network
  /// order (lane id, left before right). Each polyline refers to the shared pool.
  std::vector<ScenePolyline> query(const Vec2& centre, double radius) const;

  std::size_t boundaries() const { return boundaries_.size(); }
  std::size_t vectors() const { return pool_.size(); }
  /// Every boundary vector of the network, boundary after boundary (the shared pool).
  const std::vector<Feature>& pool() const { return pool_; }

 private:
  struct Entry {
    std::uint32_t boundary;
    std::uint32_t vector;
  };
  std::int64_t cellKey(std::int64_t ix, std::int64_t iy) const;

  std::vector<std::vector<std::pair<Vec2, Vec2>>> boundaries_;
  std::vector<std::uint32_t> boundaryStart_;  ///< pool index of each boundary's first vector
  std::vector<Feature> pool_;
  std::unordered_map<std::int64_t, std::vector<Entry>> grid_;
  double cellSize_;
};

}  // namespace vsd::vector

namespace vsd::vector {

/// The scene as a Trace over t = 0 .. F: the Ego along `ego_future` (positions at
/// t_1 .. t_F; speed, heading and acceleration from trackFromPositions), every other
/// vehicle from its vectors (positions at their end points, heading along them, speed
/// = length / dt; masked where invalid), each with the length and width its polyline
/// carries. Used to score predictions with the metric code of simulated runs.
Trace sceneTrace(const VectorizedScene& scene, const Polyline& ego_future);

/// The centre line of the lane the Ego starts on: the midline of the left/right
/// boundary pair (consecutive lane polylines of equal length) nearest to its initial
/// position; empty if the scene has no such pair.
Polyline egoLaneCentre(const VectorizedScene& scene);

/// Every lane-boundary polyline of the scene as a line (valid vectors joined where
/// they connect), for lane offsets measured at each instant on maps.
std::vector<Polyline> laneBoundaryLines(const VectorizedScene& scene);

}  // namespace vsd::vector
