#pragma once
// Ego controllers: what drives the vehicle under test.
//
// A controller sees an Observation built from SUMO's state (lane geometry,
// leader), the Ego's own kinematic state and - for controllers that ask for it
// (observesObjects) - the object list of the road users its sensors cover, and
// returns a Command with a longitudinal part (acceleration) and a lateral part
// (path curvature). The
// kinematic vehicle model (vehicle_model.hpp) applies the command; the new pose
// is then pushed into SUMO with moveToXY so that SUMO sees the Ego where the
// controller put it.
//
// Controllers are selected by name from the scenario YAML through a
// ControllerRegistry; unknown names fail with the list of available ones.

#include <array>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "vsd/core/defaults.hpp"
#include "vsd/core/road_user.hpp"
#include "vsd/core/trace.hpp"
#include "vsd/sim/controller_abi.h"
#include "vsd/sim/object_list.hpp"

namespace vsd::sim {

constexpr int kPreviewPoints = VSD_PREVIEW_POINTS;

/// What the Ego's controller sees at one instant. Scenario frame, SI units.
struct Observation {
  double time = 0.0;       ///< s since the scenario started
  VehicleState ego;        ///< own state (centre of the vehicle)
  double egoLength = kCarLength;  ///< m
  double egoWidth = kCarWidth;    ///< m

  struct Lane {
    double lateralOffset = 0.0;  ///< m, Ego centre relative to the lane centre, > 0 left
    double headingError = 0.0;   ///< rad, Ego heading minus lane direction, (-pi, pi]
    double width = kDefaultLaneWidth;  ///< m
    double previewSpacing = 4.0; ///< m between preview points
    /// Lane centre at previewSpacing * (i + 1) m ahead along the lane, in the Ego frame (x forward, y left).
    std::array<Vec2, kPreviewPoints> preview{};
  };
  std::optional<Lane> lane;  ///< absent when the Ego is off the road

  struct Leader {
    double gap = 0.0;    ///< m, bumper to bumper along the lane
    double speed = 0.0;  ///< m/s along the lane (< 0: it drives against it, towards the Ego)
    double accel = 0.0;  ///< m/s^2 along the lane (the change of `speed`)
  };
  /// SUMO's leader (Vehicle::getLeader: the vehicle SUMO assigns to the Ego's lane ahead);
  /// absent when no vehicle is ahead within range.
  std::optional<Leader> leader;

  /// The object list (ObjectSensor's coverage, in the scenario's order of road users);
  /// filled only for a controller that observesObjects().
  std::vector<ObservedObject> objects;
  /// m/s: the set speed the scenario commands the driver (its latest set_speed action, e.g.
  /// an imported OpenSCENARIO speed action on the Ego); absent until the first. Controllers
  /// that followsSetSpeed() take it in place of their own from then on.
  std::optional<double> commandedSetSpeed;
};

/// A road user of the object list as the lead of a car-following law: the bumper gap and
/// its speed along the Ego's lane, its acceleration.
Observation::Leader leaderOf(const ObservedObject& object);

struct Command {
  double accel = 0.0;      ///< m/s^2, longitudinal
  double curvature = 0.0;  ///< 1/m, > 0 turns left
};

/// Named numeric parameters from the scenario YAML (already evaluated for one
/// concrete scenario). Reading a parameter validates its range; afterwards
/// rejectUnknown() fails on names the controller does not know (typos).
class ControllerParams {
 public:
  ControllerParams(std::vector<std::pair<std::string, double>> values, std::string where);

  /// The value of `name`, or `fallback` if absent. Throws ConfigError naming
  /// the parameter, its value and [min, max] if out of range.
  double get(const std::string& name, double fallback, double min, double max) const;
  /// Like get() but absent parameters stay absent.
  std::optional<double> find(const std::string& name, double min, double max) const;
  /// Throws ConfigError for any parameter never asked for, listing the known ones.
  void rejectUnknown(const std::string& controller_name) const;

  const std::vector<std::pair<std::string, double>>& values() const { return values_; }
  /// What the parameters belong to (a scenario file's line and field), as messages name it.
  const std::string& where() const { return where_; }

 private:
  std::vector<std::pair<std::string, double>> values_;
  std::string where_;
  mutable std::vector<std::string> known_;
};

class EgoController {
 public:
  virtual ~EgoController() = default;
  /// Reads parameters (called once per concrete scenario, before reset()).
  virtual void init(const ControllerParams& params) = 0;
  /// Forgets all state from a previous scenario.
  virtual void reset() = 0;
  /// Decides the command for the next `dt` seconds. Throws vsd::Error to fail the scenario.
  virtual Command step(const Observation& observation, double dt) = 0;
  /// True if step() reads Observation::objects: the Ego's driver builds the object list
  /// only then (after init(), so a parameter may decide it).
  virtual bool observesObjects() const { return false; }
  /// True if step() follows Observation::commandedSetSpeed (the scenario's set_speed actions).
  virtual bool followsSetSpeed() const { return false; }
};

/// A setting of a scenario that only a controller observing a version of the observation
/// (controller_abi.h) of at least `abiVersion` can honour - e.g. the Ego's sensor, which a
/// version-1 controller never sees.
struct ControllerNeeds {
  int abiVersion = VSD_CONTROLLER_ABI_MIN_VERSION;  ///< the lowest version that honours the setting
  std::string where;  ///< file (and line) of the setting
  std::string field;  ///< the setting's key, e.g. "ego.sensor"
  std::string value;  ///< the setting as written
  /// The scenario commands the Ego's set speed (set_speed actions): only a controller that
  /// followsSetSpeed() honours it.
  bool setSpeed = false;
};

/// Registry of controllers by name. Built-ins are added by withBuiltins();
/// loadLibrary() adds the controllers a plugin exports.
class ControllerRegistry {
 public:
  using Factory = std::function<std::unique_ptr<EgoController>()>;

  /// A registry holding the built-in controllers (src/sim/controllers/registry.cpp lists them).
  static ControllerRegistry withBuiltins();

  /// `abi_version`: the newest version of the observation the controller reads (built-ins
  /// see the whole Observation: VSD_CONTROLLER_ABI_VERSION).
  void add(const std::string& name, const std::string& description, Factory factory,
           int abi_version = VSD_CONTROLLER_ABI_VERSION);
  /// Throws ConfigError naming `name` and listing every available controller.
  /// `where`: what named it (a scenario file's line and field), put before the message of an
  /// unknown name.
  std::unique_ptr<EgoController> create(const std::string& name, const std::string& where = "") const;
  bool contains(const std::string& name) const { return entries_.count(name) > 0; }
  /// name -> description
  std::map<std::string, std::string> available() const;
  /// The version of the observation `name` reads (it must be registered).
  int abiVersion(const std::string& name) const;
  /// Throws ConfigError (one line: where, field, value, what is allowed) if `name` reads an
  /// older observation than `needs` asks for, or does not follow a set speed it commands.
  void require(const std::string& name, const ControllerNeeds& needs) const;

  /// dlopen()s a plugin (see controller_abi.h) and registers its controllers.
  /// Throws ConfigError for a missing file, a library that cannot be loaded, a
  /// missing entry point, an ABI version mismatch or a duplicate name.
  void loadLibrary(const std::filesystem::path& library);

 private:
  struct Entry {
    std::string description;
    Factory factory;
    int abiVersion = VSD_CONTROLLER_ABI_VERSION;
  };
  std::map<std::string, Entry> entries_;
};

/// Creates and initialises the controller a scenario asks for, loading its
/// library first if one is named (relative to `scenario_dir`). Throws ConfigError if the
/// controller reads an older observation than `needs` asks for (ControllerRegistry::require).
std::unique_ptr<EgoController> makeController(ControllerRegistry& registry, const std::string& name,
                                              const std::filesystem::path& library,
                                              const std::filesystem::path& scenario_dir,
                                              const ControllerParams& params, const ControllerNeeds& needs = {});

/// Wraps a controller so that each of its steps takes `seconds` more wall time (it
/// sleeps, then returns the wrapped controller's command): a stand-in for a slow Ego
/// stack when measuring what the tools around it cost (`--ego-step-cost-ms`).
/// seconds <= 0: the controller itself.
std::unique_ptr<EgoController> withStepCost(std::unique_ptr<EgoController> controller, double seconds);

/// The C view of an Observation for a controller of ABI version `abi_version`: from
/// version 2 on, `objects` receives the object list and the view points into it.
vsd_observation toAbi(const Observation& observation, int abi_version, std::vector<vsd_object>& objects);

}  // namespace vsd::sim
