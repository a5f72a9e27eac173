#pragma once
// Pieces of the search loop shared by its source files (not a public header).

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "vsd/baseline/baseline.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/random.hpp"
#include "vsd/metrics/metrics.hpp"
#include "vsd/scenario/logical_scenario.hpp"
#include "vsd/search/criterion.hpp"
#include "vsd/search/search.hpp"
#include "vsd/search/surrogate.hpp"

namespace vsd::search::detail {

/// One extra-trees forest of `trees` trees on x -> y, seeded `seed`: the model of one
/// criterion column in the surrogates that fit the inputs (extra-trees, and vectornet's
/// --reference columns).
baseline::ExtraTrees fitForest(const Matrix& x, const Eigen::VectorXd& y, int trees, std::uint64_t seed);

/// Sample-index ranges of the streams (disjoint, so no concrete scenario is drawn twice):
/// the random stream starts at 0; round r's candidates at kPoolBase + r * kPoolStride;
/// the rate estimate's pool (and the input normalisation) at kEstimateBase.
constexpr std::uint64_t kPoolBase = std::uint64_t{1} << 40;
constexpr std::uint64_t kPoolStride = std::uint64_t{1} << 28;
constexpr std::uint64_t kEstimateBase = std::uint64_t{1} << 50;
constexpr std::uint64_t kMaxPool = kPoolStride;
/// Share of the importance proposal spread evenly over the pool: bounds every weight by 1 / share.
constexpr double kDefensiveShare = 0.2;
/// Inputs sampled to fix the normalisation of every input to [0, 1].
constexpr std::uint64_t kNormalisationSamples = 2000;

/// Maps the logical scenario's inputs to about [0, 1] (min/max of a fixed sample).
class Normaliser {
 public:
  Normaliser() = default;
  explicit Normaliser(const Matrix& raw);
  Matrix apply(const Matrix& raw) const;
  std::vector<double> apply(const std::vector<double>& raw) const;

 private:
  Eigen::RowVectorXd low_;
  Eigen::RowVectorXd scale_;
};

/// What every step of one search reads.
struct SearchContext {
  SearchOptions options;
  std::shared_ptr<const scenario::LogicalScenario> logical;
  std::shared_ptr<const metrics::MetricSet> metricSet;
  std::vector<std::string> metricNames;  ///< metricSet->names(): what a run computes and its files hold
  /// Execution::metrics' columns: metricNames, then with --reference the reference driver's
  /// metrics (`reference_<name>`) and pipeline::kReferenceCriterion. The criterion reads these.
  std::vector<std::string> columnNames;
  std::unique_ptr<Criterion> criterion;
  const SurrogateEntry* surrogate = nullptr;
  bool guides = false;  ///< the surrogate selects (false: Monte Carlo)
  std::string scenarioSha256;
  std::vector<std::filesystem::path> priors;  ///< dataset files of --prior, checked against the scenario
  Normaliser normaliser;
};

/// Inputs of concrete scenarios first, first + 1, ..., first + count - 1 (not simulated).
Matrix sampleInputs(const SearchContext& context, std::uint64_t first, std::uint64_t count);

/// A fresh surrogate for `round`, fitted on the executions (rows with the criterion's
/// metrics computable); nullptr when fewer than 2 such rows exist.
std::unique_ptr<Surrogate> fitSurrogate(const SearchContext& context, const std::vector<const Execution*>& rows,
                                        std::uint64_t round);

/// Checkpoint state: every execution of the finished rounds.
struct SearchState {
  std::uint64_t rounds = 0;
  std::vector<Execution> executions;
  /// SHA-256 of each finished round's files by name ("traces.h5", "dataset.h5"), in round order.
  std::vector<std::map<std::string, std::string>> roundFileSha256;
};
/// Reads <out>/checkpoint.json if present — before any work: throws ConfigError if it was
/// made with other options (naming the option and both values), DatasetError if it is
/// unreadable, edited (its checksum) or if a round's files are missing or are not the
/// ones it recorded (another search's, or changed).
std::optional<SearchState> readCheckpoint(const SearchContext& context);
/// Writes the checkpoint with the SHA-256 of every round's files (hashing the rounds not
/// yet in state.roundFileSha256) and a checksum of its own contents.
void writeCheckpoint(const SearchContext& context, SearchState& state);

RateEstimate estimateRate(const SearchContext& context, const std::vector<Execution>& executions);

/// The importance proposal q over a round's pool (search.cpp): 0 for the `acquired`
/// candidates, (1 - kDefensiveShare) p_i / sum(p) + kDefensiveShare / N_B for the others.
std::vector<double> importanceProposal(const std::vector<double>& probability, const std::vector<bool>& acquired);
/// `count` draws with replacement from `proposal`: pool position -> times drawn.
std::map<std::size_t, std::uint64_t> drawFromPool(const std::vector<double>& proposal, std::uint64_t count, Rng& rng);

/// Bins per normalised input of the failure-region coverage (cells = bins^inputs).
constexpr int kCoverageBins = 3;
/// The coverage cell of an execution's inputs (one bin index per input).
std::vector<int> coverageCell(const SearchContext& context, const Execution& execution);
/// Distinct cells holding a critical scenario among the first `count` executions.
std::size_t coverageCells(const SearchContext& context, const std::vector<Execution>& executions, std::size_t count);

/// Round `round`'s traces or scenes ("traces.h5", "dataset.h5"), kept in <out>/.rounds/
/// (not part of the output set) until the search's files are assembled from them.
std::filesystem::path roundFile(const SearchContext& context, std::uint64_t round, const std::string& file);

/// The first `rounds` rounds' files `file`, in round order; DatasetError naming the first
/// one missing (a folder from before .rounds/ existed, or files removed by hand).
std::vector<std::filesystem::path> roundFiles(const SearchContext& context, std::uint64_t rounds,
                                              const std::string& file);

/// Stages concrete.csv, failures.csv, learning_curve.csv, coverage.csv, estimate.json,
/// traces.h5, dataset.h5 (joined from the rounds' files) and report.html, and commits
/// them with the manifest (core/files.hpp: OutputFolder). Returns the committed paths.
std::vector<std::filesystem::path> commitSearchFolder(const SearchContext& context, OutputFolder& folder,
                                                      const SearchSummary& summary, const std::string& started);

}  // namespace vsd::search::detail
