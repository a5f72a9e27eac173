#include "vsd/pipeline/provenance.hpp"

#include <nlohmann/json.hpp>

#include "vsd/core/log.hpp"
#include "vsd/sim/sumo_session.hpp"

namespace vsd::pipeline {

void Provenance::addTo(nlohmann::json& manifest) const {
  manifest["tool_version"] = toolVersion;
  manifest["sumo_version"] = sumoVersion;
}

Provenance provenance() { return {toolVersion(), sim::SumoSession::version()}; }

}  // namespace vsd::pipeline
