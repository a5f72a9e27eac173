#include "vsd/interop/distribution.hpp"

#include <fmt/format.h>

#include <cmath>

#include "openscenario_names.hpp"
#include "vsd/core/error.hpp"
#include "vsd/interop/openscenario.hpp"
#include "xml_support.hpp"

namespace fs = std::filesystem;

namespace vsd::interop {

namespace {

using scenario::Distribution;

bool constantBounds(const Distribution& distribution) {
  return distribution.min.isConstant() && distribution.max.isConstant();
}

double value(const scenario::Expression& expression) { return expression.evaluate({}); }

/// Why an input cannot be written, or empty if it can.
std::string obstacle(const scenario::InputSpec& input, bool grid) {
  const Distribution& distribution = input.distribution;
  switch (distribution.kind) {
    case Distribution::Kind::Uniform:
      if (!constantBounds(distribution)) {
        return fmt::format("dependent range [{}, {}] (OpenSCENARIO distributions are independent per parameter)",
                           distribution.min.text(), distribution.max.text());
      }
      return {};
    case Distribution::Kind::Normal:
      if (!distribution.mean.isConstant() || !distribution.stddev.isConstant() ||
          (distribution.hasBounds && !constantBounds(distribution))) {
        return "normal distribution with parameters that depend on other inputs";
      }
      if (grid && !distribution.hasBounds) return "normal distribution without bounds has no finite grid";
      return {};
    case Distribution::Kind::Constant:
      if (!distribution.value.isConstant()) return fmt::format("value '{}' depends on other inputs", distribution.value.text());
      return {};
    case Distribution::Kind::Choice:
      return {};
  }
  return "unknown distribution";
}

std::vector<double> setValues(const Distribution& distribution) {
  if (distribution.kind == Distribution::Kind::Choice) return distribution.choices;
  return {value(distribution.value)};
}

void addRange(pugi::xml_node parent, double lower, double upper, double scale) {
  xml::child(parent, "Range", {{"lowerLimit", xml::number(lower * scale)}, {"upperLimit", xml::number(upper * scale)}});
}

void addStochastic(pugi::xml_node parent, const scenario::InputSpec& input) {
  const Distribution& distribution = input.distribution;
  const double scale = distribution.unitScale;
  pugi::xml_node node = xml::child(parent, "StochasticDistribution", {{"parameterName", input.name}});
  switch (distribution.kind) {
    case Distribution::Kind::Uniform:
      addRange(node.append_child("UniformDistribution"), value(distribution.min), value(distribution.max), scale);
      break;
    case Distribution::Kind::Normal: {
      const double stddev = value(distribution.stddev) * scale;
      pugi::xml_node normal = xml::child(node, "NormalDistribution",
                                         {{"expectedValue", xml::number(value(distribution.mean) * scale)},
                                          {"variance", xml::number(stddev * stddev)}});
      if (distribution.hasBounds) addRange(normal, value(distribution.min), value(distribution.max), scale);
      break;
    }
    case Distribution::Kind::Constant:
    case Distribution::Kind::Choice: {
      pugi::xml_node set = node.append_child("ProbabilityDistributionSet");
      const auto values = setValues(distribution);
      for (const double element : values) {
        xml::child(set, "Element", {{"value", xml::number(element * scale)}, {"weight", xml::number(1.0 / static_cast<double>(values.size()))}});
      }
      break;
    }
  }
}

void addGrid(pugi::xml_node parent, const scenario::InputSpec& input, int points) {
  const Distribution& distribution = input.distribution;
  const double scale = distribution.unitScale;
  pugi::xml_node node = xml::child(parent, "DeterministicSingleParameterDistribution", {{"parameterName", input.name}});
  if (distribution.kind == Distribution::Kind::Uniform || distribution.kind == Distribution::Kind::Normal) {
    const double lower = value(distribution.min);
    const double upper = value(distribution.max);
    pugi::xml_node range = xml::child(node, "DistributionRange", {{"stepWidth", xml::number((upper - lower) * scale / (points - 1))}});
    addRange(range, lower, upper, scale);
    return;
  }
  pugi::xml_node set = node.append_child("DistributionSet");
  for (const double element : setValues(distribution)) xml::child(set, "Element", {{"value", xml::number(element * scale)}});
}

std::vector<std::pair<std::string, std::string>> randomVariations(const scenario::LogicalScenario& logical) {
  std::vector<std::pair<std::string, std::string>> variations;
  const char* why = "random variation drawn per point or step, not a scenario parameter";
  if (!logical.road.centreNoise.isZero()) variations.emplace_back("road.centre_noise", why);
  if (!logical.road.laneWidthNoise.isZero()) variations.emplace_back("road.lane_width_noise", why);
  if (!logical.ego.headingNoise.isZero()) variations.emplace_back("vehicles.ego.heading_noise_deg", why);
  for (const auto& other : logical.others) {
    if (!other.speedNoise.isZero()) variations.emplace_back(fmt::format("vehicles.{}.speed_noise", other.id), why);
  }
  return variations;
}

}  // namespace

void DistributionOptions::validate() const {
  if (grid && *grid < 2) throw ConfigError::field("command line", "--grid", std::to_string(*grid), "at least 2 points per input");
  if (!grid && samples < 1) throw ConfigError::field("command line", "--samples", std::to_string(samples), ">= 1");
}

DistributionSummary writeParameterDistribution(const scenario::LogicalScenario& logical,
                                               const DistributionOptions& options) {
  options.validate();
  DistributionSummary summary;
  summary.output = options.output;
  std::vector<const scenario::InputSpec*> expressible;
  for (const auto& input : logical.inputs) {
    const std::string why = obstacle(input, options.grid.has_value());
    if (why.empty()) {
      expressible.push_back(&input);
      summary.written.push_back(input.name);
    } else {
      summary.notWritten.emplace_back(input.name, why);
    }
  }
  if (expressible.empty()) {
    throw ConfigError(fmt::format("{}: no input can be written as an OpenSCENARIO distribution", logical.sourceFile.string()));
  }
  const auto variations = randomVariations(logical);
  summary.notWritten.insert(summary.notWritten.end(), variations.begin(), variations.end());

  std::string description = fmt::format("vsd-sumo logical scenario {} ({}): its inputs as {}", logical.name,
                                        logical.sourceFile.filename().string(),
                                        options.grid ? "a deterministic grid" : "stochastic distributions");
  if (!summary.notWritten.empty()) {
    description += ". Not expressible here:";
    for (const auto& [name, why] : summary.notWritten) description += fmt::format(" {}: {};", name, why);
  }
  pugi::xml_document document;
  pugi::xml_node root = document.append_child("OpenSCENARIO");
  xml::child(root, "FileHeader",
             {{"author", "vsd-sumo"},
              {"date", fileDate(logical.sourceFile)},
              {"description", description},
              {"revMajor", std::to_string(names::kRevMajor)},
              {"revMinor", std::to_string(names::kRevMinor)}});
  pugi::xml_node distribution = root.append_child("ParameterValueDistribution");
  // Relative to the distribution file when it sits near the scenario, else absolute.
  const fs::path scenario_file = fs::absolute(logical.sourceFile).lexically_normal();
  const fs::path relative = scenario_file.lexically_relative(fs::absolute(options.output).parent_path());
  const bool nearby = !relative.empty() && std::distance(relative.begin(), relative.end()) <= 4;
  xml::child(distribution, "ScenarioFile", {{"filepath", (nearby ? relative : scenario_file).string()}});
  for (const auto& [name, why] : summary.notWritten) {
    distribution.append_child(pugi::node_comment).set_value(fmt::format(" not expressible: {}: {} ", name, why).c_str());
  }
  if (options.grid) {
    pugi::xml_node deterministic = distribution.append_child("Deterministic");
    for (const auto* input : expressible) addGrid(deterministic, *input, *options.grid);
  } else {
    pugi::xml_node stochastic = xml::child(distribution, "Stochastic",
                                           {{"numberOfTestRuns", std::to_string(options.samples)},
                                            {"randomSeed", std::to_string(options.seed)}});
    for (const auto* input : expressible) addStochastic(stochastic, *input);
  }
  xml::save(document, options.output);
  return summary;
}

std::string DistributionSummary::report() const {
  std::string text = fmt::format("wrote {}: {}\n", output.string(), fmt::join(written, ", "));
  if (!notWritten.empty()) {
    text += "  not expressible in OpenSCENARIO (listed in the file's description):\n";
    for (const auto& [name, why] : notWritten) text += fmt::format("    {}: {}\n", name, why);
  }
  return text;
}

}  // namespace vsd::interop
