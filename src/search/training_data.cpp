// Inputs of concrete scenarios without simulating them, their normalisation, and
// the surrogate's training matrices built from the executions.

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "search_internal.hpp"
#include "vsd/core/random.hpp"
#include "vsd/scenario/concrete_scenario.hpp"

namespace vsd::search::detail {

Normaliser::Normaliser(const Matrix& raw) {
  low_ = raw.colwise().minCoeff();
  const Eigen::RowVectorXd range = raw.colwise().maxCoeff() - low_;
  // A constant input maps to 0 instead of dividing by zero.
  scale_ = range.unaryExpr([](double r) { return r > 0.0 ? 1.0 / r : 0.0; });
}

Matrix Normaliser::apply(const Matrix& raw) const {
  return (raw.rowwise() - low_).array().rowwise() * scale_.array();
}

std::vector<double> Normaliser::apply(const std::vector<double>& raw) const {
  Matrix row(1, static_cast<Eigen::Index>(raw.size()));
  for (std::size_t i = 0; i < raw.size(); ++i) row(0, static_cast<Eigen::Index>(i)) = raw[i];
  const Matrix normalised = apply(row);
  return {normalised.data(), normalised.data() + normalised.size()};
}

Matrix sampleInputs(const SearchContext& context, std::uint64_t first, std::uint64_t count) {
  const auto inputs = static_cast<Eigen::Index>(context.logical->inputs.size());
  Matrix result(static_cast<Eigen::Index>(count), inputs);
  for (std::uint64_t i = 0; i < count; ++i) {
    const auto concrete = scenario::sampleConcreteScenario(context.logical, context.options.seed, first + i);
    for (Eigen::Index c = 0; c < inputs; ++c) {
      result(static_cast<Eigen::Index>(i), c) = concrete.inputs[static_cast<std::size_t>(c)];
    }
  }
  return result;
}

namespace {

/// Infinite values (ttc_min when the Ego never closes in) become a finite value beyond
/// the largest finite one, so that regression sees "far from critical" instead of inf.
void capInfinities(Matrix& y) {
  for (Eigen::Index c = 0; c < y.cols(); ++c) {
    double low = std::numeric_limits<double>::infinity();
    double high = -low;
    for (Eigen::Index r = 0; r < y.rows(); ++r) {
      if (std::isfinite(y(r, c))) {
        low = std::min(low, y(r, c));
        high = std::max(high, y(r, c));
      }
    }
    if (!std::isfinite(low)) low = high = 0.0;
    const double margin = std::max(1.0, 0.5 * (high - low));
    for (Eigen::Index r = 0; r < y.rows(); ++r) {
      if (y(r, c) == std::numeric_limits<double>::infinity()) y(r, c) = high + margin;
      if (y(r, c) == -std::numeric_limits<double>::infinity()) y(r, c) = low - margin;
    }
  }
}

}  // namespace

std::unique_ptr<Surrogate> fitSurrogate(const SearchContext& context, const std::vector<const Execution*>& rows,
                                        std::uint64_t round) {
  const auto& columns = context.criterion->usedColumns();
  std::vector<const Execution*> usable;
  for (const auto* row : rows) {
    const bool computable = row->failure.empty() && std::none_of(columns.begin(), columns.end(), [&](std::size_t c) {
                              return std::isnan(row->metrics[c]);
                            });
    if (computable) usable.push_back(row);
  }
  if (usable.size() < 2) return nullptr;
  const auto inputs = static_cast<Eigen::Index>(context.logical->inputs.size());
  Matrix x(static_cast<Eigen::Index>(usable.size()), inputs);
  Matrix y(static_cast<Eigen::Index>(usable.size()), static_cast<Eigen::Index>(columns.size()));
  for (std::size_t r = 0; r < usable.size(); ++r) {
    for (Eigen::Index c = 0; c < inputs; ++c) x(static_cast<Eigen::Index>(r), c) = usable[r]->inputs[static_cast<std::size_t>(c)];
    for (std::size_t m = 0; m < columns.size(); ++m) {
      y(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(m)) = usable[r]->metrics[columns[m]];
    }
  }
  capInfinities(y);
  TrainingSet data{context.normaliser.apply(x), std::move(y), columns, {}, {}};
  if (context.surrogate->learnsFromScenes) {
    data.scenes = roundFiles(context, round, "dataset.h5");
    data.priorScenes = context.priors;
  }
  SurrogateOptions options;
  options.seed = mix64(context.options.seed ^ mix64(round + 1));
  options.trees = context.options.trees;
  options.probability = context.options.probability;
  options.rankTargets = context.options.rankTargets;
  options.bnnEpochs = context.options.bnnEpochs;
  options.threads = context.options.threads;
  options.metricSet = context.metricSet;
  options.modelFile = roundFile(context, round, "vectornet.pt");
  options.priorModelFile = context.options.outputDir / ".rounds" / "vectornet-prior.pt";
  options.priorSeed = mix64(context.options.seed);
  options.vectornetSteps = context.options.vectornetSteps;
  options.futureSamples = context.options.futureSamples;
  auto surrogate = context.surrogate->make(options);
  surrogate->fit(data);
  return surrogate;
}

}  // namespace vsd::search::detail
