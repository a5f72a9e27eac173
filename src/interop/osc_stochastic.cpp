// A ParameterValueDistribution's <Stochastic> part: numberOfTestRuns parameter sets, each
// parameter drawn from its StochasticDistribution (OpenSCENARIO 1.2: ProbabilityDistributionSet,
// UniformDistribution, NormalDistribution, PoissonDistribution, Histogram).
//
// Test run i draws from the stream (seed, i, Inputs) of vsd/core/random.hpp, so a set does
// not change with numberOfTestRuns, and the draws are the same with every standard library
// (std::erfc and std::lgamma aside). The seed is the file's randomSeed, else the run's.

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "osc_template.hpp"
#include "vsd/core/random.hpp"

namespace vsd::interop::osc {

namespace {

/// Test runs a file may ask for (as many sets as a deterministic grid may hold).
constexpr std::int64_t kMaxTestRuns = 10'000'000;
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
  double truncatedNormal(Rng& rng) const;
  double poisson(Rng& rng) const;
};

std::size_t ParameterDraw::pick(Rng& rng) const {
  double total = 0.0;
  for (const double weight : weights) total += weight;
  double point = rng.uniform01() * total;
  std::size_t last_weighted = 0;
  for (std::size_t i = 0; i < weights.size(); ++i) {
    if (weights[i] <= 0.0) continue;
    if (point < weights[i]) return i;
    point -= weights[i];
    last_weighted = i;
  }
  return last_weighted;  // rounding left `point` at the end: never an element of weight 0
}

/// P(X > x) and P(X <= x) of the standard normal distribution, each accurate in its own tail.
double upperTail(double z) { return 0.5 * std::erfc(z / std::sqrt(2.0)); }
double lowerTail(double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); }

/// A normal draw truncated to [lower, upper] by inverting its distribution function: a
/// uniform share of the range's probability, solved by bisection on std::erfc (exact to
/// rounding however little of the distribution the range holds).
double ParameterDraw::truncatedNormal(Rng& rng) const {
  if (stddev == 0.0 || (std::isinf(lower) && std::isinf(upper))) {
    return stddev == 0.0 ? std::clamp(mean, lower, upper) : rng.normal(mean, stddev);
  }
  const double a = (lower - mean) / stddev;
  const double b = (upper - mean) / stddev;
  // Above the mean, work with upper-tail probabilities (they keep their digits there).
  const bool upper_side = a > 0.0;
  const auto tail = [&](double z) { return upper_side ? upperTail(z) : lowerTail(z); };
  const double at_a = tail(a);
  const double at_b = tail(b);
  if (!(std::abs(at_a - at_b) > 0.0)) {
    throw ConfigError(fmt::format("{}: parameter '{}': its Range [{}, {}] holds no share of N({}, {}) that a double "
                                  "can tell (expected a range nearer the expected value)",
                                  where, name, xml::number(lower), xml::number(upper), xml::number(mean),
                                  xml::number(stddev * stddev)));
  }
  const double target = at_a + rng.uniform01() * (at_b - at_a);
  double lo = std::isinf(a) ? std::min(b, 0.0) - 40.0 : a;
  double hi = std::isinf(b) ? std::max(a, 0.0) + 40.0 : b;
  for (int i = 0; i < 200 && lo < hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    // tail() falls with z on the upper side and rises on the lower side.
    const bool before_target = upper_side ? tail(mid) > target : tail(mid) < target;
    (before_target ? lo : hi) = mid;
  }
  return std::clamp(mean + stddev * 0.5 * (lo + hi), lower, upper);
}

/// A Poisson draw: without a Range by Knuth's product of uniforms; with one, by its
/// probabilities over the whole numbers in the Range (exact however far in the tail).
double ParameterDraw::poisson(Rng& rng) const {
  if (std::isinf(upper)) {
    double value = 0.0;
    do {
      const double limit = std::exp(-mean);
      double product = rng.uniform01();
      value = 0.0;
      while (product > limit) {
        product *= rng.uniform01();
        value += 1.0;
      }
    } while (value < lower);
    return value;
  }
  // Past 10,000 counts beyond the first a Poisson of mean <= 500 holds nothing a double keeps.
  const double first = std::max(0.0, std::ceil(lower));
  const double last = std::min(std::floor(upper), first + 10'000.0);
  std::vector<double> log_p;
  for (double k = first; k <= last; k += 1.0) log_p.push_back(k * std::log(mean) - mean - std::lgamma(k + 1.0));
  if (log_p.empty()) {
    throw ConfigError(fmt::format("{}: parameter '{}': its Range [{}, {}] holds no whole number (a Poisson draw is "
                                  "one)", where, name, xml::number(lower), xml::number(upper)));
  }
  const double top = *std::max_element(log_p.begin(), log_p.end());
  double total = 0.0;
  for (double& value : log_p) total += (value = std::exp(value - top));
  double point = rng.uniform01() * total;
  for (std::size_t i = 0; i < log_p.size(); ++i) {
    if (point < log_p[i]) return first + static_cast<double>(i);
    point -= log_p[i];
  }
  return last;
}

std::string ParameterDraw::draw(Rng& rng) const {
  switch (kind) {
    case Kind::Set: return values[pick(rng)];
    case Kind::Uniform: return xml::number(rng.uniform(lower, upper));
    case Kind::Normal: return xml::number(truncatedNormal(rng));
    case Kind::Poisson: return xml::number(poisson(rng));
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
