#include "vsd/sim/controller.hpp"

#include <dlfcn.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "vsd/sim/activity.hpp"
#include "vsd/core/error.hpp"

namespace fs = std::filesystem;

namespace vsd::sim {

// --- parameters ------------------------------------------------------------------------

ControllerParams::ControllerParams(std::vector<std::pair<std::string, double>> values, std::string where)
    : values_(std::move(values)), where_(std::move(where)) {}

std::optional<double> ControllerParams::find(const std::string& name, double min, double max) const {
  if (std::find(known_.begin(), known_.end(), name) == known_.end()) known_.push_back(name);
  for (const auto& [key, value] : values_) {
    if (key != name) continue;
    if (!(value >= min && value <= max)) {
      throw ConfigError(fmt::format("{}: params.{}: got {}, expected a value in [{}, {}]", where_, name, value, min, max));
    }
    return value;
  }
  return std::nullopt;
}

double ControllerParams::get(const std::string& name, double fallback, double min, double max) const {
  return find(name, min, max).value_or(fallback);
}

void ControllerParams::rejectUnknown(const std::string& controller_name) const {
  for (const auto& [key, value] : values_) {
    if (std::find(known_.begin(), known_.end(), key) == known_.end()) {
      throw ConfigError(fmt::format("{}: params.{}: unknown parameter of controller '{}' (it knows: {})", where_, key,
                                    controller_name, fmt::join(known_, ", ")));
    }
  }
}

// --- registry --------------------------------------------------------------------------

void ControllerRegistry::add(const std::string& name, const std::string& description, Factory factory,
                             int abi_version) {
  if (!entries_.emplace(name, Entry{description, std::move(factory), abi_version}).second) {
    throw ConfigError(fmt::format("controller '{}' is registered twice", name));
  }
}

int ControllerRegistry::abiVersion(const std::string& name) const { return entries_.at(name).abiVersion; }

void ControllerRegistry::require(const std::string& name, const ControllerNeeds& needs) const {
  const auto it = entries_.find(name);
  if (it == entries_.end()) return;  // unknown: create() says so
  // An instance says whether it follows a set speed (only asked when a scenario commands one).
  if (needs.setSpeed && !it->second.factory()->followsSetSpeed()) {
    std::vector<std::string> allowed;
    for (const auto& [known, entry] : entries_) {
      if (entry.factory()->followsSetSpeed()) allowed.push_back(known);
    }
    throw ConfigError(fmt::format("{}: {}: {}: controller '{}' takes no set speed (allowed: {})", needs.where,
                                  needs.field, needs.value, name, fmt::join(allowed, ", ")));
  }
  if (it->second.abiVersion >= needs.abiVersion) return;
  std::vector<std::string> allowed;
  for (const auto& [known, entry] : entries_) {
    if (entry.abiVersion >= needs.abiVersion) allowed.push_back(known);
  }
  throw ConfigError(fmt::format(
      "{}: {}: {}: controller '{}' reads version {} of the observation, the setting needs version {} or later "
      "(allowed: {}, or a plugin declaring abi_version {})",
      needs.where, needs.field, needs.value, name, it->second.abiVersion, needs.abiVersion, fmt::join(allowed, ", "),
      needs.abiVersion));
}

std::map<std::string, std::string> ControllerRegistry::available() const {
  std::map<std::string, std::string> result;
  for (const auto& [name, entry] : entries_) result.emplace(name, entry.description);
  return result;
}

std::unique_ptr<EgoController> ControllerRegistry::create(const std::string& name, const std::string& where) const {
  const auto it = entries_.find(name);
  if (it == entries_.end()) {
    std::vector<std::string> names;
    for (const auto& [known, entry] : entries_) names.push_back(known);
    throw ConfigError(fmt::format("{}unknown controller '{}' (available: {})", where.empty() ? "" : where + ": ", name,
                                  fmt::join(names, ", ")));
  }
  return it->second.factory();
}

namespace {

/// Keeps a plugin loaded for as long as any of its controllers lives.
class LibraryHandle {
 public:
  explicit LibraryHandle(void* handle) : handle_(handle) {}
  LibraryHandle(const LibraryHandle&) = delete;
  LibraryHandle& operator=(const LibraryHandle&) = delete;
  ~LibraryHandle() {
    if (handle_ != nullptr) ::dlclose(handle_);
  }
  void* get() const { return handle_; }

 private:
  void* handle_;
};

/// Adapts a plugin controller (C ABI) to EgoController.
class PluginController final : public EgoController {
 public:
  PluginController(std::shared_ptr<LibraryHandle> library, const vsd_controller_api* api)
      : library_(std::move(library)), api_(api) {}

  bool observesObjects() const override { return api_->abi_version >= 2; }
  PluginController(const PluginController&) = delete;
  PluginController& operator=(const PluginController&) = delete;
  ~PluginController() override { destroy(); }

  void init(const ControllerParams& params) override {
    destroy();
    std::vector<const char*> names;
    std::vector<double> values;
    for (const auto& [name, value] : params.values()) {
      names.push_back(name.c_str());
      values.push_back(value);
    }
    std::array<char, 512> error{};
    instance_ = api_->create(names.data(), values.data(), static_cast<int>(names.size()), error.data(),
                             static_cast<int>(error.size()));
    if (instance_ == nullptr) {
      error.back() = '\0';
      throw ConfigError(fmt::format("controller '{}' rejected its parameters: {}", api_->name,
                                    error[0] != '\0' ? error.data() : "(no reason given)"));
    }
  }

  void reset() override {
    if (instance_ != nullptr && api_->reset != nullptr) api_->reset(instance_);
  }

  Command step(const Observation& observation, double dt) override {
    const vsd_observation abi = toAbi(observation, api_->abi_version, objects_);
    vsd_command command{0.0, 0.0};
    const int status = api_->step(instance_, &abi, dt, &command);
    if (status != 0) throw Error(fmt::format("controller '{}' step failed with status {}", api_->name, status));
    if (!std::isfinite(command.accel) || !std::isfinite(command.curvature)) {
      throw Error(fmt::format("controller '{}' returned a non-finite command", api_->name));
    }
    return {command.accel, command.curvature};
  }

 private:
  void destroy() {
    const ActivityScope in_controller(Activity::Controller);
    if (instance_ != nullptr && api_->destroy != nullptr) api_->destroy(instance_);
    instance_ = nullptr;
  }

  std::shared_ptr<LibraryHandle> library_;
  const vsd_controller_api* api_;
  vsd_controller* instance_ = nullptr;
  std::vector<vsd_object> objects_;  ///< the object list's C view, kept between steps to reuse its memory
};

}  // namespace

void ControllerRegistry::loadLibrary(const fs::path& library) {
  if (!fs::exists(library)) {
    throw ConfigError(fmt::format("controller library '{}' does not exist", library.string()));
  }
  ::dlerror();
  void* raw = ::dlopen(fs::absolute(library).c_str(), RTLD_NOW | RTLD_LOCAL);
  if (raw == nullptr) {
    const char* reason = ::dlerror();
    throw ConfigError(fmt::format("controller library '{}' cannot be loaded: {}", library.string(),
                                  reason != nullptr ? reason : "unknown reason"));
  }
  auto handle = std::make_shared<LibraryHandle>(raw);
  auto* entry = reinterpret_cast<vsd_controller_entry_fn>(::dlsym(raw, "vsd_controller_entry"));
  if (entry == nullptr) {
    throw ConfigError(fmt::format(
        "controller library '{}' does not export vsd_controller_entry (expected a plugin built against "
        "include/vsd/sim/controller_abi.h)",
        library.string()));
  }
  int count = 0;
  for (int index = 0;; ++index) {
    const vsd_controller_api* api = entry(index);
    if (api == nullptr) break;
    if (api->abi_version < VSD_CONTROLLER_ABI_MIN_VERSION || api->abi_version > VSD_CONTROLLER_ABI_VERSION) {
      throw ConfigError(fmt::format("controller library '{}': controller #{} has ABI version {}, expected {} to {}",
                                    library.string(), index, api->abi_version, VSD_CONTROLLER_ABI_MIN_VERSION,
                                    VSD_CONTROLLER_ABI_VERSION));
    }
    if (api->name == nullptr || api->create == nullptr || api->step == nullptr) {
      throw ConfigError(fmt::format("controller library '{}': controller #{} lacks a name, create() or step()",
                                    library.string(), index));
    }
    if (contains(api->name)) continue;  // the same library loaded twice: keep the first registration
    add(api->name, api->description != nullptr ? api->description : "",
        [handle, api] { return std::make_unique<PluginController>(handle, api); }, api->abi_version);
    ++count;
    if (index > 1000) break;
  }
  if (count == 0 && entry(0) == nullptr) {
    throw ConfigError(fmt::format("controller library '{}' exports no controllers", library.string()));
  }
}

std::unique_ptr<EgoController> makeController(ControllerRegistry& registry, const std::string& name,
                                              const fs::path& library, const fs::path& scenario_dir,
                                              const ControllerParams& params, const ControllerNeeds& needs) {
  // Loading a plugin, creating and resetting its controller all run its code.
  const ActivityScope in_controller(Activity::Controller);
  if (!library.empty() && !registry.contains(name)) {
    registry.loadLibrary(library.is_absolute() ? library : scenario_dir / library);
  }
  registry.require(name, needs);
  auto controller = registry.create(name, params.where());
  controller->init(params);
  controller->reset();
  return controller;
}

Observation::Leader leaderOf(const ObservedObject& object) {
  return {object.relation.longitudinalGap, object.longitudinalSpeed(), object.state.accel};
}

namespace {

static_assert(VSD_OBJECT_CAR == static_cast<int>(RoadUserType::Car) &&
                  VSD_OBJECT_PEDESTRIAN == static_cast<int>(RoadUserType::Pedestrian) &&
                  VSD_OBJECT_STATIONARY == static_cast<int>(RoadUserType::StationaryObject) &&
                  VSD_OBJECT_BICYCLE == static_cast<int>(RoadUserType::Bicycle),
              "controller_abi.h's object kinds follow RoadUserType");

vsd_object toAbi(const ObservedObject& object) {
  vsd_object abi{};
  abi.id = object.id;
  abi.type = static_cast<int>(object.type);
  abi.x = object.state.x;
  abi.y = object.state.y;
  abi.heading = object.state.heading;
  abi.speed = object.state.speed;
  abi.accel = object.state.accel;
  abi.length = object.length;
  abi.width = object.width;
  const PathRelation& relation = object.relation;
  abi.longitudinal_distance = relation.longitudinalDistance;
  abi.longitudinal_gap = relation.longitudinalGap;
  abi.lateral_distance = relation.lateralDistance;
  abi.lateral_gap = relation.lateralGap;
  abi.lane_offset = relation.objectOffset;
  abi.relative_heading = relation.relativeHeading;
  abi.relative_lane = relation.relativeLane;
  abi.in_path = relation.inPath ? 1 : 0;
  return abi;
}

}  // namespace

vsd_observation toAbi(const Observation& observation, int abi_version, std::vector<vsd_object>& objects) {
  vsd_observation abi{};
  abi.time = observation.time;
  abi.x = observation.ego.x;
  abi.y = observation.ego.y;
  abi.heading = observation.ego.heading;
  abi.speed = observation.ego.speed;
  abi.accel = observation.ego.accel;
  abi.length = observation.egoLength;
  abi.width = observation.egoWidth;
  if (observation.lane) {
    abi.has_lane = 1;
    abi.lane_lateral_offset = observation.lane->lateralOffset;
    abi.lane_heading_error = observation.lane->headingError;
    abi.lane_width = observation.lane->width;
    abi.preview_spacing = observation.lane->previewSpacing;
    for (int i = 0; i < kPreviewPoints; ++i) {
      abi.preview_x[i] = observation.lane->preview[static_cast<std::size_t>(i)].x();
      abi.preview_y[i] = observation.lane->preview[static_cast<std::size_t>(i)].y();
    }
  }
  if (observation.leader) {
    abi.has_leader = 1;
    abi.leader_gap = observation.leader->gap;
    abi.leader_speed = observation.leader->speed;
    abi.leader_accel = observation.leader->accel;
  }
  objects.clear();
  if (abi_version >= 2) {
    for (const auto& object : observation.objects) objects.push_back(toAbi(object));
    abi.object_count = static_cast<int>(objects.size());
    abi.objects = objects.empty() ? nullptr : objects.data();
  }
  return abi;
}

}  // namespace vsd::sim
