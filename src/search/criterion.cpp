#include "vsd/search/criterion.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>
#include <regex>

#include "vsd/core/error.hpp"
#include "vsd/metrics/metrics.hpp"

namespace vsd::search {

namespace {

bool mentions(const std::string& expression, const std::string& identifier) {
  const std::regex word("(^|[^A-Za-z0-9_])" + identifier + "($|[^A-Za-z0-9_])");
  return std::regex_search(expression, word);
}

/// Identifiers of the expression that are neither metrics of the run nor muparser functions/constants.
std::vector<std::string> identifiersOf(const std::string& expression) {
  static const std::regex identifier("[A-Za-z_][A-Za-z0-9_]*");
  std::vector<std::string> names;
  for (auto it = std::sregex_iterator(expression.begin(), expression.end(), identifier); it != std::sregex_iterator();
       ++it) {
    names.push_back(it->str());
  }
  return names;
}

/// A metric the registry knows but this scenario does not compute gets its own hint.
void rejectUnknownMetrics(const std::string& expression, const std::string& where,
                          const std::vector<std::string>& metric_names) {
  for (const auto& name : identifiersOf(expression)) {
    const bool computed = std::find(metric_names.begin(), metric_names.end(), name) != metric_names.end();
    if (computed || metrics::findMetric(name) == nullptr) continue;
    throw ConfigError(fmt::format("{}: metric '{}' is not computed by this scenario (its metrics: {}); add it to "
                                  "the scenario's `metrics:`",
                                  where, name, fmt::join(metric_names, ", ")));
  }
}

}  // namespace

Criterion::Criterion(const std::string& text, const scenario::LogicalScenario& logical,
                     const std::vector<std::string>& metric_names) {
  std::string where = fmt::format("--criterion '{}'", text);
  name_ = text;
  expression_ = text;
  for (const auto& named : logical.criteria) {
    if (named.name == text) {
      expression_ = named.expression;
      where = named.where.empty() ? logical.sourceFile.string() + ": criteria." + named.name : named.where;
    }
  }
  if (expression_.find_first_not_of(" \t") == std::string::npos) {
    throw ConfigError::field("command line", "--criterion", "''",
                             "an expression over metrics such as 'd_min < 2' or a criterion name of the scenario");
  }
  rejectUnknownMetrics(expression_, where, metric_names);
  for (std::size_t m = 0; m < metric_names.size(); ++m) {
    if (!mentions(expression_, metric_names[m])) continue;
    used_.push_back(metric_names[m]);
    usedColumns_.push_back(m);
  }
  std::vector<std::string> named;
  for (const auto& criterion : logical.criteria) named.push_back(criterion.name);
  const std::string named_list = named.empty() ? std::string("none defined") : fmt::format("{}", fmt::join(named, ", "));
  try {
    onAll_ = scenario::Expression::compile(expression_, metric_names, where);
  } catch (const ConfigError& error) {
    throw ConfigError(fmt::format("{}; the scenario's named criteria: {}", error.what(), named_list));
  }
  if (used_.empty()) {
    throw ConfigError(fmt::format("{}: uses no metric; expected an expression over {} or one of the scenario's "
                                  "criteria ({})",
                                  where, fmt::join(metric_names, ", "), named_list));
  }
  onUsed_ = scenario::Expression::compile(expression_, used_, where);
}

std::optional<bool> Criterion::verdict(const std::vector<double>& metric_values) const {
  for (const auto column : usedColumns_) {
    if (column >= metric_values.size() || std::isnan(metric_values[column])) return std::nullopt;
  }
  const double value = onAll_.evaluate(metric_values);
  if (std::isnan(value)) return std::nullopt;
  return value != 0.0;
}

bool Criterion::meetsUsed(const std::vector<double>& used_values) const {
  const double value = onUsed_.evaluate(used_values);
  return !std::isnan(value) && value != 0.0;
}

}  // namespace vsd::search
