#pragma once
// Strict YAML reading for the project's configuration files: every message has the
// form "file:line: field: problem", unknown keys are rejected with the allowed ones,
// numbers and expressions are checked where they are read.

#include <yaml-cpp/yaml.h>

#include <set>
#include <string>
#include <vector>

#include "vsd/scenario/logical_scenario.hpp"

namespace vsd::scenario {

class YamlReader {
 public:
  explicit YamlReader(std::string file) : file_(std::move(file)) {}

  std::string where(const YAML::Node& node, const std::string& field) const;
  [[noreturn]] void fail(const YAML::Node& node, const std::string& field, const std::string& problem) const;
  void requireMap(const YAML::Node& node, const std::string& field) const;
  void checkKeys(const YAML::Node& node, const std::string& field, const std::set<std::string>& allowed) const;
  std::string scalar(const YAML::Node& node, const std::string& field) const;
  double number(const YAML::Node& node, const std::string& field) const;
  double number(const YAML::Node& map, const std::string& key, const std::string& field, double fallback) const;
  /// A whole number in [minimum, maximum] (ConfigError naming the field otherwise).
  int integer(const YAML::Node& map, const std::string& key, const std::string& field, int fallback, int minimum,
              int maximum = 1'000'000) const;
  Expression expression(const YAML::Node& node, const std::string& field, const std::vector<std::string>& variables) const;
  Distribution distribution(const YAML::Node& node, const std::string& field, const std::vector<std::string>& variables,
                            const std::set<std::string>& extra_keys = {}) const;
  void checkOrder(const Expression& min, const Expression& max, const YAML::Node& node, const std::string& field) const;

 private:
  std::string file_;
};

/// Parses YAML text; throws ConfigError "file:line: malformed YAML: ..." on syntax errors.
YAML::Node loadYaml(const std::string& text, const std::string& source_name);

}  // namespace vsd::scenario
