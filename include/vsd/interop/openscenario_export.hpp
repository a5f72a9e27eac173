#pragma once
// `vsd-sumo scenario export`: concrete scenarios as OpenDRIVE + OpenSCENARIO files.
//
// Sources:
//   a logical scenario (YAML)  -> the concrete scenarios `run` would simulate with the same
//                                 --samples/--seed/--first-sample (sampling is deterministic);
//   a run folder               -> the scenarios of its concrete.csv, re-sampled from the
//                                 scenario file its manifest names (checked against the
//                                 SHA-256 recorded there); `--only failures` keeps those
//                                 that fail one of the scenario's criteria.
// Output folder: <name>_<sample:06>.xosc + .xodr per scenario, vsd_controllers.xosc, and
// manifest.json last (every file's SHA-256 and size); built under a temporary name and
// renamed when complete.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace vsd::interop {

struct ScenarioExportOptions {
  enum class Only { All, Failures };

  std::filesystem::path input;      ///< logical scenario (.yaml) or run folder
  std::filesystem::path outputDir;
  std::string format = "openscenario";
  std::uint64_t samples = 0;        ///< YAML input: number of concrete scenarios
  std::uint64_t seed = 0;           ///< YAML input
  std::uint64_t firstSample = 0;    ///< YAML input
  Only only = Only::All;            ///< run folder input
  bool force = false;               ///< replace an existing output folder
  std::string commandLine;          ///< recorded in the manifest

  /// Throws ConfigError naming the flag.
  void validate() const;
};

struct ScenarioExportSummary {
  std::filesystem::path outputDir;
  std::string functionalScenario;
  std::uint64_t considered = 0;  ///< concrete scenarios looked at
  std::uint64_t exported = 0;
  double seconds = 0.0;
  std::string report() const;
};

/// Throws ConfigError for bad options or input (a run folder without its scenario file,
/// a changed scenario file, `--only failures` on a scenario without criteria, an existing
/// output folder without --force), IoError for files that cannot be written. Nothing is
/// left at `outputDir` unless the export completed.
ScenarioExportSummary exportScenarios(const ScenarioExportOptions& options);

}  // namespace vsd::interop
