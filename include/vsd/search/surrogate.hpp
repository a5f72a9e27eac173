#pragma once
// Surrogates of `vsd-sumo search`: models fitted on the executed concrete scenarios
// (normalised inputs -> the metrics a criterion reads) that predict, for candidates
// not yet simulated, the probability of meeting the criterion. One registry entry
// per surrogate (name, description, factory, abilities); an unknown name lists the known ones.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "vsd/search/criterion.hpp"
#include "vsd/vector/scene.hpp"

namespace vsd::metrics {
class MetricSet;
}

namespace vsd::search {

using Matrix = Eigen::MatrixXd;  ///< rows = concrete scenarios

/// What a surrogate learns from: the executions whose criterion metrics are computable.
struct TrainingSet {
  Matrix x;  ///< [n, inputs] normalised to about [0, 1]
  Matrix y;  ///< [n, criterion.usedMetrics()] finite (infinities capped)
  /// Where each column of y stands among the execution's columns (Criterion::usedColumns):
  /// below the metric set's size a metric of the Ego's own run, beyond it a --reference
  /// column (executionColumns).
  std::vector<std::size_t> columns;
  /// Vectorized scenes of every completed execution with its simulated future (the rounds'
  /// dataset.h5 files, in round order). For scene models.
  std::vector<std::filesystem::path> scenes;
  /// The --prior datasets (other functional scenarios or maps). For scene models.
  std::vector<std::filesystem::path> priorScenes;
};

/// The candidates of one round (sampled, never simulated).
struct CandidateSet {
  Matrix x;  ///< [n, inputs] normalised
  /// The vectorized scene of row i before simulation (pipeline::plannedScene); throws
  /// ConfigError when it cannot be planned (a vehicle off its road: SUMO fails it too).
  std::function<vector::VectorizedScene(std::size_t row)> scene;
};

/// Settings shared by every surrogate; each takes what applies to it.
struct SurrogateOptions {
  std::uint64_t seed = 1;  ///< derived per round by the loop, so a resumed search refits identically
  int trees = 50;          ///< extra-trees (and vectornet's --reference columns): forest size per target metric
  int bnnEpochs = 200;     ///< bnn: training epochs per fit
  int threads = 2;         ///< bnn: libtorch threads
  /// extra-trees: how the trees' predictions become a probability: "shifts" (share of
  /// tree predictions shifted by -1, 0, +1 spreads that meet the criterion) or "tail"
  /// (tailProbability of the trees' mean and spread).
  std::string probability = "shifts";
  /// extra-trees: fit each metric's empirical rank (0..1) instead of its value, and map
  /// predictions back through the empirical quantiles, extrapolated linearly beyond the
  /// observed range (so that a criterion below every observed value gets a probability).
  bool rankTargets = false;
  /// vectornet: the metric set whose names() the criterion indexes (metrics of predicted futures).
  std::shared_ptr<const metrics::MetricSet> metricSet;
  /// vectornet: where this round's model is written.
  std::filesystem::path modelFile;
  /// vectornet with --prior: the model pre-trained on the prior datasets alone, written once
  /// per search (seeded with `priorSeed`) and fine-tuned from in every round.
  std::filesystem::path priorModelFile;
  std::uint64_t priorSeed = 1;
  int vectornetSteps = 400;   ///< vectornet: optimizer steps of each round's training
  int futureSamples = 16;     ///< vectornet: sampled futures per candidate
};

class Surrogate {
 public:
  virtual ~Surrogate() = default;
  /// False for plain Monte Carlo: the loop then executes the random stream only.
  virtual bool guidesSelection() const = 0;
  /// Fits on every execution so far (n >= 2).
  virtual void fit(const TrainingSet& data) = 0;
  /// Predicted probability (0..1) that each candidate meets the criterion.
  virtual std::vector<double> probability(const CandidateSet& candidates, const Criterion& criterion) const = 0;
};

struct SurrogateEntry {
  std::string name;
  std::string description;  ///< one line: what it fits and where its probability comes from
  std::function<std::unique_ptr<Surrogate>(const SurrogateOptions&)> make;
  /// It learns from the vectorized scenes (the rounds' datasets and --prior) and judges the
  /// criterion on the Ego's predicted futures (values that are not metrics of the Ego's own
  /// trajectory, such as the --reference driver's outcome, it must learn otherwise).
  bool learnsFromScenes = false;
};

/// The surrogates a search can name, one entry each, in a fixed order. A registry is an
/// object handed to its users, never a process-wide list: the built-ins come from
/// withBuiltins(); a test or a tool with a surrogate of its own adds it to its own registry
/// and hands that to the search (SearchOptions::surrogates).
class SurrogateRegistry {
 public:
  /// The built-in surrogates (the one list: src/search/surrogates.cpp).
  static SurrogateRegistry withBuiltins();
  /// Adds a surrogate written outside this module (its own file and this one call).
  /// Throws ConfigError for a name that is taken or an entry without a name or a factory.
  void add(SurrogateEntry entry);
  /// Throws ConfigError "--surrogate 'x': unknown surrogate (known: random, extra-trees, bnn, vectornet)".
  const SurrogateEntry& find(const std::string& name) const;
  const std::vector<SurrogateEntry>& entries() const { return entries_; }

 private:
  std::vector<SurrogateEntry> entries_;
};

/// The built-in surrogates (SurrogateRegistry::withBuiltins()), built once and never changed:
/// what a search uses unless it is handed another registry.
std::shared_ptr<const SurrogateRegistry> builtinSurrogates();

// Factories, one per file (surrogate_*.cpp); listed in SurrogateRegistry::withBuiltins().
std::unique_ptr<Surrogate> makeRandomSurrogate(const SurrogateOptions& options);
std::unique_ptr<Surrogate> makeExtraTreesSurrogate(const SurrogateOptions& options);
std::unique_ptr<Surrogate> makeBnnSurrogate(const SurrogateOptions& options);
std::unique_ptr<Surrogate> makeVectorNetSurrogate(const SurrogateOptions& options);

/// Fraction of the shifted predictions `centre + z * spread` (z from `shifts`) that meet
/// the criterion: the spread-based probability both model surrogates use.
double shiftedProbability(const std::vector<double>& centre, const std::vector<double>& spread,
                          const std::vector<double>& shifts, const Criterion& criterion);

/// Gaussian tail probability that N(centre, spread^2) per metric meets the criterion,
/// continuous everywhere (ranks candidates far from the criterion by how far): z = the
/// smallest number of spreads (up to 6; grid 0.1, then bisection) by which the centre must move, every
/// metric up or down, to meet it; p = Phi(-z). A centre that meets it already gets
/// Phi(z'), z' the smallest move that leaves it. Zero spread: 1 or 0.
/// `toMetrics` (optional) maps values on the scale the model predicts on (e.g. ranks) to
/// metric values in place before the criterion judges them.
double tailProbability(const std::vector<double>& centre, const std::vector<double>& spread,
                       const Criterion& criterion,
                       const std::function<void(std::vector<double>&)>& toMetrics = {});

}  // namespace vsd::search
