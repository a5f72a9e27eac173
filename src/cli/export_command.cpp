#include <fmt/format.h>

#include <memory>

#include "commands.hpp"
#include "flags.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/output_policy.hpp"
#include "vsd/pipeline/cluster.hpp"
#include "vsd/pipeline/map_export.hpp"

namespace vsd::cli {

namespace {
/// "name=value" -> (name, value); ConfigError otherwise.
std::pair<std::string, double> parseParam(const std::string& text) {
  const auto equals = text.find('=');
  if (equals == std::string::npos || equals == 0) {
    throw ConfigError::field("command line", "--controller-param", text, "name=value");
  }
  const std::string value = text.substr(equals + 1);
  if (!checkRealText(value).empty()) {
    throw ConfigError::field("command line", "--controller-param", text, "name=<finite decimal number>");
  }
  return {text.substr(0, equals), std::stod(value)};
}
/// The output policy (docs/output-policy.md) for the dataset file: its subject is the
/// export's label, as pipeline::exportMap chooses it (--label, else the map file's name).
void checkExportOutput(const pipeline::ExportOptions& options, bool force) {
  const std::filesystem::path map = options.openDrive.empty() ? options.source.mainFile() : options.openDrive;
  const std::string label = options.label.empty() ? map.stem().string() : options.label;
  std::vector<std::pair<std::string, std::filesystem::path>> inputs = {
      {"config", options.source.config}, {"--net", options.source.net}, {"--opendrive", options.openDrive}};
  for (const auto& routes : options.source.routes) inputs.emplace_back("--routes", routes);
  checkOutput({options.output, &output_kinds::datasetFile(), label, force, "--out", "--force", inputs});
}

}  // namespace

void addExportCommand(CLI::App& app, CommandContext& context) {
  auto options = std::make_shared<pipeline::ExportOptions>();
  auto config = std::make_shared<std::string>();
  auto params = std::make_shared<std::vector<std::string>>();
  auto begin = std::make_shared<double>(0.0);
  auto end = std::make_shared<double>(0.0);
  CLI::App* command = app.add_subcommand(
      "export", "Vectorized scenes (dataset .h5) from an arbitrary SUMO map with its own demand");
  command->add_option("config", *config, "SUMO configuration (.sumocfg)");
  command->add_option("--net", options->source.net, "SUMO network (with --routes)");
  command->add_option("--opendrive", options->openDrive, "OpenDRIVE map, imported with netconvert (with --routes)");
  command->add_option("--routes", options->source.routes, "Route files (demand) for --net / --opendrive");
  command->add_option("-o,--out", options->output, "Dataset file to write (.h5)")->required();
  auto force = std::make_shared<bool>(false);
  command->add_flag("--force", *force, "Replace a dataset file of another label (docs/output-policy.md)");
  command->add_option("--egos", options->egos, "Egos: all | random:K | vtype:NAME | id,id,...")->capture_default_str();
  addNumber(command, "-s,--seed", options->seed, "Seed (Ego choice and SUMO)")->capture_default_str();
  addNumber(command, "--step", options->step, "Time step (s)")->capture_default_str();
  addNumber(command, "--horizon", options->horizon, "Ego future per sample (s)")->capture_default_str();
  addNumber(command, "--history", options->history, "Past before t0 in the polylines (s)")->capture_default_str();
  addNumber(command, "--stride", options->stride, "Time between window starts of one Ego (s)")->capture_default_str();
  addNumber(command, "--radius", options->radius, "Lanes and vehicles within this distance of the Ego (m)")
      ->capture_default_str();
  addNumber(command, "--max-vector-length", options->maxVectorLength, "Longest lane-boundary vector (m)")
      ->capture_default_str();
  CLI::Option* begin_flag = addNumber(command, "--begin", *begin, "Simulation begin (s; default: the map's)");
  CLI::Option* end_flag = addNumber(command, "--end", *end, "Simulation end (s; default: the map's)");
  command->add_option("--label", options->label, "Label of the samples (default: the map file's name)");
  addNumber(command, "--max-samples", options->maxSamples, "Stop after this many samples (0: no limit)")
      ->capture_default_str();
  addNumber(command, "--lane-change-duration", options->laneChangeDuration,
                      "SUMO lane changes take this long (s); 0: the map's own (instantaneous, or sublane)")
      ->capture_default_str();
  addNumber(command, "--compression", options->compression, "Deflate level of the vectors: 0 (none, fastest) .. 9")
      ->capture_default_str();
  addNumber(command, "--step-timeout", options->watchdog.stepTimeout,
                      "Watchdog: longest Ego controller call or libsumo step (s); a closed-loop Ego exceeding it is "
                      "taken out")
      ->capture_default_str();
  command->add_flag("--closed-loop", options->closedLoop, "Drive every Ego with an Ego controller instead of SUMO");
  command->add_option("--controller", options->controller, "Controller for --closed-loop")->capture_default_str();
  command->add_option("--controller-library", options->controllerLibrary, "Plugin library holding --controller");
  command->add_option("--controller-param", *params, "Controller parameter name=value (repeatable)");
  command->add_option("--sumo-option", options->source.sumoOptions, "Extra SUMO argument (repeatable)");
  command->callback([=, &context] {
    context.action = [=] {
      options->source.config = *config;
      if (begin_flag->count() > 0) options->begin = *begin;
      if (end_flag->count() > 0) options->end = *end;
      for (const auto& param : *params) options->controllerParams.push_back(parseParam(param));
      checkExportOutput(*options, *force);
      if (pipeline::launchedAsMpiRank()) {
        const auto communicator = pipeline::joinMpiJob();
        const auto result = pipeline::exportOnCluster(*options, *communicator);
        fmt::print("{}", result.report);
        return result.exitCode;
      }
      const auto summary = pipeline::exportMap(*options);
      fmt::print("{}", summary.report());
      return 0;
    };
  });
}

}  // namespace vsd::cli
