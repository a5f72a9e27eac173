#pragma once
// Regression metamodels on concrete inputs (the paper's baselines): extra trees
// and a Bayesian neural network. They map a logical scenario's inputs x to
// evaluation metrics y, per functional scenario. Free of libtorch.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace vsd::baseline {

using Matrix = Eigen::MatrixXd;  ///< rows = samples

/// Extremely randomized trees (Geurts et al. 2006) for regression, as scikit-learn's
/// ExtraTreesRegressor: no bootstrap; at every node `maxFeatures` features are drawn
/// without replacement, one cut per feature uniformly between the node's min and max,
/// and the cut with the largest decrease of the summed output variance wins. Multi-output.
struct ExtraTreesOptions {
  int trees = 100;
  double maxFeatures = 1.0;  ///< fraction of the features tried per node (sklearn's float max_features)
  int minSamplesSplit = 2;
  std::uint64_t seed = 1;
  void validate() const;  ///< ConfigError naming the option
};

class ExtraTrees {
 public:
  explicit ExtraTrees(ExtraTreesOptions options = {});
  ~ExtraTrees();
  ExtraTrees(ExtraTrees&&) noexcept;
  ExtraTrees& operator=(ExtraTrees&&) noexcept;

  /// x [n, d], y [n, outputs]; throws ConfigError for empty or mismatched data.
  void fit(const Matrix& x, const Matrix& y);
  Matrix predict(const Matrix& x) const;
  /// One [n, outputs] prediction per tree (their mean is predict()): the forest's spread.
  std::vector<Matrix> predictPerTree(const Matrix& x) const;
  std::size_t nodes() const;

 private:
  void checkPredictable(const Matrix& x) const;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Bayes by Backprop (Blundell et al. 2015): a multilayer perceptron whose weights are
/// Gaussians (mean, softplus(rho)) with a N(0, prior_std^2) prior, trained on the
/// evidence lower bound with the local reparameterisation trick, plus a learned
/// homoscedastic noise per output. Inputs and targets are standardised. Predictions
/// average `samples` weight draws: mean, and std = sqrt(noise^2 + variance of the draws).
struct BnnOptions {
  int hidden = 64;
  int layers = 2;
  int epochs = 400;
  int batchSize = 128;
  double learningRate = 3e-3;
  double priorStd = 1.0;
  int samples = 64;          ///< weight draws per prediction
  std::uint64_t seed = 1;
  int threads = 2;           ///< libtorch threads (OpenBLAS stays single-threaded)
  void validate() const;
};

struct BnnPrediction {
  Matrix mean;  ///< [n, outputs]
  Matrix std;   ///< [n, outputs], predictive standard deviation
};

class BayesianNetwork {
 public:
  explicit BayesianNetwork(BnnOptions options = {});
  ~BayesianNetwork();
  BayesianNetwork(BayesianNetwork&&) noexcept;
  BayesianNetwork& operator=(BayesianNetwork&&) noexcept;

  void fit(const Matrix& x, const Matrix& y);
  BnnPrediction predict(const Matrix& x) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Concrete inputs and metrics of a run (concrete.csv), completed rows only.
struct MetricTable {
  std::filesystem::path path;
  std::string functionalScenario;
  std::vector<std::string> inputNames;
  std::vector<std::string> targetNames;
  Matrix inputs;               ///< [n, inputs]
  Matrix targets;              ///< [n, targets]
  std::vector<std::uint64_t> samples;  ///< sample index of each row
  std::size_t skipped = 0;     ///< failed runs or non-finite targets left out
};

/// Reads a run's concrete.csv (or its folder). `inputs` empty: every column that is
/// neither bookkeeping nor a metric. Throws DatasetError naming the file and column
/// for a missing column, an unknown metric, mixed functional scenarios or no usable row.
MetricTable readMetricTable(const std::filesystem::path& csv_or_run, const std::vector<std::string>& targets,
                            const std::vector<std::string>& inputs = {});

/// The functional scenario of a run's concrete.csv (its first row).
std::string functionalScenarioOf(const std::filesystem::path& csv_or_run);

/// The concrete.csv of a run folder (checked against the folder's manifest, as every
/// reader of a run folder does), or the given path if it is a table itself. Throws
/// DatasetError naming the path for an incomplete folder or an HDF5 file (a dataset is
/// not what baseline learns from).
std::filesystem::path concreteTableOf(const std::filesystem::path& run);

/// Mean absolute error per column.
std::vector<double> meanAbsoluteError(const Matrix& predicted, const Matrix& truth);

}  // namespace vsd::baseline

namespace vsd::baseline {

/// `vsd-sumo baseline`: fit a metamodel on one run's concrete.csv, evaluate it on another's.
/// Extra trees are fitted per target (one forest per metric, as scikit-learn's single-output
/// ExtraTreesRegressor on each column); the BNN standardises its targets and fits them jointly.
struct BaselineOptions {
  std::filesystem::path train;             ///< run folder (or its concrete.csv)
  std::filesystem::path test;              ///< run folder (or its concrete.csv) of the same functional scenario
  std::string model = "extra-trees";       ///< extra-trees | bnn (the names of search's surrogates; "et": old name)
  std::vector<std::string> targets;        ///< metrics to predict
  std::vector<std::string> inputs;         ///< default: every input column
  std::size_t maxTrainRows = 0;            ///< use the first N completed rows (0: all)
  std::filesystem::path predictionsCsv;    ///< optional: per test row truth, prediction (and std)
  ExtraTreesOptions extraTrees;
  BnnOptions bnn;
};

/// A baseline model as its registry entry describes it (src/baseline/run_baseline.cpp).
struct BaselineModel {
  std::string name;                   ///< --model value (also the name of search's surrogate)
  std::vector<std::string> oldNames;  ///< still accepted, deprecated
  std::string title;                  ///< in reports ("extra trees")
};

/// Every baseline model, in registry order.
std::vector<BaselineModel> baselineModels();

struct BaselineReport {
  std::string model;
  std::string modelTitle;  ///< the entry's title
  std::string functionalScenario;
  std::size_t trainRows = 0;
  std::size_t testRows = 0;
  std::size_t skipped = 0;
  std::vector<std::string> targets;
  std::vector<std::string> units;     ///< per target ("m", "m/s^2")
  std::vector<double> mae;            ///< per target, in its unit
  std::vector<double> meanStd;        ///< BNN: mean predictive std per target (empty for ET)
  double fitSeconds = 0.0;
  double predictSeconds = 0.0;
  std::string report() const;
};

/// Throws ConfigError/DatasetError for unknown models or metrics, missing columns, or a
/// test set of another functional scenario than the training set.
BaselineReport runBaseline(const BaselineOptions& options);

}  // namespace vsd::baseline
