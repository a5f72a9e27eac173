#pragma once
// The registry of scenario file formats: one entry per format, chosen by extension and
// content (as Lanelet2's parser factory chooses a map parser). `vsd-sumo run` and
// `vsd-sumo scenario check` ask the registry which format a file is and what it can do;
// nothing else compares extensions or format names. Adding a format touches its own
// files and this registry's table (scenario_formats.cpp).

#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "vsd/interop/openscenario_import.hpp"
#include "vsd/pipeline/run.hpp"

namespace vsd::interop {

/// What files of a format can be used for.
struct ScenarioFormatAbilities {
  bool run = false;           ///< `vsd-sumo run FILE`
  bool samples = false;       ///< --samples chooses how many concrete scenarios (else the file fixes it)
  bool seed = false;          ///< --seed and --first-sample apply (sampling)
  bool distributed = false;   ///< mpirun and --shard
  bool step = false;          ///< --step applies
  bool importOptions = false; ///< --duration, --ego, --controller, --controller-map apply
  bool check = false;         ///< `vsd-sumo scenario check FILE`
  /// `vsd-sumo scenario export` can re-sample a run of it into OpenSCENARIO files (a logical
  /// scenario; a file that is already OpenSCENARIO is its own export).
  bool exportable = false;
};

/// A `run` as the command line gave it.
struct ScenarioRunRequest {
  pipeline::RunOptions options;
  OscImportOptions import;
  std::vector<std::string> givenFlags;  ///< flags given on the command line (e.g. "--samples")
  bool given(const std::string& flag) const;
};

struct ScenarioFormat {
  std::string name;
  std::string description;
  std::vector<std::string> extensions;  ///< with the dot, lower case
  /// True if a file with a matching extension is this format, judged by its first bytes.
  std::function<bool(const std::string& head)> recognises;
  ScenarioFormatAbilities can;
  /// Runs the file; returns the report `run` prints. Set if can.run.
  std::function<std::string(const ScenarioRunRequest&)> run;
  /// What the file holds, line by line. Set if can.check.
  std::function<ScenarioCheck(const std::filesystem::path&, const OscImportOptions&)> check;
  /// Set for formats that are logical scenarios: loads one. A parameter distribution over
  /// such a template fixes the inputs each set names (vsd-sumo's own `scenario distribution`).
  std::function<std::shared_ptr<const scenario::LogicalScenario>(const std::filesystem::path&)> logical;
};

/// Every format, most specific first.
const std::vector<ScenarioFormat>& scenarioFormats();

/// The format of `file` (by extension, then content). Throws ConfigError naming the file and
/// the formats there are, IoError if it cannot be read.
const ScenarioFormat& scenarioFormatOf(const std::filesystem::path& file);

/// "name (extensions): description" per format, for usage texts and docs.
std::string scenarioFormatList();

}  // namespace vsd::interop
