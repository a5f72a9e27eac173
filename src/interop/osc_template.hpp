#pragma once
// An OpenSCENARIO scenario translated into the scenario language (private to the
// interop module; docs/openscenario-import.md). The translation is YAML text in the
// language (`vsd-scenario/1`), which the language's own reader then loads and checks:
// an imported scenario is sampled, simulated, vectorised and predicted exactly like a
// YAML one, and `scenario check --yaml` shows what a file became.
//
// Every number is resolved at import (parameters are constants of one concrete
// scenario; a ParameterValueDistribution imports the template once per parameter set),
// so relative positions and references become absolute ones in the language.

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "osc_catalogs.hpp"
#include "osc_findings.hpp"
#include "osc_parameters.hpp"
#include "osc_road.hpp"
#include "vsd/core/road_user.hpp"
#include "vsd/interop/openscenario_import.hpp"
#include "xml_support.hpp"

namespace vsd::interop::osc {

/// Where an entity's reference point is (reference-line coordinates of the road).
struct Placement {
  double s = 0.0;        ///< m along the reference line
  double t = 0.0;        ///< m across it, > 0 left
  double heading = 0.0;  ///< rad, relative to the road's direction
  int lane = 0;          ///< language lane (0 = rightmost driving lane)
};

/// A <Controller> element as defined: in the scenario file or a catalog entry.
struct ControllerDefinition {
  std::shared_ptr<const xml::Reader> catalog;  ///< the catalog entry's reader; null: the scenario file's
  const xml::Reader* reader = nullptr;         ///< the reader of `node`'s file
  pugi::xml_node node;
};

struct Entity {
  std::string name;  ///< as in the file
  std::string id;    ///< in the language ("ego" for the Ego)
  std::string where;
  RoadUserType type = RoadUserType::Car;
  double length = 0.0;
  double width = 0.0;
  double centreAhead = 0.0;  ///< m the bounding box centre lies ahead of the reference point
  std::optional<std::string> controller;  ///< the controller's name (ObjectController / AssignControllerAction)
  std::string controllerWhere;
  ControllerDefinition controllerDefinition;  ///< its ObjectController's <Controller>
  pugi::xml_node position;      ///< the Init's <Position>
  std::optional<Placement> placement;
  bool placing = false;         ///< cycle guard while resolving relative positions
  pugi::xml_node speedTarget;   ///< the Init's <SpeedActionTarget> (step)
  pugi::xml_node gradualSpeed;  ///< the Init's <SpeedAction> if it is not a step
  pugi::xml_node distanceAction;  ///< the Init's <LongitudinalDistanceAction>: a place relative to another
  std::optional<double> speed;  ///< m/s, initial
  bool speeding = false;
  YAML::Node actions = YAML::Node(YAML::NodeType::Sequence);
  bool movesLaterally = false;
  bool activatedAtStart = false;  ///< the Init activates its controller
  /// The domains the Init activates: "true" (both), "longitudinal" or "lateral".
  std::string initDomains = "true";

  bool isVehicle() const { return type != RoadUserType::Pedestrian && type != RoadUserType::StationaryObject; }
  /// A vehicle placed facing back along the road (within 0.01 deg of 180): it drives against
  /// it (`direction: against`). Once placed.
  bool drivesAgainstRoad() const {
    return isVehicle() && placement && std::abs(std::abs(placement->heading) - kPi) <= 0.01 * kPi / 180.0;
  }
};

/// The vsd-sumo controller that drives the Ego.
struct ControllerChoice {
  std::string name;
  YAML::Node params;  ///< null: its defaults
  std::filesystem::path library;  ///< a plugin's shared library (absolute); empty: a built-in

  /// The scenario language's controller node: name, params, library.
  YAML::Node languageNode() const;
};

/// The --controller-map file (read at the first lookup, once per translation) and the defaults.
class ControllerMap {
 public:
  explicit ControllerMap(const OscImportOptions& options) : file_(options.controllerMap) {}
  bool given() const { return !file_.empty(); }
  /// The vsd-sumo controller a file's controller name maps onto (the map file, then the
  /// defaults); throws ConfigError naming `where` for a name that maps nowhere, and the map file
  /// for an entry that names no built-in controller (or `script`) and no plugin library.
  ControllerChoice choice(const std::string& name, const std::string& where) const;

 private:
  std::filesystem::path file_;
  mutable std::optional<YAML::Node> map_;  ///< the file's map, once read
};

/// One file's translation in progress.
struct Translation {
  Translation(xml::Reader& r, Findings& f, const OscImportOptions& o)
      : reader(r), findings(f), options(o), controllerMap(o) {}

  xml::Reader& reader;
  Findings& findings;
  const OscImportOptions& options;
  ControllerMap controllerMap;
  CarriagewayRoad road;
  std::vector<Entity> entities;
  /// ScenarioObjects refused while they were read (check goes on): what names them says nothing more.
  std::set<std::string> refusedEntities;
  Entity* ego = nullptr;
  ControllerChoice controller;
  Catalogs* catalogs = nullptr;  ///< the file's catalogs (set while it is translated)
  /// Language action ids by the file's Action name (an Action with several actors has several).
  std::map<std::string, std::vector<std::string>> actionIds;
  /// The file's Events by name, for conditions on their state. A name given twice is kept
  /// without an actor (ambiguous).
  struct EventRecord {
    pugi::xml_node node;
    const Entity* actor = nullptr;        ///< its first actor; null: the name is not unique
    ParameterValues scope;                ///< the parameters its Story sees
    std::vector<std::string> actionIds;  ///< its actions' language ids
    int act = -1;                         ///< the Act it is in (index into acts)
  };
  std::map<std::string, EventRecord> events;
  /// The file's Acts, for their Events' starts and conditions on their state.
  struct ActRecord {
    std::string name;
    pugi::xml_node node;
    ParameterValues scope;            ///< the parameters its Story sees
    std::vector<std::string> events;  ///< its Events' names
  };
  std::vector<ActRecord> acts;
  std::map<std::string, int> actByName;  ///< index into acts; -1: a name given twice (names no one Act)
  std::map<std::string, std::string> eventOfAction;  ///< the file's Action name -> its Event's name
  int eventStartsFollowed = 0;  ///< nesting of Event and Act starts being translated (a cycle is refused)
  /// s: when the conditions being read are first checked: 0, or the start of the Act whose
  /// Event they start (esmini checks an Event's conditions only while its Act runs).
  double firstCheck = 0.0;
  /// The Act (index into acts) that starts later than t = 0 whose Event's conditions are being
  /// read; -1: none (or an Act that runs from t = 0).
  int laterAct = -1;
  std::set<std::string> usedIds = {"ego"};
  double duration = 0.0;  ///< s; 0: not known from the file
  /// s: the first ActivateControllerAction of the Ego in the Story (none: it drives from t = 0).
  std::optional<double> egoActiveFrom;
  /// The Story hands the Ego to another controller, or switches a domain off, somewhere.
  bool egoHandedOver = false;
  /// A condition measures between reference points: road users carry theirs (centreAhead).
  bool measuresReferencePoints = false;

  Entity& entity(const pugi::xml_node& node, const std::string& name);
  std::string where(const pugi::xml_node& node) const { return reader.where(node); }
};

/// A name as a language identifier (letters, digits, _; letter first), unique in `used`.
std::string identifier(const std::string& name, std::set<std::string>& used);

/// The controller map's word for a controller vsd-sumo does not simulate: its entity follows
/// its script (e.g. esmini's sloppyDriver, which adds deviations to a scripted vehicle).
inline constexpr const char* kFollowsItsScript = "script";
/// Appended to a refusal that `--network` would not meet (the road, a SUMO controller's traffic).
inline constexpr const char* kTryTheNetwork =
    " (`--network` simulates the file's Init on SUMO's network of its roads instead, where netconvert reads them)";
/// The built-in controller that keeps the Ego's speed and lane: the Ego following its script.
inline constexpr const char* kKeepsItsLane = "keep_lane";

// osc_entities.cpp
/// The name of the controller a <Controller> or controller <CatalogReference> under `parent`
/// gives; `where` is set to its place in the file and `definition` (if given) to its <Controller>.
std::string controllerName(Translation& translation, Catalogs& catalogs, const pugi::xml_node& parent,
                           std::string& where, ControllerDefinition* definition = nullptr);
void readEntities(Translation& translation, const pugi::xml_node& root, Catalogs& catalogs);
void readInit(Translation& translation, const pugi::xml_node& storyboard);
/// Resolves every entity's start (relative positions and speeds after their references).
void placeEntities(Translation& translation);
/// Where the Init's vehicles drive (LanePositions with their orientations): on the left side
/// only, all along the reference line or all against it (in right-hand traffic, the file
/// drives the left side as its carriageway, that way); anything else, or a vehicle placed by a
/// road or world position: Right.
enum class InitCarriageway { Right, LeftAlong, LeftAgainst };
InitCarriageway initCarriageway(const Translation& translation);
/// A place that does not move (WorldPosition, LanePosition, RoadPosition), for conditions and
/// teleports:
/// a position relative to a road user would move with it, which the language's places do not.
Placement fixedPlace(Translation& translation, const pugi::xml_node& position);

// osc_positions.cpp
/// Refuses a pitch `p` or roll `r` other than 0 on `node` (vsd-sumo is planar).
void requirePlanar(const xml::Reader& reader, const pugi::xml_node& node);
/// A position's <Orientation>: its heading (rad) and whether it is absolute (else relative).
struct OrientationElement {
  double h = 0.0;
  bool absolute = false;
};
/// The <Orientation> under `position` (pitch and roll 0), none without one.
std::optional<OrientationElement> readOrientation(const xml::Reader& reader, const pugi::xml_node& position);

// osc_template.cpp
/// The OpenSCENARIO file's root, header and global parameters (`assigned` replacing declared
/// values; their notes in `findings`); refuses another root, a header of another major revision.
Parameters readScenarioHead(xml::Reader& reader, const ParameterValues& assigned, const std::string& assigned_where,
                            Findings& findings);
/// The Ego: the one entity with a controller that is not mapped to its script, else the
/// entity --ego names (kDefaultEgo), driven by --controller; `controller` is set to what drives it.
Entity& findEgo(Translation& translation, ControllerChoice& controller);
/// The OpenDRIVE file the <RoadNetwork>'s <LogicFile> names (noted: a SceneGraphFile is not used).
std::filesystem::path roadNetworkFile(Translation& translation, const pugi::xml_node& root,
                                      const std::filesystem::path& xosc);
/// m of the road's length (along the language's centre line) that is vsd-sumo's scenario
/// region; the road goes on straight beyond it.
double regionLength(const CarriagewayRoad& road);
/// rad: the heading (in the OpenDRIVE file's frame) of the language's +x: the road's start
/// heading, turned where the road turns by more than kMaxArcTurn over its region so that every
/// segment of its centre line heads within kMaxArcTurn of +x.
double frameHeading(const CarriagewayRoad& road);

/// The language's along/lane/offset of an entity's bounding-box centre.
struct LanguagePlace {
  double s = 0.0;       ///< m along the language's road
  int lane = 0;         ///< language lane
  double offset = 0.0;  ///< m from the lane's centre, > 0 left
};

/// Where the bounding-box centre of an entity lies whose reference point is at `p` (the
/// centre `centre_ahead` m ahead of it along its heading); `keep_lane`: on `p`'s lane, else
/// on the lane nearest the centre.
LanguagePlace languagePlace(const CarriagewayRoad& road, const Placement& p, double centre_ahead, bool keep_lane);

// osc_storyboard.cpp
void readStories(Translation& translation, const pugi::xml_node& storyboard);
/// The scenario's duration (translation.duration): --duration, else a StopTrigger of one simulation
/// time, at most the longest window when `window_bound` (the language's runs).
void readStopTrigger(Translation& translation, const pugi::xml_node& storyboard, bool window_bound = true);
// osc_template.cpp
struct TranslationResult {
  std::string yaml;                    ///< empty if refused
  std::optional<std::string> violated; ///< a violated constraint
  std::vector<std::pair<std::string, double>> inputs;
};
/// String parameters a sweep varies, with the values in the order that codes them.
using StringCodes = std::map<std::string, std::vector<std::string>>;
TranslationResult translate(const std::filesystem::path& xosc, const OscImportOptions& options,
                            const ParameterValues& assigned, const std::string& assigned_where, Findings& findings,
                            const StringCodes& codes = {});

/// The language's reading of a translation, recorded as coming from `file`.
std::shared_ptr<const scenario::LogicalScenario> loadLanguage(const std::filesystem::path& file, const std::string& yaml);

/// How one parameter set of a grid fares before any simulation; `run` (which fails a Refused or
/// CannotStart set alone and runs the others) and `scenario check` count sets by it.
struct SetVerdict {
  enum class Kind {
    Runs,
    Skipped,      ///< violates the template's constraints
    Refused,      ///< its values take the file outside what the import supports
    CannotStart,  ///< its sample fails the language's per-sample checks or the simulation's start
                  ///< (a road user inside the Ego at t = 0, or off its road)
  };
  Kind kind = Kind::Runs;
  std::string message;  ///< why, for every kind but Runs
  /// Runs: the first pair of road users its start lets overlap (checkStart), empty if none.
  std::string overlap;
};
/// What the simulation meets at the start of `concrete`: throws ConfigError where it refuses the
/// start (a road user inside the Ego, or off its road), as `run` would; returns the pairs of road
/// users it lets start overlapping (sim::ScriptedTraffic::startOverlaps).
std::vector<std::string> checkStart(const scenario::ConcreteScenario& concrete);
/// Imports set `set` of `grid` (string parameters coded by `codes`) and checks sample `index`
/// of it with `seed`.
SetVerdict judgeSet(const ParameterGrid& grid, const OscImportOptions& import, const StringCodes& codes,
                    std::size_t set, std::uint64_t seed, std::uint64_t index);

/// A speed action's YAML (`speed:` item) from <SpeedAction>, for Init and Story.
YAML::Node speedAction(Translation& translation, const Entity& actor, const pugi::xml_node& action);
/// The Ego's `set_speed:` item from a <SpeedAction> on it (Init or Story): its controller's
/// set speed from then on, as esmini's ACC takes a speed action on its Ego; the dynamics are
/// the controller's own (noted). Refuses a relative target.
YAML::Node egoSetSpeed(Translation& translation, const pugi::xml_node& action);
/// The language's shape of a transition from a TransitionDynamics' dynamicsShape (sinusoidal is
/// its smooth one); a step is refused unless `step_allowed`.
std::string shapeOf(Translation& translation, const pugi::xml_node& dynamics, bool step_allowed);
/// A `coordinateSystem` the language can follow: entity, road or lane (one lane frame along
/// the road); any other (trajectory) is refused with `why`.
void requireLaneFrame(const xml::Reader& reader, const pugi::xml_node& node, const std::string& why);
/// --step and --duration as the language will take them (a step SUMO counts; a duration of
/// whole steps within the window), named as the user wrote them: ConfigError, a usage error.
void checkCommandLine(const OscImportOptions& options);
/// The appearance domains of an Activate- or AssignControllerAction (`attributes`: animation
/// and lighting, or their activate... forms): read, and noted where activated (not simulated).
void readAppearanceDomains(Translation& translation, const pugi::xml_node& action,
                           std::initializer_list<const char*> attributes);
/// The dimension and value of dynamics whose pace is not used (a step; the Ego's, which its
/// controller paces): still read, so that a bad one is refused by name, not ignored.
void unusedPace(const xml::Reader& reader, const pugi::xml_node& dynamics);
/// A speed action's YAML that keeps tracking a <RelativeTargetSpeed continuous="true"> of
/// `actor` at once (shape step).
YAML::Node continuousSpeed(Translation& translation, const Entity& actor, const pugi::xml_node& target);
/// The Init's speed actions that act after t = 0 (gradual ones, continuous targets) as the
/// language's actions at t = 0; after the Ego is known (their references name it).
void addInitialSpeedActions(Translation& translation);

/// The parameter sets of a <Stochastic> distribution (osc_stochastic.cpp): numberOfTestRuns
/// sets, run i drawn from (seed, i); the seed is the file's randomSeed, else `run_seed`.
std::vector<std::map<std::string, std::string>> drawStochasticSets(const xml::Reader& reader,
                                                                   const pugi::xml_node& stochastic,
                                                                   std::uint64_t run_seed);

}  // namespace vsd::interop::osc
