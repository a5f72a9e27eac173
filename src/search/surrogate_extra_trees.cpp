// `extra-trees`: the baseline module's extra trees, one forest per metric the
// criterion reads. Probability: over the trees t and shifts z in {-1, 0, +1}, the
// fraction of predictions m_t(x) + z * s(x) that meet the criterion, s(x) being the
// trees' standard deviation at x. The shifts keep the probability above 0 next to the
// observed critical region (fully grown trees only predict values they have seen).
// With SurrogateOptions::probability "tail": the Gaussian tail of the trees' mean and
// spread (tailProbability), which is above 0 everywhere and so still ranks the
// candidates when no tree comes near a rare criterion.

#include <algorithm>
#include <cmath>

#include "search_internal.hpp"
#include "vsd/baseline/baseline.hpp"
#include "vsd/search/surrogate.hpp"

namespace vsd::search {

namespace {

class ExtraTreesSurrogate final : public Surrogate {
 public:
  explicit ExtraTreesSurrogate(const SurrogateOptions& options) : options_(options) {}

  bool guidesSelection() const override { return true; }

  void fit(const TrainingSet& data) override {
    const Matrix& x = data.x;
    const Matrix& y = data.y;
    forests_.clear();
    quantiles_.clear();
    for (Eigen::Index target = 0; target < y.cols(); ++target) {
      Eigen::VectorXd values = y.col(target);
      if (options_.rankTargets) {
        quantiles_.emplace_back(values.data(), values.data() + values.size());
        std::sort(quantiles_.back().begin(), quantiles_.back().end());
        for (Eigen::Index r = 0; r < values.size(); ++r) values(r) = rankOf(quantiles_.back(), values(r));
      }
      forests_.push_back(detail::fitForest(x, values, options_.trees, options_.seed + static_cast<std::uint64_t>(target)));
    }
  }

  std::vector<double> probability(const CandidateSet& candidates, const Criterion& criterion) const override {
    const Matrix& x = candidates.x;
    // per target: one [n, 1] prediction per tree
    std::vector<std::vector<Matrix>> per_tree;
    for (const auto& forest : forests_) per_tree.push_back(forest.predictPerTree(x));
    const std::size_t targets = per_tree.size();
    const std::size_t trees = per_tree.front().size();
    static const std::vector<double> kShifts = {-1.0, 0.0, 1.0};
    std::vector<double> result(static_cast<std::size_t>(x.rows()));
    std::vector<double> values(targets);
    std::vector<double> spread(targets);
    std::vector<double> centre(targets);
    for (Eigen::Index r = 0; r < x.rows(); ++r) {
      for (std::size_t m = 0; m < targets; ++m) {
        double sum = 0.0;
        double squares = 0.0;
        for (std::size_t t = 0; t < trees; ++t) {
          const double value = per_tree[m][t](r, 0);
          sum += value;
          squares += value * value;
        }
        const double mean = sum / static_cast<double>(trees);
        centre[m] = mean;
        spread[m] = std::sqrt(std::max(0.0, squares / static_cast<double>(trees) - mean * mean));
      }
      if (options_.probability == "tail") {
        result[static_cast<std::size_t>(r)] =
            options_.rankTargets ? tailProbability(centre, spread, criterion, [this](std::vector<double>& v) { toMetrics(v); })
                                 : tailProbability(centre, spread, criterion);
        continue;
      }
      double probability = 0.0;
      for (std::size_t t = 0; t < trees; ++t) {
        for (std::size_t m = 0; m < targets; ++m) values[m] = per_tree[m][t](r, 0);
        probability += options_.rankTargets ? shiftedRankProbability(values, spread, criterion)
                                            : shiftedProbability(values, spread, kShifts, criterion);
      }
      result[static_cast<std::size_t>(r)] = probability / static_cast<double>(trees);
    }
    return result;
  }

 private:
  /// Mid-rank of `value` among the sorted values, scaled to 0..1.
  static double rankOf(const std::vector<double>& sorted, double value) {
    const auto below = std::lower_bound(sorted.begin(), sorted.end(), value) - sorted.begin();
    const auto upto = std::upper_bound(sorted.begin(), sorted.end(), value) - sorted.begin();
    const double n = static_cast<double>(sorted.size());
    return n > 1 ? (0.5 * static_cast<double>(below + upto - 1)) / (n - 1.0) : 0.5;
  }

  /// The metric value at rank u: linear between the sorted values, beyond them along the
  /// line through the end value and the one a tenth of the data further in.
  static double valueAt(const std::vector<double>& sorted, double u) {
    const double n = static_cast<double>(sorted.size());
    if (sorted.size() < 2) return sorted.empty() ? 0.0 : sorted.front();
    const double position = u * (n - 1.0);
    const auto reach = std::max<std::size_t>(1, sorted.size() / 10);
    if (position <= 0.0) {
      const double slope = (sorted[reach] - sorted.front()) / static_cast<double>(reach);
      return sorted.front() + position * slope;
    }
    if (position >= n - 1.0) {
      const double slope = (sorted.back() - sorted[sorted.size() - 1 - reach]) / static_cast<double>(reach);
      return sorted.back() + (position - (n - 1.0)) * slope;
    }
    const auto low = static_cast<std::size_t>(position);
    const double fraction = position - static_cast<double>(low);
    return sorted[low] + fraction * (sorted[low + 1] - sorted[low]);
  }

  void toMetrics(std::vector<double>& values) const {
    for (std::size_t m = 0; m < values.size(); ++m) values[m] = valueAt(quantiles_[m], values[m]);
  }

  double shiftedRankProbability(const std::vector<double>& centre, const std::vector<double>& spread,
                                const Criterion& criterion) const {
    std::vector<double> values(centre.size());
    std::size_t meeting = 0;
    for (const double z : {-1.0, 0.0, 1.0}) {
      for (std::size_t m = 0; m < centre.size(); ++m) values[m] = centre[m] + z * spread[m];
      toMetrics(values);
      if (criterion.meetsUsed(values)) ++meeting;
    }
    return static_cast<double>(meeting) / 3.0;
  }

  SurrogateOptions options_;
  std::vector<baseline::ExtraTrees> forests_;
  std::vector<std::vector<double>> quantiles_;  ///< per target with rankTargets: its fitted values, sorted
};

}  // namespace

std::unique_ptr<Surrogate> makeExtraTreesSurrogate(const SurrogateOptions& options) {
  return std::make_unique<ExtraTreesSurrogate>(options);
}

}  // namespace vsd::search
