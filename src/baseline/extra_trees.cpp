#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "vsd/baseline/baseline.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/random.hpp"

namespace vsd::baseline {

void ExtraTreesOptions::validate() const {
  if (trees < 1 || trees > 100000) throw ConfigError::field("extra trees", "trees", std::to_string(trees), "1 .. 100000");
  if (!(maxFeatures > 0.0 && maxFeatures <= 1.0)) {
    throw ConfigError::field("extra trees", "max_features", fmt::format("{}", maxFeatures), "in (0, 1]");
  }
  if (minSamplesSplit < 2) {
    throw ConfigError::field("extra trees", "min_samples_split", std::to_string(minSamplesSplit), ">= 2 (a count)");
  }
}

namespace {

/// A tree in flat arrays: node i splits on feature[i] at threshold[i] (left: <=), or is a
/// leaf (feature -1) holding `outputs` values from value[i * outputs].
struct Tree {
  std::vector<int> feature;
  std::vector<double> threshold;
  std::vector<int> left;
  std::vector<int> right;
  std::vector<double> value;
};

class TreeBuilder {
 public:
  TreeBuilder(const Matrix& x, const Matrix& y, const ExtraTreesOptions& options, Rng& rng)
      : x_(x), y_(y), options_(options), rng_(rng), outputs_(static_cast<int>(y.cols())) {
    features_ = static_cast<int>(x.cols());
    tried_ = std::max(1, static_cast<int>(options.maxFeatures * features_));
  }

  Tree build() {
    std::vector<int> rows(static_cast<std::size_t>(x_.rows()));
    std::iota(rows.begin(), rows.end(), 0);
    grow(rows, 0, static_cast<int>(rows.size()));
    return std::move(tree_);
  }

 private:
  int addLeaf(const std::vector<int>& rows, int begin, int end) {
    const int node = static_cast<int>(tree_.feature.size());
    tree_.feature.push_back(-1);
    tree_.threshold.push_back(0.0);
    tree_.left.push_back(-1);
    tree_.right.push_back(-1);
    for (int o = 0; o < outputs_; ++o) {
      double sum = 0.0;
      for (int i = begin; i < end; ++i) sum += y_(rows[static_cast<std::size_t>(i)], o);
      tree_.value.push_back(sum / (end - begin));
    }
    return node;
  }

  /// Sum over outputs of the sum of squared deviations (n * variance).
  double impurity(const std::vector<int>& rows, int begin, int end) const {
    double total = 0.0;
    for (int o = 0; o < outputs_; ++o) {
      double sum = 0.0;
      double sum_sq = 0.0;
      for (int i = begin; i < end; ++i) {
        const double v = y_(rows[static_cast<std::size_t>(i)], o);
        sum += v;
        sum_sq += v * v;
      }
      total += sum_sq - sum * sum / (end - begin);
    }
    return total;
  }

  int grow(std::vector<int>& rows, int begin, int end) {
    const int n = end - begin;
    if (n < options_.minSamplesSplit || impurity(rows, begin, end) <= 1e-12) return addLeaf(rows, begin, end);

    // Features in random order; like sklearn, constant features are skipped and do not
    // count towards the features tried, and the search goes on until one is found.
    std::vector<int> order(static_cast<std::size_t>(features_));
    std::iota(order.begin(), order.end(), 0);
    int best_feature = -1;
    double best_threshold = 0.0;
    double best_score = std::numeric_limits<double>::infinity();
    int tried = 0;
    for (int f = features_; f > 0 && tried < tried_; --f) {
      const auto pick = static_cast<int>(rng_.below(static_cast<std::uint64_t>(f)));
      std::swap(order[static_cast<std::size_t>(pick)], order[static_cast<std::size_t>(f - 1)]);
      const int feature = order[static_cast<std::size_t>(f - 1)];
      double lo = std::numeric_limits<double>::infinity();
      double hi = -std::numeric_limits<double>::infinity();
      for (int i = begin; i < end; ++i) {
        const double v = x_(rows[static_cast<std::size_t>(i)], feature);
        lo = std::min(lo, v);
        hi = std::max(hi, v);
      }
      if (!(hi > lo + 1e-12)) continue;  // constant in this node
      ++tried;
      const double threshold = rng_.uniform(lo, hi);
      // Score = impurity left + right (lower is better), from running sums.
      std::vector<double> sum_left(static_cast<std::size_t>(outputs_), 0.0);
      std::vector<double> sum_right(static_cast<std::size_t>(outputs_), 0.0);
      double sq_left = 0.0;
      double sq_right = 0.0;
      int count_left = 0;
      for (int i = begin; i < end; ++i) {
        const int row = rows[static_cast<std::size_t>(i)];
        const bool left = x_(row, feature) <= threshold;
        count_left += left ? 1 : 0;
        for (int o = 0; o < outputs_; ++o) {
          const double v = y_(row, o);
          (left ? sum_left : sum_right)[static_cast<std::size_t>(o)] += v;
          (left ? sq_left : sq_right) += v * v;
        }
      }
      const int count_right = n - count_left;
      if (count_left == 0 || count_right == 0) continue;
      double score = sq_left + sq_right;
      for (int o = 0; o < outputs_; ++o) {
        score -= sum_left[static_cast<std::size_t>(o)] * sum_left[static_cast<std::size_t>(o)] / count_left;
        score -= sum_right[static_cast<std::size_t>(o)] * sum_right[static_cast<std::size_t>(o)] / count_right;
      }
      if (score < best_score) {
        best_score = score;
        best_feature = feature;
        best_threshold = threshold;
      }
    }
    if (best_feature < 0) return addLeaf(rows, begin, end);

    const auto middle = std::partition(rows.begin() + begin, rows.begin() + end, [&](int row) {
      return x_(row, best_feature) <= best_threshold;
    });
    const int split = static_cast<int>(middle - rows.begin());
    const int node = static_cast<int>(tree_.feature.size());
    tree_.feature.push_back(best_feature);
    tree_.threshold.push_back(best_threshold);
    tree_.left.push_back(-1);
    tree_.right.push_back(-1);
    tree_.value.insert(tree_.value.end(), static_cast<std::size_t>(outputs_), 0.0);
    const int left = grow(rows, begin, split);
    const int right = grow(rows, split, end);
    tree_.left[static_cast<std::size_t>(node)] = left;
    tree_.right[static_cast<std::size_t>(node)] = right;
    return node;
  }

  const Matrix& x_;
  const Matrix& y_;
  const ExtraTreesOptions& options_;
  Rng& rng_;
  int outputs_;
  int features_ = 0;
  int tried_ = 1;
  Tree tree_;
};

}  // namespace

struct ExtraTrees::Impl {
  ExtraTreesOptions options;
  std::vector<Tree> trees;
  int outputs = 0;
  int features = 0;
};

ExtraTrees::ExtraTrees(ExtraTreesOptions options) : impl_(std::make_unique<Impl>()) {
  options.validate();
  impl_->options = options;
}
ExtraTrees::~ExtraTrees() = default;
ExtraTrees::ExtraTrees(ExtraTrees&&) noexcept = default;
ExtraTrees& ExtraTrees::operator=(ExtraTrees&&) noexcept = default;

void ExtraTrees::fit(const Matrix& x, const Matrix& y) {
  if (x.rows() == 0 || x.rows() != y.rows() || y.cols() == 0 || x.cols() == 0) {
    throw ConfigError(fmt::format("extra trees: cannot fit {} x {} inputs to {} x {} targets", x.rows(), x.cols(),
                                  y.rows(), y.cols()));
  }
  impl_->outputs = static_cast<int>(y.cols());
  impl_->features = static_cast<int>(x.cols());
  impl_->trees.clear();
  for (int t = 0; t < impl_->options.trees; ++t) {
    Rng rng = Rng::derive(impl_->options.seed, static_cast<std::uint64_t>(t), RandomStream::Training);
    impl_->trees.push_back(TreeBuilder(x, y, impl_->options, rng).build());
  }
}

namespace {

/// The leaf of `tree` that input row `r` of x falls into.
std::size_t leafOf(const Tree& tree, const Matrix& x, Eigen::Index r) {
  int node = 0;
  while (tree.feature[static_cast<std::size_t>(node)] >= 0) {
    const auto n = static_cast<std::size_t>(node);
    node = x(r, tree.feature[n]) <= tree.threshold[n] ? tree.left[n] : tree.right[n];
  }
  return static_cast<std::size_t>(node);
}

}  // namespace

void ExtraTrees::checkPredictable(const Matrix& x) const {
  if (impl_->trees.empty()) throw Error("extra trees: predict() before fit()");
  if (x.cols() != impl_->features) {
    throw ConfigError(fmt::format("extra trees: fitted on {} inputs, asked with {}", impl_->features, x.cols()));
  }
}

Matrix ExtraTrees::predict(const Matrix& x) const {
  Matrix result = Matrix::Zero(x.rows(), impl_->outputs);
  for (const auto& tree_prediction : predictPerTree(x)) result += tree_prediction;
  return result / static_cast<double>(impl_->trees.size());
}

std::vector<Matrix> ExtraTrees::predictPerTree(const Matrix& x) const {
  checkPredictable(x);
  const auto outputs = static_cast<std::size_t>(impl_->outputs);
  std::vector<Matrix> predictions;
  predictions.reserve(impl_->trees.size());
  for (const auto& tree : impl_->trees) {
    Matrix prediction(x.rows(), impl_->outputs);
    for (Eigen::Index r = 0; r < x.rows(); ++r) {
      const std::size_t leaf = leafOf(tree, x, r);
      for (std::size_t o = 0; o < outputs; ++o) {
        prediction(r, static_cast<Eigen::Index>(o)) = tree.value[leaf * outputs + o];
      }
    }
    predictions.push_back(std::move(prediction));
  }
  return predictions;
}

std::size_t ExtraTrees::nodes() const {
  std::size_t count = 0;
  for (const auto& tree : impl_->trees) count += tree.feature.size();
  return count;
}

std::vector<double> meanAbsoluteError(const Matrix& predicted, const Matrix& truth) {
  std::vector<double> errors;
  for (Eigen::Index c = 0; c < truth.cols(); ++c) errors.push_back((predicted.col(c) - truth.col(c)).cwiseAbs().mean());
  return errors;
}

}  // namespace vsd::baseline
