// vsd-sumo: without libtorch; the model commands are vsd-sumo-ml's (see
// addModelCommands in commands.hpp).

#include "commands.hpp"

namespace vsd::cli {

bool addModelCommands(CLI::App& /*app*/, CommandContext& /*context*/) { return false; }

}  // namespace vsd::cli
