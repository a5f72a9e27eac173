#pragma once
// What made an output, as every manifest and report records it: this tool's version and
// the SUMO that simulated. One call, so that modules above the pipeline record SUMO's
// version without reaching into the simulation module.

#include <nlohmann/json_fwd.hpp>

#include <string>

namespace vsd::pipeline {

struct Provenance {
  std::string toolVersion;  ///< vsd-sumo's version with the commit it was built from (toolVersion())
  std::string sumoVersion;  ///< libsumo's version, as SUMO reports it

  /// Sets a manifest's "tool_version" and "sumo_version".
  void addTo(nlohmann::json& manifest) const;
};

/// The provenance of this binary.
Provenance provenance();

}  // namespace vsd::pipeline
