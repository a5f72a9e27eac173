// `bnn`: the baseline module's Bayesian neural network (Bayes by Backprop) on the
// inputs, fitted jointly on the metrics the criterion reads. Probability: the
// fraction of 16 equally probable quantiles of its Gaussian posterior predictive,
// mean + z_q * std (the same z_q for every metric), that meet the criterion.

#include <cmath>

#include "vsd/baseline/baseline.hpp"
#include "vsd/search/surrogate.hpp"

namespace vsd::search {

namespace {

/// z_q = Phi^-1((q + 0.5) / 16), q = 0..15.
const std::vector<double>& normalQuantiles() {
  static const std::vector<double> quantiles = {-1.8627, -1.3180, -1.0100, -0.7764, -0.5791, -0.4023,
                                                -0.2372, -0.0784, 0.0784,  0.2372,  0.4023,  0.5791,
                                                0.7764,  1.0100,  1.3180,  1.8627};
  return quantiles;
}

class BnnSurrogate final : public Surrogate {
 public:
  explicit BnnSurrogate(const SurrogateOptions& options) {
    baseline::BnnOptions bnn;
    bnn.seed = options.seed;
    bnn.epochs = options.bnnEpochs;
    bnn.threads = options.threads;
    bnnOptions_ = bnn;
  }

  bool guidesSelection() const override { return true; }

  void fit(const TrainingSet& data) override {
    const Matrix& x = data.x;
    const Matrix& y = data.y;
    network_ = std::make_unique<baseline::BayesianNetwork>(bnnOptions_);
    network_->fit(x, y);
  }

  std::vector<double> probability(const CandidateSet& candidates, const Criterion& criterion) const override {
    const Matrix& x = candidates.x;
    const auto prediction = network_->predict(x);
    const auto targets = static_cast<std::size_t>(prediction.mean.cols());
    std::vector<double> result(static_cast<std::size_t>(x.rows()));
    std::vector<double> mean(targets);
    std::vector<double> spread(targets);
    for (Eigen::Index r = 0; r < x.rows(); ++r) {
      for (std::size_t m = 0; m < targets; ++m) {
        mean[m] = prediction.mean(r, static_cast<Eigen::Index>(m));
        spread[m] = prediction.std(r, static_cast<Eigen::Index>(m));
      }
      result[static_cast<std::size_t>(r)] = shiftedProbability(mean, spread, normalQuantiles(), criterion);
    }
    return result;
  }

 private:
  baseline::BnnOptions bnnOptions_;
  std::unique_ptr<baseline::BayesianNetwork> network_;
};

}  // namespace

std::unique_ptr<Surrogate> makeBnnSurrogate(const SurrogateOptions& options) {
  return std::make_unique<BnnSurrogate>(options);
}

}  // namespace vsd::search
