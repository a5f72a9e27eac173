#pragma once
// Parts of the scenario parser shared by its source files (internal to the scenario module).

#include <string>
#include <vector>

#include "vsd/scenario/logical_scenario.hpp"
#include "vsd/scenario/yaml_reader.hpp"

namespace vsd::scenario::detail {

/// Letters first, then letters, digits and underscores.
bool isIdentifier(const std::string& name);

/// `vehicles`: the Ego and the other road users with their actions; trigger references
/// (road users, actions) are resolved and checked for cycles. Needs the road parsed.
void parseRoadUsers(const YamlReader& reader, const YAML::Node& node, LogicalScenario& scenario);

}  // namespace vsd::scenario::detail
