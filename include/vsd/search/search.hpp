#pragma once
// `vsd-sumo search`: find the concrete scenarios of a logical scenario that meet a
// criterion (e.g. `d_min < 2`) with few executions, and estimate how often they occur.
//
// The loop (one checkpoint per round, <out>/checkpoint.json, written atomically):
//   round 0   the initial design: the first `initial` concrete scenarios of the logical
//             scenario's random stream (sample indices 0, 1, ..., as `run` with the same seed);
//   round r   fit the surrogate on every executed scenario (normalised inputs -> the
//             criterion's metrics); sample a pool of `pool` candidates (own sample indices,
//             never simulated); acquisition = p * (1 + diversity * d), p the predicted
//             probability of meeting the criterion, d in [0, 1] the normalised distance to
//             the nearest critical scenario found or candidate already chosen; the best
//             (1 - estimateShare) of the round are "acquired"; the rest are "importance" draws
//             from the other candidates with probability
//             q_i = 0.8 p_i / sum(p) + 0.2 / N_B
//             (with replacement; a candidate drawn twice is simulated once). Everything is
//             simulated by the pipeline's batch simulation (the code `run` uses);
//   until     `budget` executions. A re-run with the same --out resumes after the last
//             finished round without repeating an execution; same seed, same choices.
//
// Rate estimate of P(criterion) under the logical scenario's distribution (unbiased):
// stratified importance sampling over the rounds' pools, see src/search/estimate.cpp. The
// random surrogate is plain Monte Carlo with a Wilson interval.
//
// Outputs in <out>, one set (core/files.hpp: OutputFolder; manifest.json last, with every
// file's hash and size): concrete.csv (every execution), failures.csv, learning_curve.csv,
// coverage.csv, estimate.json, traces.h5 and dataset.h5 (as `run` writes them: a search's
// executions can train a model), report.html. Resume state, not part of the set:
// checkpoint.json and .rounds/ (each round's traces and scenes).

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "vsd/baseline/baseline.hpp"
#include "vsd/search/surrogate.hpp"

namespace vsd::search {

struct SearchOptions {
  std::filesystem::path scenarioFile;
  std::filesystem::path outputDir;    ///< required
  std::string criterion;              ///< expression over metrics or a criterion name of the scenario
  std::string surrogate = "extra-trees";  ///< a name of `surrogates`
  /// Where `surrogate` is looked up. Carried with the options rather than passed beside them
  /// because everything that reads the options (validation, the search's context, its
  /// checkpoint and training data) needs the entry; shared and const, so that copies of the
  /// options are cheap and nothing changes it under a running search.
  std::shared_ptr<const SurrogateRegistry> surrogates = builtinSurrogates();
  std::uint64_t budget = 2000;        ///< simulations in total, initial design included (executionBudget())
  std::uint64_t initial = 200;        ///< executions of the initial design (random stream)
  std::uint64_t roundSize = 100;      ///< executions per later round
  double estimateShare = 0.4;         ///< share of each later round drawn by importance sampling (0..1)
  std::uint64_t pool = 10000;         ///< candidates scored per round (and for the rate estimate)
  double diversity = 1.0;             ///< weight of the distance term in the acquisition (>= 0)
  /// The surrogates' defaults are the baselines' (`baseline` fits the same models; docs/cli.md "Vocabulary").
  int trees = baseline::ExtraTreesOptions{}.trees;  ///< extra-trees surrogate: trees per metric
  std::string probability = "shifts"; ///< extra-trees: "shifts" or "tail" (SurrogateOptions::probability)
  bool rankTargets = false;           ///< extra-trees: fit metric ranks (SurrogateOptions::rankTargets)
  int bnnEpochs = baseline::BnnOptions{}.epochs;    ///< bnn surrogate: epochs per fit
  /// vectornet: datasets (files or run/export folders) of other functional scenarios or
  /// maps mixed into its training from the first round; their step and horizon must be
  /// the scenario's (ConfigError naming the folder and the value otherwise).
  std::vector<std::filesystem::path> priors;
  int vectornetSteps = 400;           ///< vectornet: optimizer steps of each round's training (from scratch)
  int futureSamples = 16;             ///< vectornet: sampled futures per candidate (probability = share meeting it)
  std::uint64_t seed = 1;
  int jobs = 1;                       ///< worker processes for the simulations
  int threads = 2;                    ///< libtorch threads (bnn, vectornet)
  double egoStepCost = 0.0;           ///< s of extra wall time per Ego step (pipeline::RunOptions::egoStepCost)
  /// `--reference NAME`: every execution also runs with this built-in controller as the
  /// Ego (pipeline::RunOptions::reference), so each costs two simulations of the budget and
  /// the criterion may read the reference columns (`reference_<metric>`, and
  /// pipeline::kReferenceCriterion, the regulation's pass criterion). Empty: none.
  std::string reference;
  std::string commandLine;            ///< recorded in the manifest
  /// Throws ConfigError naming the flag and the accepted range (e.g. budget < initial).
  void validate() const;
  /// Simulations one execution costs: 2 with --reference (the system and the reference driver), else 1.
  std::uint64_t simulationsPerExecution() const { return reference.empty() ? 1 : 2; }
  /// Executions the budget pays for.
  std::uint64_t executionBudget() const { return budget / simulationsPerExecution(); }
};

/// The columns of an execution's values (Execution::metrics) for a scenario computing
/// `metricNames`: those, then with a `reference` controller `reference_<metric>` for each
/// and pipeline::kReferenceCriterion. A criterion is checked against these names.
std::vector<std::string> executionColumns(const std::vector<std::string>& metricNames, const std::string& reference);
/// The column of the reference driver's value of `metric` ("reference_d_min").
std::string referenceColumn(const std::string& metric);

/// One executed concrete scenario.
struct Execution {
  std::uint64_t round = 0;
  std::string origin;             ///< "initial", "random" (random stream), "acquired" or "importance"
  std::uint64_t sample = 0;       ///< sample index: the scenario is sampleConcreteScenario(seed, sample)
  double acquisition = 0.0;       ///< NaN unless acquired
  double predicted = 0.0;         ///< surrogate's probability when chosen; NaN in round 0 / for random
  std::string failure;            ///< why the simulation failed; empty when it completed
  int verdict = -1;               ///< 1 critical, 0 not, -1 unknown (failed run or NaN metric)
  std::vector<double> inputs;
  std::vector<double> metrics;
  // Its part in the rate estimate (draws == 0: none, e.g. acquired and never drawn):
  std::uint64_t draws = 0;        ///< times drawn for the estimate (importance draws may repeat)
  double weight = 0.0;            ///< 1 / (N q): importance weight (N = pool); 1 for random-stream draws
  bool fromRandomStream() const { return origin == "initial" || origin == "random"; }
};

/// P(criterion) under the logical scenario's distribution.
struct RateEstimate {
  std::string method;             ///< "monte-carlo" or "importance-sampling"
  double estimate = 0.0;
  double low = 0.0;               ///< 95 % interval
  double high = 0.0;
  std::uint64_t draws = 0;        ///< contributions the estimate averages
  std::uint64_t randomExecutions = 0;  ///< random-stream executions (round 0 and random rounds)
  std::uint64_t randomCritical = 0;
  double randomEstimate = 0.0;    ///< critical share of the random-stream executions alone
  double randomLow = 0.0;         ///< its Wilson 95 % interval
  double randomHigh = 0.0;
  /// Width of plain random sampling's Wilson interval with the whole budget, at this estimate.
  double sameBudgetRandomWidth = 0.0;
};

struct SearchSummary {
  std::string functionalScenario;
  std::string criterion;          ///< name
  std::string expression;
  std::string surrogate;
  std::string reference;          ///< --reference controller; empty: none
  std::uint64_t seed = 0;
  std::uint64_t executions = 0;   ///< concrete scenarios executed (with a reference: two simulations each)
  std::uint64_t critical = 0;     ///< executions meeting the criterion
  std::uint64_t failedRuns = 0;   ///< simulations that did not complete
  std::uint64_t resumedFrom = 0;  ///< executions already in the checkpoint when started
  std::uint64_t rounds = 0;
  std::size_t coverageCells = 0;  ///< distinct cells (3 per normalised input) holding a critical scenario
  bool criterionSeenInInitialDesign = false;
  RateEstimate estimate;
  double seconds = 0.0;
  double surrogateSeconds = 0.0;  ///< fitting + candidate sampling + scoring, all rounds
  double simulationSeconds = 0.0;
  std::vector<Execution> executionsList;
  std::vector<std::filesystem::path> outputs;
  std::string report() const;
};

/// Runs (or resumes) a search. Throws ConfigError for bad options, an unknown criterion,
/// metric or surrogate, or a checkpoint made with other options; SumoError when a round's
/// simulations all fail (the checkpoint keeps every finished round).
SearchSummary runSearch(const SearchOptions& options);

/// P(criterion) by plain Monte Carlo over `samples` concrete scenarios drawn with `seed`
/// (sample indices 0 .. samples - 1 of the logical scenario's stream, as `run --seed`),
/// simulated and judged as a search with `options` judges its executions (its criterion,
/// its --reference): the reference a search's rate estimate is checked against
/// (`bench search --true-rate-samples`). Runs without a verdict count as not critical, as in
/// the search's estimate. options.outputDir is not used (nothing is written).
struct MonteCarloRate {
  std::uint64_t seed = 0;
  std::uint64_t samples = 0;
  std::uint64_t critical = 0;
  std::uint64_t withoutVerdict = 0;  ///< failed simulations or metrics not computable
  double estimate = 0.0;             ///< critical / samples
  double low = 0.0;                  ///< Wilson 95 % interval
  double high = 0.0;
  double seconds = 0.0;
};
MonteCarloRate monteCarloRate(SearchOptions options, std::uint64_t seed, std::uint64_t samples);

/// Removes a search folder's search (search --force, after the output policy recognised
/// the folder): the files its manifest lists, the manifest, the checkpoint and the round
/// files, so that the next search there starts afresh. Files no manifest lists stay.
/// Throws DatasetError if the folder has no readable manifest.
void discardSearchState(const std::filesystem::path& folder);

/// The HTML report of one or more searches of one criterion (report module): their
/// learning curves and rate estimates with intervals side by side.
std::string searchReportHtml(const std::vector<const SearchSummary*>& searches,
                             const std::vector<std::pair<std::string, std::string>>& provenance);

/// Wilson score interval (95 %) of `successes` out of `trials`; {0, 1} when trials == 0.
std::pair<double, double> wilsonInterval(std::uint64_t successes, std::uint64_t trials);

}  // namespace vsd::search
