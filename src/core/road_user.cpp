#include "vsd/core/road_user.hpp"

namespace vsd {

const std::vector<RoadUserKind>& roadUserKinds() {
  // Car: the paper's Ego and Co (5.0 x 1.8 m). Truck and bus: the EU's 2.55 m maximum width
  // (Directive 96/53/EC) and a 12 m rigid vehicle. Pedestrian: 0.5 m deep along the walking
  // direction, 0.7 m across the shoulders and swinging arms. Bicycle: an adult's bicycle with
  // its rider, 1.8 m long and 0.65 m across the handlebars; it rides in lanes.
  static const std::vector<RoadUserKind> kinds = {
      {RoadUserType::Car, "car", "passenger car", kCarLength, kCarWidth, true, false, "passenger"},
      {RoadUserType::Van, "van", "light commercial vehicle", 5.5, 2.0, true, false, "delivery"},
      {RoadUserType::Truck, "truck", "heavy goods vehicle", 12.0, 2.55, true, false, "truck"},
      {RoadUserType::Bus, "bus", "bus or coach", 12.0, 2.55, true, false, "bus"},
      {RoadUserType::Motorbike, "motorbike", "powered two-wheeler", 2.2, 0.8, true, false, "motorcycle"},
      {RoadUserType::Pedestrian, "pedestrian", "person on foot", 0.5, 0.7, false, false, "pedestrian"},
      {RoadUserType::StationaryObject, "stationary_object", "object that never moves (debris, a barrier)", 1.0, 1.0,
       false, true, "ignoring"},
      {RoadUserType::Bicycle, "bicycle", "pedal cycle with its rider", 1.8, 0.65, true, false, "bicycle"},
  };
  return kinds;
}

const RoadUserKind& roadUserKind(RoadUserType type) { return roadUserKinds().at(static_cast<std::size_t>(type)); }

std::optional<RoadUserType> findRoadUserType(const std::string& name) {
  for (const auto& kind : roadUserKinds()) {
    if (name == kind.name) return kind.type;
  }
  return std::nullopt;
}

std::string roadUserTypeList() {
  std::string list;
  for (const auto& kind : roadUserKinds()) list += (list.empty() ? "" : ", ") + std::string(kind.name);
  return list;
}

}  // namespace vsd
