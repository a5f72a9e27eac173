// `random`: plain Monte Carlo, the reference every other surrogate is compared with.

#include "vsd/search/surrogate.hpp"

namespace vsd::search {

namespace {

class RandomSurrogate final : public Surrogate {
 public:
  bool guidesSelection() const override { return false; }
  void fit(const TrainingSet&) override {}
  /// Monte Carlo has no model: every candidate is equally likely to be critical.
  std::vector<double> probability(const CandidateSet& candidates, const Criterion&) const override {
    return std::vector<double>(static_cast<std::size_t>(candidates.x.rows()), 0.0);
  }
};

}  // namespace

std::unique_ptr<Surrogate> makeRandomSurrogate(const SurrogateOptions&) { return std::make_unique<RandomSurrogate>(); }

}  // namespace vsd::search
