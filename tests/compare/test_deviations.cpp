// `vsd-sumo deviations`: recorded Ego behaviour scored against a small calibrated model
// trained once on synthetic ACC-like scenes (tests/model/synthetic_scenes.hpp). The tests
// check what a user relies on - a changed behaviour is flagged and said to be longitudinal
// or lateral, unseen labels are apart, outputs and bad input - not the model's accuracy.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <fstream>

#include "../model/synthetic_scenes.hpp"
#include "test_support.hpp"
#include "vsd/compare/deviations.hpp"
#include "vsd/core/csv.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/model/model.hpp"
#include "vsd/pipeline/scenes.hpp"

using namespace vsd;
using namespace vsd::compare;
namespace fs = std::filesystem;

namespace {

/// How a field scene's recorded Ego future is changed from the synthetic one.
enum class Change { None, Brakes, Swerves };

/// The recorded future of the synthetic scene `i`, changed: Brakes travels half the
/// distance along the lane (a deceleration the scenes never had), Swerves drifts 3 m across.
vector::VectorizedScene fieldScene(std::uint64_t i, Change change, const std::string& label = "acc") {
  auto scene = test::syntheticScene(i, label);
  const auto start = scene.egoInitialState();
  const Vec2 u = headingVector(start.heading);
  const Vec2 n(-u.y(), u.x());
  for (std::size_t k = 0; k < scene.target.size(); ++k) {
    const double t = static_cast<double>(k + 1) / static_cast<double>(scene.target.size());
    if (change == Change::Brakes) scene.target[k] = start.position() + 0.5 * (scene.target[k] - start.position());
    if (change == Change::Swerves) scene.target[k] += 3.0 * t * n;
  }
  return scene;
}

fs::path writeField(const fs::path& path, const std::vector<vector::VectorizedScene>& scenes, int horizon = 25) {
  vector::DatasetHeader header;
  header.step = 0.2;
  header.horizon = horizon;
  vector::DatasetWriter writer(path, header);
  for (auto scene : scenes) {
    scene.target.resize(static_cast<std::size_t>(horizon));
    scene.targetValid.resize(static_cast<std::size_t>(horizon));
    writer.append(scene);
  }
  writer.close();
  return path;
}

/// One calibrated kinematic model per test process (a few seconds).
class DeviationsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TemporaryDirectory();
    auto options = test::tinyTraining(test::writeDataset(dir_->path() / "acc.h5", 120), dir_->path() / "k.pt");
    options.config.decoder = "kinematic";
    options.config.decoderOptions = {{"calibrate", 1.0}};
    options.steps = 40;
    options.validationFraction = 0.5;  // 60 held-out scenes calibrate it
    auto metric_set = std::make_shared<const metrics::MetricSet>(std::vector<std::string>{"a_min", "d_min", "lane_offset_max"},
                                                                 pipeline::sceneAvailability("generated"), "test");
    auto binding = std::make_shared<model::MetricBinding>();
    binding->names = metric_set->names();
    binding->compute = [metric_set](const vector::VectorizedScene& scene, const model::Trajectory& future) {
      return pipeline::metricsOfFuture(*metric_set, scene, future.positions, future.states);
    };
    options.metrics = binding;
    model::train(options);
    model_ = options.output;
  }
  static void TearDownTestSuite() { delete dir_; }

  static DeviationOptions optionsFor(const fs::path& data, const fs::path& out) {
    DeviationOptions options;
    options.model = model_;
    options.data = {data};
    options.output = out;
    options.threads = 1;
    options.drawn = 2;
    return options;
  }

  static TemporaryDirectory* dir_;
  static fs::path model_;
};
TemporaryDirectory* DeviationsTest::dir_ = nullptr;
fs::path DeviationsTest::model_;

TEST_F(DeviationsTest, FlagsChangedBehaviourAndSaysAlongWhichAxisItDeviates) {
  const model::Predictor predictor(model_, 1);
  EXPECT_EQ(predictor.info().roadUsers, std::vector<std::string>{"car"});  // what it trained on is recorded
  const auto available = pipeline::sceneAvailability("generated");
  const DeviationScorer scorer(predictor, "k.pt", metrics::defaultMetrics(available), available, 1);
  EXPECT_EQ(scorer.metricNames(), (std::vector<std::string>{"a_min", "d_min", "lane_offset_max"}));  // the calibrated ones
  std::vector<vector::VectorizedScene> clean, brakes, swerves;
  for (std::uint64_t i = 200; i < 240; ++i) {
    clean.push_back(fieldScene(i, Change::None));
    brakes.push_back(fieldScene(i, Change::Brakes));
    swerves.push_back(fieldScene(i, Change::Swerves));
  }
  DeviationResult result;
  result.metricNames = scorer.metricNames();
  result.metricUnits = scorer.metricUnits();
  result.step = 0.2;
  for (const auto* set : {&clean, &brakes, &swerves}) {
    for (auto& row : scorer.score(*set, {}, "field")) result.scenes.push_back(std::move(row));
  }
  const auto ranked = rankDeviations(result);
  std::size_t clean_flagged = 0, brakes_flagged = 0, swerves_flagged = 0, brakes_longitudinal = 0, swerves_lateral = 0;
  for (std::size_t i = 0; i < 40; ++i) {
    const auto& c = result.scenes[i];
    const auto& b = result.scenes[40 + i];
    const auto& s = result.scenes[80 + i];
    ASSERT_EQ(c.status, SceneStatus::Scored);
    EXPECT_GE(c.p, 0.0);
    EXPECT_LE(c.p, 1.0);
    clean_flagged += c.flagged ? 1 : 0;
    for (const auto& tail : b.metrics) {
      // No smaller than the 60 held-out scenes resolve: beyond their largest score, 1 / 61.
      if (!std::isnan(tail.p)) {
        EXPECT_GE(tail.p, 1.0 / 61.0 - 1e-12);
      }
    }
    brakes_flagged += b.flagged ? 1 : 0;
    swerves_flagged += s.flagged ? 1 : 0;
    EXPECT_GT(b.regionExcess, 1.0);  // its path leaves the calibrated 90 % region
    brakes_longitudinal += b.axis == "longitudinal" && b.longitudinal < 0.0 ? 1 : 0;
    swerves_lateral += s.axis == "lateral" && s.lateral > 0.0 ? 1 : 0;
    if (b.flagged) {
      EXPECT_NE(b.reason.find("calibrated 90 % interval"), std::string::npos) << b.reason;
      EXPECT_NE(b.group.find("acc: "), std::string::npos) << b.group;
    }
  }
  EXPECT_LE(clean_flagged, 8u);  // level 0.05 of 40: a handful at most on scenes like the tests'
  EXPECT_GE(brakes_flagged, 36u);  // a tiny model's intervals are wide: most, not all
  EXPECT_GE(swerves_flagged, 36u);
  EXPECT_GE(brakes_longitudinal, 36u);
  EXPECT_GE(swerves_lateral, 36u);
  // Ranked most surprising first, flagged only.
  for (std::size_t r = 1; r < ranked.size(); ++r) EXPECT_LE(result.scenes[ranked[r - 1]].p, result.scenes[ranked[r]].p);
  for (const auto i : ranked) EXPECT_TRUE(result.scenes[i].flagged);
}

TEST_F(DeviationsTest, WritesATableWithUnitsAndAReportAndSetsUnseenLabelsApart) {
  TemporaryDirectory dir;
  std::vector<vector::VectorizedScene> scenes;
  for (std::uint64_t i = 300; i < 310; ++i) scenes.push_back(fieldScene(i, i % 2 ? Change::Brakes : Change::None));
  for (std::uint64_t i = 310; i < 313; ++i) scenes.push_back(fieldScene(i, Change::None, "lk"));  // never trained on
  const auto field = writeField(dir.path() / "field.h5", scenes);
  const auto out = dir.path() / "report";
  const auto summary = findDeviations(optionsFor(field, out));
  EXPECT_EQ(summary.scored(), 10u);
  EXPECT_EQ(summary.outOfDistribution(), 3u);
  EXPECT_GE(summary.ranked.size(), 5u);  // the five braking scenes at least
  for (const auto i : summary.ranked) EXPECT_EQ(summary.result.scenes[i].label, "acc");

  const auto table = CsvTable::read(out / "deviations.csv");
  EXPECT_EQ(table.rows(), 13u);
  for (const std::string column : {"p", "flagged", "rank", "group", "axis", "along_m", "across_m", "region_time_s",
                                   "a_min_recorded_m_s2", "a_min_p05_m_s2", "a_min_p", "d_min_median_m", "v0_ego_m_s",
                                   "status", "reason"}) {
    EXPECT_TRUE(table.findColumn(column)) << column;
  }
  const auto status = *table.findColumn("status");
  std::size_t apart = 0;
  for (std::size_t r = 0; r < table.rows(); ++r) apart += table.cell(r, status) == "out_of_distribution" ? 1 : 0;
  EXPECT_EQ(apart, 3u);
  const auto html = readTextFile(out / "report.html");
  EXPECT_NE(html.find("What deviates"), std::string::npos);
  EXPECT_NE(html.find("calibrated 90 % region"), std::string::npos);  // the drawn region's legend
  EXPECT_NE(html.find("Out of the model&#39;s distribution"), std::string::npos);
  EXPECT_TRUE(fs::exists(out / "manifest.json"));
  // The same data and model again: its own report is replaced.
  EXPECT_NO_THROW(findDeviations(optionsFor(field, out)));
}

/// Runs `options` expecting an error of type E whose one line holds `needle`, and nothing written.
template <typename E>
void expectRefused(const DeviationOptions& options, const std::string& needle) {
  try {
    findDeviations(options);
    ADD_FAILURE() << "accepted; expected: " << needle;
  } catch (const E& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find(needle), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
  EXPECT_FALSE(fs::exists(options.output)) << options.output;
}

TEST_F(DeviationsTest, BadInputIsOneLineAndWritesNothing) {
  TemporaryDirectory dir;
  std::vector<vector::VectorizedScene> scenes = {fieldScene(400, Change::None), fieldScene(401, Change::None)};
  const auto field = writeField(dir.path() / "field.h5", scenes);
  const auto out = dir.path() / "out";
  for (const double level : {0.0, 1.0, -0.1, 1.5}) {
    auto options = optionsFor(field, out);
    options.level = level;
    expectRefused<ConfigError>(options, "--level");
  }
  expectRefused<ModelError>(optionsFor(writeField(dir.path() / "short.h5", scenes, 20), out), "20 steps of 0.2 s");
  fs::create_directories(dir.path() / "empty");
  expectRefused<DatasetError>(optionsFor(dir.path() / "empty", out), "empty");
  auto pedestrian = scenes;
  pedestrian[1].polylines[pedestrian[1].egoPolyline == 0 ? 1 : 0].roadUser = RoadUserType::Pedestrian;
  for (auto& polyline : pedestrian[1].polylines) {
    if (polyline.type == vector::ObjectType::Vehicle) polyline.roadUser = RoadUserType::Pedestrian;
  }
  expectRefused<ModelError>(optionsFor(writeField(dir.path() / "pedestrian.h5", pedestrian), out), "'pedestrian'");
  // A model without calibrated metric intervals.
  auto plain = test::tinyTraining(test::writeDataset(dir.path() / "acc.h5", 20), dir.path() / "plain.pt");
  plain.config.decoder = "kinematic";
  plain.steps = 2;
  model::train(plain);
  auto options = optionsFor(field, out);
  options.model = plain.output;
  expectRefused<ModelError>(options, "calibrate=1");
}

TEST_F(DeviationsTest, CalibrationRunsRankTheFieldAndFlagChangedBehaviourWithTheLevelsShareOfCleanScenes) {
  TemporaryDirectory dir;
  std::vector<vector::VectorizedScene> runs, field;
  for (std::uint64_t i = 500; i < 700; ++i) runs.push_back(fieldScene(i, Change::None));  // clean, never trained on
  for (std::uint64_t i = 200; i < 240; ++i) field.push_back(fieldScene(i, Change::None));
  for (std::uint64_t i = 240; i < 260; ++i) field.push_back(fieldScene(i, Change::Brakes));
  for (std::uint64_t i = 260; i < 280; ++i) field.push_back(fieldScene(i, Change::Swerves));
  auto options = optionsFor(writeField(dir.path() / "field.h5", field), dir.path() / "report");
  options.calibration = {writeField(dir.path() / "runs.h5", runs)};
  const auto summary = findDeviations(options);
  EXPECT_EQ(summary.result.calibrationRuns, 200u);
  std::size_t clean_flagged = 0, changed_flagged = 0, path_p = 0;
  for (std::size_t i = 0; i < 80; ++i) {
    const auto& row = summary.result.scenes[i];
    ASSERT_EQ(row.status, SceneStatus::Scored);
    EXPECT_GE(row.pathP, 1.0 / 201.0 - 1e-12);  // ranked among 200 runs
    path_p += std::isnan(row.pathP) ? 0 : 1;
    (i < 40 ? clean_flagged : changed_flagged) += row.flagged ? 1 : 0;
    for (const auto& tail : row.metrics) {
      if (!std::isfinite(tail.p05)) continue;
      EXPECT_NEAR(tail.p05 + tail.p95, 2.0 * tail.mostLikely, 1e-9);  // around the most likely future
    }
  }
  EXPECT_EQ(path_p, 80u);
  EXPECT_LE(clean_flagged, 8u);
  EXPECT_GE(changed_flagged, 38u);
  const auto table = CsvTable::read(options.output / "deviations.csv");
  for (const std::string column : {"path_p", "region_mean_excess_90", "a_min_most_likely_m_s2"}) {
    EXPECT_TRUE(table.findColumn(column)) << column;
  }
  EXPECT_NE(readTextFile(options.output / "report.html").find("conformal ranks among 200 clean calibration runs"),
            std::string::npos);
}

TEST_F(DeviationsTest, CalibrationRunsThatCannotRankTheFieldAreOneLineAndWriteNothing) {
  TemporaryDirectory dir;
  std::vector<vector::VectorizedScene> runs, other_label;
  for (std::uint64_t i = 500; i < 519; ++i) runs.push_back(fieldScene(i, Change::None));
  for (std::uint64_t i = 500; i < 530; ++i) other_label.push_back(fieldScene(i, Change::None, "acc_lk"));
  const auto field = writeField(dir.path() / "field.h5", {fieldScene(200, Change::None)});
  const auto out = dir.path() / "out";
  auto options = optionsFor(field, out);
  // 19 runs: one extreme p of four (three metrics and the path) gives Simes' 4 / 20, never below 0.05.
  options.calibration = {writeField(dir.path() / "few.h5", runs)};
  expectRefused<ConfigError>(options, "at least 80 clean runs");
  options.calibration = {writeField(dir.path() / "other.h5", other_label)};
  expectRefused<ConfigError>(options, "0 runs of label 'acc'");
  fs::create_directories(dir.path() / "empty");
  options.calibration = {dir.path() / "empty"};
  expectRefused<DatasetError>(options, "--calibration");
}

// The command line: --calibration is passed through, and a bad one is one line, exit 2, nothing written.
TEST_F(DeviationsTest, TheCommandRanksAmongCalibrationRunsAndRefusesTooFewInOneLine) {
  TemporaryDirectory dir;
  std::vector<vector::VectorizedScene> runs, field;
  for (std::uint64_t i = 500; i < 600; ++i) runs.push_back(fieldScene(i, Change::None));
  for (std::uint64_t i = 200; i < 210; ++i) field.push_back(fieldScene(i, i % 2 ? Change::Brakes : Change::None));
  const auto field_file = writeField(dir.path() / "field.h5", field);
  const auto runs_file = writeField(dir.path() / "runs.h5", runs);
  const auto command = [&](const std::string& level, const fs::path& out) {
    return test::run({test::vsdSumo().string(), "--quiet", "deviations", "--model", model_.string(), "--data",
                      field_file.string(), "--calibration", runs_file.string(), "--threads", "1", "--level", level,
                      "--out", out.string()},
                     dir.path());
  };
  const auto ok = command("0.05", dir.path() / "report");
  ASSERT_EQ(ok.exitCode, 0) << ok.output;
  EXPECT_THAT(ok.output, testing::HasSubstr("deviations: 10 scenes, 10 scored"));
  EXPECT_THAT(ok.output, testing::HasSubstr("p-values: conformal ranks among 100 clean calibration runs"));
  EXPECT_THAT(readTextFile(dir.path() / "report" / "report.html"),
              testing::HasSubstr("conformal ranks among 100 clean calibration runs"));
  const auto few = command("0.01", dir.path() / "strict");  // 100 runs: one extreme p of four gives 4 / 101
  EXPECT_EQ(few.exitCode, 2) << few.output;  // a flag value
  EXPECT_THAT(few.output, testing::HasSubstr("--calibration " + runs_file.string()));
  EXPECT_THAT(few.output, testing::HasSubstr("at least 400 clean runs"));
  EXPECT_EQ(std::count(few.output.begin(), few.output.end(), '\n'), 1) << few.output;
  EXPECT_FALSE(fs::exists(dir.path() / "strict"));
}

TEST(RunCalibration, PValuesAreConformalRanksAndIntervalsTheRunsNinetyPercentScore) {
  const auto row = [](const std::string& label, double metric_error, double excess) {
    SceneDeviation s;
    s.label = label;
    s.regionExcess = excess;
    s.regionMeanExcess = excess;  // the path's score
    MetricTail tail;
    tail.mostLikely = 1.0;
    tail.recorded = 1.0 + metric_error;
    s.metrics = {tail};
    return s;
  };
  std::vector<SceneDeviation> runs;
  for (int i = 1; i <= 20; ++i) runs.push_back(row("acc", i % 2 ? i : -i, i));  // scores 1 .. 20 either side
  const RunCalibration calibration(runs, 1, "runs.h5", 0.1);  // 2 p-values: 20 runs let one alone reach 2 / 21
  EXPECT_EQ(calibration.runs("acc"), 20u);
  EXPECT_EQ(calibration.runs("lk"), 0u);
  auto far = row("acc", -20.5, 0.5);
  calibration.apply(far);
  EXPECT_DOUBLE_EQ(far.metrics[0].p, 1.0 / 21.0);      // beyond every run
  EXPECT_DOUBLE_EQ(far.pathP, 21.0 / 21.0);             // inside every run's path
  EXPECT_DOUBLE_EQ(far.metrics[0].p05, 1.0 - 19.0);     // the ceil(0.9 * 21) = 19th smallest score
  EXPECT_DOUBLE_EQ(far.metrics[0].p95, 1.0 + 19.0);
  EXPECT_DOUBLE_EQ(far.p, std::min(2.0 * (1.0 / 21.0), 1.0));  // Simes over metric and path
  EXPECT_FALSE(far.pathWorst);
  auto middle = row("acc", 10.0, 15.0);
  calibration.apply(middle);
  EXPECT_DOUBLE_EQ(middle.metrics[0].p, 12.0 / 21.0);  // 1 + runs scoring 10 .. 20
  EXPECT_DOUBLE_EQ(middle.pathP, 7.0 / 21.0);           // 1 + runs of excess 15 .. 20
  EXPECT_TRUE(middle.pathWorst);
  auto unknown = row("lk", 0.0, 0.0);
  EXPECT_THROW(calibration.apply(unknown), ConfigError);
  // Only the recorded value is finite (a time to collision where the most likely future never
  // closes in): beyond every run.
  auto one_sided = row("acc", 0.0, 0.5);
  one_sided.metrics[0].mostLikely = std::numeric_limits<double>::infinity();
  calibration.apply(one_sided);
  EXPECT_DOUBLE_EQ(one_sided.metrics[0].p, 1.0 / 21.0);
  // No metric defined (the model's calibration could not score it), but a path: ranked by it.
  auto path_only = row("acc", 0.0, 30.0);
  path_only.metrics[0].recorded = std::numeric_limits<double>::quiet_NaN();
  path_only.status = SceneStatus::NotScored;
  calibration.apply(path_only);
  EXPECT_EQ(path_only.status, SceneStatus::Scored);
  EXPECT_DOUBLE_EQ(path_only.p, 1.0 / 21.0);
  EXPECT_TRUE(path_only.pathWorst);
  const RunCalibration strict(runs, 1, "runs.h5", 0.05);  // 2 p-values at 0.05: 40 runs needed
  auto middle_again = row("acc", 10.0, 15.0);
  EXPECT_THROW(strict.apply(middle_again), ConfigError);
}

TEST(DeviationRanking, MostSurprisingFirstGroupedByLabelAxisAndMetric) {
  DeviationResult result;
  result.metricNames = {"a_min", "y_max"};
  result.metricUnits = {"m/s^2", "m"};
  result.step = 0.2;
  const auto scene = [](double p, std::size_t worst, double recorded, const std::string& axis) {
    SceneDeviation s;
    s.label = "acc_lk";
    s.p = p;
    s.worstMetric = worst;
    s.axis = axis;
    s.metrics = {{recorded, 0.0, -1.0, 1.0, p}, {recorded, 0.0, -1.0, 1.0, p}};
    return s;
  };
  result.scenes = {scene(0.2, 0, -3.0, "longitudinal"), scene(0.001, 0, -3.0, "longitudinal"),
                   scene(0.01, 1, 2.0, "lateral"), scene(0.04, 0, 2.0, "longitudinal")};
  result.scenes.push_back(scene(0.0, 0, -3.0, "longitudinal"));
  result.scenes.back().status = SceneStatus::OutOfDistribution;  // never flagged
  const auto ranked = rankDeviations(result);
  EXPECT_EQ(ranked, (std::vector<std::size_t>{1, 2, 3}));
  EXPECT_EQ(result.scenes[1].group, "acc_lk: longitudinal, a_min lower than predicted");
  EXPECT_EQ(result.scenes[2].group, "acc_lk: lateral, y_max higher than predicted");
  EXPECT_NE(result.scenes[1].reason.find("below its calibrated 90 % interval"), std::string::npos)
      << result.scenes[1].reason;
  EXPECT_FALSE(result.scenes[0].flagged);
  EXPECT_FALSE(result.scenes[4].flagged);
}

}  // namespace
