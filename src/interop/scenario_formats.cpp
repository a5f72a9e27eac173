#include "vsd/interop/scenario_formats.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cctype>
#include <fstream>

#include "osc_network.hpp"
#include "vsd/core/error.hpp"
#include "vsd/interop/run_openscenario.hpp"
#include "vsd/scenario/concrete_scenario.hpp"

namespace fs = std::filesystem;

namespace vsd::interop {

namespace {

/// Bytes of a file its format is judged by: an OpenSCENARIO file names its kind near the top.
constexpr std::size_t kHeadBytes = 64 * 1024;

bool contains(const std::string& head, const char* text) { return head.find(text) != std::string::npos; }

/// An OpenSCENARIO document's kind: the element after the FileHeader.
bool isDistribution(const std::string& head) { return contains(head, "<ParameterValueDistribution"); }
bool isCatalog(const std::string& head) { return contains(head, "<Catalog ") || contains(head, "<Catalog>"); }
bool isExport(const std::string& head) { return contains(head, "name=\"vsd-sumo."); }

ScenarioCheck checkYaml(const fs::path& file, const OscImportOptions&) {
  ScenarioCheck check;
  try {
    const auto logical = scenario::loadLogicalScenario(file);
    check.lines.push_back({ScenarioCheck::Line::Kind::Mapped,
                           fmt::format("{}: logical scenario '{}' with {} inputs", file.string(), logical->name,
                                       logical->inputs.size())});
  } catch (const ConfigError& error) {
    check.lines.push_back({ScenarioCheck::Line::Kind::Refused, error.what()});
  }
  return check;
}

ScenarioCheck checkExport(const fs::path& file, const OscImportOptions& options) {
  ScenarioCheck check;
  try {
    ImportOptions import;
    import.step = options.step;
    importOpenScenario(file, import);
    check.lines.push_back({ScenarioCheck::Line::Kind::Mapped, fmt::format("{}: a concrete scenario vsd-sumo exported",
                                                                          file.string())});
  } catch (const ConfigError& error) {
    check.lines.push_back({ScenarioCheck::Line::Kind::Refused, error.what()});
  }
  return check;
}

/// A file that is one concrete scenario has nothing to sample: a sampling flag given is a usage error.
void refuseSamplingFlags(const ScenarioRunRequest& request) {
  for (const char* flag : {"--samples", "--seed", "--first-sample"}) {
    if (!request.given(flag)) continue;
    throw ConfigError(fmt::format("command line: {}: {} is one concrete scenario, there is nothing to sample (a "
                                  "ParameterValueDistribution file runs a sweep)",
                                  flag, request.options.scenarioFile.string()));
  }
}

std::string runExport(const ScenarioRunRequest& request) {
  refuseSamplingFlags(request);
  ImportOptions import;
  import.step = request.import.step;
  return runOpenScenario(request.options, import).report();
}

/// A network scenario runs as an export of its map: flags of the language's runs do not apply.
void refuseLanguageRunFlags(const ScenarioRunRequest& request) {
  for (const char* flag : {"--jobs", "--net-batch", "--reference", "--keep-nets", "--fcd", "--max-failures",
                           "--ego-step-cost-ms", "--net-writer"}) {
    if (!request.given(flag)) continue;
    throw ConfigError(fmt::format("command line: {}: not for a network scenario (--network runs {} as `vsd-sumo "
                                  "export` runs a map, in one process)",
                                  flag, request.options.scenarioFile.string()));
  }
}

std::string runTemplateFile(const ScenarioRunRequest& request) {
  refuseSamplingFlags(request);
  if (request.import.network) {
    refuseLanguageRunFlags(request);
    return osc::runNetworkScenario(request.options, request.import);
  }
  return runTemplate(request.options, request.import).report();
}

std::string runDistribution(const ScenarioRunRequest& request) {
  if (request.import.network) {
    throw ConfigError(fmt::format("command line: --network: {} is a parameter distribution: a network scenario is "
                                  "one concrete scenario (run its template with --network)",
                                  request.options.scenarioFile.string()));
  }
  if (request.given("--first-sample")) {
    throw ConfigError(fmt::format("command line: --first-sample: {} is a parameter distribution: it runs its "
                                  "parameter sets in order (--samples draws some of them with --seed)",
                                  request.options.scenarioFile.string()));
  }
  return runVariation(request.options, request.import, request.given("--samples")).report();
}

std::vector<ScenarioFormat> makeFormats() {
  std::vector<ScenarioFormat> formats;
  ScenarioFormat yaml{"vsd-scenario", "logical scenario in the scenario language (docs/scenario-language.md)",
                      {".yaml", ".yml"}, nullptr, {}, nullptr, checkYaml,
                      [](const fs::path& file) { return scenario::loadLogicalScenario(file); }};
  yaml.can = {true, true, true, true, false, false, true, true};
  yaml.run = [](const ScenarioRunRequest& request) { return pipeline::runScenarios(request.options).report(); };
  ScenarioFormat exported{"openscenario-export", "a concrete scenario `vsd-sumo scenario export` wrote (read back exactly)",
                          {".xosc"}, isExport, {}, runExport, checkExport, nullptr};
  exported.can = {true, false, false, false, true, false, true};
  ScenarioFormat distribution{"openscenario-distribution",
                              "OpenSCENARIO ParameterValueDistribution: its template over the parameter grid",
                              {".xosc"}, isDistribution, {}, runDistribution, checkOpenScenario, nullptr};
  distribution.can = {true, true, true, false, true, true, true};
  ScenarioFormat catalog{"openscenario-catalog", "OpenSCENARIO catalog (read through the scenarios that reference it)",
                         {".xosc"}, isCatalog, {}, nullptr, nullptr, nullptr};
  ScenarioFormat openscenario{"openscenario", "OpenSCENARIO 1.0-1.2 scenario (docs/openscenario-import.md)",
                              {".xosc"}, nullptr, {}, runTemplateFile, checkOpenScenario, nullptr};
  openscenario.can = {true, false, false, false, true, true, true};
  for (auto* format : {&yaml, &exported, &distribution, &catalog, &openscenario}) formats.push_back(std::move(*format));
  return formats;
}

std::string head(const fs::path& file) {
  if (!fs::is_regular_file(file)) throw IoError(fmt::format("{}: not a regular file", file.string()));
  std::ifstream stream(file, std::ios::binary);
  if (!stream) throw IoError(fmt::format("{}: cannot be opened", file.string()));
  std::string bytes(kHeadBytes, '\0');
  stream.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  bytes.resize(static_cast<std::size_t>(stream.gcount()));
  return bytes;
}

}  // namespace

bool ScenarioRunRequest::given(const std::string& flag) const {
  return std::find(givenFlags.begin(), givenFlags.end(), flag) != givenFlags.end();
}

const std::vector<ScenarioFormat>& scenarioFormats() {
  static const std::vector<ScenarioFormat> kFormats = makeFormats();
  return kFormats;
}

const ScenarioFormat& scenarioFormatOf(const fs::path& file) {
  std::string extension = file.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  std::string bytes;
  bool read = false;
  for (const auto& format : scenarioFormats()) {
    if (std::find(format.extensions.begin(), format.extensions.end(), extension) == format.extensions.end()) continue;
    if (!format.recognises) return format;
    if (!read) {
      bytes = head(file);
      read = true;
    }
    if (format.recognises(bytes)) return format;
  }
  throw ConfigError(fmt::format("{}: not a scenario file vsd-sumo reads (formats: {})", file.string(),
                                scenarioFormatList()));
}

std::string scenarioFormatList() {
  std::vector<std::string> entries;
  for (const auto& format : scenarioFormats()) {
    entries.push_back(fmt::format("{} ({})", format.name, fmt::join(format.extensions, ", ")));
  }
  return fmt::format("{}", fmt::join(entries, "; "));
}

}  // namespace vsd::interop
