// The surrogate registry and the probability rule the model surrogates share.

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "vsd/core/error.hpp"
#include "search_internal.hpp"
#include "vsd/search/surrogate.hpp"

namespace vsd::search {

SurrogateRegistry SurrogateRegistry::withBuiltins() {
  SurrogateRegistry registry;
  registry.add({"random", "plain Monte Carlo: executes the logical scenario's random stream (the reference)",
                makeRandomSurrogate});
  registry.add({"extra-trees",
                "extra trees per criterion metric on the inputs; probability from the spread over the trees",
                makeExtraTreesSurrogate});
  registry.add({"bnn", "Bayesian neural network on the inputs; probability from its posterior predictive mean and std",
                makeBnnSurrogate});
  registry.add({"vectornet",
                "VectorNet (kinematic decoder) on the vectorized scenes, retrained each round; probability = share of "
                "its sampled futures whose metrics meet the criterion (--reference columns: extra trees on the inputs)",
                makeVectorNetSurrogate, /*learnsFromScenes=*/true});
  return registry;
}

std::shared_ptr<const SurrogateRegistry> builtinSurrogates() {
  // Const and built from withBuiltins(): a shared default, not a list anyone can add to.
  static const auto builtins = std::make_shared<const SurrogateRegistry>(SurrogateRegistry::withBuiltins());
  return builtins;
}

void SurrogateRegistry::add(SurrogateEntry entry) {
  if (entry.name.empty() || !entry.make) throw ConfigError("a surrogate entry needs a name and a factory");
  for (const auto& existing : entries_) {
    if (existing.name == entry.name) throw ConfigError(fmt::format("surrogate '{}' is registered twice", entry.name));
  }
  entries_.push_back(std::move(entry));
}

const SurrogateEntry& SurrogateRegistry::find(const std::string& name) const {
  std::string known;
  for (const auto& entry : entries_) {
    if (entry.name == name) return entry;
    known += (known.empty() ? "" : ", ") + entry.name;
  }
  throw ConfigError(fmt::format("--surrogate '{}': unknown surrogate (known: {})", name, known));
}

double shiftedProbability(const std::vector<double>& centre, const std::vector<double>& spread,
                          const std::vector<double>& shifts, const Criterion& criterion) {
  std::vector<double> values(centre.size());
  std::size_t meeting = 0;
  for (const double z : shifts) {
    for (std::size_t m = 0; m < centre.size(); ++m) values[m] = centre[m] + z * spread[m];
    if (criterion.meetsUsed(values)) ++meeting;
  }
  return static_cast<double>(meeting) / static_cast<double>(shifts.size());
}

namespace {

/// Smallest z (to ~1e-6) at which some move of every metric by +-z spreads gives `wanted`
/// as the criterion's verdict: the first of the grid 0, 0.1, ..., 6 that does, refined by
/// bisection from the grid point before it; infinity if none.
double smallestMove(const std::vector<double>& centre, const std::vector<double>& spread, const Criterion& criterion,
                    const std::function<void(std::vector<double>&)>& to_metrics, bool wanted) {
  const std::size_t metrics = centre.size();
  // Every sign pattern for up to 3 metrics; beyond that all up or all down.
  const std::size_t patterns = metrics <= 3 ? (std::size_t{1} << metrics) : 2;
  std::vector<double> values(metrics);
  auto gives = [&](double z, std::size_t pattern) {
    for (std::size_t m = 0; m < metrics; ++m) {
      const bool up = metrics <= 3 ? ((pattern >> m) & 1U) != 0 : pattern == 1;
      values[m] = centre[m] + (up ? z : -z) * spread[m];
    }
    if (to_metrics) to_metrics(values);
    return criterion.meetsUsed(values) == wanted;
  };
  for (int step = 0; step <= 60; ++step) {
    for (std::size_t pattern = 0; pattern < patterns; ++pattern) {
      if (!gives(0.1 * step, pattern)) continue;
      if (step == 0) return 0.0;
      double low = 0.1 * (step - 1);
      double high = 0.1 * step;
      for (int i = 0; i < 20; ++i) {
        const double middle = 0.5 * (low + high);
        (gives(middle, pattern) ? high : low) = middle;
      }
      return high;
    }
  }
  return std::numeric_limits<double>::infinity();
}

double standardNormalCdf(double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); }

}  // namespace

double tailProbability(const std::vector<double>& centre, const std::vector<double>& spread,
                       const Criterion& criterion, const std::function<void(std::vector<double>&)>& toMetrics) {
  std::vector<double> values = centre;
  if (toMetrics) toMetrics(values);
  const bool meets = criterion.meetsUsed(values);
  if (std::all_of(spread.begin(), spread.end(), [](double s) { return !(s > 0.0); })) return meets ? 1.0 : 0.0;
  if (meets) return standardNormalCdf(smallestMove(centre, spread, criterion, toMetrics, false));
  return standardNormalCdf(-smallestMove(centre, spread, criterion, toMetrics, true));
}

namespace detail {

baseline::ExtraTrees fitForest(const Matrix& x, const Eigen::VectorXd& y, int trees, std::uint64_t seed) {
  baseline::ExtraTreesOptions options;
  options.trees = trees;
  options.seed = seed;
  baseline::ExtraTrees forest(options);
  forest.fit(x, y);
  return forest;
}

}  // namespace detail

}  // namespace vsd::search
