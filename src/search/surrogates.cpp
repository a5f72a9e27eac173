// The surrogate registry and the probability rule the model surrogates share.

#include <fmt/format.h>

#include "vsd/core/error.hpp"
#include "vsd/search/surrogate.hpp"

namespace vsd::search {

const std::vector<SurrogateEntry>& surrogateRegistry() {
  static const std::vector<SurrogateEntry> entries = {
      {"random", "plain Monte Carlo: executes the logical scenario's random stream (the reference)",
       makeRandomSurrogate},
      {"extra-trees", "extra trees per criterion metric on the inputs; probability from the spread over the trees",
       makeExtraTreesSurrogate},
      {"bnn", "Bayesian neural network on the inputs; probability from its posterior predictive mean and std",
       makeBnnSurrogate},
  };
  return entries;
}

const SurrogateEntry& findSurrogate(const std::string& name) {
  std::string known;
  for (const auto& entry : surrogateRegistry()) {
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

}  // namespace vsd::search
