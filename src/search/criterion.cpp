#include "vsd/search/criterion.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>

#include "vsd/core/criterion_syntax.hpp"
#include "vsd/core/error.hpp"
#include "vsd/metrics/metrics.hpp"
#include "vsd/pipeline/run.hpp"
#include "vsd/pipeline/scenes.hpp"
#include "vsd/search/search.hpp"

namespace vsd::search {

namespace {

/// A metric the registry knows but this scenario does not compute gets its own hint.
void rejectUnknownMetrics(const std::vector<std::string>& names, const std::string& where,
                          const std::vector<std::string>& metric_names) {
  for (const auto& name : names) {
    const bool computed = std::find(metric_names.begin(), metric_names.end(), name) != metric_names.end();
    if (computed || metrics::findMetric(name) == nullptr) continue;
    throw ConfigError(fmt::format("{}: metric '{}' is not computed by this scenario (its metrics: {}); add it to "
                                  "the scenario's `metrics:`",
                                  where, name, fmt::join(metric_names, ", ")));
  }
}

/// A single word that is not a criterion of the scenario: a name that does not exist.
void refuseMisspeltName(const std::string& text, const scenario::LogicalScenario& logical) {
  const bool word = !text.empty() && text.find_first_not_of(
                                         "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_") == std::string::npos;
  if (!word || std::isdigit(static_cast<unsigned char>(text.front()))) return;
  std::vector<std::string> names;
  for (const auto& criterion : logical.criteria) names.push_back(criterion.name);
  throw ConfigError(fmt::format("command line: --criterion '{}': neither a comparison (e.g. 'd_min < 2') nor a criterion of {} "
                                "(its criteria: {})",
                                text, logical.sourceFile.string(),
                                names.empty() ? std::string("none") : fmt::format("{}", fmt::join(names, ", "))));
}

/// pipeline::referenceAvoidsSutCollides as an expression over the metrics: "(d_min <= 0) and
/// reference_d_min > 0" — a metric at or below its collision threshold, the reference driver's
/// above every threshold (metrics::MetricSet::collision); empty if no metric has a rule.
std::string collidesWhereReferenceDoesNot(const scenario::LogicalScenario& logical) {
  const metrics::MetricSet metric_set(logical.metrics, pipeline::scenarioAvailability(logical),
                                      logical.sourceFile.string() + ": metrics");
  std::vector<std::string> collides;
  std::vector<std::string> reference_clear;
  for (const auto& name : metric_set.names()) {
    const auto& threshold = metrics::findMetric(name)->collisionAtOrBelow;
    if (!threshold) continue;
    collides.push_back(fmt::format("{} <= {}", name, *threshold));
    reference_clear.push_back(fmt::format("{} > {}", referenceColumn(name), *threshold));
  }
  if (collides.empty()) return "";
  return fmt::format("({}) and {}", fmt::join(collides, " or "), fmt::join(reference_clear, " and "));
}

}  // namespace

Criterion::Criterion(const std::string& text, const scenario::LogicalScenario& logical,
                     const std::vector<std::string>& metric_names) {
  std::string where = "command line: --criterion";  // a usage error (exit 2) when the flag's text is wrong
  if (text.find_first_not_of(" \t") == std::string::npos) {
    throw ConfigError::field("command line", "--criterion", "''",
                             "a criterion over metrics such as 'd_min < 2' or a criterion name of the scenario");
  }
  const auto yaml = std::find_if(logical.criteria.begin(), logical.criteria.end(),
                                 [&](const scenario::Criterion& c) { return c.name == text; });
  if (text == pipeline::kReferenceCriterion) {
    // The regulation's pass criterion by its name: a column only a search with --reference has.
    if (std::find(metric_names.begin(), metric_names.end(), text) == metric_names.end()) {
      throw ConfigError(fmt::format("{} '{}': needs --reference NAME (e.g. --reference r157_reference_driver): "
                                    "it compares the system under test with the reference driver",
                                    where, text));
    }
    name_ = text;
    // Written over the metrics it stands for (d_min <= 0 and reference_d_min > 0), not over its
    // 0/1 column: a surrogate then learns both clearances, which vary smoothly over the inputs,
    // instead of a flag that is 0 nearly everywhere (docs/search.md measures the difference).
    expression_ = collidesWhereReferenceDoesNot(logical);
    if (expression_.empty()) {
      throw ConfigError(fmt::format("{} '{}': needs a scenario whose metrics tell a collision ({}: metrics lists "
                                    "none with a collision rule, such as d_min)",
                                    where, text, logical.sourceFile.string()));
    }
  } else if (yaml != logical.criteria.end()) {
    name_ = yaml->name;
    expression_ = yaml->expression;
    where = yaml->where.empty() ? logical.sourceFile.string() + ": criteria." + yaml->name : yaml->where;
  } else {
    // The one syntax of a criterion flag (compare's too): "criterion" or "name: criterion".
    const auto split = splitNamedCriterion(text, where);
    name_ = split.name;
    expression_ = split.criterion;
    refuseMisspeltName(expression_, logical);
  }
  const CheckedCriterion checked = checkCriterion(expression_, where);
  rejectUnknownMetrics(checked.names, where, metric_names);
  for (std::size_t m = 0; m < metric_names.size(); ++m) {
    if (std::find(checked.names.begin(), checked.names.end(), metric_names[m]) == checked.names.end()) continue;
    used_.push_back(metric_names[m]);
    usedColumns_.push_back(m);
  }
  std::vector<std::string> named;
  for (const auto& criterion : logical.criteria) named.push_back(criterion.name);
  const std::string named_list = named.empty() ? std::string("none defined") : fmt::format("{}", fmt::join(named, ", "));
  try {
    onAll_ = scenario::Expression::compile(checked.expression, metric_names, where);
  } catch (const ConfigError& error) {
    throw ConfigError(fmt::format("{}; the scenario's named criteria: {}", error.what(), named_list));
  }
  if (used_.empty()) {
    throw ConfigError(fmt::format("{}: uses no metric; expected an expression over {} or one of the scenario's "
                                  "criteria ({})",
                                  where, fmt::join(metric_names, ", "), named_list));
  }
  onUsed_ = scenario::Expression::compile(checked.expression, used_, where);
}

std::optional<bool> Criterion::verdict(const std::vector<double>& metric_values) const {
  for (const auto column : usedColumns_) {
    if (column >= metric_values.size() || std::isnan(metric_values[column])) return std::nullopt;
  }
  const double value = onAll_.evaluate(metric_values);
  if (std::isnan(value)) return std::nullopt;
  return value != 0.0;
}

std::optional<bool> Criterion::verdictOfUsed(const std::vector<double>& used_values) const {
  for (const double value : used_values) {
    if (std::isnan(value)) return std::nullopt;
  }
  const double value = onUsed_.evaluate(used_values);
  if (std::isnan(value)) return std::nullopt;
  return value != 0.0;
}

bool Criterion::meetsUsed(const std::vector<double>& used_values) const {
  const double value = onUsed_.evaluate(used_values);
  return !std::isnan(value) && value != 0.0;
}

}  // namespace vsd::search
