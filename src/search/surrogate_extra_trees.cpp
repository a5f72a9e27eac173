// `extra-trees`: the baseline module's extra trees, one forest per metric the
// criterion reads. Probability: over the trees t and shifts z in {-1, 0, +1}, the
// fraction of predictions m_t(x) + z * s(x) that meet the criterion, s(x) being the
// trees' standard deviation at x. The shifts keep the probability above 0 next to the
// observed critical region (fully grown trees only predict values they have seen).
// With SurrogateOptions::probability "tail": the Gaussian tail of the trees' mean and
// spread (tailProbability), which is above 0 everywhere and so still ranks the
// candidates when no tree comes near a rare criterion.

#include <cmath>

#include "vsd/baseline/baseline.hpp"
#include "vsd/search/surrogate.hpp"

namespace vsd::search {

namespace {

class ExtraTreesSurrogate final : public Surrogate {
 public:
  explicit ExtraTreesSurrogate(const SurrogateOptions& options) : options_(options) {}

  bool guidesSelection() const override { return true; }

  void fit(const Matrix& x, const Matrix& y) override {
    forests_.clear();
    for (Eigen::Index target = 0; target < y.cols(); ++target) {
      baseline::ExtraTreesOptions tree_options;
      tree_options.trees = options_.trees;
      tree_options.seed = options_.seed + static_cast<std::uint64_t>(target);
      baseline::ExtraTrees forest(tree_options);
      forest.fit(x, y.col(target));
      forests_.push_back(std::move(forest));
    }
  }

  std::vector<double> probability(const Matrix& x, const Criterion& criterion) const override {
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
        result[static_cast<std::size_t>(r)] = tailProbability(centre, spread, criterion);
        continue;
      }
      double probability = 0.0;
      for (std::size_t t = 0; t < trees; ++t) {
        for (std::size_t m = 0; m < targets; ++m) values[m] = per_tree[m][t](r, 0);
        probability += shiftedProbability(values, spread, kShifts, criterion);
      }
      result[static_cast<std::size_t>(r)] = probability / static_cast<double>(trees);
    }
    return result;
  }

 private:
  SurrogateOptions options_;
  std::vector<baseline::ExtraTrees> forests_;
};

}  // namespace

std::unique_ptr<Surrogate> makeExtraTreesSurrogate(const SurrogateOptions& options) {
  return std::make_unique<ExtraTreesSurrogate>(options);
}

}  // namespace vsd::search
