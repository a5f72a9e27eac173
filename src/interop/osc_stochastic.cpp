// A ParameterValueDistribution's <Stochastic> part: numberOfTestRuns parameter sets, each
// parameter drawn from its StochasticDistribution (OpenSCENARIO 1.2: ProbabilityDistributionSet,
// UniformDistribution, NormalDistribution, PoissonDistribution, Histogram).
//
// Test run i draws from the stream (seed, i, Inputs) of vsd/core/random.hpp - the inputs of
// the i-th concrete scenario - so a set does not change with numberOfTestRuns, and the draws
// are the same with every standard library. The seed is the file's randomSeed, else the run's.

#include <fmt/format.h>

#include <cmath>
#include <limits>

#include "osc_template.hpp"
#include "vsd/core/random.hpp"

namespace vsd::interop::osc {

namespace {

/// Test runs a file may ask for (as many sets as a deterministic grid may hold).
constexpr std::int64_t kMaxTestRuns = 10'000'000;
/// Draws per value of a truncated distribution before its Range is called empty.
constexpr int kMaxRejections = 10'000;
/// Poisson means drawn by multiplying uniforms (exp(-mean) stays a normal double).
constexpr double kMaxPoissonMean = 500.0;

/// One parameter's distribution, read and checked once, drawn once per test run.
struct ParameterDraw {
  enum class Kind { Set, Uniform, Normal, Poisson, Histogram };
  std::string name;
  std::string where;  ///< "file:line: <Element>" of the distribution, for messages
  Kind kind = Kind::Set;
  std::vector<std::string> values;             ///< Set: element values
  std::vector<std::pair<double, double>> bins;  ///< Histogram: [lower, upper) of each bin
  std::vector<double> weights;                  ///< Set, Histogram
  double lower = -std::numeric_limits<double>::infinity();  ///< Range (Uniform: required)
  double upper = std::numeric_limits<double>::infinity();
  double mean = 0.0;    ///< Normal, Poisson
  double stddev = 0.0;  ///< Normal

  std::string draw(Rng& rng) const;

 private:
  std::size_t pick(Rng& rng) const;
  template <typename Draw>
  double truncated(Draw&& draw) const;
};

std::size_t ParameterDraw::pick(Rng& rng) const {
  double total = 0.0;
  for (const double weight : weights) total += weight;
  double point = rng.uniform01() * total;
  for (std::size_t i = 0; i + 1 < weights.size(); ++i) {
    if (point < weights[i]) return i;
    point -= weights[i];
  }
  return weights.size() - 1;
}

template <typename Draw>
double ParameterDraw::truncated(Draw&& draw) const {
  for (int attempt = 0; attempt < kMaxRejections; ++attempt) {
    const double value = draw();
    if (value >= lower && value <= upper) return value;
  }
  throw ConfigError(fmt::format("{}: parameter '{}': {} draws fell outside its Range [{}, {}] (expected a range that "
                                "holds a share of the distribution)",
                                where, name, kMaxRejections, xml::number(lower), xml::number(upper)));
}

std::string ParameterDraw::draw(Rng& rng) const {
  switch (kind) {
    case Kind::Set: return values[pick(rng)];
    case Kind::Uniform: return xml::number(rng.uniform(lower, upper));
    case Kind::Normal: return xml::number(truncated([&] { return rng.normal(mean, stddev); }));
    case Kind::Poisson:
      return xml::number(truncated([&] {
        // Knuth: the count of uniforms whose product stays above exp(-mean).
        const double limit = std::exp(-mean);
        double product = rng.uniform01();
        double count = 0.0;
        while (product > limit) {
          product *= rng.uniform01();
          count += 1.0;
        }
        return count;
      }));
    case Kind::Histogram: {
      const auto& [low, high] = bins[pick(rng)];
      return xml::number(rng.uniform(low, high));
    }
  }
  return {};
}

/// <Range lowerLimit upperLimit>, lower <= upper.
void readRange(const xml::Reader& reader, const pugi::xml_node& range, double& lower, double& upper) {
  reader.requireSubset(range, {});
  lower = reader.number(range, "lowerLimit");
  upper = reader.number(range, "upperLimit");
  if (!(lower <= upper)) {
    reader.fail(range, fmt::format("lowerLimit {} > upperLimit {}", xml::number(lower), xml::number(upper)));
  }
}

void readWeighted(const xml::Reader& reader, const pugi::xml_node& node, const char* element, ParameterDraw& draw) {
  for (const pugi::xml_node& item : node.children(element)) {
    draw.weights.push_back(reader.number(item, "weight", NumberRange::atLeast(0.0)));
    if (draw.kind == ParameterDraw::Kind::Set) {
      reader.requireSubset(item, {});
      draw.values.push_back(reader.text(item, "value"));
    } else {
      reader.requireSubset(item, {"Range"});
      double low = 0.0;
      double high = 0.0;
      readRange(reader, reader.only(item, "Range"), low, high);
      draw.bins.emplace_back(low, high);
    }
  }
  double total = 0.0;
  for (const double weight : draw.weights) total += weight;
  if (draw.weights.empty() || !(total > 0.0)) {
    reader.fail(node, fmt::format("expected at least one <{}> and a weight > 0 among them", element));
  }
}

ParameterDraw readDistribution(const xml::Reader& reader, const pugi::xml_node& node) {
  reader.requireSubset(node, {"ProbabilityDistributionSet", "UniformDistribution", "NormalDistribution",
                              "PoissonDistribution", "Histogram"});
  const pugi::xml_node choice = reader.choice(node, {"ProbabilityDistributionSet", "UniformDistribution",
                                                     "NormalDistribution", "PoissonDistribution", "Histogram"});
  ParameterDraw draw;
  draw.name = reader.text(node, "parameterName");
  draw.where = reader.where(choice);
  const std::string kind = choice.name();
  if (kind == "ProbabilityDistributionSet") {
    reader.requireSubset(choice, {"Element"});
    readWeighted(reader, choice, "Element", draw);
  } else if (kind == "Histogram") {
    draw.kind = ParameterDraw::Kind::Histogram;
    reader.requireSubset(choice, {"Bin"});
    readWeighted(reader, choice, "Bin", draw);
  } else if (kind == "UniformDistribution") {
    draw.kind = ParameterDraw::Kind::Uniform;
    readRange(reader, reader.only(choice, "Range"), draw.lower, draw.upper);
  } else {
    reader.requireSubset(choice, {"Range"});
    draw.kind = kind == "NormalDistribution" ? ParameterDraw::Kind::Normal : ParameterDraw::Kind::Poisson;
    draw.mean = kind == "NormalDistribution" ? reader.number(choice, "expectedValue")
                                             : reader.number(choice, "expectedValue", NumberRange::aboveUpTo(0.0, kMaxPoissonMean));
    if (kind == "NormalDistribution") draw.stddev = std::sqrt(reader.number(choice, "variance", NumberRange::atLeast(0.0)));
    if (const pugi::xml_node range = choice.child("Range")) readRange(reader, range, draw.lower, draw.upper);
  }
  return draw;
}

}  // namespace

std::vector<std::map<std::string, std::string>> drawStochasticSets(const xml::Reader& reader,
                                                                   const pugi::xml_node& stochastic,
                                                                   std::uint64_t run_seed) {
  reader.requireSubset(stochastic, {"StochasticDistribution"});
  const auto runs = reader.integer(stochastic, "numberOfTestRuns", 1, kMaxTestRuns);
  const auto file_seed = reader.optionalNumber(stochastic, "randomSeed", NumberRange::closed(0.0, 9.007199254740992e15));
  if (file_seed && std::floor(*file_seed) != *file_seed) {
    reader.fail(stochastic, fmt::format("randomSeed {}: expected a whole number", xml::number(*file_seed)));
  }
  const std::uint64_t seed = file_seed ? static_cast<std::uint64_t>(*file_seed) : run_seed;
  std::vector<ParameterDraw> draws;
  for (const pugi::xml_node& node : stochastic.children("StochasticDistribution")) {
    draws.push_back(readDistribution(reader, node));
  }
  if (draws.empty()) reader.fail(stochastic, "expected at least one <StochasticDistribution>");
  std::vector<std::map<std::string, std::string>> sets(static_cast<std::size_t>(runs));
  for (std::size_t run = 0; run < sets.size(); ++run) {
    Rng rng = Rng::derive(seed, run, RandomStream::Inputs);
    for (const ParameterDraw& draw : draws) sets[run][draw.name] = draw.draw(rng);
  }
  return sets;
}

}  // namespace vsd::interop::osc
