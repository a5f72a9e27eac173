// `vsd-sumo search`: criteria, the surrogate registry, option checks, resuming,
// determinism and that a guiding surrogate beats Monte Carlo on a small budget.

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <numeric>
#include <nlohmann/json.hpp>

#include "extension/nearest_neighbour_surrogate.hpp"
#include "test_support.hpp"
#include "vsd/core/csv.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/metrics/metrics.hpp"
#include "vsd/model/model.hpp"
#include "vsd/pipeline/scenes.hpp"
#include "vsd/scenario/logical_scenario.hpp"
#include "vsd/search/criterion.hpp"
#include "vsd/search/search.hpp"
#include "vsd/search/surrogate.hpp"
#include "vsd/sim/trace_file.hpp"
#include "vsd/vector/dataset.hpp"
#include "../../src/search/search_internal.hpp"

namespace fs = std::filesystem;
using testing::HasSubstr;

namespace vsd::search {
namespace {

const std::vector<std::string> kMetrics = {"a_min", "d_min", "p_lat_max", "y_max", "ttc_min", "thw_min",
                                           "lane_offset_max"};

/// cut_in with a system under test that brakes weakly (0.5 m/s^2): it collides in many cut-ins
/// the reference driver avoids (11 of 100 in a run of this variant). Written into `folder`.
fs::path weakCutIn(const fs::path& folder) {
  const auto weak = folder / "weak_cut_in.yaml";
  test::writeFile(weak, test::scenarioVariant("alks/cut_in.yaml", "set_speed: Ego_InitSpeed_Ve0_kph / 3.6}",
                                              "set_speed: Ego_InitSpeed_Ve0_kph / 3.6, max_decel: 0.5, "
                                              "emergency_trigger: 5}"));
  return weak;
}

/// A run folder of `samples` concrete scenarios of the library scenario `name` (e.g.
/// "alks/cut_in.yaml"), written to `out`; throws with vsd-sumo's output if the run fails.
fs::path runLibraryScenario(const fs::path& out, const std::string& name, int samples) {
  const auto result = test::run({test::vsdSumo().string(), "-q", "run", test::scenarioFile(name).string(), "-n",
                                 std::to_string(samples), "--out", out.string()},
                                out.parent_path());
  if (result.exitCode != 0) throw std::runtime_error("run " + name + ": " + result.output);
  return out;
}

TEST(SearchCriterion, ExpressionReadsItsMetricsAndJudges) {
  const auto logical = scenario::loadLogicalScenario(test::scenarioFile("acc_lk.yaml"));
  const Criterion criterion("ttc_min < 1 || d_min < 0.5", *logical, kMetrics);
  EXPECT_EQ(criterion.usedMetrics(), (std::vector<std::string>{"d_min", "ttc_min"}));
  std::vector<double> values = {-3, 5.0, 0, 0, 0.8, 1, 0};
  EXPECT_EQ(criterion.verdict(values), std::optional<bool>(true));
  values[4] = 2.0;
  EXPECT_EQ(criterion.verdict(values), std::optional<bool>(false));
  values[1] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(criterion.verdict(values), std::nullopt);  // a failed run has no verdict
  EXPECT_TRUE(criterion.meetsUsed({0.4, 9.0}));
}

TEST(SearchCriterion, NamedCriterionComesFromTheScenario) {
  const auto logical = scenario::loadLogicalScenario(test::scenarioFile("acc_lk.yaml"));
  const Criterion criterion("close_approach", *logical, kMetrics);
  EXPECT_EQ(criterion.expression(), "d_min < 2");
  EXPECT_EQ(criterion.usedMetrics(), std::vector<std::string>{"d_min"});
}

// UN R157's pass criterion by its name stands for the clearances it is made of, so that a
// surrogate learns two metrics that vary smoothly over the inputs rather than a 0/1 flag that
// is 0 nearly everywhere; its verdict is the flag's (the system collides, the reference not).
TEST(SearchCriterion, TheRegulationsCriterionReadsBothClearancesAndJudgesLikeItsColumn) {
  const auto logical = scenario::loadLogicalScenario(test::scenarioFile("alks/cut_in.yaml"));
  const auto columns = executionColumns(logical->metrics, "r157_reference_driver");
  const Criterion criterion("reference_avoids_sut_collides", *logical, columns);
  EXPECT_EQ(criterion.name(), "reference_avoids_sut_collides");
  EXPECT_EQ(criterion.usedMetrics(), (std::vector<std::string>{"d_min", "reference_d_min"}));
  const auto d_min = criterion.usedColumns()[0];
  const auto reference_d_min = criterion.usedColumns()[1];
  std::vector<double> values(columns.size(), 1.0);
  for (const auto& [sut, reference, critical] :
       std::vector<std::tuple<double, double, bool>>{{-0.1, 0.5, true}, {0.0, 0.01, true}, {-0.1, 0.0, false},
                                                     {0.2, 0.5, false}, {0.2, -1.0, false}}) {
    values[d_min] = sut;
    values[reference_d_min] = reference;
    EXPECT_EQ(criterion.verdict(values), std::optional<bool>(critical)) << sut << " " << reference;
  }
  values[reference_d_min] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(criterion.verdict(values), std::nullopt) << "the reference run failed: no verdict";

  const auto no_collision = scenario::loadLogicalScenario(test::scenarioFile("alks/free_driving.yaml"));
  EXPECT_THAT(test::configErrorOf([&] {
                Criterion("reference_avoids_sut_collides", *no_collision,
                          executionColumns(no_collision->metrics, "r157_reference_driver"));
              }),
              HasSubstr("free_driving.yaml: metrics lists none with a collision rule"));
}

TEST(SearchCriterion, BadCriteriaGetOneLineNamingWhatIsKnown) {
  const auto logical = scenario::loadLogicalScenario(test::scenarioFile("acc_lk.yaml"));
  const std::string unknown = test::configErrorOf([&] { Criterion("dmin < 2", *logical, kMetrics); });
  EXPECT_THAT(unknown, HasSubstr("dmin"));
  EXPECT_THAT(unknown, HasSubstr("ttc_min"));
  EXPECT_THAT(unknown, HasSubstr("close_approach"));
  EXPECT_EQ(unknown.find('\n'), std::string::npos);
  // A registered metric the scenario does not compute is named as such.
  const std::string not_computed = test::configErrorOf([&] { Criterion("ttc_min < 1", *logical, {"a_min", "d_min"}); });
  EXPECT_THAT(not_computed, HasSubstr("'ttc_min' is not computed by this scenario"));
  EXPECT_THAT(test::configErrorOf([&] { Criterion("d_min < (2", *logical, kMetrics); }), HasSubstr("d_min < (2"));
  EXPECT_THAT(test::configErrorOf([&] { Criterion("1 < 2", *logical, kMetrics); }), HasSubstr("uses no metric"));
}

TEST(SearchSurrogates, UnknownNameListsTheKnownOnes) {
  const std::string message = test::configErrorOf([] { builtinSurrogates()->find("gaussian-process"); });
  EXPECT_THAT(message, HasSubstr("random, extra-trees, bnn"));
}

TEST(SearchSurrogates, TailProbabilityIsTheGaussianTailBeyondTheCriterion) {
  const auto logical = scenario::loadLogicalScenario(test::scenarioFile("acc_lk.yaml"));
  const Criterion criterion("ttc_min < 1", *logical, kMetrics);
  // Two spreads above the threshold: Phi(-2); half a spread below it: Phi(0.5) (scipy.stats.norm.cdf).
  EXPECT_NEAR(tailProbability({3.0}, {1.0}, criterion), 0.0227501319, 1e-6);
  EXPECT_NEAR(tailProbability({0.5}, {1.0}, criterion), 0.6914624613, 1e-6);
  EXPECT_GT(tailProbability({9.0}, {2.0}, criterion), 0.0);  // far, yet ranked
  EXPECT_LT(tailProbability({9.0}, {2.0}, criterion), tailProbability({5.0}, {2.0}, criterion));
  EXPECT_EQ(tailProbability({3.0}, {0.0}, criterion), 0.0);
  EXPECT_EQ(tailProbability({0.5}, {0.0}, criterion), 1.0);
}

TEST(SearchSurrogates, RankTargetsMapBackToMetricValuesAndReachBelowTheObservedRange) {
  const auto logical = scenario::loadLogicalScenario(test::scenarioFile("acc_lk.yaml"));
  SurrogateOptions options;
  options.trees = 20;
  options.probability = "tail";
  options.rankTargets = true;
  const auto surrogate = makeExtraTreesSurrogate(options);
  Matrix x(50, 1);
  Matrix y(50, 1);
  for (Eigen::Index i = 0; i < 50; ++i) {
    x(i, 0) = static_cast<double>(i) / 49.0;
    y(i, 0) = 0.5 + 2.0 * x(i, 0);  // d_min from 0.5 to 2.5 m
  }
  surrogate->fit({x, y, {1}, {}, {}});  // y is d_min (column 1)
  CandidateSet candidates;
  candidates.x.resize(3, 1);
  candidates.x << 0.1, 0.9, 0.01;
  // Inside the observed range: judged on metric values, not on ranks (d_min < 1.5 <=> x < 0.5).
  const auto inside = surrogate->probability(candidates, Criterion("d_min < 1.5", *logical, kMetrics));
  EXPECT_GT(inside[0], 0.5);
  EXPECT_LT(inside[1], 0.5);
  // Just below every observed value: still a probability, largest where d_min is smallest.
  const auto below = surrogate->probability(candidates, Criterion("d_min < 0.49", *logical, kMetrics));
  EXPECT_GT(below[2], 0.0);
  EXPECT_GT(below[2], below[1]);
}

SearchOptions smallSearch(const fs::path& out, const std::string& surrogate, std::uint64_t budget) {
  SearchOptions options;
  options.scenarioFile = test::scenarioFile("acc_lk.yaml");
  options.outputDir = out;
  options.criterion = "d_min < 8";
  options.surrogate = surrogate;
  options.budget = budget;
  options.initial = 40;
  options.roundSize = 20;
  options.pool = 1000;
  options.trees = 20;
  return options;
}

/// smallSearch of weakCutIn (written into `work`) for UN R157's criterion with the reference
/// driver: 10 initial executions, rounds of 5 from a pool of 200, 10 trees; out: work/out.
SearchOptions regulationSearch(const fs::path& work, const std::string& surrogate, std::uint64_t budget) {
  auto options = smallSearch(work / "out", surrogate, budget);
  options.scenarioFile = weakCutIn(work);
  options.criterion = "reference_avoids_sut_collides";
  options.reference = "r157_reference_driver";
  options.initial = 10;
  options.roundSize = 5;
  options.pool = 200;
  options.trees = 10;
  return options;
}

TEST(SearchOptions, BudgetBelowTheInitialDesignIsRefusedBeforeAnythingIsWritten) {
  TemporaryDirectory work("vsd-test-search");
  auto options = smallSearch(work.path() / "out", "extra-trees", 30);
  const std::string message = test::configErrorOf([&] { runSearch(options); });
  EXPECT_THAT(message, HasSubstr("--budget"));
  EXPECT_THAT(message, HasSubstr("--initial (40)"));
  EXPECT_FALSE(fs::exists(work.path() / "out"));
  options.budget = 100;
  options.surrogate = "gp";
  EXPECT_THAT(test::configErrorOf([&] { runSearch(options); }), HasSubstr("unknown surrogate"));
  EXPECT_FALSE(fs::exists(work.path() / "out"));
}

std::vector<std::string> column(const fs::path& csv, const std::string& name) {
  const auto table = CsvTable::read(csv);
  std::vector<std::string> values;
  for (std::size_t r = 0; r < table.rows(); ++r) values.push_back(table.cell(r, table.column(name)));
  return values;
}

TEST(SearchLoop, ResumesWithoutRepeatingAndMakesTheSameChoicesAsAnUninterruptedSearch) {
  TemporaryDirectory work("vsd-test-search");
  const auto resumed = work.path() / "resumed";
  runSearch(smallSearch(resumed, "extra-trees", 60));  // "interrupted" after 60 executions
  // An interrupted search has committed nothing yet: no manifest and none of its outputs
  // (files no manifest lists would be a user's, and a commit refuses to replace them).
  for (const auto& [name, entry] : readManifestOutputs(resumed)) fs::remove(resumed / name);
  fs::remove(resumed / "manifest.json");
  const auto summary = runSearch(smallSearch(resumed, "extra-trees", 100));
  EXPECT_EQ(summary.resumedFrom, 60u);
  EXPECT_EQ(summary.executions, 100u);
  const auto samples = column(resumed / "concrete.csv", "sample");
  EXPECT_EQ(std::set<std::string>(samples.begin(), samples.end()).size(), samples.size()) << "an execution repeated";

  auto straight = smallSearch(work.path() / "straight", "extra-trees", 100);
  straight.jobs = 2;  // same choices whatever the number of simulation workers
  runSearch(straight);
  EXPECT_EQ(readTextFile(resumed / "concrete.csv"), readTextFile(work.path() / "straight" / "concrete.csv"));
  const auto origins = column(resumed / "concrete.csv", "origin");
  EXPECT_EQ(std::count(origins.begin(), origins.end(), "acquired"), 36);  // 3 rounds of 20, 8 importance draws each
  EXPECT_TRUE(fs::exists(resumed / "manifest.json"));
  // One output set like run's: every file listed with its hash; traces and scenes of every
  // execution (scenes of the completed ones), stored under their sample indices.
  EXPECT_TRUE(checkOutputFolder(resumed, true).empty());
  const auto listed = readManifestOutputs(resumed);
  for (const char* file : {"concrete.csv", "failures.csv", "learning_curve.csv", "coverage.csv", "estimate.json",
                           "traces.h5", "dataset.h5", "report.html"}) {
    EXPECT_EQ(listed.count(file), 1u) << file;
  }
  const auto validation = vector::validateDataset(resumed);  // what `vsd-sumo dataset validate <out>` checks
  EXPECT_TRUE(validation.ok()) << (validation.problems.empty() ? "" : validation.problems.front());
  const sim::TraceFileReader traces(resumed / "traces.h5");
  ASSERT_EQ(traces.size(), samples.size());
  EXPECT_EQ(std::to_string(traces.sample(70)), samples[70]);
  const auto statuses = column(resumed / "concrete.csv", "status");
  EXPECT_EQ(vector::DatasetReader(resumed / "dataset.h5").size(),
            static_cast<std::size_t>(std::count(statuses.begin(), statuses.end(), "ok")));
  EXPECT_THAT(readTextFile(resumed / "report.html"), HasSubstr("extra-trees (seed 1)"));

  auto other = smallSearch(resumed, "extra-trees", 120);
  other.seed = 2;
  EXPECT_THAT(test::configErrorOf([&] { runSearch(other); }), HasSubstr("seed"));
}

/// The DatasetError message of `action`, or "no DatasetError".
std::string datasetErrorOf(const std::function<void()>& action) {
  try {
    action();
  } catch (const DatasetError& error) {
    return error.what();
  }
  return "no DatasetError";
}

// Issue 29: a resumed search refuses — at once, before simulating — a checkpoint that was
// edited and round files that are not its own; `dataset validate` refuses a search folder
// whose dataset holds another search's samples.
TEST(SearchLoop, ForeignOrEditedCheckpointsAndRoundFilesAreRefusedAtTheStart) {
  TemporaryDirectory work("vsd-test-search-foreign");
  const auto mine = work.path() / "mine";
  const auto other = work.path() / "other";
  runSearch(smallSearch(mine, "random", 60));
  auto other_options = smallSearch(other, "random", 60);
  other_options.seed = 2;
  runSearch(other_options);
  const auto resume = [&](const fs::path& folder) {
    const std::string message = datasetErrorOf([&] { runSearch(smallSearch(folder, "random", 100)); });
    // Refused before any round ran: no round 3 files appeared.
    EXPECT_FALSE(fs::exists(folder / ".rounds" / "round-00003.dataset.h5"));
    return message;
  };

  const auto swapped = work.path() / "swapped";
  fs::copy(mine, swapped, fs::copy_options::recursive);
  fs::copy_file(other / ".rounds" / "round-00000.dataset.h5", swapped / ".rounds" / "round-00000.dataset.h5",
                fs::copy_options::overwrite_existing);
  EXPECT_THAT(resume(swapped), HasSubstr("round-00000.dataset.h5: not the file of round 0 that checkpoint.json records"));

  const auto cut = work.path() / "cut";
  fs::copy(mine, cut, fs::copy_options::recursive);
  fs::resize_file(cut / ".rounds" / "round-00001.traces.h5", 1000);
  EXPECT_THAT(resume(cut), HasSubstr("round-00001.traces.h5: not the file of round 1"));

  const auto edited = work.path() / "edited";
  fs::copy(mine, edited, fs::copy_options::recursive);
  std::string checkpoint = readTextFile(edited / "checkpoint.json");
  const auto at = checkpoint.find("\"sample\":");
  checkpoint.insert(at + 9, "1");
  writeTextFileAtomically(edited / "checkpoint.json", checkpoint);
  EXPECT_THAT(resume(edited), HasSubstr("checkpoint.json: edited after it was written"));

  // A search folder whose dataset.h5 is another search's (its manifest made to match the file).
  const auto joined = work.path() / "joined";
  fs::copy(mine, joined, fs::copy_options::recursive);
  fs::copy_file(other / "dataset.h5", joined / "dataset.h5", fs::copy_options::overwrite_existing);
  auto manifest = nlohmann::json::parse(readTextFile(joined / "manifest.json"));
  manifest["outputs"]["dataset.h5"] = {{"sha256", sha256OfFile(joined / "dataset.h5")},
                                       {"bytes", fs::file_size(joined / "dataset.h5")}};
  writeTextFileAtomically(joined / "manifest.json", sealManifest(manifest).dump(2));
  const auto validation = vector::validateDataset(joined);
  ASSERT_FALSE(validation.ok());
  EXPECT_THAT(validation.problems.front(), HasSubstr("inputs differ from"));
  EXPECT_TRUE(vector::validateDataset(mine).ok());
}

TEST(SearchLoop, ExtraTreesFindMoreCriticalScenariosThanRandomSampling) {
  TemporaryDirectory work("vsd-test-search");
  const auto random = runSearch(smallSearch(work.path() / "random", "random", 160));
  const auto trees = runSearch(smallSearch(work.path() / "trees", "extra-trees", 160));
  EXPECT_EQ(random.executions, 160u);
  EXPECT_GT(trees.critical, random.critical + random.critical / 2) << random.critical << " vs " << trees.critical;
  // Both estimates target the same rate; random's is the plain share.
  EXPECT_EQ(random.estimate.method, "monte-carlo");
  EXPECT_EQ(trees.estimate.method, "importance-sampling");
  EXPECT_LE(trees.estimate.low, trees.estimate.estimate);
  EXPECT_GE(trees.estimate.high, trees.estimate.estimate);
  EXPECT_EQ(column(work.path() / "trees" / "failures.csv", "critical").size(), trees.critical);
}

// docs/design.md "Adding a surrogate": the surrogate's own file plus one registry line,
// then `search` (its library call), handed that registry, picks executions with it by name;
// the built-in registry, and so every other search, stays as it was.
TEST(SearchLoop, ASurrogateAddedFromItsOwnFileChoosesTheExecutions) {
  auto surrogates = SurrogateRegistry::withBuiltins();
  surrogates.add(test::nearestNeighbourSurrogate());  // the one line a newcomer writes
  TemporaryDirectory work("vsd-test-search");
  auto options = smallSearch(work.path() / "nn", "nearest-neighbour", 60);
  options.surrogates = std::make_shared<const SurrogateRegistry>(surrogates);
  const auto summary = runSearch(options);
  EXPECT_EQ(summary.surrogate, "nearest-neighbour");
  EXPECT_EQ(summary.executions, 60u);
  std::size_t acquired = 0;
  std::size_t acquired_likely = 0;
  for (const auto& execution : summary.executionsList) {
    if (execution.origin != "acquired") continue;
    ++acquired;
    // Its probabilities are the surrogate's own two values; the acquisition prefers the likely ones.
    EXPECT_TRUE(execution.predicted == 0.9 || execution.predicted == 0.1) << execution.predicted;
    acquired_likely += execution.predicted == 0.9 ? 1 : 0;
  }
  EXPECT_GT(acquired, 0u);
  EXPECT_GT(acquired_likely, 0u);
  EXPECT_THAT(test::configErrorOf([&] { runSearch(smallSearch(work.path() / "builtins", "nearest-neighbour", 60)); }),
              HasSubstr("--surrogate 'nearest-neighbour': unknown surrogate"));
  EXPECT_FALSE(fs::exists(work.path() / "builtins"));
  EXPECT_THAT(test::configErrorOf([&] { surrogates.add(test::nearestNeighbourSurrogate()); }),
              HasSubstr("registered twice"));
}

TEST(SearchLoop, ACriterionNeverMetInTheInitialDesignDoesNotStopTheSearch) {
  TemporaryDirectory work("vsd-test-search");
  auto options = smallSearch(work.path() / "never", "extra-trees", 60);
  options.criterion = "d_min < -1000";
  const auto summary = runSearch(options);
  EXPECT_EQ(summary.executions, 60u);
  EXPECT_EQ(summary.critical, 0u);
  EXPECT_FALSE(summary.criterionSeenInInitialDesign);
  EXPECT_THAT(summary.report(), HasSubstr("not met in the initial design"));
  // No critical draw: the interval still has room above 0 (rule of three on the weights).
  EXPECT_EQ(summary.estimate.estimate, 0.0);
  EXPECT_GT(summary.estimate.high, 0.0);
}

// vectornet learns from scenes: a prior (another functional scenario) pre-trains a model
// once, every round fine-tunes it on the executions' scenes; it scores candidates' planned
// scenes, resumes like the other surrogates and makes the same choices whether resumed or not.
TEST(SearchVectorNet, APriorPreTrainsTheModelAndTheSearchResumesWithTheSameChoices) {
  TemporaryDirectory work("vsd-test-search");
  const auto prior = runLibraryScenario(work.path() / "lk", "lk.yaml", 30);
  auto vectornet = [&](const fs::path& out, std::uint64_t budget) {
    auto options = smallSearch(out, "vectornet", budget);
    options.pool = 100;
    options.priors = {prior};
    options.vectornetSteps = 8;  // a tiny training: this test is about the loop, not accuracy
    options.futureSamples = 4;
    return options;
  };
  const auto resumed = work.path() / "resumed";
  runSearch(vectornet(resumed, 40));  // "interrupted" after the initial design
  // An interrupted search has committed nothing yet: no manifest and none of its outputs
  // (files no manifest lists would be a user's, and a commit refuses to replace them).
  for (const auto& [name, entry] : readManifestOutputs(resumed)) fs::remove(resumed / name);
  fs::remove(resumed / "manifest.json");
  const auto summary = runSearch(vectornet(resumed, 60));
  EXPECT_EQ(summary.resumedFrom, 40u);
  EXPECT_EQ(summary.executions, 60u);
  runSearch(vectornet(work.path() / "straight", 60));
  EXPECT_EQ(readTextFile(resumed / "concrete.csv"), readTextFile(work.path() / "straight" / "concrete.csv"));
  EXPECT_TRUE(fs::exists(resumed / ".rounds" / "round-00001.vectornet.pt"));
  // The prior model learnt lk alone, every round's model (fine-tuned from it) acc_lk alone.
  EXPECT_EQ(model::Predictor(resumed / ".rounds" / "vectornet-prior.pt").info().labels, std::vector<std::string>{"lk"});
  EXPECT_EQ(model::Predictor(resumed / ".rounds" / "round-00001.vectornet.pt").info().labels,
            std::vector<std::string>{"acc_lk"});
  EXPECT_FALSE(fs::exists(resumed / ".rounds" / "vectornet-prior.pt.partial"));
  // The probability is the share of 4 sampled futures meeting the criterion, or below
  // 1/8 (the Gaussian tail) where none does.
  const auto origins = column(resumed / "concrete.csv", "origin");
  const auto predicted = column(resumed / "concrete.csv", "predicted_probability");
  for (std::size_t i = 0; i < origins.size(); ++i) {
    if (origins[i] != "acquired") continue;
    const double p = std::stod(predicted[i]);
    EXPECT_TRUE(p < 0.125 || p * 4.0 == std::round(p * 4.0)) << predicted[i];
  }

  // A prior with another time base is refused in one line naming the folder and the value.
  const auto fine = work.path() / "lk_fine.yaml";
  writeTextFileAtomically(fine, test::scenarioVariant("lk.yaml", "step: 0.2", "step: 0.1"));
  const auto fine_run = work.path() / "lk_fine";
  ASSERT_EQ(test::run({test::vsdSumo().string(), "-q", "run", fine.string(), "-n", "3", "--out", fine_run.string()},
                      work.path())
                .exitCode,
            0);
  auto refused = vectornet(work.path() / "refused", 60);
  refused.priors = {fine_run};
  const auto message = test::configErrorOf([&] { runSearch(refused); });
  EXPECT_THAT(message, HasSubstr("--prior " + fine_run.string() + ": step 0.1 s"));
  EXPECT_EQ(std::count(message.begin(), message.end(), '\n'), 0) << message;
  refused.priors = {prior};
  refused.surrogate = "extra-trees";
  EXPECT_THAT(test::configErrorOf([&] { runSearch(refused); }), HasSubstr("it does not learn from scenes"));
  EXPECT_FALSE(fs::exists(work.path() / "refused"));
}

// UN R157's pass criterion in a search: with --reference every execution runs twice (both
// count against the budget), the reference driver's metrics and the criterion's value are
// columns of executions.csv, and the criterion marks exactly the scenarios where the
// system under test collides and the reference driver does not.
TEST(SearchReference, TheRegulationsCriterionCostsTwoSimulationsAndMarksWhereOnlyTheSystemCollides) {
  TemporaryDirectory work("vsd-test-search");
  const auto options = regulationSearch(work.path(), "extra-trees", 60);
  const auto summary = runSearch(options);
  EXPECT_EQ(summary.executions, 30u) << "60 simulations buy 30 executions with a reference driver";
  const auto csv = options.outputDir / "concrete.csv";
  const auto table = CsvTable::read(csv);
  ASSERT_EQ(table.rows(), 30u);
  std::size_t critical = 0;
  for (std::size_t r = 0; r < table.rows(); ++r) {
    const std::string verdict = table.cell(r, table.column("critical"));
    const std::string value = table.cell(r, table.column("reference_avoids_sut_collides"));
    if (verdict.empty()) continue;  // a failed run
    EXPECT_EQ(verdict == "1", value == "1") << "row " << r;
    const double sut = std::stod(table.cell(r, table.column("d_min")));
    const double reference = std::stod(table.cell(r, table.column("reference_d_min")));
    EXPECT_EQ(verdict == "1", sut <= 0.0 && reference > 0.0) << "row " << r << ": " << sut << " vs " << reference;
    critical += verdict == "1" ? 1 : 0;
  }
  EXPECT_GT(critical, 0u);
  EXPECT_EQ(critical, summary.critical);
  EXPECT_THAT(summary.report(), HasSubstr("r157_reference_driver as the Ego (60 simulations)"));
}

// With --reference the criterion also reads the reference driver's outcome, which the
// scenes (the system's own futures) cannot carry: vectornet learns those columns from the
// inputs (extra trees) and judges each sampled future with each tree's prediction. Here the
// reference driver collides (reference_d_min -1) below input 0.5 and clears 5 m above it.
TEST(SearchVectorNet, LearnsTheReferenceDriversOutcomeFromTheInputs) {
  TemporaryDirectory work("vsd-test-search");
  const auto run_folder = runLibraryScenario(work.path() / "cut_in", "alks/cut_in.yaml", 12);
  const auto logical = scenario::loadLogicalScenario(test::scenarioFile("alks/cut_in.yaml"));
  SurrogateOptions options;
  options.metricSet = std::make_shared<const metrics::MetricSet>(logical->metrics, pipeline::scenarioAvailability(*logical),
                                                                 "cut_in metrics");
  options.modelFile = work.path() / "round.pt";
  options.vectornetSteps = 8;  // the system's part is not what this test is about
  options.futureSamples = 4;
  options.trees = 10;
  options.threads = 1;
  const auto columns = executionColumns(options.metricSet->names(), "r157_reference_driver");
  const auto judge = [&](const std::string& text) {
    const Criterion criterion(text, *logical, columns);
    constexpr Eigen::Index kRows = 40;
    TrainingSet data;
    data.x.resize(kRows, 1);
    data.y.resize(kRows, static_cast<Eigen::Index>(criterion.usedColumns().size()));
    data.columns = criterion.usedColumns();
    for (Eigen::Index r = 0; r < kRows; ++r) {
      data.x(r, 0) = static_cast<double>(r) / static_cast<double>(kRows - 1);
      for (std::size_t m = 0; m < data.columns.size(); ++m) {
        const bool reference = columns[data.columns[m]].rfind("reference_", 0) == 0;
        data.y(r, static_cast<Eigen::Index>(m)) = reference ? (data.x(r, 0) < 0.5 ? -1.0 : 5.0) : 3.0;
      }
    }
    data.scenes = {run_folder / "dataset.h5"};
    auto surrogate = makeVectorNetSurrogate(options);
    surrogate->fit(data);
    const vector::DatasetReader reader(run_folder / "dataset.h5");
    const auto scene = reader.scene(0);
    CandidateSet candidates;
    candidates.x.resize(2, 1);
    candidates.x << 0.1, 0.9;
    candidates.scene = [&](std::size_t) { return scene; };
    return surrogate->probability(candidates, criterion);
  };
  // Every future meets the system's part; the reference part decides alone.
  EXPECT_EQ(judge("d_min <= 1000 and reference_d_min > 0"), (std::vector<double>{0.0, 1.0}));
  EXPECT_EQ(judge("d_min <= 1000 and reference_d_min <= 0"), (std::vector<double>{1.0, 0.0}));
  // Without reference columns the futures alone decide, as before.
  EXPECT_EQ(judge("d_min <= 1000"), (std::vector<double>{1.0, 1.0}));
}

// The regulation's criterion searched with vectornet and a prior of another ALKS scenario:
// the prior pre-trains the system's model, each execution costs two simulations, and the
// reference driver's clearance is a column the rounds learn from.
TEST(SearchVectorNet, SearchesTheRegulationsCriterionWithAPriorOfAnotherAlksScenario) {
  TemporaryDirectory work("vsd-test-search");
  const auto prior = runLibraryScenario(work.path() / "lead_brake", "alks/lead_brake.yaml", 20);
  auto options = regulationSearch(work.path(), "vectornet", 40);
  options.priors = {prior};
  options.pool = 60;
  options.vectornetSteps = 8;
  options.futureSamples = 4;
  const auto summary = runSearch(options);
  EXPECT_EQ(summary.executions, 20u) << "40 simulations buy 20 executions with a reference driver";
  EXPECT_EQ(model::Predictor(options.outputDir / ".rounds" / "vectornet-prior.pt").info().labels,
            std::vector<std::string>{"lead_brake"});
  const auto table = CsvTable::read(options.outputDir / "concrete.csv");
  ASSERT_EQ(table.rows(), 20u);
  std::size_t guided = 0;  // chosen by the surrogate's probability: acquired or importance draws
  for (std::size_t r = 0; r < table.rows(); ++r) {
    if (table.cell(r, table.column("origin")) == "initial") continue;
    ++guided;
    const double p = std::stod(table.cell(r, table.column("predicted_probability")));
    EXPECT_TRUE(p >= 0.0 && p <= 1.0) << p;
    EXPECT_FALSE(table.cell(r, table.column("reference_d_min")).empty()) << "row " << r;
  }
  EXPECT_EQ(guided, 10u);
}

TEST(SearchReference, TheCriterionNeedsAReferenceAndTwoSimulationsPerExecution) {
  TemporaryDirectory work("vsd-test-search");
  SearchOptions options;
  options.scenarioFile = test::scenarioFile("alks/cut_in.yaml");
  options.outputDir = work.path() / "out";
  options.criterion = "reference_avoids_sut_collides";
  options.budget = 40;
  options.initial = 10;
  EXPECT_THAT(test::configErrorOf([&] { runSearch(options); }), HasSubstr("needs --reference NAME"));
  options.reference = "r157_reference_driver";
  options.budget = 15;  // 10 initial executions need 20 simulations
  EXPECT_THAT(test::configErrorOf([&] { runSearch(options); }), HasSubstr(">= --initial (10) x 2"));
  EXPECT_FALSE(fs::exists(options.outputDir));
}

TEST(SearchEstimate, TheImportanceProposalFollowsThePredictedProbabilityWithAnEvenShare) {
  const auto q = detail::importanceProposal({0.0, 0.5, 1.0, 0.9}, {false, false, false, true});
  EXPECT_NEAR(q[0], 0.2 / 3.0, 1e-12);
  EXPECT_NEAR(q[1], 0.8 * 0.5 / 1.5 + 0.2 / 3.0, 1e-12);
  EXPECT_NEAR(q[2], 0.8 * 1.0 / 1.5 + 0.2 / 3.0, 1e-12);
  EXPECT_EQ(q[3], 0.0);  // acquired: simulated in full, never drawn
  // Nothing predicted: an even draw over the stratum.
  EXPECT_EQ(detail::importanceProposal({0.0, 0.0}, {false, false}), (std::vector<double>{0.5, 0.5}));
}

TEST(SearchEstimate, StratifiedImportanceSamplingIsUnbiasedAndItsIntervalCoversThePoolsRate) {
  // Rounds of synthetic pools whose surrogate overstates the true rate (r = p^2, as measured
  // in stratum B of acc_lk), the best 30 acquired, 20 importance draws each: over many
  // repetitions the estimate averages the pools' critical share and its 95 % interval
  // covers it about 95 % of the time.
  constexpr std::size_t kPool = 2000;
  constexpr std::uint64_t kRounds = 10;
  detail::SearchContext context;
  context.options.pool = kPool;
  context.options.budget = 500;
  context.guides = true;
  Rng rng(42);
  double estimate_sum = 0.0;
  double truth_sum = 0.0;
  std::size_t covered = 0;
  constexpr int kRepetitions = 400;
  for (int repetition = 0; repetition < kRepetitions; ++repetition) {
    std::vector<Execution> executions;
    double pool_share = 0.0;
    for (std::uint64_t round = 1; round <= kRounds; ++round) {
      std::vector<double> p(kPool);
      std::vector<int> y(kPool);
      for (std::size_t i = 0; i < kPool; ++i) {
        p[i] = rng.uniform01() < 0.05 ? 0.2 + 0.7 * rng.uniform01() : 0.05 * rng.uniform01();
        y[i] = rng.uniform01() < p[i] * p[i] ? 1 : 0;
        pool_share += y[i];
      }
      std::vector<std::size_t> order(kPool);
      std::iota(order.begin(), order.end(), 0);
      std::partial_sort(order.begin(), order.begin() + 30, order.end(), [&](auto a, auto b) { return p[a] > p[b]; });
      std::vector<bool> acquired(kPool, false);
      for (std::size_t k = 0; k < 30; ++k) {
        acquired[order[k]] = true;
        Execution e;
        e.round = round;
        e.origin = "acquired";
        e.verdict = y[order[k]];
        executions.push_back(e);
      }
      const auto proposal = detail::importanceProposal(p, acquired);
      for (const auto& [position, times] : detail::drawFromPool(proposal, 20, rng)) {
        Execution e;
        e.round = round;
        e.origin = "importance";
        e.verdict = y[position];
        e.draws = times;
        e.weight = 1.0 / (static_cast<double>(kPool) * proposal[position]);
        executions.push_back(e);
      }
    }
    const double truth = pool_share / static_cast<double>(kPool * kRounds);
    const auto estimate = detail::estimateRate(context, executions);
    EXPECT_EQ(estimate.method, "importance-sampling");
    estimate_sum += estimate.estimate;
    truth_sum += truth;
    covered += estimate.low <= truth && truth <= estimate.high ? 1 : 0;
  }
  const double mean_truth = truth_sum / kRepetitions;
  EXPECT_NEAR(estimate_sum / kRepetitions, mean_truth, 0.03 * mean_truth);
  EXPECT_GE(static_cast<double>(covered) / kRepetitions, 0.90);
}

TEST(SearchEstimate, WilsonIntervalMatchesTheReference) {
  // scipy.stats.binomtest(8, 1000).proportion_ci(method="wilson") = (0.0040591958, 0.0157063345)
  const auto [low, high] = wilsonInterval(8, 1000);
  EXPECT_NEAR(low, 0.0040591958, 1e-9);
  EXPECT_NEAR(high, 0.0157063345, 1e-9);
  EXPECT_EQ(wilsonInterval(0, 0), (std::pair<double, double>(0.0, 1.0)));
}

}  // namespace
}  // namespace vsd::search

namespace vsd::search {
namespace {

TEST(SearchCli, BadFlagsAreOneLineWithExitCodeTwoAndNoFolder) {
  TemporaryDirectory work("vsd-test-search-cli");
  const auto out = work.path() / "out";
  const std::string scenario = test::scenarioFile("acc_lk.yaml").string();
  for (const std::vector<std::string>& flags :
       {std::vector<std::string>{"--criterion", "dmin < 2"}, {"--criterion", "d_min < 2", "--budget", "50"},
        {"--criterion", "d_min < 2", "--surrogate", "gp"}, {"--criterion", "d_min < 2", "--pool", "0"},
        {"--criterion", "d_min < 2", "--probability", "gauss"}, {"--criterion", "d_min < 2", "--ego-step-cost-ms", "-1"},
        {"--criterion", "d_min < 2", "--prior", scenario}}) {
    std::vector<std::string> argv = {test::vsdSumo().string(), "-q", "search", scenario, "--out", out.string()};
    argv.insert(argv.end(), flags.begin(), flags.end());
    const auto result = test::run(argv, work.path());
    EXPECT_EQ(result.exitCode, 2) << result.output;  // the command line is wrong: a usage error (docs/cli.md)
    EXPECT_THAT(result.output, HasSubstr("vsd-sumo: error: command line: "));
    EXPECT_EQ(std::count(result.output.begin(), result.output.end(), '\n'), 1) << result.output;
    EXPECT_FALSE(fs::exists(out));
  }
}

// `bench search --true-rate-samples --out` (docs/benchmarks.md, results/search): the true
// rate is `run`'s share of critical scenarios for that seed, every search's interval is
// checked against it, and the results folder follows the output policy.
TEST(SearchBenchCli, TheTrueRateIsRunsShareAndEachIntervalIsCheckedAgainstIt) {
  TemporaryDirectory work("vsd-test-search-bench");
  const auto out = work.path() / "bench";
  const std::string scenario = test::scenarioFile("acc_lk.yaml").string();
  const std::vector<std::string> bench = {test::vsdSumo().string(), "-q", "bench", "search", scenario,
                                          "--criterion", "d_min < 5", "--budget", "120", "--initial", "40",
                                          "--round", "40", "--pool", "400", "--seeds", "2", "--first-seed", "21",
                                          "--true-rate-samples", "400", "--true-rate-seed", "77"};
  auto argv = bench;
  argv.insert(argv.end(), {"--out", out.string()});
  const auto result = test::run(argv, work.path());
  ASSERT_EQ(result.exitCode, 0) << result.output;

  // The same 400 scenarios as `run --seed 77`: the same critical count.
  const auto run_out = work.path() / "run";
  ASSERT_EQ(test::run({test::vsdSumo().string(), "-q", "run", scenario, "--samples", "400", "--seed", "77", "--out",
                       run_out.string()},
                      work.path())
                .exitCode,
            0);
  const auto concrete = CsvTable::read(run_out / "concrete.csv");
  std::uint64_t critical = 0;
  for (std::size_t r = 0; r < concrete.rows(); ++r) {
    critical += concrete.number(r, concrete.column("d_min")) < 5.0 ? 1 : 0;
  }
  const auto manifest = nlohmann::json::parse(readTextFile(out / "manifest.json"));
  EXPECT_EQ(manifest.at("true_rate").at("critical").get<std::uint64_t>(), critical);
  EXPECT_GT(critical, 0u);
  const double rate = 100.0 * manifest.at("true_rate").at("estimate").get<double>();
  // The wall time (what the docs' time budgets are checked against) holds the true-rate run and
  // every search.
  const double true_rate_seconds = manifest.at("true_rate").at("seconds").get<double>();
  double search_seconds = 0.0;

  // Every search's row: covered exactly when its interval holds the true rate; the summary counts them.
  const auto searches = CsvTable::read(out / "searches.csv");
  ASSERT_EQ(searches.rows(), 4u);  // random and extra-trees, seeds 21 and 22
  std::map<std::string, int> covered;
  for (std::size_t r = 0; r < searches.rows(); ++r) {
    const double low = std::stod(searches.cell(r, searches.column("low_percent")));
    const double high = std::stod(searches.cell(r, searches.column("high_percent")));
    const bool covers = low <= rate && rate <= high;
    EXPECT_EQ(searches.cell(r, searches.column("covers_true_rate")), covers ? "1" : "0") << r;
    EXPECT_THAT(searches.cell(r, searches.column("seed")), testing::AnyOf("21", "22"));
    covered[searches.cell(r, searches.column("surrogate"))] += covers ? 1 : 0;
    search_seconds += searches.number(r, searches.column("seconds"));
    // The learning curve: one cumulative count per round (the initial design, then the search's
    // rounds), never falling, ending at the total.
    const auto curve = searches.cell(r, searches.column("critical_by_round"));
    std::vector<int> counts;
    for (std::size_t from = 0; from <= curve.size();) {
      const auto to = std::min(curve.find('/', from), curve.size());
      counts.push_back(std::stoi(curve.substr(from, to - from)));
      from = to + 1;
    }
    EXPECT_GE(counts.size(), 3u) << curve;  // the initial design and at least two rounds of 40 in 120
    EXPECT_TRUE(std::is_sorted(counts.begin(), counts.end())) << curve;
    EXPECT_LE(counts.front(), 40) << curve;
    EXPECT_EQ(std::to_string(counts.back()), searches.cell(r, searches.column("critical"))) << curve;
  }
  EXPECT_GT(true_rate_seconds, 0.0);
  EXPECT_GE(manifest.at("seconds").get<double>(), true_rate_seconds + search_seconds);
  EXPECT_NE(readTextFile(out / "README.md").find("- Wall time: "), std::string::npos);
  const auto surrogates = CsvTable::read(out / "surrogates.csv");
  ASSERT_EQ(surrogates.rows(), 2u);
  for (std::size_t r = 0; r < surrogates.rows(); ++r) {
    const auto name = surrogates.cell(r, surrogates.column("surrogate"));
    EXPECT_EQ(surrogates.cell(r, surrogates.column("covers_true_rate")), fmt::format("{}/2", covered[name])) << name;
  }

  // A re-run replaces its own folder; another kind's folder and a true-rate seed a search uses are refused.
  EXPECT_EQ(test::run(argv, work.path()).exitCode, 0);
  auto onto_run = bench;
  onto_run.insert(onto_run.end(), {"--out", run_out.string()});
  const auto refused = test::run(onto_run, work.path());
  EXPECT_NE(refused.exitCode, 0);
  EXPECT_THAT(refused.output, HasSubstr("run folder"));
  EXPECT_TRUE(fs::exists(run_out / "concrete.csv"));
  auto same_seed = bench;
  same_seed.insert(same_seed.end(), {"--true-rate-seed", "22", "--out", (work.path() / "other").string()});
  const auto clash = test::run(same_seed, work.path());
  EXPECT_NE(clash.exitCode, 0);
  EXPECT_THAT(clash.output, HasSubstr("--true-rate-seed"));
  EXPECT_EQ(std::count(clash.output.begin(), clash.output.end(), '\n'), 1) << clash.output;
  EXPECT_FALSE(fs::exists(work.path() / "other"));
}

// `bench search --reference` (results/alks_search): every execution of every search, and of
// the true-rate run, also runs the reference driver; both count against the budget, and the
// true rate of UN R157's criterion is `run --reference`'s count of its column for that seed.
TEST(SearchBenchCli, WithAReferenceDriverEachExecutionCostsTwoSimulationsAndTheTrueRateIsRunsCount) {
  TemporaryDirectory work("vsd-test-search-bench");
  const auto weak = weakCutIn(work.path());
  const auto out = work.path() / "bench";
  const auto result = test::run({test::vsdSumo().string(), "-q", "bench", "search", weak.string(), "--reference",
                                 "r157_reference_driver", "--criterion", "reference_avoids_sut_collides", "--budget",
                                 "60", "--initial", "10", "--round", "10", "--pool", "200", "--seeds", "1",
                                 "--true-rate-samples", "100", "--true-rate-seed", "5", "--out", out.string()},
                                work.path());
  ASSERT_EQ(result.exitCode, 0) << result.output;
  const auto searches = CsvTable::read(out / "searches.csv");
  ASSERT_EQ(searches.rows(), 2u);  // random and extra-trees
  for (std::size_t r = 0; r < searches.rows(); ++r) {
    EXPECT_EQ(searches.cell(r, searches.column("executions")), "30") << "60 simulations buy 30 executions";
  }
  const auto manifest = nlohmann::json::parse(readTextFile(out / "manifest.json"));
  EXPECT_EQ(manifest.at("reference").get<std::string>(), "r157_reference_driver");
  EXPECT_THAT(readTextFile(out / "README.md"), HasSubstr("Reference driver: `r157_reference_driver`"));

  const auto run_out = work.path() / "run";
  ASSERT_EQ(test::run({test::vsdSumo().string(), "-q", "run", weak.string(), "--samples", "100", "--seed", "5",
                       "--reference", "r157_reference_driver", "--out", run_out.string()},
                      work.path())
                .exitCode,
            0);
  const auto concrete = CsvTable::read(run_out / "concrete.csv");
  std::uint64_t fails = 0;
  for (std::size_t r = 0; r < concrete.rows(); ++r) {
    fails += concrete.cell(r, concrete.column("reference_avoids_sut_collides")) == "1" ? 1 : 0;
  }
  EXPECT_GT(fails, 0u);
  EXPECT_EQ(manifest.at("true_rate").at("critical").get<std::uint64_t>(), fails);
}

// The true rate is plain Monte Carlo: the priors of the surrogates compared (bench search
// --surrogates vectornet --prior ... --true-rate-samples N) neither change nor refuse it.
TEST(SearchBench, TheTrueRateIgnoresThePriorsOfTheSurrogates) {
  TemporaryDirectory work("vsd-test-search-bench");
  const auto prior = work.path() / "acc";
  ASSERT_EQ(test::run({test::vsdSumo().string(), "-q", "run", test::scenarioFile("acc.yaml").string(), "--samples",
                       "20", "--out", prior.string()},
                      work.path())
                .exitCode,
            0);
  SearchOptions options;
  options.scenarioFile = test::scenarioFile("acc_lk.yaml");
  options.criterion = "d_min < 5";
  const auto plain = monteCarloRate(options, 9, 60);
  options.priors = {prior};
  const auto with_priors = monteCarloRate(options, 9, 60);
  EXPECT_EQ(with_priors.critical, plain.critical);
  EXPECT_GT(plain.critical, 0u);
}

// Numeric flags are checked where they enter (src/cli/flags.hpp): no wrap-around of a
// negative budget into 2^64 - 5, no infinite pool, no zero seeds in the bench.
TEST(SearchCli, NumbersFromFlagsAreCheckedWhereTheyEnter) {
  TemporaryDirectory work("vsd-test-search-cli");
  const auto out = work.path() / "out";
  const std::string scenario = test::scenarioFile("acc_lk.yaml").string();
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"search", scenario, "--out", out.string(), "-c", "d_min < 2", "--budget", "-5"},
       "--budget: got '-5', expected a whole number"},
      {{"search", scenario, "--out", out.string(), "-c", "d_min < 2", "--pool", "inf"},
       "--pool: got 'inf', expected a whole number"},
      {{"search", scenario, "--out", out.string(), "-c", "d_min < 2", "--diversity", "nan"},
       "--diversity: got 'nan', expected a finite decimal number"},
      {{"bench", "search", scenario, "--budget", "-5"}, "--budget: got '-5', expected a whole number"},
      {{"bench", "search", scenario, "--seeds", "0"}, "--seeds"},
      {{"bench", "search", scenario, "--first-seed", "18446744073709551615"}, "--first-seed"},  // would wrap around
      // Every search's options are checked before the true-rate run (which would take minutes here).
      {{"bench", "search", scenario, "--surrogates", "random,extra-trees", "--reference", "r157_reference_driver",
        "--budget", "60", "--initial", "40", "--true-rate-samples", "100000"},
       ">= --initial (40) x 2"},
  };
  for (const auto& [flags, expected] : cases) {
    std::vector<std::string> argv = {test::vsdSumo().string(), "-q"};
    argv.insert(argv.end(), flags.begin(), flags.end());
    const auto result = test::run(argv, work.path());
    EXPECT_EQ(result.exitCode, 2) << result.output;  // a flag's value: a usage error (docs/cli.md)
    EXPECT_THAT(result.output, HasSubstr(expected));
    EXPECT_EQ(std::count(result.output.begin(), result.output.end(), '\n'), 1) << result.output;
    EXPECT_FALSE(fs::exists(out));
  }
}

}  // namespace
}  // namespace vsd::search
