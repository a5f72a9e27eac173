#include "vsd/scenario/yaml_reader.hpp"

#include <fmt/format.h>

#include <cmath>

#include "vsd/core/error.hpp"
#include "vsd/core/numbers.hpp"
#include "vsd/core/road_user.hpp"

namespace vsd::scenario {

std::string YamlReader::where(const YAML::Node& node, const std::string& field) const {
  const auto mark = node.Mark();
  if (mark.line >= 0) return fmt::format("{}:{}: {}", file_, mark.line + 1, field);
  return fmt::format("{}: {}", file_, field);
}

void YamlReader::fail(const YAML::Node& node, const std::string& field, const std::string& problem) const {
  throw ConfigError(fmt::format("{}: {}", where(node, field), problem));
}

void YamlReader::requireMap(const YAML::Node& node, const std::string& field) const {
  if (!node.IsMap()) fail(node, field, "expected a mapping (key: value pairs)");
}

void YamlReader::checkKeys(const YAML::Node& node, const std::string& field, const std::set<std::string>& allowed) const {
  requireMap(node, field);
  for (const auto& entry : node) {
    const auto key = entry.first.as<std::string>();
    if (allowed.count(key) == 0) {
      fail(entry.first, field.empty() ? key : field + "." + key,
           fmt::format("unknown key '{}' (allowed: {})", key, fmt::join(allowed, ", ")));
    }
  }
}

std::string YamlReader::scalar(const YAML::Node& node, const std::string& field) const {
  if (!node.IsScalar()) fail(node, field, "expected a single value");
  return node.Scalar();
}

double YamlReader::number(const YAML::Node& node, const std::string& field) const {
  // "file:line" (the field is named once, by parseReal's message).
  const std::string location = node.Mark().line >= 0 ? fmt::format("{}:{}", file_, node.Mark().line + 1) : file_;
  return parseReal(scalar(node, field), NumberRange::any(), location, field);
}

double YamlReader::number(const YAML::Node& map, const std::string& key, const std::string& field, double fallback) const {
  const auto node = map[key];
  if (!node) return fallback;
  return number(node, field);
}

int YamlReader::integer(const YAML::Node& map, const std::string& key, const std::string& field, int fallback, int minimum,
                        int maximum) const {
  const auto node = map[key];
  if (!node) return fallback;
  const std::string location = node.Mark().line >= 0 ? fmt::format("{}:{}", file_, node.Mark().line + 1) : file_;
  return static_cast<int>(parseInteger(scalar(node, field), minimum, maximum, location, field));
}

Expression YamlReader::expression(const YAML::Node& node, const std::string& field, const std::vector<std::string>& variables) const {
  return Expression::compile(scalar(node, field), variables, where(node, field));
}

Distribution YamlReader::distribution(const YAML::Node& node, const std::string& field, const std::vector<std::string>& variables,
                          const std::set<std::string>& extra_keys) const {
  Distribution result;
  result.where = where(node, field);
  if (node.IsScalar()) {  // shorthand: a constant
    result.kind = Distribution::Kind::Constant;
    result.value = expression(node, field, variables);
    return result;
  }
  std::set<std::string> allowed = {"distribution", "min", "max", "mean", "std", "value", "choices"};
  allowed.insert(extra_keys.begin(), extra_keys.end());
  checkKeys(node, field, allowed);
  std::string kind = node["distribution"] ? scalar(node["distribution"], field + ".distribution") : "";
  if (kind.empty()) {
    if (node["value"]) kind = "constant";
    else if (node["choices"]) kind = "choice";
    else if (node["mean"] || node["std"]) kind = "normal";
    else kind = "uniform";
  }
  auto require = [&](const char* key) {
    if (!node[key]) fail(node, field, fmt::format("'{}' distribution needs '{}'", kind, key));
    return expression(node[key], field + "." + key, variables);
  };
  auto forbid = [&](std::initializer_list<const char*> keys) {
    for (const char* key : keys) {
      if (node[key]) fail(node[key], field + "." + key, fmt::format("not used by a '{}' distribution", kind));
    }
  };
  if (kind == "uniform") {
    forbid({"mean", "std", "value", "choices"});
    result.kind = Distribution::Kind::Uniform;
    result.min = require("min");
    result.max = require("max");
    checkOrder(result.min, result.max, node, field);
  } else if (kind == "normal") {
    forbid({"value", "choices"});
    result.kind = Distribution::Kind::Normal;
    result.mean = require("mean");
    result.stddev = require("std");
    if (result.stddev.isConstant() && result.stddev.evaluate({}) < 0.0) {
      throw ConfigError::field(where(node["std"], field + ".std"), field + ".std", result.stddev.text(),
                               "a standard deviation >= 0");
    }
    if (node["min"] || node["max"]) {
      result.hasBounds = true;
      result.min = require("min");
      result.max = require("max");
      checkOrder(result.min, result.max, node, field);
    }
  } else if (kind == "constant") {
    forbid({"min", "max", "mean", "std", "choices"});
    result.kind = Distribution::Kind::Constant;
    result.value = require("value");
  } else if (kind == "choice") {
    forbid({"min", "max", "mean", "std", "value"});
    result.kind = Distribution::Kind::Choice;
    const auto choices = node["choices"];
    if (!choices.IsSequence() || choices.size() == 0) {
      fail(choices, field + ".choices", "expected a non-empty list of numbers");
    }
    for (std::size_t i = 0; i < choices.size(); ++i) {
      // A road-user type name stands for its code (`type: lead_type` draws a type).
      const auto type = choices[i].IsScalar() ? findRoadUserType(choices[i].Scalar()) : std::nullopt;
      result.choices.push_back(type ? static_cast<double>(*type)
                                    : number(choices[i], fmt::format("{}.choices[{}]", field, i)));
    }
  } else {
    throw ConfigError::field(where(node["distribution"], field + ".distribution"), field + ".distribution", kind,
                             "one of uniform, normal, constant, choice");
  }
  return result;
}

void YamlReader::checkOrder(const Expression& min, const Expression& max, const YAML::Node& node, const std::string& field) const {
  if (min.isConstant() && max.isConstant() && min.evaluate({}) > max.evaluate({})) {
    throw ConfigError(fmt::format("{}: min {} > max {} (expected min <= max)", where(node, field), min.text(),
                                  max.text()));
  }
}


YAML::Node loadYaml(const std::string& text, const std::string& source_name) {
  try {
    return YAML::Load(text);
  } catch (const YAML::Exception& error) {
    throw ConfigError(fmt::format("{}:{}: malformed YAML: {}", source_name, error.mark.line + 1, error.msg));
  }
}

}  // namespace vsd::scenario
