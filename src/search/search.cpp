#include "vsd/search/search.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <set>
#include <tuple>

#include "search_internal.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/interrupt.hpp"
#include "vsd/core/log.hpp"
#include "vsd/core/progress.hpp"
#include "vsd/core/random.hpp"
#include "vsd/core/statistics.hpp"
#include "vsd/metrics/metrics.hpp"
#include "vsd/pipeline/outcome_files.hpp"
#include "vsd/pipeline/run.hpp"
#include "vsd/pipeline/scenes.hpp"
#include "vsd/road/road_geometry.hpp"
#include "vsd/report/numbers.hpp"
#include "vsd/scenario/concrete_scenario.hpp"
#include "vsd/vector/dataset.hpp"

namespace fs = std::filesystem;

namespace vsd::search {

using detail::SearchContext;
using detail::SearchState;

std::string referenceColumn(const std::string& metric) { return "reference_" + metric; }

std::vector<std::string> executionColumns(const std::vector<std::string>& metricNames, const std::string& reference) {
  std::vector<std::string> columns = metricNames;
  if (reference.empty()) return columns;
  for (const auto& name : metricNames) columns.push_back(referenceColumn(name));
  columns.emplace_back(pipeline::kReferenceCriterion);
  return columns;
}

void SearchOptions::validate() const {
  const std::string where = "command line";
  if (outputDir.empty()) throw ConfigError::field(where, "--out", "''", "an output folder");
  if (initial < 2) throw ConfigError::field(where, "--initial", std::to_string(initial), ">= 2");
  if (budget < initial * simulationsPerExecution()) {
    throw ConfigError::field(where, "--budget", std::to_string(budget),
                             fmt::format(">= --initial ({}) x {}: the initial design alone needs that many simulations",
                                         initial, simulationsPerExecution()));
  }
  if (budget > 10'000'000) throw ConfigError::field(where, "--budget", std::to_string(budget), "<= 10000000");
  if (roundSize < 1 || roundSize > 100'000) {
    throw ConfigError::field(where, "--round", std::to_string(roundSize), "1 .. 100000");
  }
  if (!(estimateShare >= 0.0 && estimateShare <= 1.0)) {
    throw ConfigError::field(where, "--estimate-share", fmt::format("{}", estimateShare), "0 .. 1");
  }
  if (pool < 1 || pool > detail::kMaxPool) {
    throw ConfigError::field(where, "--pool", std::to_string(pool), fmt::format("1 .. {}", detail::kMaxPool));
  }
  if (!(diversity >= 0.0 && std::isfinite(diversity))) {
    throw ConfigError::field(where, "--diversity", fmt::format("{}", diversity), "a finite number >= 0");
  }
  if (trees < 1 || trees > 10'000) throw ConfigError::field(where, "--trees", std::to_string(trees), "1 .. 10000");
  if (probability != "shifts" && probability != "tail") {
    throw ConfigError::field(where, "--probability", probability, "shifts or tail");
  }
  if (bnnEpochs < 1) throw ConfigError::field(where, "--bnn-epochs", std::to_string(bnnEpochs), ">= 1");
  if (vectornetSteps < 1 || vectornetSteps > 1'000'000) {
    throw ConfigError::field(where, "--vectornet-steps", std::to_string(vectornetSteps), "1 .. 1000000");
  }
  if (futureSamples < 1 || futureSamples > 1000) {
    throw ConfigError::field(where, "--future-samples", std::to_string(futureSamples), "1 .. 1000");
  }
  if (!surrogates) throw ConfigError::field(where, "surrogates", "none", "a surrogate registry");
  const auto& entry = surrogates->find(surrogate);
  if (!priors.empty() && !entry.learnsFromScenes) {
    throw ConfigError::field(where, "--prior", priors.front().string(),
                             fmt::format("no --prior with --surrogate {}: it does not learn from scenes", surrogate));
  }
  if (jobs < 1 || jobs > 256) throw ConfigError::field(where, "--jobs", std::to_string(jobs), "1 .. 256");
  if (threads < 1 || threads > 256) throw ConfigError::field(where, "--threads", std::to_string(threads), "1 .. 256");
  if (!(egoStepCost >= 0.0 && egoStepCost <= 10.0)) {
    throw ConfigError::field(where, "--ego-step-cost-ms", fmt::format("{}", egoStepCost * 1000.0), "0 .. 10000");
  }
}

std::pair<double, double> wilsonInterval(std::uint64_t successes, std::uint64_t trials) {
  if (trials == 0) return {0.0, 1.0};
  const auto interval =
      vsd::wilsonInterval(static_cast<double>(successes) / static_cast<double>(trials), static_cast<std::size_t>(trials));
  return {interval.low, interval.high};
}

namespace detail {

/// Importance proposal over the pool candidates not acquired this round (the stratum B):
/// q_i = (1 - a) p_i / sum_B(p) + a / N_B, 0 for acquired ones. For a binary outcome the
/// variance sum_B r_i / q_i of importance sampling is smallest for q proportional to
/// sqrt(r_i), r_i the candidate's true rate. The surrogates' p overstate r in stratum B (its
/// best candidates were acquired): measured on acc_lk / d_min < 2 with extra-trees, r was
/// about p^2 (p 0.13 -> 1 %, 0.29 -> 10 %, 0.47 -> 22 %), so q proportional to p; it gave
/// intervals 1.17x narrower than p^2 and 1.5x narrower than sqrt(p (1 - p)) over 10 seeds
/// (README "Search benchmark"). The even share a keeps every weight 1 / (N q_i) below 1 / a.
std::vector<double> importanceProposal(const std::vector<double>& probability, const std::vector<bool>& acquired) {
  double total = 0.0;
  double stratum = 0.0;
  for (std::size_t i = 0; i < probability.size(); ++i) {
    if (acquired[i]) continue;
    total += std::max(0.0, probability[i]);
    stratum += 1.0;
  }
  std::vector<double> proposal(probability.size(), 0.0);
  for (std::size_t i = 0; i < probability.size(); ++i) {
    if (acquired[i]) continue;
    proposal[i] = total > 0.0 ? (1.0 - kDefensiveShare) * std::max(0.0, probability[i]) / total +
                                    kDefensiveShare / stratum
                              : 1.0 / stratum;
  }
  return proposal;
}

/// `count` draws with replacement from the proposal; returns pool position -> times drawn.
std::map<std::size_t, std::uint64_t> drawFromPool(const std::vector<double>& proposal, std::uint64_t count, Rng& rng) {
  std::vector<double> cumulative(proposal.size());
  std::partial_sum(proposal.begin(), proposal.end(), cumulative.begin());
  std::map<std::size_t, std::uint64_t> drawn;
  for (std::uint64_t k = 0; k < count; ++k) {
    const double u = rng.uniform01() * cumulative.back();
    const auto at = std::upper_bound(cumulative.begin(), cumulative.end(), u) - cumulative.begin();
    ++drawn[std::min(static_cast<std::size_t>(at), proposal.size() - 1)];
  }
  return drawn;
}

}  // namespace detail

namespace {

/// The dataset files of the --prior folders, each checked against the scenario's step
/// and horizon (a model learns one time base).
std::vector<fs::path> priorDatasets(const std::vector<fs::path>& priors, const scenario::LogicalScenario& logical) {
  std::vector<fs::path> files;
  for (const auto& prior : priors) {
    for (const auto& file : vector::datasetFiles(prior)) {
      const vector::DatasetReader reader(file);
      const auto& header = reader.header();
      if (std::abs(header.step - logical.step) > 1e-9) {
        throw ConfigError(fmt::format("--prior {}: step {} s, but {} has step {} s (a model learns one time base)",
                                      prior.string(), header.step, logical.sourceFile.string(), logical.step));
      }
      if (header.horizon != logical.steps()) {
        throw ConfigError(fmt::format("--prior {}: horizon {} steps, but {} has {} steps", prior.string(),
                                      header.horizon, logical.sourceFile.string(), logical.steps()));
      }
      files.push_back(file);
    }
  }
  return files;
}

/// An execution's values in executionColumns() order: the system's metrics, then with
/// --reference the reference driver's and the regulation's pass criterion (NaN where a run failed).
std::vector<double> executionValues(const SearchContext& context, const pipeline::ScenarioOutcome& outcome) {
  std::vector<double> values = outcome.metrics;
  if (context.options.reference.empty()) return values;
  const auto& reference = outcome.referenceMetrics;
  for (std::size_t m = 0; m < context.metricNames.size(); ++m) {
    values.push_back(m < reference.size() ? reference[m] : std::numeric_limits<double>::quiet_NaN());
  }
  const auto& metric_set = *context.metricSet;
  values.push_back(pipeline::referenceAvoidsSutCollides(
      outcome, [&metric_set](const std::vector<double>& metrics) { return metric_set.collision(metrics); }));
  return values;
}

SearchContext makeContext(const SearchOptions& options) {
  options.validate();
  SearchContext context;
  context.options = options;
  // The registry lives as long as the context's copy of the options holds it.
  context.surrogate = &context.options.surrogates->find(options.surrogate);
  context.guides = context.surrogate->make(SurrogateOptions{})->guidesSelection();
  context.logical = scenario::loadLogicalScenario(options.scenarioFile);
  context.metricSet = std::make_shared<const metrics::MetricSet>(
      context.logical->metrics, pipeline::scenarioAvailability(*context.logical),
      context.logical->sourceFile.string() + ": metrics");
  context.metricNames = context.metricSet->names();
  context.columnNames = executionColumns(context.metricNames, options.reference);
  context.criterion = std::make_unique<Criterion>(options.criterion, *context.logical, context.columnNames);
  context.scenarioSha256 = sha256OfFile(context.logical->sourceFile);
  context.priors = priorDatasets(options.priors, *context.logical);
  context.normaliser =
      detail::Normaliser(detail::sampleInputs(context, detail::kEstimateBase, detail::kNormalisationSamples));
  return context;
}

/// What one round executes.
struct RoundPlan {
  std::vector<Execution> chosen;  ///< sample, origin, acquisition, predicted set; results not yet
};

std::uint64_t randomStreamUsed(const std::vector<Execution>& executions) {
  return static_cast<std::uint64_t>(
      std::count_if(executions.begin(), executions.end(), [](const Execution& e) { return e.fromRandomStream(); }));
}

/// Draws of the logical scenario's distribution itself: weight 1.
void addRandomStream(RoundPlan& plan, std::uint64_t next, std::uint64_t count, const std::string& origin) {
  for (std::uint64_t i = 0; i < count; ++i) {
    Execution execution;
    execution.origin = origin;
    execution.sample = next + i;
    execution.acquisition = std::numeric_limits<double>::quiet_NaN();
    execution.predicted = std::numeric_limits<double>::quiet_NaN();
    execution.draws = 1;
    execution.weight = 1.0;
    plan.chosen.push_back(execution);
  }
}

/// Distance (normalised inputs) below which a candidate counts as close to a chosen point.
double diversityLength(std::size_t inputs) { return 0.25 * std::sqrt(static_cast<double>(inputs)); }

/// Greedy batch selection: acquisition = p * (1 + w * d) (+ a tiny d so that, where every
/// p is 0, the most distant candidates come first); d = min(distance to the nearest critical
/// scenario found or candidate chosen this round / length, 1).
std::vector<std::size_t> selectCandidates(const Matrix& normalised_pool, const std::vector<double>& probability,
                                          const std::vector<std::vector<double>>& critical_found, std::uint64_t count,
                                          double weight, std::vector<double>& acquisition_out) {
  const auto rows = static_cast<std::size_t>(normalised_pool.rows());
  const double length = diversityLength(static_cast<std::size_t>(normalised_pool.cols()));
  std::vector<double> nearest(rows, std::numeric_limits<double>::infinity());
  auto update_nearest = [&](const Eigen::RowVectorXd& point) {
    for (std::size_t i = 0; i < rows; ++i) {
      nearest[i] = std::min(nearest[i], (normalised_pool.row(static_cast<Eigen::Index>(i)) - point).norm());
    }
  };
  for (const auto& found : critical_found) {
    update_nearest(Eigen::Map<const Eigen::RowVectorXd>(found.data(), static_cast<Eigen::Index>(found.size())));
  }
  std::vector<bool> taken(rows, false);
  std::vector<std::size_t> chosen;
  for (std::uint64_t k = 0; k < count && k < rows; ++k) {
    std::size_t best = rows;
    double best_value = -1.0;
    for (std::size_t i = 0; i < rows; ++i) {
      if (taken[i]) continue;
      const double d = std::min(nearest[i] / length, 1.0);
      const double value = probability[i] * (1.0 + weight * d) + 1e-9 * d;
      if (value > best_value) {
        best_value = value;
        best = i;
      }
    }
    taken[best] = true;
    chosen.push_back(best);
    acquisition_out.push_back(best_value);
    update_nearest(normalised_pool.row(static_cast<Eigen::Index>(best)));
  }
  return chosen;
}

/// The surrogate's view of one round's candidate pool.
struct ScoredPool {
  std::uint64_t firstSample = 0;
  Matrix normalised;
  std::vector<double> probability;
};

ScoredPool scorePool(const SearchContext& context, const SearchState& state) {
  std::vector<const Execution*> rows;
  for (const auto& execution : state.executions) rows.push_back(&execution);
  const auto surrogate = detail::fitSurrogate(context, rows, state.rounds);
  ScoredPool pool;
  pool.firstSample = detail::kPoolBase + state.rounds * detail::kPoolStride;
  pool.normalised = context.normaliser.apply(detail::sampleInputs(context, pool.firstSample, context.options.pool));
  CandidateSet candidates;
  candidates.x = pool.normalised;
  candidates.scene = [logical = context.logical, seed = context.options.seed, first = pool.firstSample](std::size_t row) {
    return pipeline::plannedScene(scenario::sampleConcreteScenario(logical, seed, first + row));
  };
  pool.probability = surrogate ? surrogate->probability(candidates, *context.criterion)
                               : std::vector<double>(static_cast<std::size_t>(pool.normalised.rows()), 0.0);
  return pool;
}

void addAcquired(const SearchContext& context, const SearchState& state, const ScoredPool& pool, RoundPlan& plan,
                 std::uint64_t count) {
  std::vector<std::vector<double>> critical_found;
  for (const auto& execution : state.executions) {
    if (execution.verdict == 1) critical_found.push_back(context.normaliser.apply(execution.inputs));
  }
  std::vector<double> acquisition;
  const auto chosen = selectCandidates(pool.normalised, pool.probability, critical_found, count,
                                       context.options.diversity, acquisition);
  for (std::size_t c = 0; c < chosen.size(); ++c) {
    Execution execution;
    execution.origin = "acquired";
    execution.sample = pool.firstSample + chosen[c];
    execution.acquisition = acquisition[c];
    execution.predicted = pool.probability[chosen[c]];
    plan.chosen.push_back(execution);
  }
}

/// Importance draws for the rate estimate from the candidates not acquired this round (a
/// candidate drawn twice is simulated once and counts twice).
void addImportanceDraws(const SearchContext& context, const SearchState& state, const ScoredPool& pool,
                        RoundPlan& plan, std::uint64_t count) {
  std::vector<bool> acquired(pool.probability.size(), false);
  for (const auto& execution : plan.chosen) acquired[execution.sample - pool.firstSample] = true;
  if (count == 0 || std::all_of(acquired.begin(), acquired.end(), [](bool a) { return a; })) return;
  const auto proposal = detail::importanceProposal(pool.probability, acquired);
  Rng rng = Rng::derive(context.options.seed, state.rounds, RandomStream::SearchSelection);
  for (const auto& [position, times] : detail::drawFromPool(proposal, count, rng)) {
    Execution execution;
    execution.origin = "importance";
    execution.sample = pool.firstSample + position;
    execution.acquisition = std::numeric_limits<double>::quiet_NaN();
    execution.predicted = pool.probability[position];
    execution.draws = times;
    execution.weight = 1.0 / (static_cast<double>(proposal.size()) * proposal[position]);
    plan.chosen.push_back(execution);
  }
}

RoundPlan planRound(const SearchContext& context, const SearchState& state, double& surrogate_seconds) {
  RoundPlan plan;
  const std::uint64_t done = state.executions.size();
  const std::uint64_t next_random = randomStreamUsed(state.executions);
  if (state.rounds == 0) {
    addRandomStream(plan, next_random, context.options.initial, "initial");
    return plan;
  }
  const std::uint64_t size = std::min(context.options.roundSize, context.options.executionBudget() - done);
  if (!context.guides) {
    addRandomStream(plan, next_random, size, "random");
    return plan;
  }
  const auto importance =
      static_cast<std::uint64_t>(std::llround(context.options.estimateShare * static_cast<double>(size)));
  const auto start = std::chrono::steady_clock::now();
  const ScoredPool pool = scorePool(context, state);
  addAcquired(context, state, pool, plan, size - importance);
  addImportanceDraws(context, state, pool, plan, importance);
  surrogate_seconds += secondsSince(start);
  return plan;
}

/// Simulates the plan's scenarios with the pipeline's batch simulation (as `run` does),
/// fills in their results and writes the round's traces and scenes (as `run` writes them)
/// to <out>/.rounds/, committed before the round's checkpoint.
void executePlan(const SearchContext& context, std::uint64_t round, RoundPlan& plan) {
  pipeline::RunOptions run;
  run.samples = plan.chosen.size();
  run.seed = context.options.seed;
  run.jobs = context.options.jobs;
  run.egoStepCost = context.options.egoStepCost;
  run.reference = context.options.reference;
  run.writeFiles = false;
  const auto logical = context.logical;
  const std::uint64_t seed = context.options.seed;
  std::vector<std::uint64_t> samples;
  for (const auto& execution : plan.chosen) samples.push_back(execution.sample);
  // The batch places scenario i in layout cell i; its draws come from its own sample index.
  run.source = [logical, seed, samples](std::uint64_t i) {
    auto concrete = scenario::sampleConcreteScenario(logical, seed, samples[i]);
    concrete.index = i;
    auto road = road::buildRoadGeometry(concrete);
    return pipeline::ScenarioWithRoad{std::move(concrete), std::move(road)};
  };
  ensureDirectory(detail::roundFile(context, round, "").parent_path());
  AtomicOutput traces(detail::roundFile(context, round, "traces.h5"));
  AtomicOutput dataset(detail::roundFile(context, round, "dataset.h5"));
  pipeline::OutcomeFiles files(*logical, context.metricNames, run.compression, traces.tempPath(), dataset.tempPath(),
                               traces.finalPath(), dataset.finalPath());
  pipeline::runScenarios(logical, run, [&](const pipeline::ScenarioOutcome& outcome) {
    auto& execution = plan.chosen[outcome.index];
    execution.inputs = outcome.inputs;
    execution.metrics = executionValues(context, outcome);
    execution.failure = outcome.failure;
    const auto verdict = outcome.ok() ? context.criterion->verdict(execution.metrics) : std::nullopt;
    execution.verdict = verdict ? (*verdict ? 1 : 0) : -1;
    pipeline::ScenarioOutcome stored = outcome;  // stored under its sample index, not its layout cell
    stored.index = execution.sample;
    files.write(stored);
  });
  files.close();
  traces.commitUnlessInterrupted();
  dataset.commitUnlessInterrupted();
}

}  // namespace

std::size_t detail::coverageCells(const SearchContext& context, const std::vector<Execution>& executions,
                                  std::size_t count) {
  std::set<std::vector<int>> cells;
  for (std::size_t i = 0; i < count && i < executions.size(); ++i) {
    if (executions[i].verdict == 1) cells.insert(coverageCell(context, executions[i]));
  }
  return cells.size();
}

std::vector<int> detail::coverageCell(const SearchContext& context, const Execution& execution) {
  std::vector<int> cell;
  for (const double u : context.normaliser.apply(execution.inputs)) {
    cell.push_back(std::clamp(static_cast<int>(std::floor(kCoverageBins * u)), 0, kCoverageBins - 1));
  }
  return cell;
}

namespace {

std::uint64_t countCritical(const std::vector<Execution>& executions) {
  return static_cast<std::uint64_t>(
      std::count_if(executions.begin(), executions.end(), [](const Execution& e) { return e.verdict == 1; }));
}

void runRounds(const SearchContext& context, SearchState& state, SearchSummary& summary) {
  Progress progress(fmt::format("search {}", context.logical->name), context.options.executionBudget(), "executions");
  progress.advance(state.executions.size());
  while (state.executions.size() < context.options.executionBudget()) {
    throwIfInterrupted();
    RoundPlan plan = planRound(context, state, summary.surrogateSeconds);
    const auto start = std::chrono::steady_clock::now();
    executePlan(context, state.rounds, plan);
    summary.simulationSeconds += secondsSince(start);
    for (auto& execution : plan.chosen) {
      execution.round = state.rounds;
      state.executions.push_back(std::move(execution));
    }
    ++state.rounds;
    detail::writeCheckpoint(context, state);
    progress.advance(plan.chosen.size());
    if (context.guides && state.rounds == 1 && countCritical(state.executions) == 0) {
      spdlog::warn("search: '{}' was met by none of the {} initial executions; the search goes on, guided by the "
                   "predicted metrics",
                   context.criterion->name(), state.executions.size());
    }
    spdlog::debug("search round {}: {} executions, {} critical", state.rounds - 1, state.executions.size(),
                  countCritical(state.executions));
  }
  progress.finish();
}

}  // namespace

SearchSummary runSearch(const SearchOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const std::string started = utcTimestamp();
  const SearchContext context = makeContext(options);
  OutputFolder folder(options.outputDir);  // locked; its files change as one set at the end
  SearchState state = detail::readCheckpoint(context).value_or(SearchState{});
  for (const char* file : {"traces.h5", "dataset.h5"}) detail::roundFiles(context, state.rounds, file);  // before any work

  SearchSummary summary;
  summary.functionalScenario = context.logical->name;
  summary.criterion = context.criterion->name();
  summary.expression = context.criterion->expression();
  summary.surrogate = options.surrogate;
  summary.reference = options.reference;
  summary.seed = options.seed;
  summary.resumedFrom = state.executions.size();
  runRounds(context, state, summary);

  summary.executions = state.executions.size();
  summary.rounds = state.rounds;
  summary.critical = countCritical(state.executions);
  summary.failedRuns = static_cast<std::uint64_t>(std::count_if(
      state.executions.begin(), state.executions.end(), [](const Execution& e) { return !e.failure.empty(); }));
  summary.criterionSeenInInitialDesign = std::any_of(state.executions.begin(), state.executions.end(), [](const Execution& e) {
    return e.round == 0 && e.verdict == 1;
  });
  summary.coverageCells = detail::coverageCells(context, state.executions, state.executions.size());
  const auto estimate_start = std::chrono::steady_clock::now();
  summary.estimate = detail::estimateRate(context, state.executions);
  summary.surrogateSeconds += secondsSince(estimate_start);
  summary.executionsList = std::move(state.executions);
  summary.seconds = secondsSince(start);
  summary.outputs = detail::commitSearchFolder(context, folder, summary, started);
  return summary;
}

MonteCarloRate monteCarloRate(SearchOptions options, std::uint64_t seed, std::uint64_t samples) {
  if (samples < 1) throw ConfigError::field("command line", "--true-rate-samples", "0", ">= 1");
  const auto start = std::chrono::steady_clock::now();
  if (options.outputDir.empty()) options.outputDir = ".";  // validated, never written
  options.priors.clear();  // plain Monte Carlo learns nothing: priors belong to a surrogate (bench search --prior)
  const SearchContext context = makeContext(options);
  pipeline::RunOptions run;
  run.samples = samples;
  run.seed = seed;
  run.jobs = options.jobs;
  run.egoStepCost = options.egoStepCost;
  run.reference = options.reference;
  run.writeFiles = false;
  MonteCarloRate rate;
  rate.seed = seed;
  rate.samples = samples;
  pipeline::runScenarios(context.logical, run, [&](const pipeline::ScenarioOutcome& outcome) {
    const auto verdict = outcome.ok() ? context.criterion->verdict(executionValues(context, outcome)) : std::nullopt;
    if (!verdict) ++rate.withoutVerdict;
    if (verdict.value_or(false)) ++rate.critical;
  });
  rate.estimate = static_cast<double>(rate.critical) / static_cast<double>(samples);
  std::tie(rate.low, rate.high) = wilsonInterval(rate.critical, samples);
  rate.seconds = secondsSince(start);
  return rate;
}

std::string SearchSummary::report() const {
  std::string text = fmt::format("{}: search for '{}'{} with surrogate {}: {} executions in {} rounds, {:.1f} s "
                                 "(simulation {:.1f} s, surrogate {:.1f} s)\n",
                                 functionalScenario, criterion, criterion == expression ? "" : " (" + expression + ")",
                                 surrogate, executions, rounds, seconds, simulationSeconds, surrogateSeconds);
  if (!reference.empty()) {
    text += fmt::format("  each execution ran twice: the system under test and {} as the Ego ({} simulations)\n",
                        reference, 2 * executions);
  }
  if (resumedFrom > 0) text += fmt::format("  resumed after {} executions of an earlier run\n", resumedFrom);
  text += fmt::format("  critical: {} ({:.2f} % of executions), in {} input cells; failed simulations: {}\n", critical,
                      executions == 0 ? 0.0 : 100.0 * static_cast<double>(critical) / static_cast<double>(executions),
                      coverageCells, failedRuns);
  if (!criterionSeenInInitialDesign) text += "  note: the criterion was not met in the initial design\n";
  const auto& e = estimate;
  // As many digits as the interval makes meaningful (report::percentWithInterval).
  text += fmt::format("  P(criterion) = {} (95 %, {}); random stream alone: {}/{} = {}; plain random sampling of the "
                      "whole budget: interval width ~{:.{}f} %\n",
                      report::percentWithInterval(e.estimate, e.low, e.high),
                      fmt::format("{}, {} draws", e.method, e.draws), e.randomCritical, e.randomExecutions,
                      report::percentWithInterval(e.randomEstimate, e.randomLow, e.randomHigh),
                      100 * e.sameBudgetRandomWidth, report::decimalsFor(100 * e.sameBudgetRandomWidth));
  if (!outputs.empty()) {
    text += "  outputs:\n";
    for (const auto& path : outputs) text += fmt::format("    {}\n", path.string());
  }
  return text;
}

}  // namespace vsd::search
