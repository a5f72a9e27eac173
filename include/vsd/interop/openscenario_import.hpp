#pragma once
// OpenSCENARIO 1.0-1.2 as validation teams write it, imported into the scenario
// language (docs/openscenario-import.md): parameters with ${...} expressions and
// constraints, catalogs, vehicles/pedestrians/misc objects, positions, speed, lane-change,
// lane-offset and controller actions, Story/Act/ManeuverGroup/Maneuver/Event with their
// conditions; ParameterValueDistribution files as sweeps. What cannot be mapped is
// refused with one line naming file, line and element (`vsd-sumo scenario check` lists
// every such line at once).
//
// This is the import of files written elsewhere. Files vsd-sumo exported itself are read
// back by importOpenScenario (openscenario.hpp), which knows their per-step scripts.

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "vsd/pipeline/run.hpp"
#include "vsd/scenario/logical_scenario.hpp"

namespace vsd::interop {

/// The entity that is the Ego of a file without controllers, and its controller, by default.
inline constexpr const char* kDefaultEgo = "Ego";
inline constexpr const char* kDefaultEgoController = "alks";

struct OscImportOptions {
  std::optional<double> step;      ///< s; unset: the scenario language's default step
  /// s simulated; unset: the file's StopTrigger when it is a simulation time that fits the
  /// window (at most kMaxWindowSteps steps). A StopTrigger of another kind needs it.
  std::optional<double> duration;
  /// The Ego when no entity has a controller: this entity (unset: kDefaultEgo), driven by
  /// `controller` (unset: kDefaultEgoController). Set where an entity has one: refused.
  std::optional<std::string> ego;
  std::optional<std::string> controller;
  /// YAML map from the file's controller names to vsd-sumo controllers (empty: the defaults).
  std::filesystem::path controllerMap;
  /// `--data-root`: the folder every file a scenario names (its road network, catalog
  /// directories, a distribution's template) must lie in, e.g. esmini's resources/, whose
  /// scenarios in xosc/ name roads in ../xodr/. Empty: the naming file's own folder.
  std::filesystem::path dataRoot;
  /// `scenario check --seed`: the seed a Stochastic distribution without its own randomSeed
  /// draws its sets with, as `run --seed` would (`run` passes its seed directly).
  std::uint64_t checkSeed = 1;
  /// `--network`: simulate the file's Init on SUMO's network of its OpenDRIVE file (or a SUMO
  /// controller's configuration) instead of translating it into the scenario language.
  bool network = false;
};

/// The file's controller names that map onto a built-in controller by default
/// (name in the file -> vsd-sumo controller).
const std::map<std::string, std::string>& defaultControllerMap();

/// What `scenario check` found: one line per element, in file order.
struct ScenarioCheck {
  struct Line {
    enum class Kind { Mapped, Note, Refused } kind;
    std::string text;
  };
  std::vector<Line> lines;
  std::string yaml;            ///< the translation into the scenario language (if it would run)
  bool runnable() const;
  /// The lines prefixed "ok", "note", "REFUSED" and a closing count.
  std::string report() const;
};

/// Checks a scenario template or a parameter distribution without simulating: a template
/// element by element at its declared values; a distribution's template likewise, then every
/// parameter set imported and counted (skipped by a constraint, refused, would run; a refused
/// set is a refusal line naming the first). Never throws ConfigError for the files' content:
/// refusals are lines.
ScenarioCheck checkOpenScenario(const std::filesystem::path& file, const OscImportOptions& options);

/// The template as a logical scenario of the language, at its declared parameter values
/// with `assigned` replacing some (text values, typed by the declarations). Throws
/// ConfigError (one line) at the first refusal or violated constraint.
std::shared_ptr<const scenario::LogicalScenario> importTemplate(const std::filesystem::path& xosc,
                                                                const OscImportOptions& options,
                                                                const std::map<std::string, std::string>& assigned = {});

/// `vsd-sumo run TEMPLATE.xosc`: one concrete scenario, sample 0 of options.seed (options' sample
/// count and first sample are replaced).
pipeline::RunSummary runTemplate(pipeline::RunOptions options, const OscImportOptions& import);

/// The parameter sets of a ParameterValueDistribution file and its template. Throws
/// ConfigError for elements outside what is read (naming them).
struct ParameterGrid {
  std::filesystem::path file;
  std::filesystem::path scenarioFile;  ///< the template: an OpenSCENARIO file or a logical scenario
  /// Set when the template is a logical scenario (a format with ScenarioFormat::logical, read
  /// once): each set fixes the inputs it names.
  std::shared_ptr<const scenario::LogicalScenario> logicalTemplate;
  std::vector<std::map<std::string, std::string>> sets;
};
/// The parameter sets of a ParameterValueDistribution: a Deterministic grid (the product of
/// its distributions, the last varying fastest), or numberOfTestRuns Stochastic draws from
/// the file's randomSeed, else from `seed` (a run's --seed).
ParameterGrid readParameterDistribution(const std::filesystem::path& file, const OscImportOptions& options,
                                        std::uint64_t seed = 1);

/// `vsd-sumo run VARIATION.xosc`: the template at every parameter set that satisfies its
/// ConstraintGroups, one concrete scenario (row of concrete.csv) each; the others are
/// skipped and counted in the report. --samples (if given and fewer than the sets that can
/// run) draws that many of them with --seed, run in grid order.
struct SweepSummary {
  pipeline::RunSummary run;
  std::uint64_t sets = 0;     ///< in the grid
  std::uint64_t skipped = 0;  ///< violating a constraint
  /// Satisfying the constraints, but failing alone: values the import refuses (a lane the road
  /// lacks, say) or road users that cannot start (one inside the Ego, or off the road).
  std::uint64_t refused = 0;
  std::uint64_t simulated = 0;  ///< sets run: all the others, or --samples of them
  std::uint64_t drawnWithSeed = 0;  ///< --seed the --samples sets were drawn with (when fewer than the others)
  std::string firstSkipped;   ///< the first violation, as reported
  std::string firstRefused;   ///< the first refusal, as reported
  /// Of the sets run (all, or the drawn ones): those whose road users other than the Ego start
  /// overlapping (the import lets them: OpenSCENARIO has no rule against it), and the first such pair.
  std::uint64_t overlapping = 0;
  std::string firstOverlapping;
  std::string report() const;
};
SweepSummary runVariation(pipeline::RunOptions options, const OscImportOptions& import, bool samples_given);

/// The import work of a whole sweep without its simulation (`vsd-sumo bench import`): the
/// grid read, every set imported and its start checked as runVariation does before the sweep,
/// then every set that would run imported again, sampled and its road built, as the sweep's
/// workers do before they simulate it.
struct SweepImportTiming {
  SweepSummary counts;        ///< sets, skipped, refused (failed at the start), simulated (= would run)
  double gridSeconds = 0.0;   ///< reading the distribution and building the grid
  double acceptSeconds = 0.0; ///< every set imported and checked
  double sampleSeconds = 0.0; ///< every set that would run: imported, sampled, road built
  /// The sweep's import overhead per concrete scenario (ms): the check per set of the grid
  /// plus the workers' import per set run.
  double millisecondsPerSet() const;
};
SweepImportTiming timeSweepImport(const std::filesystem::path& file, const OscImportOptions& import, std::uint64_t seed);

}  // namespace vsd::interop
