#include "vsd/vector/vectorize.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "vsd/core/error.hpp"

namespace vsd::vector {

std::pair<Polyline, Polyline> laneBoundaries(const Polyline& centre, double width) {
  return {offsetPolyline(centre, 0.5 * width), offsetPolyline(centre, -0.5 * width)};
}

std::vector<std::pair<Vec2, Vec2>> splitIntoVectors(const Polyline& line, double max_length) {
  std::vector<std::pair<Vec2, Vec2>> vectors;
  for (std::size_t i = 0; i + 1 < line.size(); ++i) {
    const Vec2& a = line[i];
    const Vec2& b = line[i + 1];
    const double length = (b - a).norm();
    if (length <= 0.0) continue;
    const int parts = max_length > 0.0 ? std::max(1, static_cast<int>(std::ceil(length / max_length))) : 1;
    for (int p = 0; p < parts; ++p) {
      vectors.emplace_back(a + (b - a) * (static_cast<double>(p) / parts), a + (b - a) * (static_cast<double>(p + 1) / parts));
    }
  }
  return vectors;
}

ScenePolyline boundaryPolyline(const std::vector<std::pair<Vec2, Vec2>>& vectors) {
  ScenePolyline polyline;
  polyline.type = ObjectType::LaneBoundary;
  polyline.vectors.reserve(vectors.size());
  for (const auto& [start, end] : vectors) {
    polyline.vectors.push_back(
        {start.x(), start.y(), end.x(), end.y(), static_cast<double>(ObjectType::LaneBoundary), 0.0, 0.0});
  }
  polyline.valid.assign(polyline.vectors.size(), 1);
  return polyline;
}

VectorizedScene buildScene(const std::string& label, const Trace& trace, std::size_t t0_index,
                           std::vector<ScenePolyline> lane_polylines) {
  if (trace.vehicles.empty()) throw Error("internal: buildScene without an Ego");
  const VehicleTrack& ego = trace.ego();
  if (!ego.validAt(t0_index)) throw Error("internal: buildScene with an Ego absent at t0");
  const double dt = trace.step;
  if (!(dt > 0.0)) throw Error("internal: buildScene with a trace without a step");
  VectorizedScene scene;
  scene.label = label;
  scene.step = dt;
  scene.polylines = std::move(lane_polylines);

  auto timestamp = [&](std::size_t k) { return (static_cast<double>(k) - static_cast<double>(t0_index)) * dt; };
  auto motion = [&](const VehicleTrack& track, std::size_t first, std::size_t last, ObjectType type) {
    ScenePolyline polyline;
    polyline.type = type;
    polyline.length = track.length;
    polyline.roadUser = track.type;
    polyline.width = track.width;
    for (std::size_t k = first + 1; k <= last && k < track.states.size(); ++k) {
      const auto& from = track.states[k - 1];
      const auto& to = track.states[k];
      polyline.vectors.push_back({from.x, from.y, to.x, to.y, static_cast<double>(type), 0.0, timestamp(k)});
      polyline.valid.push_back(track.validAt(k - 1) && track.validAt(k) ? 1 : 0);
    }
    return polyline;
  };

  for (std::size_t v = 1; v < trace.vehicles.size(); ++v) {
    ScenePolyline polyline = motion(trace.vehicles[v], 0, trace.vehicles[v].states.size() - 1, ObjectType::Vehicle);
    if (std::any_of(polyline.valid.begin(), polyline.valid.end(), [](std::uint8_t valid) { return valid != 0; })) {
      scene.polylines.push_back(std::move(polyline));
    }
  }

  ScenePolyline ego_polyline = motion(ego, 0, t0_index, ObjectType::Ego);
  ego_polyline.vectors.push_back(egoInitialVector(ego.states[t0_index], dt, 0));
  ego_polyline.valid.push_back(1);
  scene.egoPolyline = scene.polylines.size();
  scene.polylines.push_back(std::move(ego_polyline));

  for (std::size_t k = t0_index + 1; k < ego.states.size(); ++k) {
    scene.target.push_back(ego.states[k].position());
    scene.targetValid.push_back(ego.validAt(k) ? 1 : 0);
  }
  numberPolylines(scene);
  return scene;
}

std::vector<ScenePolyline> regionLanePolylines(const std::vector<LaneGeometry>& lanes, double x_min, double x_max) {
  std::vector<ScenePolyline> polylines;
  for (const auto& lane : lanes) {
    // Clip the centre first: its points are the generator's lane points, so the
    // region keeps exactly points - 1 segments; the boundaries follow from it.
    const Polyline centre = clipToXRange(lane.centre, x_min, x_max);
    if (centre.size() < 2) continue;
    const auto [left, right] = laneBoundaries(centre, lane.width);
    polylines.push_back(boundaryPolyline(splitIntoVectors(left, 0.0)));
    polylines.push_back(boundaryPolyline(splitIntoVectors(right, 0.0)));
  }
  return polylines;
}

LaneIndex::LaneIndex(const std::vector<LaneGeometry>& lanes, double max_vector_length, double cell_size)
    : cellSize_(cell_size) {
  if (!(max_vector_length > 0.0)) throw ConfigError("lane vectors: max vector length must be > 0 m");
  std::vector<const LaneGeometry*> ordered;
  for (const auto& lane : lanes) ordered.push_back(&lane);
  std::sort(ordered.begin(), ordered.end(), [](const auto* a, const auto* b) { return a->id < b->id; });
  for (const auto* lane : ordered) {
    if (lane->centre.size() < 2) continue;
    const auto [left, right] = laneBoundaries(lane->centre, lane->width);
    for (const Polyline* side : {&left, &right}) {
      const auto boundary = static_cast<std::uint32_t>(boundaries_.size());
      boundaries_.push_back(splitIntoVectors(*side, max_vector_length));
      const auto& vectors = boundaries_.back();
      boundaryStart_.push_back(static_cast<std::uint32_t>(pool_.size()));
      const auto lane_polyline = boundaryPolyline(vectors);
      pool_.insert(pool_.end(), lane_polyline.vectors.begin(), lane_polyline.vectors.end());
      for (std::uint32_t v = 0; v < vectors.size(); ++v) {
        // Register the vector in every cell its bounding box touches (vectors are short).
        const Vec2 lo = vectors[v].first.cwiseMin(vectors[v].second);
        const Vec2 hi = vectors[v].first.cwiseMax(vectors[v].second);
        for (auto ix = static_cast<std::int64_t>(std::floor(lo.x() / cellSize_));
             ix <= static_cast<std::int64_t>(std::floor(hi.x() / cellSize_)); ++ix) {
          for (auto iy = static_cast<std::int64_t>(std::floor(lo.y() / cellSize_));
               iy <= static_cast<std::int64_t>(std::floor(hi.y() / cellSize_)); ++iy) {
            grid_[cellKey(ix, iy)].push_back({boundary, v});
          }
        }
      }
    }
  }
}

std::int64_t LaneIndex::cellKey(std::int64_t ix, std::int64_t iy) const {
  return (ix + (std::int64_t{1} << 30)) * (std::int64_t{1} << 31) + (iy + (std::int64_t{1} << 30));
}

std::vector<ScenePolyline> LaneIndex::query(const Vec2& centre, double radius) const {
  if (!(radius >= 0.0) || !centre.allFinite()) {
    throw Error(fmt::format("internal: lane query at ({}, {}) with radius {}", centre.x(), centre.y(), radius));
  }
  std::vector<std::uint32_t> hits;  // pool indices of the vectors within the radius
  const double radius_sq = radius * radius;
  const auto collect = [&](const std::vector<Entry>& entries) {
    for (const Entry& entry : entries) {
      const auto& [a, b] = boundaries_[entry.boundary][entry.vector];
      const Vec2 delta = b - a;
      const double length_sq = delta.squaredNorm();
      const double fraction = length_sq > 0.0 ? std::clamp((centre - a).dot(delta) / length_sq, 0.0, 1.0) : 0.0;
      if ((a + fraction * delta - centre).squaredNorm() <= radius_sq) {
        hits.push_back(boundaryStart_[entry.boundary] + entry.vector);
      }
    }
  };
  // Cells of the circle's bounding box, or every occupied cell when those are fewer
  // (a radius larger than the network): the work is bounded by the network's size.
  const double span = 2.0 * radius / cellSize_ + 2.0;
  if (span * span > static_cast<double>(grid_.size())) {
    for (const auto& [key, entries] : grid_) collect(entries);
  } else {
    const auto ix0 = static_cast<std::int64_t>(std::floor((centre.x() - radius) / cellSize_));
    const auto ix1 = static_cast<std::int64_t>(std::floor((centre.x() + radius) / cellSize_));
    const auto iy0 = static_cast<std::int64_t>(std::floor((centre.y() - radius) / cellSize_));
    const auto iy1 = static_cast<std::int64_t>(std::floor((centre.y() + radius) / cellSize_));
    for (auto ix = ix0; ix <= ix1; ++ix) {
      for (auto iy = iy0; iy <= iy1; ++iy) {
        const auto it = grid_.find(cellKey(ix, iy));
        if (it != grid_.end()) collect(it->second);
      }
    }
  }
  // Pool order is network order; a vector spanning two cells is found twice.
  std::sort(hits.begin(), hits.end());
  hits.erase(std::unique(hits.begin(), hits.end()), hits.end());
  std::vector<ScenePolyline> polylines;
  std::size_t i = 0;
  while (i < hits.size()) {
    // A run of consecutive pool vectors that belong to one boundary.
    const std::uint32_t first = hits[i];
    const auto boundary_end = std::upper_bound(boundaryStart_.begin(), boundaryStart_.end(), first);
    const std::uint32_t limit = boundary_end == boundaryStart_.end() ? static_cast<std::uint32_t>(pool_.size())
                                                                     : *boundary_end;
    std::size_t j = i + 1;
    while (j < hits.size() && hits[j] == hits[j - 1] + 1 && hits[j] < limit) ++j;
    ScenePolyline polyline;
    polyline.type = ObjectType::LaneBoundary;
    polyline.vectors.assign(pool_.begin() + first, pool_.begin() + first + static_cast<std::ptrdiff_t>(j - i));
    polyline.valid.assign(j - i, 1);
    polyline.sharedStart = first;
    polylines.push_back(std::move(polyline));
    i = j;
  }
  return polylines;
}

}  // namespace vsd::vector

namespace vsd::vector {

Trace sceneTrace(const VectorizedScene& scene, const Polyline& ego_future) {
  const double dt = scene.step;
  const std::size_t instants = ego_future.size() + 1;
  Trace trace;
  trace.step = dt;
  const auto initial = scene.egoInitialState();
  Polyline positions = {initial.position()};
  positions.insert(positions.end(), ego_future.begin(), ego_future.end());
  VehicleTrack ego = trackFromPositions(positions, dt, initial.speed, initial.heading);
  ego.id = "ego";
  ego.role = VehicleRole::Ego;
  ego.length = scene.polylines.at(scene.egoPolyline).length;
  ego.width = scene.polylines.at(scene.egoPolyline).width;
  ego.type = scene.polylines.at(scene.egoPolyline).roadUser;
  for (std::size_t k = 1; k < instants && k - 1 < scene.targetValid.size(); ++k) ego.valid[k] = scene.targetValid[k - 1];
  trace.vehicles.push_back(std::move(ego));

  for (const auto& polyline : scene.polylines) {
    if (polyline.type != ObjectType::Vehicle) continue;
    VehicleTrack track;
    track.length = polyline.length;
    track.width = polyline.width;
    track.type = polyline.roadUser;
    track.states.assign(instants, VehicleState{});
    track.valid.assign(instants, 0);
    for (std::size_t v = 0; v < polyline.vectors.size(); ++v) {
      if (!polyline.valid[v]) continue;
      const auto& f = polyline.vectors[v];
      const auto end_instant = std::lround(f[6] / dt);
      const Vec2 start(f[0], f[1]);
      const Vec2 end(f[2], f[3]);
      const double heading = (end - start).norm() > 1e-9 ? headingOf(end - start) : 0.0;
      const double speed = (end - start).norm() / dt;
      // A vector's end point sets its instant; its start point fills the instant
      // before only if no earlier vector ended there (e.g. after a masked step).
      if (end_instant >= 1 && end_instant - 1 < static_cast<long>(instants) &&
          !track.valid[static_cast<std::size_t>(end_instant - 1)]) {
        track.states[static_cast<std::size_t>(end_instant - 1)] = {start.x(), start.y(), heading, speed, 0.0};
        track.valid[static_cast<std::size_t>(end_instant - 1)] = 1;
      }
      if (end_instant >= 0 && end_instant < static_cast<long>(instants)) {
        track.states[static_cast<std::size_t>(end_instant)] = {end.x(), end.y(), heading, speed, 0.0};
        track.valid[static_cast<std::size_t>(end_instant)] = 1;
      }
    }
    fillAccelerationFromSpeed(track, dt);
    trace.vehicles.push_back(std::move(track));
  }
  return trace;
}

Polyline egoLaneCentre(const VectorizedScene& scene) {
  const Vec2 ego = scene.egoInitialState().position();
  Polyline best;
  double best_distance = std::numeric_limits<double>::infinity();
  for (std::size_t p = 0; p + 1 < scene.polylines.size(); ++p) {
    const auto& left = scene.polylines[p];
    const auto& right = scene.polylines[p + 1];
    if (left.type != ObjectType::LaneBoundary || right.type != ObjectType::LaneBoundary ||
        left.vectors.size() != right.vectors.size() || left.vectors.empty()) {
      continue;
    }
    Polyline centre;
    for (std::size_t v = 0; v < left.vectors.size(); ++v) {
      centre.emplace_back(0.5 * (left.vectors[v][0] + right.vectors[v][0]), 0.5 * (left.vectors[v][1] + right.vectors[v][1]));
    }
    centre.emplace_back(0.5 * (left.vectors.back()[2] + right.vectors.back()[2]),
                        0.5 * (left.vectors.back()[3] + right.vectors.back()[3]));
    const double distance = std::abs(MeasuredPolyline(centre).project(ego).lateralOffset);
    if (distance < best_distance) {
      best_distance = distance;
      best = std::move(centre);
    }
    ++p;  // boundaries come in (left, right) pairs
  }
  return best;
}

std::vector<Polyline> laneBoundaryLines(const VectorizedScene& scene) {
  std::vector<Polyline> lines;
  for (const auto& polyline : scene.polylines) {
    if (polyline.type != ObjectType::LaneBoundary) continue;
    Polyline line;
    for (std::size_t v = 0; v < polyline.vectors.size(); ++v) {
      if (!polyline.valid[v]) continue;
      const auto& f = polyline.vectors[v];
      const Vec2 start(f[0], f[1]);
      if (!line.empty() && (line.back() - start).norm() > 1e-6) {  // a break: a new line
        lines.push_back(std::move(line));
        line.clear();
      }
      if (line.empty()) line.push_back(start);
      line.emplace_back(f[2], f[3]);
    }
    if (line.size() >= 2) lines.push_back(std::move(line));
  }
  return lines;
}

}  // namespace vsd::vector
