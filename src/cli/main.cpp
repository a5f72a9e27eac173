// vsd-sumo: scenario-based testing with SUMO, vectorized scenario descriptions
// and VectorNet. Subcommands only parse flags and call the libraries.

#include <fmt/format.h>

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "commands.hpp"
#include "usage.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/interrupt.hpp"
#include "vsd/core/log.hpp"
#include "vsd/pipeline/cluster.hpp"

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

/// The subcommand named on the command line: the first argument that is not a flag
/// (the top-level options are flags without values), or "" if there is none.
std::string subcommandOf(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    if (argv[i][0] != '-') return argv[i];
  }
  return "";
}

/// True if this executable handles the command line itself: vsd-sumo-ml always;
/// vsd-sumo for its own subcommands and --version.
bool handledHere(const CLI::App& app, bool has_model_commands, int argc, char** argv) {
  if (has_model_commands) return true;
  const std::string name = subcommandOf(argc, argv);
  if (name.empty()) {
    for (int i = 1; i < argc; ++i) {
      if (std::strcmp(argv[i], "--version") == 0) return true;
    }
    return false;  // top-level help lists every command: vsd-sumo-ml has them all
  }
  for (const auto* command : app.get_subcommands({})) {
    if (command->get_name() == name) return true;
  }
  return false;
}

/// Replaces this process with vsd-sumo-ml and the same arguments; returns only if it
/// cannot be started.
int handOverToModelExecutable(char** argv) {
  const std::string target = vsd::cli::siblingExecutable("vsd-sumo-ml");
  ::execv(target.c_str(), argv);
  std::fprintf(stderr, "vsd-sumo: error: %s: cannot start it (%s); it holds the commands train, predict, evaluate, "
               "baseline, experiment, compare, bench and search and is built next to vsd-sumo\n",
               target.c_str(), std::strerror(errno));
  return 1;
}

}  // namespace

namespace vsd::cli {

std::string siblingExecutable(const std::string& name) {
  std::error_code error;
  const auto self = std::filesystem::read_symlink("/proc/self/exe", error);
  return error ? name : (self.parent_path() / name).string();
}

}  // namespace vsd::cli

int main(int argc, char** argv) {
  CLI::App app{"vsd-sumo: scenario-based testing of automated vehicles with SUMO, vectorized scenario descriptions "
               "and VectorNet motion prediction"};
  app.set_version_flag("--version", vsd::toolVersion());
  const std::string mpi = vsd::pipeline::mpiLibraryVersion();
  app.footer(mpi.empty() ? "MPI: not in this build (install libopenmpi-dev and rebuild for mpirun -n N vsd-sumo run)"
                         : "MPI: " + mpi + " (mpirun -n N vsd-sumo run|export: the work is split over the ranks)");
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
  vsd::cli::addMergeCommand(app, context);
  vsd::cli::addScenarioCommand(app, context);
  const bool has_model_commands = vsd::cli::addModelCommands(app, context);
  if (!handledHere(app, has_model_commands, argc, argv)) return handOverToModelExecutable(argv);

  std::vector<std::string> args(argv + 1, argv + argc);
  for (const auto& note : vsd::cli::replaceDeprecatedSpellings(app, args)) {
    std::fprintf(stderr, "vsd-sumo: note: %s\n", note.c_str());
  }
  try {
    std::vector<std::string> reversed(args.rbegin(), args.rend());  // CLI11 takes them last first, and consumes them
    app.name(argv[0]);
    app.parse(reversed);
  } catch (const CLI::ParseError& error) {
    if (error.get_exit_code() == 0) return app.exit(error);  // --help, --version
    // A command line that does not parse is a usage error: one line naming the word, exit code 2.
    std::fprintf(stderr, "vsd-sumo: error: command line: %s (see --help)\n",
                 vsd::cli::usageMessage(app, args, error.what()).c_str());
    return vsd::cli::kUsageExit;
  }
  vsd::configureLogging(quiet ? vsd::Verbosity::Quiet : verbose ? vsd::Verbosity::Verbose : vsd::Verbosity::Normal);
  vsd::installInterruptHandlers();
  try {
    const int status = context.action ? context.action() : 0;
    if (vsd::interrupted()) {
      // The signal came after the point of no return (the outputs were already
      // being put in place): they are complete, but the signal is still reported.
      std::fprintf(stderr, "vsd-sumo: interrupted by signal %d after the outputs were complete\n",
                   vsd::interruptSignal());
      return 128 + vsd::interruptSignal();
    }
    return status;
  } catch (const vsd::InterruptedError& error) {
    std::fprintf(stderr, "vsd-sumo: %s\n", error.what());
    return error.exitCode();
  } catch (const vsd::ConfigError& error) {
    std::fprintf(stderr, "vsd-sumo: error: %s\n", error.what());
    return vsd::cli::isUsageError(error) ? vsd::cli::kUsageExit : 1;
  } catch (const vsd::Error& error) {
    std::fprintf(stderr, "vsd-sumo: error: %s\n", error.what());
    return 1;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "vsd-sumo: internal error: %s\n", error.what());
    return 3;
  }
}
