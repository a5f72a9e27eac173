// vsd-sumo-ml: the commands that need libtorch (see addModelCommands in commands.hpp).

#include "commands.hpp"

namespace vsd::cli {

bool addModelCommands(CLI::App& app, CommandContext& context) {
  addTrainCommand(app, context);
  addPredictCommand(app, context);
  addEvaluateCommand(app, context);
  addBaselineCommand(app, context);
  addExperimentCommand(app, context);
  addCompareCommand(app, context);
  addDeviationsCommand(app, context);
  addBenchCommand(app, context);
  addSearchCommand(app, context);
  return true;
}

}  // namespace vsd::cli
