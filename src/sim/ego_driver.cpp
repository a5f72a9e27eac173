#include "vsd/sim/ego_driver.hpp"

#include <libsumo/libsumo.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>

#include "vsd/sim/activity.hpp"
#include "vsd/sim/builtin_controllers.hpp"
#include "vsd/core/error.hpp"

namespace vsd::sim {

const LaneCache::Entry& LaneCache::get(const std::string& lane_id, const Vec2& offset) {
  auto it = entries_.find(lane_id);
  if (it == entries_.end()) {
    LaneGeometry lane = fetchLane(lane_id, offset);
    it = entries_.emplace(lane_id, Entry{MeasuredPolyline(std::move(lane.centre)), lane.width}).first;
  }
  return it->second;
}

void LaneCache::put(const LaneGeometry& lane) {
  entries_.insert_or_assign(lane.id, Entry{MeasuredPolyline(lane.centre), lane.width});
}

const MeasuredPolyline& LaneCache::centre(const std::string& lane_id, const Vec2& offset) {
  return get(lane_id, offset).centre;
}

double LaneCache::width(const std::string& lane_id, const Vec2& offset) { return get(lane_id, offset).width; }

EgoDriver::EgoDriver(std::string vehicle_id, std::unique_ptr<EgoController> controller, const VehicleState& initial,
                     double length, double width, const Vec2& offset, VehicleLimits limits)
    : vehicleId_(std::move(vehicle_id)),
      state_(initial),
      length_(length),
      width_(width),
      offset_(offset),
      limits_(limits) {
  controllers_.push_back(std::move(controller));
  drivers_ = {controllers_.front().get(), controllers_.front().get()};
  minGap_ = libsumo::Vehicle::getMinGap(vehicleId_);
}

std::size_t EgoDriver::addController(std::unique_ptr<EgoController> controller) {
  controllers_.push_back(std::move(controller));  // the driving one stays: it does not move in memory
  return controllers_.size() - 1;
}

void EgoDriver::useController(std::size_t slot, double time, ControlDomains domains) {
  EgoController* next = controllers_.at(slot).get();
  if (next != drivers_[0] && next != drivers_[1]) next->reset();
  for (const std::size_t domain : {std::size_t{0}, std::size_t{1}}) {
    if (!drives(domains, domain == 0 ? ControlDomains::Longitudinal : ControlDomains::Lateral)) continue;
    drivers_[domain] = next;
    activeFrom_[domain] = std::min(activeFrom_[domain], time);
  }
}

SumoPlacement::SumoPlacement(const std::vector<LaneGeometry>& lanes) {
  narrowest_ = std::numeric_limits<double>::infinity();
  for (const auto& lane : lanes) {
    lanes_.emplace_back(lane.centre);
    narrowest_ = std::min(narrowest_, lane.width);
  }
}

int SumoPlacement::keepRoute(const Vec2& front, double width) const {
  // SUMO keeps a vehicle on its lane while |lateral offset| < (lane width + vehicle width) / 2,
  // measured from the nearest lane's shape; 1 cm covers the rounding of the frame shift.
  constexpr double kMargin = 0.01;
  const auto inside = [&](std::size_t lane) {
    return std::abs(lanes_[lane].project(front).lateralOffset) < 0.5 * (narrowest_ + width) - kMargin;
  };
  // Any lane will do: the one that held the last vehicle placed is asked first (a vehicle
  // mostly stays in its lane from step to step), then the others in order.
  if (lastInside_ < lanes_.size() && inside(lastInside_)) return 1;
  for (std::size_t lane = 0; lane < lanes_.size(); ++lane) {
    if (lane == lastInside_ || !inside(lane)) continue;
    lastInside_ = lane;
    return 1;
  }
  return 3;
}

bool sumoIgnoresLateralPositions() {
  const auto option = [](const char* name) { return libsumo::Simulation::getOption(name); };
  try {
    return std::stod(option("lateral-resolution")) <= 0.0 && option("fcd-output").empty() &&
           option("collision.check-junctions") == "false";
  } catch (const std::exception&) {
    return false;  // an option SUMO does not report as expected: place exactly
  }
}

namespace {

/// The point SUMO positions a vehicle by (frame net - offset): its front bumper, against the road its rear one.
Vec2 sumoFront(const VehicleState& state, double length, bool against_road) {
  const double ahead = against_road ? -0.5 * length : 0.5 * length;
  return state.position() + ahead * headingVector(state.heading);
}

/// The lane (of `lanes`) nearest to `front` and SUMO's position along it; with `only_if_beyond`, only if a vehicle
/// `width` m wide there lies beyond every lane as SUMO counts it: |lateral offset| >= (lane width + vehicle width)
/// / 2 (SUMO 1.15, sublane model or not). 1 cm sooner: a vehicle so near the edge is put on the lane first too,
/// which changes nothing, while one SUMO finds beyond it by the rounding of the frame shift would crash its FCD
/// output.
std::optional<std::pair<std::string, double>> nearestLane(const Vec2& front, double width,
                                                          const std::vector<LaneGeometry>& lanes,
                                                          bool only_if_beyond) {
  constexpr double kMargin = 0.01;
  const LaneGeometry* nearest = nullptr;
  PolylineProjection foot;
  double shape_length = 0.0;
  for (const auto& lane : lanes) {
    const MeasuredPolyline centre(lane.centre);
    const PolylineProjection projection = centre.project(front);
    const double across = std::abs(projection.lateralOffset);
    if (only_if_beyond && across < 0.5 * (lane.width + width) - kMargin) return std::nullopt;
    if (nearest != nullptr && across >= std::abs(foot.lateralOffset)) continue;
    nearest = &lane;
    foot = projection;
    shape_length = centre.length();
  }
  if (nearest == nullptr) return std::nullopt;
  // SUMO measures along its lane's length, which netconvert may make differ from the shape's.
  const double length = libsumo::Lane::getLength(nearest->id);
  const double along = shape_length > 0.0 ? foot.arcLength * length / shape_length : 0.0;
  return std::make_pair(nearest->id, std::clamp(along, 0.0, length));
}

}  // namespace

void placeInSumo(const std::string& vehicle_id, const VehicleState& state, double length, double width,
                 const Vec2& offset, const SumoPlacement& placement, bool against_road) {
  const Vec2 front = sumoFront(state, length, against_road);
  const Vec2 net_front = front + offset;
  libsumo::Vehicle::moveToXY(vehicle_id, "", -1, net_front.x(), net_front.y(), sumoAngleFromHeading(state.heading),
                             placement.keepRoute(front, width));
  libsumo::Vehicle::setSpeed(vehicle_id, state.speed);
}

void enterSumo(const std::string& vehicle_id, const VehicleState& state, double length, double width,
               const Vec2& offset, const SumoPlacement& placement, const std::vector<LaneGeometry>& lanes,
               bool against_road) {
  const auto lane = nearestLane(sumoFront(state, length, against_road), width, lanes, /*only_if_beyond=*/true);
  if (lane) libsumo::Vehicle::moveTo(vehicle_id, lane->first, lane->second);
  placeInSumo(vehicle_id, state, length, width, offset, placement, against_road);
}

Observation::Lane observeLane(const MeasuredPolyline& preview_line, const PolylineProjection& projection,
                              const VehicleState& state, double width, double shift) {
  Observation::Lane lane;
  lane.lateralOffset = projection.lateralOffset - shift;
  lane.headingError = wrapAngle(state.heading - projection.heading);
  lane.width = width;
  const double cos_h = std::cos(state.heading);
  const double sin_h = std::sin(state.heading);
  for (int i = 0; i < kPreviewPoints; ++i) {
    const double along = projection.arcLength + lane.previewSpacing * (i + 1);
    Vec2 point = preview_line.pointAt(along);
    if (shift != 0.0) point += shift * headingVector(preview_line.headingAt(along) + 0.5 * kPi);
    const Vec2 ahead = point - state.position();
    lane.preview[static_cast<std::size_t>(i)] = Vec2(cos_h * ahead.x() + sin_h * ahead.y(), -sin_h * ahead.x() + cos_h * ahead.y());
  }
  return lane;
}

void EgoDriver::pushToSumo() const { placeInSumo(vehicleId_, state_, length_, width_, offset_, placement_, false); }

void EgoDriver::enterSumo(const std::vector<LaneGeometry>& lanes) const {
  sim::enterSumo(vehicleId_, state_, length_, width_, offset_, placement_, lanes, false);
}

void EgoDriver::teleport(const VehicleState& placed, const std::vector<LaneGeometry>& lanes) {
  state_.x = placed.x;
  state_.y = placed.y;
  state_.heading = placed.heading;
  // moveToXY takes effect with SUMO's next step, moveTo at once: the lane the observation reads
  // (getLaneID) is already the one it landed on.
  const auto lane = nearestLane(sumoFront(state_, length_, false), width_, lanes, /*only_if_beyond=*/false);
  if (lane) libsumo::Vehicle::moveTo(vehicleId_, lane->first, lane->second);
  pushToSumo();
}

void EgoDriver::knowAgainstRoad(std::vector<std::string> vehicle_ids) {
  againstRoad_ = std::move(vehicle_ids);
  std::sort(againstRoad_.begin(), againstRoad_.end());
}

Observation EgoDriver::observe(double time, LaneCache& lanes, const std::vector<RoadUserState>& road_users) const {
  Observation observation;
  observation.commandedSetSpeed = commandedSetSpeed_;
  observation.time = time;
  observation.ego = state_;
  observation.egoLength = length_;
  observation.egoWidth = width_;

  const std::string lane_id = libsumo::Vehicle::getLaneID(vehicleId_);
  const MeasuredPolyline* centre_ptr = nullptr;
  MeasuredPolyline extended;
  if (!lane_id.empty()) {
    centre_ptr = &lanes.centre(lane_id, offset_);
    auto projection = centre_ptr->project(state_.position());
    // Near the end of the lane the preview continues along the route (through the
    // junction's internal lane); on a single long road this never happens.
    const double preview_end = projection.arcLength + Observation::Lane{}.previewSpacing * kPreviewPoints;
    if (preview_end > centre_ptr->length()) {
      extended = routeAhead(lane_id, lanes, preview_end);
      centre_ptr = &extended;
    }
    observation.lane =
        observeLane(*centre_ptr, projection, state_, lanes.width(lane_id, offset_), keptLaneShift(lane_id));
  }

  const auto [leader_id, distance] = libsumo::Vehicle::getLeader(vehicleId_, kLeaderRange);
  if (!leader_id.empty()) {
    Observation::Leader leader;
    leader.gap = distance + minGap_;  // getLeader() measures from the Ego's front + minGap
    leader.speed = libsumo::Vehicle::getSpeed(leader_id);
    leader.accel = libsumo::Vehicle::getAcceleration(leader_id);
    if (std::binary_search(againstRoad_.begin(), againstRoad_.end(), leader_id)) {
      leader.speed = -leader.speed;  // SUMO's magnitude, towards the Ego
      leader.accel = -leader.accel;
    }
    observation.leader = leader;
  }
  if ((drivers_[0]->observesObjects() || drivers_[1]->observesObjects()) && !road_users.empty()) {
    const Footprint ego{state_.position(), state_.heading, length_, width_};
    if (observation.lane) {
      observation.objects = observeObjects(*centre_ptr, observation.lane->width, ego, road_users, sensor_);
    } else {
      // Off the road the reference line is the Ego's own heading and "lanes" are as wide as the Ego.
      const Vec2 along = headingVector(state_.heading);
      const MeasuredPolyline heading_line(Polyline{state_.position() - along, state_.position() + along});
      observation.objects = observeObjects(heading_line, width_, ego, road_users, sensor_);
    }
  }
  return observation;
}

double EgoDriver::keptLaneShift(const std::string& lane_id) const {
  if (!commandedLaneOffset_) return 0.0;
  // SUMO names a lane <edge>_<index>; the index counts the road's lanes from the right.
  const auto separator = lane_id.rfind('_');
  std::size_t index = 0;
  const char* first = lane_id.data() + separator + 1;
  const char* last = lane_id.data() + lane_id.size();
  if (separator == std::string::npos || lane_id.compare(0, separator, roadEdge_) != 0 ||
      std::from_chars(first, last, index).ptr != last || index >= laneOffsets_.size()) {
    return 0.0;  // a lane off the scenario's road (a junction's): the Ego keeps it
  }
  return *commandedLaneOffset_ - laneOffsets_[index];
}

MeasuredPolyline EgoDriver::routeAhead(const std::string& lane_id, LaneCache& lanes, double length) const {
  Polyline path = lanes.centre(lane_id, offset_).points();
  std::vector<std::string> continuation;
  for (const auto& best : libsumo::Vehicle::getBestLanes(vehicleId_)) {
    if (best.laneID == lane_id) continuation = best.continuationLanes;
  }
  std::string previous = lane_id;
  auto append = [&](const std::string& id) {
    const Polyline& points = lanes.centre(id, offset_).points();
    const bool joined = !path.empty() && (points.front() - path.back()).norm() < 1e-6;
    path.insert(path.end(), points.begin() + (joined ? 1 : 0), points.end());
  };
  for (const auto& next : continuation) {
    if (next == previous || next.empty()) continue;
    for (const auto& link : libsumo::Lane::getLinks(previous)) {
      if (link.approachedLane == next && !link.approachedInternal.empty()) append(link.approachedInternal);
    }
    append(next);
    previous = next;
    if (polylineLength(path) >= length) break;
  }
  return MeasuredPolyline(std::move(path));
}

void EgoDriver::step(double time, double dt, double heading_noise, LaneCache& lanes,
                     const std::vector<RoadUserState>& road_users) {
  const Observation observation = observe(time, lanes, road_users);
  // Per domain, its controller once activated; before, the Ego's default: constant speed, and
  // lane keeping by pure pursuit.
  EgoController* longitudinal = time + 1e-9 < activeFrom_[0] ? nullptr : drivers_[0];
  EgoController* lateral = time + 1e-9 < activeFrom_[1] ? nullptr : drivers_[1];
  Command command;
  if (!longitudinal && !lateral) {
    command.accel = 0.0;
    command.curvature = PurePursuitLateral().curvature(observation);
  } else if (longitudinal == lateral) {
    const ActivityScope in_controller(Activity::Controller);
    command = longitudinal->step(observation, dt);
  } else {
    const ActivityScope in_controller(Activity::Controller);
    command.accel = longitudinal ? longitudinal->step(observation, dt).accel : 0.0;
    command.curvature =
        lateral ? lateral->step(observation, dt).curvature : PurePursuitLateral().curvature(observation);
  }
  if (!std::isfinite(command.accel) || !std::isfinite(command.curvature)) {
    throw Error("controller returned a non-finite command");
  }
  state_ = advanceKinematic(state_, command, dt, heading_noise, limits_);
  pushToSumo();
}

}  // namespace vsd::sim
