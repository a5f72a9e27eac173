// vsd-sumo: scenario-based testing with SUMO, vectorized scenario descriptions
// and VectorNet. Subcommands only parse flags and call the libraries.

#include <fmt/format.h>

#include <algorithm>
#include <cstdio>

#include "commands.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/interrupt.hpp"
#include "vsd/core/log.hpp"

namespace {

std::string joinCommandLine(int argc, char** argv) {
  std::string line;
  for (int i = 0; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg.find_first_of(" \t\"'") != std::string::npos) arg = "'" + arg + "'";
    line += (i == 0 ? "" : " ") + arg;
  }
  return line;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"vsd-sumo: scenario-based testing of automated vehicles with SUMO, vectorized scenario descriptions "
               "and VectorNet motion prediction"};
  app.set_version_flag("--version", vsd::toolVersion());
  app.require_subcommand(1);
  bool quiet = false;
  bool verbose = false;
  app.add_flag("-q,--quiet", quiet, "Only warnings and errors on stderr, no progress");
  app.add_flag("-v,--verbose", verbose, "Debug messages on stderr");
  // -q/-v are global but may also follow the subcommand (`vsd-sumo run x.yaml -q`).
  app.fallthrough();

  vsd::cli::CommandContext context;
  context.commandLine = joinCommandLine(argc, argv);
  vsd::cli::addRunCommand(app, context);
  vsd::cli::addExportCommand(app, context);
  vsd::cli::addDatasetCommand(app, context);
  vsd::cli::addTrainCommand(app, context);
  vsd::cli::addPredictCommand(app, context);
  vsd::cli::addEvaluateCommand(app, context);
  vsd::cli::addBaselineCommand(app, context);
  vsd::cli::addExperimentCommand(app, context);
  vsd::cli::addCompareCommand(app, context);
  vsd::cli::addBenchCommand(app, context);
  vsd::cli::addScenarioCommand(app, context);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    if (error.get_exit_code() == 0) return app.exit(error);  // --help, --version
    // Bad flags are bad input like any other: one line, exit code 1.
    std::string message = error.what();
    std::replace(message.begin(), message.end(), '\n', ' ');
    std::fprintf(stderr, "vsd-sumo: error: command line: %s (see --help)\n", message.c_str());
    return 1;
  }
  vsd::configureLogging(quiet ? vsd::Verbosity::Quiet : verbose ? vsd::Verbosity::Verbose : vsd::Verbosity::Normal);
  vsd::installInterruptHandlers();
  try {
    return context.action ? context.action() : 0;
  } catch (const vsd::InterruptedError& error) {
    std::fprintf(stderr, "vsd-sumo: %s\n", error.what());
    return 130;
  } catch (const vsd::Error& error) {
    std::fprintf(stderr, "vsd-sumo: error: %s\n", error.what());
    return 1;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "vsd-sumo: internal error: %s\n", error.what());
    return 3;
  }
}
