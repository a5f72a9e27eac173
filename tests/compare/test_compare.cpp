// `vsd-sumo compare` end to end: a small model trained once, fresh scenarios predicted
// without simulating them, then simulated and compared.
#include <gtest/gtest.h>

#include <cmath>

#include "test_support.hpp"
#include "vsd/compare/compare.hpp"
#include "vsd/core/csv.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/model/model.hpp"
#include "vsd/pipeline/map_export.hpp"
#include "vsd/pipeline/run.hpp"

using namespace vsd;
using namespace vsd::compare;
namespace fs = std::filesystem;

namespace {

/// Simulates `samples` scenarios of a paper scenario into `out` (concrete.csv, dataset.h5, ...).
void simulate(const std::string& scenario, const fs::path& out, std::uint64_t samples, std::uint64_t seed) {
  pipeline::RunOptions run;
  run.scenarioFile = test::scenarioFile(scenario);
  run.outputDir = out;
  run.samples = samples;
  run.seed = seed;
  pipeline::runScenarios(run);
}

/// One small model for all of the suite's test processes: acc_lk, 300 scenarios, a short
/// schedule (~15 s, built once per build of this test). The tests check consistency
/// (compare vs evaluate, failures, errors), not accuracy.
class CompareTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    fixture_ = test::sharedFixture("compare-acc_lk-model", [](const fs::path& dir) {
      simulate("acc_lk.yaml", dir / "train", 300, 5);
      model::TrainOptions train;
      train.data = {dir / "train"};
      train.output = dir / "m.pt";
      train.steps = 300;
      train.patience = 1000;
      model::train(train);
    });
  }
  static fs::path modelFile() { return fixture_ / "m.pt"; }
  static fs::path trainingData() { return fixture_ / "train"; }

  CompareOptions scenarioOptions(const fs::path& out, std::uint64_t samples = 60) const {
    CompareOptions options;
    options.model = modelFile();
    options.scenarioFile = test::scenarioFile("acc_lk.yaml");
    options.samples = samples;
    options.seed = 99;
    options.output = out;
    options.worst = 3;
    return options;
  }

  static fs::path fixture_;
  TemporaryDirectory work_;
};
fs::path CompareTest::fixture_;

std::string errorOf(const std::function<void()>& call) {
  try {
    call();
  } catch (const Error& error) {
    return error.what();
  }
  return "";
}

}  // namespace

// The prediction from scenes built *before* simulation must score like `evaluate` on the
// scenes the simulation stored (same seed, same scenarios): this is what makes the
// comparison a test of the model and not of the vectorization.
TEST_F(CompareTest, ScenarioModeScoresLikeEvaluateOnTheSimulatedScenes) {
  const auto summary = runComparison(scenarioOptions(work_.path() / "report"));
  const auto& stats = summary.statistics;
  EXPECT_EQ(stats.compared + stats.failed, 60u);
  EXPECT_GE(stats.compared, 55u);

  simulate("acc_lk.yaml", work_.path() / "simulated", 60, 99);
  const model::Predictor predictor(modelFile());
  const auto evaluation = model::evaluate(predictor, {work_.path() / "simulated"});
  EXPECT_EQ(evaluation.overall.samples, stats.compared);
  EXPECT_NEAR(stats.ade.mean, evaluation.overall.ade, 0.01);
  EXPECT_NEAR(stats.fde.mean, evaluation.overall.fde, 0.02);

  // Every metric of the scenario, with MAE, bias and the reconstruction floor.
  ASSERT_EQ(stats.metrics.size(), 7u);
  for (const auto& metric : stats.metrics) {
    EXPECT_GT(metric.pairs + metric.bothInfinite + metric.finitenessMismatch, 0u) << metric.name;
    if (metric.pairs > 0) {
      EXPECT_TRUE(std::isfinite(metric.mae)) << metric.name;
    }
    EXPECT_TRUE(metric.floorMae.has_value()) << metric.name;
  }
  // d_min is the clearance between footprints: positions are exact (float rounding and
  // netconvert's 1 cm), headings of the scenes come from each step's displacement, not
  // SUMO's angle - a degree turns a corner 1.5 cm: a few cm in all.
  EXPECT_LT(*stats.metrics[1].floorMae, 0.05);
  ASSERT_EQ(stats.criteria.size(), 1u);
  const auto& criterion = stats.criteria[0];
  EXPECT_EQ(criterion.bothFail + criterion.falseAlarm + criterion.missed + criterion.bothPass + criterion.undefined,
            stats.compared);

  // comparison.csv agrees with concrete.csv of the separate run: same scenarios, same simulation.
  const auto compared = CsvTable::read(work_.path() / "report" / "comparison.csv");
  const auto concrete = CsvTable::read(work_.path() / "simulated" / "concrete.csv");
  ASSERT_EQ(compared.rows(), 60u);
  for (std::size_t row = 0; row < 60; ++row) {
    EXPECT_EQ(compared.cell(row, compared.column("sample")), concrete.cell(row, concrete.column("sample")));
    EXPECT_EQ(compared.cell(row, compared.column("v_ego")), concrete.cell(row, concrete.column("v_ego")));
    EXPECT_EQ(compared.cell(row, compared.column("d_min_simulated_m")), concrete.cell(row, concrete.column("d_min")));
  }
  const auto html = readTextFile(work_.path() / "report" / "report.html");
  EXPECT_NE(html.find("The 3 scenarios with the largest ADE"), std::string::npos);
  EXPECT_NE(html.find("VectorNet prediction"), std::string::npos);
  EXPECT_NE(html.find(sha256OfFile(modelFile())), std::string::npos);
  EXPECT_LT(fs::file_size(work_.path() / "report" / "report.html"), 5u * 1024 * 1024);
  // The same scoring without a report (what `vsd-sumo bench model` scores with): the same rows, nothing written.
  const auto rows = compareScenarioPredictions(scenarioOptions(work_.path() / "not written"), predictor);
  EXPECT_FALSE(fs::exists(work_.path() / "not written"));
  ASSERT_EQ(rows.scenarios.size(), summary.comparison.scenarios.size());
  EXPECT_EQ(rows.metricNames, summary.comparison.metricNames);
  const auto same = [](const std::vector<double>& a, const std::vector<double>& b) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i) {
      if (!(a[i] == b[i] || (std::isnan(a[i]) && std::isnan(b[i])))) return false;
    }
    return true;
  };
  for (std::size_t i = 0; i < rows.scenarios.size(); ++i) {
    const auto& row = rows.scenarios[i];
    const auto& shown = summary.comparison.scenarios[i];
    EXPECT_EQ(row.failure, shown.failure) << i;
    EXPECT_EQ(row.ade, shown.ade) << i;
    EXPECT_TRUE(same(row.predicted, shown.predicted)) << i;
    EXPECT_TRUE(same(row.reference, shown.reference)) << i;
    EXPECT_TRUE(same(row.fromReferencePositions, shown.fromReferencePositions)) << i;
  }
  // Nothing but the two outputs, and no temporary folder left beside them.
  std::size_t entries = 0;
  for (const auto& entry : fs::directory_iterator(work_.path())) entries += entry.path().filename().string()[0] == '.';
  EXPECT_EQ(entries, 0u);
}

TEST_F(CompareTest, AScenarioSumoFailsOnIsListedAndTheRestIsCompared) {
  const auto scenario = test::writeFile(work_.path() / "short_road.yaml", test::shortRoadScenario());
  auto options = scenarioOptions(work_.path() / "short");
  options.scenarioFile = scenario;
  options.samples = 40;
  const auto summary = runComparison(options);
  EXPECT_GT(summary.statistics.failed, 0u);
  EXPECT_GT(summary.statistics.compared, 0u);
  const auto html = readTextFile(work_.path() / "short" / "report.html");
  EXPECT_NE(html.find("without a simulated reference"), std::string::npos);
  EXPECT_NE(html.find("vehicle &#39;co&#39; reached the end of its road"), std::string::npos);
  const auto csv = CsvTable::read(work_.path() / "short" / "comparison.csv");
  std::size_t failed = 0;
  for (std::size_t row = 0; row < csv.rows(); ++row) failed += csv.cell(row, csv.column("status")) == "failed";
  EXPECT_EQ(failed, summary.statistics.failed);
}

// Dataset mode on the simulated run's own dataset: predicted vs recorded is exactly `evaluate`.
TEST_F(CompareTest, DatasetModeComparesAgainstTheRecordedFuture) {
  simulate("acc.yaml", work_.path() / "acc", 50, 3);
  CompareOptions options;
  options.model = modelFile();
  options.data = {work_.path() / "acc"};
  options.output = work_.path() / "dataset_report";
  options.criteria = {"close: d_min < 2", "ttc_min < 1.5"};
  const auto summary = runComparison(options);
  const model::Predictor predictor(modelFile());
  const auto evaluation = model::evaluate(predictor, {work_.path() / "acc"});
  EXPECT_EQ(summary.statistics.compared, evaluation.overall.samples);
  EXPECT_NEAR(summary.statistics.ade.mean, evaluation.overall.ade, 1e-9);
  EXPECT_EQ(summary.comparison.referenceName, "recorded");
  // A generated dataset brings its scenario's metrics.
  EXPECT_EQ(summary.comparison.metricNames, (std::vector<std::string>{"a_min", "d_min", "p_lat_max", "y_max",
                                                                      "ttc_min", "thw_min", "lane_offset_max"}));
  ASSERT_EQ(summary.statistics.criteria.size(), 2u);
  EXPECT_EQ(summary.statistics.criteria[1].name, "ttc_min < 1.5");
  const auto csv = CsvTable::read(work_.path() / "dataset_report" / "comparison.csv");
  EXPECT_TRUE(csv.findColumn("d_min_recorded_m").has_value());
  EXPECT_TRUE(csv.findColumn("close_recorded_fail").has_value());
}

// A real OSM-imported map (Debian's sumo-tools) with its own traffic: nothing to simulate
// again, the prediction is compared with the recorded future of each Ego window.
TEST_F(CompareTest, DatasetModeWorksOnAnExportedRealMap) {
  pipeline::ExportOptions exporting;
  exporting.source.config = "/usr/share/sumo/tools/game/A10KW.sumocfg";
  exporting.output = work_.path() / "a10.h5";
  exporting.egos = "random:20";
  exporting.seed = 3;
  exporting.end = 120.0;
  pipeline::exportMap(exporting);
  CompareOptions options;
  options.model = modelFile();
  options.data = {exporting.output};
  options.output = work_.path() / "map_report";
  options.criteria = {"close: d_min < 2"};
  const auto summary = runComparison(options);
  EXPECT_GT(summary.statistics.compared, 20u);
  // Every default metric a recorded Ego future allows (the Ego's own deceleration and jerk too).
  const std::vector<std::string> names = {"a_min",   "d_min",           "d_lon_min", "ttc_min",  "thw_min",
                                          "lane_offset_max", "pet_min", "drac_max", "decel_max", "jerk_max"};
  EXPECT_EQ(summary.comparison.metricNames, names);
  // The recorded futures of SUMO's drivers: they keep to their lanes (offsets within half
  // a lane, lane changes included) and do not collide - a car side by side in the next
  // lane is not a collision (centre distances minus half lengths counted one).
  std::size_t offsets = 0;
  for (const auto& row : summary.comparison.scenarios) {
    if (!row.failure.empty()) continue;
    const double d_min = row.reference[1];
    const double lane_offset = row.reference[5];
    if (std::isfinite(d_min)) {
      // SUMO checks no collisions on junctions by default (collision.check-junctions):
      // there its drivers' footprints overlap by up to ~0.2 m; side by side gave -2 m.
      EXPECT_GT(d_min, -0.5) << row.sample;
    }
    if (std::isfinite(lane_offset)) {
      ++offsets;
      EXPECT_LT(lane_offset, 2.0) << row.sample;
    }
  }
  EXPECT_GT(offsets, summary.statistics.compared / 2);
  EXPECT_TRUE(std::isfinite(summary.statistics.ade.mean));
  const auto html = readTextFile(work_.path() / "map_report" / "report.html");
  EXPECT_NE(html.find("Predicted vs recorded"), std::string::npos);
  EXPECT_NE(html.find("a10.h5"), std::string::npos);
  EXPECT_NE(html.find("Ego: initial vector and recorded future"), std::string::npos);
}

TEST_F(CompareTest, BadInputGetsOneClearErrorAndLeavesNothingBehind) {
  // The output policy (docs/output-policy.md): the user's notes are kept next to the report;
  // a report of another scenario is replaced only with --force.
  const auto existing = work_.path() / "existing";
  test::writeFile(existing / "keep.txt", "mine");
  runComparison(scenarioOptions(existing, 5));
  EXPECT_TRUE(fs::exists(existing / "report.html"));
  auto other = scenarioOptions(existing, 5);
  other.scenarioFile = test::scenarioFile("lk.yaml");
  EXPECT_NE(errorOf([&] { runComparison(other); }).find("holds a comparison report folder of acc_lk with"),
            std::string::npos)
      << errorOf([&] { runComparison(other); });
  other.force = true;
  runComparison(other);
  EXPECT_TRUE(fs::exists(existing / "keep.txt"));  // the report's files replaced; a file it never wrote is kept
  EXPECT_NE(readTextFile(existing / "manifest.json").find("\"subject\": \"lk with"), std::string::npos);

  // A model for another step/horizon than the scenario's.
  const auto longer = test::writeFile(work_.path() / "longer.yaml",
                                      test::scenarioVariant("acc_lk.yaml", "duration: 5.0", "duration: 6.0"));
  auto options = scenarioOptions(work_.path() / "out_longer", 5);
  options.scenarioFile = longer;
  EXPECT_NE(errorOf([&] { runComparison(options); }).find("30 steps of 0.2 s, but the model"), std::string::npos);
  // A model written for another feature schema.
  const auto v2 = work_.path() / "v2.pt";
  ASSERT_TRUE(test::writeModelForFeatureSchemaV2(modelFile(), v2));
  options = scenarioOptions(work_.path() / "out_v2", 5);
  options.model = v2;
  EXPECT_NE(errorOf([&] { runComparison(options); }).find("feature schema v2"), std::string::npos);
  // A corrupt model file.
  const auto corrupt = test::writeFile(work_.path() / "corrupt.pt", "not a model");
  options = scenarioOptions(work_.path() / "out_corrupt", 5);
  options.model = corrupt;
  EXPECT_NE(errorOf([&] { runComparison(options); }).find("corrupt.pt"), std::string::npos);
  // A criterion over a metric the run does not compute.
  options = CompareOptions{};
  options.model = modelFile();
  options.data = {trainingData()};
  options.output = work_.path() / "out_criterion";
  options.criteria = {"close: gap_min < 2"};
  EXPECT_NE(errorOf([&] { runComparison(options); }).find("gap_min"), std::string::npos);
  // Scenario and datasets at once.
  options.scenarioFile = test::scenarioFile("acc.yaml");
  EXPECT_NE(errorOf([&] { runComparison(options); }).find("either a logical scenario"), std::string::npos);
  for (const char* out : {"out_longer", "out_v2", "out_corrupt", "out_criterion"}) {
    EXPECT_FALSE(fs::exists(work_.path() / out)) << out;
  }
  std::size_t hidden = 0;
  for (const auto& entry : fs::directory_iterator(work_.path())) hidden += entry.path().filename().string()[0] == '.';
  EXPECT_EQ(hidden, 0u);
}

TEST_F(CompareTest, CommandLineRefusesAScenarioWithoutAnEgo) {
  const auto no_ego = test::writeFile(work_.path() / "no_ego.yaml", test::scenarioVariant("lk.yaml", "  ego:", "  egg:"));
  const auto result = test::run({test::vsdSumo().string(), "compare", no_ego.string(), "--model", modelFile().string(),
                                 "--out", (work_.path() / "out").string()},
                                work_.path());
  EXPECT_NE(result.exitCode, 0);
  EXPECT_NE(result.output.find("no_ego.yaml"), std::string::npos) << result.output;
  EXPECT_NE(result.output.find("vehicles"), std::string::npos) << result.output;
  EXPECT_FALSE(fs::exists(work_.path() / "out"));
}
