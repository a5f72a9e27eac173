#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <pugixml.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "test_support.hpp"
#include "vsd/core/csv.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/metrics/metrics.hpp"
#include "vsd/pipeline/run.hpp"
#include "vsd/pipeline/scenes.hpp"
#include "vsd/sim/trace_file.hpp"
#include "vsd/vector/dataset.hpp"

using namespace vsd;
using namespace vsd::pipeline;
namespace fs = std::filesystem;

namespace {

RunOptions options(const fs::path& scenario, const fs::path& out, std::uint64_t samples) {
  RunOptions result;
  result.scenarioFile = scenario;
  result.outputDir = out;
  result.samples = samples;
  result.seed = 7;
  return result;
}

std::vector<double> allStates(const fs::path& traces) {
  sim::TraceFileReader reader(traces);
  std::vector<double> values;
  for (std::size_t row = 0; row < reader.size(); ++row) {
    for (const auto& track : reader.trace(row).vehicles) {
      for (const auto& s : track.states) values.insert(values.end(), {s.x, s.y, s.heading, s.speed, s.accel});
    }
  }
  return values;
}

}  // namespace

TEST(Run, WritesConcreteCsvTracesAndManifest) {
  TemporaryDirectory dir;
  auto run_options = options(test::scenarioFile("acc_lk.yaml"), dir.path() / "out", 40);
  run_options.commandLine = "vsd-sumo run scenarios/acc_lk.yaml --samples 40";
  const auto summary = runScenarios(run_options);
  EXPECT_EQ(summary.ok + summary.failed, 40u);
  EXPECT_EQ(summary.ok, 40u);

  const auto csv = CsvTable::read(dir.path() / "out" / "concrete.csv");
  EXPECT_EQ(csv.rows(), 40u);
  const std::vector<std::string> expected_header = {
      "functional_scenario", "sample", "seed", "status", "failure", "a0", "a1", "a2", "a3", "v_ego", "x_co", "v_co",
      "t_v_co", "a_co", "t_a_co", "a_min", "d_min", "p_lat_max", "y_max", "ttc_min", "thw_min", "lane_offset_max"};
  EXPECT_EQ(csv.header(), expected_header);
  for (std::size_t row = 0; row < csv.rows(); ++row) {
    EXPECT_EQ(csv.cell(row, 0), "acc_lk");
    EXPECT_EQ(csv.cell(row, 1), std::to_string(row));
    EXPECT_EQ(csv.cell(row, 2), "7");
    EXPECT_EQ(csv.cell(row, 3), "ok");
    EXPECT_TRUE(std::isfinite(csv.number(row, csv.column("d_min"))));
  }

  sim::TraceFileReader traces(dir.path() / "out" / "traces.h5");
  EXPECT_EQ(traces.size(), 40u);
  EXPECT_EQ(traces.functionalScenario(), "acc_lk");
  EXPECT_EQ(traces.vehicleIds(), (std::vector<std::string>{"ego", "co"}));
  const auto trace = traces.trace(5);
  EXPECT_EQ(trace.instants(), 26u);
  EXPECT_DOUBLE_EQ(trace.ego().states[0].x, -50.0);

  const auto manifest = nlohmann::json::parse(readTextFile(dir.path() / "out" / "manifest.json"));
  EXPECT_EQ(manifest["scenario_sha256"], sha256OfFile(test::scenarioFile("acc_lk.yaml")));
  EXPECT_EQ(manifest["seed"], 7);
  EXPECT_EQ(manifest["command_line"], "vsd-sumo run scenarios/acc_lk.yaml --samples 40");
  EXPECT_NE(manifest["sumo_version"].get<std::string>().find("1.15"), std::string::npos);
  EXPECT_FALSE(manifest["tool_version"].get<std::string>().empty());
  EXPECT_EQ(manifest["outputs"]["traces.h5"]["sha256"], sha256OfFile(dir.path() / "out" / "traces.h5"));
  // Nothing temporary is left behind.
  for (const auto& entry : fs::directory_iterator(dir.path() / "out")) {
    EXPECT_NE(entry.path().filename().string().front(), '.') << entry.path();
  }
}

TEST(Run, SameSeedGivesIdenticalOutputsWhateverJobsAndBatch) {
  TemporaryDirectory dir;
  auto a = options(test::scenarioFile("acc_lk.yaml"), dir.path() / "a", 45);
  a.batch = 7;
  auto b = options(test::scenarioFile("acc_lk.yaml"), dir.path() / "b", 45);
  b.batch = 20;
  b.jobs = 2;
  auto c = options(test::scenarioFile("acc_lk.yaml"), dir.path() / "c", 45);
  c.batch = 1000;
  c.jobs = 3;
  runScenarios(a);
  runScenarios(b);
  runScenarios(c);
  const auto csv_a = readTextFile(dir.path() / "a" / "concrete.csv");
  EXPECT_EQ(csv_a, readTextFile(dir.path() / "b" / "concrete.csv"));
  EXPECT_EQ(csv_a, readTextFile(dir.path() / "c" / "concrete.csv"));
  const auto states_a = allStates(dir.path() / "a" / "traces.h5");
  EXPECT_EQ(states_a, allStates(dir.path() / "b" / "traces.h5"));
  EXPECT_EQ(states_a, allStates(dir.path() / "c" / "traces.h5"));
  EXPECT_EQ(sha256OfFile(dir.path() / "a" / "traces.h5"), sha256OfFile(dir.path() / "b" / "traces.h5"));

  auto other_seed = options(test::scenarioFile("acc_lk.yaml"), dir.path() / "d", 45);
  other_seed.seed = 8;
  runScenarios(other_seed);
  EXPECT_NE(csv_a, readTextFile(dir.path() / "d" / "concrete.csv"));
}

// `vsd-sumo bench isolation` compares the two; it measures only the cost if they compute the same.
TEST(Run, InTheCallingProcessTheSameBatchesGiveTheSameOutputsAsInAWorker) {
  TemporaryDirectory dir;
  auto worker = options(test::scenarioFile("acc_lk.yaml"), dir.path() / "worker", 12);
  worker.batch = 5;  // three batches, the last one short
  auto in_process = worker;
  in_process.outputDir = dir.path() / "in_process";
  in_process.isolation = RunOptions::Isolation::None;
  const auto a = runScenarios(worker);
  const auto b = runScenarios(in_process);
  EXPECT_EQ(b.ok, a.ok);
  EXPECT_GT(a.ok, 0u);
  for (const char* file : {"concrete.csv", "traces.h5", "dataset.h5"}) {
    EXPECT_EQ(sha256OfFile(dir.path() / "in_process" / file), sha256OfFile(dir.path() / "worker" / file)) << file;
  }
  in_process.jobs = 2;  // one process cannot be two workers
  EXPECT_THROW(in_process.validate(), ConfigError);
}

TEST(Run, PerScenarioFaultsAreRecordedAndTheRestGoesOn) {
  TemporaryDirectory dir;
  const auto scenario = test::writeFile(
      dir.path() / "short_road.yaml",
      test::shortRoadScenario());
  const auto summary = runScenarios(options(scenario, dir.path() / "out", 40));
  EXPECT_GT(summary.failed, 0u);
  EXPECT_GT(summary.ok, 0u);
  const auto csv = CsvTable::read(dir.path() / "out" / "concrete.csv");
  std::size_t failed_rows = 0;
  for (std::size_t row = 0; row < csv.rows(); ++row) {
    if (csv.cell(row, csv.column("status")) != "failed") continue;
    ++failed_rows;
    EXPECT_NE(csv.cell(row, csv.column("failure")).find("vehicle 'co' reached the end of its road"), std::string::npos);
    EXPECT_TRUE(std::isnan(csv.number(row, csv.column("d_min"))));
  }
  EXPECT_EQ(failed_rows, summary.failed);
  sim::TraceFileReader traces(dir.path() / "out" / "traces.h5");
  EXPECT_EQ(traces.size(), 40u);
}

TEST(Run, RunLevelFaultsLeaveNoOutputThatLooksComplete) {
  TemporaryDirectory dir;
  // An unknown controller: rejected before anything is written.
  const auto unknown = test::writeFile(
      dir.path() / "unknown.yaml", test::scenarioVariant("acc.yaml", "name: paper_ego", "name: paper_egoo"));
  try {
    runScenarios(options(unknown, dir.path() / "out1", 10));
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& error) {
    EXPECT_NE(std::string(error.what()).find("unknown controller 'paper_egoo'"), std::string::npos);
  }
  EXPECT_FALSE(fs::exists(dir.path() / "out1"));

  // An option that could write files is refused before anything runs (issue 29: the allow-list).
  const auto injected = test::writeFile(
      dir.path() / "injected.yaml",
      test::scenarioVariant("acc.yaml", "criteria:", "sumo: {sumo_options: [--fcd-output, /tmp/x.xml]}\ncriteria:"));
  try {
    runScenarios(options(injected, dir.path() / "out0", 10));
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& error) {
    EXPECT_NE(std::string(error.what()).find("sumo_options[0]: got '--fcd-output', expected an option a scenario file "
                                             "may pass to SUMO"),
              std::string::npos)
        << error.what();
  }
  EXPECT_FALSE(fs::exists(dir.path() / "out0"));

  // netconvert rejects every network (an allowed option, a value it refuses): the run
  // stops, nothing is left behind.
  const auto broken = test::writeFile(
      dir.path() / "netconvert.yaml",
      test::scenarioVariant("acc.yaml", "criteria:", "sumo: {netconvert_options: [--default.lanewidth, \"-1\"]}\ncriteria:"));
  try {
    runScenarios(options(broken, dir.path() / "out2", 10));
    FAIL() << "expected SumoError";
  } catch (const SumoError& error) {
    EXPECT_NE(std::string(error.what()).find("netconvert failed"), std::string::npos) << error.what();
  }
  EXPECT_FALSE(fs::exists(dir.path() / "out2"));  // created by the failed run, so removed with it

  // An earlier complete run is not damaged by a failing one.
  runScenarios(options(test::scenarioFile("acc.yaml"), dir.path() / "out3", 5));
  const auto before = readTextFile(dir.path() / "out3" / "concrete.csv");
  EXPECT_THROW(runScenarios(options(broken, dir.path() / "out3", 10)), SumoError);
  EXPECT_EQ(readTextFile(dir.path() / "out3" / "concrete.csv"), before);
  EXPECT_TRUE(fs::exists(dir.path() / "out3" / "manifest.json"));
}

TEST(Run, KeepsNetsAndWritesFcdOnRequest) {
  TemporaryDirectory dir;
  auto run_options = options(test::scenarioFile("lk.yaml"), dir.path() / "out", 12);
  run_options.batch = 5;
  run_options.fcd = true;
  runScenarios(run_options);
  for (int b = 0; b < 3; ++b) {
    const auto stem = "batch_0000" + std::to_string(b);
    EXPECT_TRUE(fs::exists(dir.path() / "out" / "nets" / (stem + ".net.xml")));
    EXPECT_TRUE(fs::exists(dir.path() / "out" / "nets" / (stem + ".sumocfg")));
    EXPECT_TRUE(fs::exists(dir.path() / "out" / "fcd" / (stem + ".fcd.xml")));
  }
  const auto fcd = readTextFile(dir.path() / "out" / "fcd" / "batch_00002.fcd.xml");
  EXPECT_NE(fcd.find("id=\"s10.ego\""), std::string::npos);
}

// Asking for SUMO's FCD switches SUMO's sublane model on where road users move across
// lanes (FCD shows a vehicle half-way through its lane change, between the lane centres),
// and it changes no outcome: vsd-sumo's metrics come from its own states either way.
TEST(Run, FcdShowsLaneChangesHalfWayAndChangesNoOutcome) {
  TemporaryDirectory dir;
  auto run_options = options(test::scenarioFile("alks/cut_in.yaml"), dir.path() / "plain", 4);
  runScenarios(run_options);
  run_options.outputDir = dir.path() / "fcd";
  run_options.fcd = true;
  runScenarios(run_options);
  EXPECT_EQ(readTextFile(dir.path() / "plain" / "concrete.csv"), readTextFile(dir.path() / "fcd" / "concrete.csv"));

  pugi::xml_document fcd;
  ASSERT_TRUE(fcd.load_file((dir.path() / "fcd" / "fcd" / "batch_00000.fcd.xml").c_str()));
  constexpr double kLaneWidth = 3.5;  // m, scenarios/alks/cut_in.yaml
  double farthest_from_a_centre = 0.0;
  double first_y = std::numeric_limits<double>::quiet_NaN();
  for (const auto& step : fcd.child("fcd-export").children("timestep")) {
    for (const auto& vehicle : step.children("vehicle")) {
      if (std::string(vehicle.attribute("id").value()) != "s0.cut_in_vehicle") continue;
      const double y = vehicle.attribute("y").as_double();
      if (std::isnan(first_y)) first_y = y;  // starts on a lane centre
      const double lanes_away = (y - first_y) / kLaneWidth;
      farthest_from_a_centre =
          std::max(farthest_from_a_centre, kLaneWidth * std::abs(lanes_away - std::round(lanes_away)));
    }
  }
  EXPECT_GT(farthest_from_a_centre, 1.0);
}

TEST(Run, ExternalControllerPluginDrivesTheEgo) {
  TemporaryDirectory dir;
  std::string text = test::scenarioVariant("acc_lk.yaml", "params: {time_gap: 2.0, set_speed: v_ego}",
                                          "params: {time_gap: 3.0, set_speed: v_ego}");
  text.replace(text.find("name: paper_ego"), std::string("name: paper_ego").size(),
               "name: cautious_ego\n      library: " + test::cautiousEgoPlugin().string() + "\n     ");
  const auto scenario = test::writeFile(dir.path() / "plugin.yaml", text);
  const auto summary = runScenarios(options(scenario, dir.path() / "out", 30));
  EXPECT_EQ(summary.ok, 30u);
  // Its 3 s time gap makes it keep more distance than the built-in 2 s controller.
  const auto builtin = runScenarios(options(test::scenarioFile("acc_lk.yaml"), dir.path() / "builtin", 30));
  const auto mean_thw = [](const RunSummary& s) {
    for (const auto& metric : s.metrics) {
      if (metric.name == "thw_min") return metric.mean;
    }
    return 0.0;
  };
  EXPECT_GT(mean_thw(summary), mean_thw(builtin));
}

TEST(Run, OptionsAreValidated) {
  RunOptions bad = options(test::scenarioFile("acc.yaml"), "unused", 0);
  EXPECT_THROW(bad.validate(), ConfigError);
  bad.samples = 10;
  bad.batch = 5000;
  EXPECT_THROW(bad.validate(), ConfigError);
  bad.batch = 10;
  bad.jobs = 0;
  EXPECT_THROW(bad.validate(), ConfigError);
}

TEST(Run, DatasetHoldsThePaperSceneOfEveryCompletedRun) {
  TemporaryDirectory dir;
  auto run_options = options(test::scenarioFile("acc.yaml"), dir.path() / "out", 15);
  runScenarios(run_options);
  sim::TraceFileReader traces(dir.path() / "out" / "traces.h5");
  const vector::DatasetReader dataset(dir.path() / "out" / "dataset.h5");
  ASSERT_EQ(dataset.size(), 15u);
  EXPECT_EQ(dataset.header().inputNames, (std::vector<std::string>{"v_ego", "x_co", "v_co", "t_v_co", "a_co", "t_a_co"}));
  const auto csv = CsvTable::read(dir.path() / "out" / "concrete.csv");
  for (std::size_t i = 0; i < dataset.size(); ++i) {
    const auto scene = dataset.scene(i);
    const auto trace = traces.trace(i);
    // (2 lane boundaries * 24 + Co * 25 + Ego * 1) vectors of 7 features, as in the paper's footnote.
    ASSERT_EQ(scene.polylines.size(), 4u);
    EXPECT_EQ(scene.polylines[0].vectors.size(), 24u);
    EXPECT_EQ(scene.polylines[1].vectors.size(), 24u);
    EXPECT_EQ(scene.polylines[2].vectors.size(), 25u);
    EXPECT_EQ(scene.polylines[3].vectors.size(), 1u);
    EXPECT_EQ(scene.vectorCount(), 74u);
    // Geometry against the trace (float32 storage: millimetres).
    const auto& co = trace.vehicles[1];
    for (std::size_t k = 1; k <= 25; ++k) {
      EXPECT_NEAR(scene.polylines[2].vectors[k - 1][2], co.states[k].x, 1e-3);
      EXPECT_NEAR(scene.polylines[2].vectors[k - 1][3], co.states[k].y, 1e-3);
      EXPECT_NEAR(scene.target[k - 1].x(), trace.ego().states[k].x, 1e-3);
    }
    const auto ego = scene.egoInitialState();
    EXPECT_NEAR(ego.x, trace.ego().states[0].x, 1e-9);
    EXPECT_NEAR(ego.speed, trace.ego().states[0].speed, 1e-3);
    EXPECT_NEAR(ego.heading, trace.ego().states[0].heading, 1e-4);
    // Lane boundaries: half a lane width from the Ego's lane centre at its start.
    const Vec2 left(scene.polylines[0].vectors[0][0], scene.polylines[0].vectors[0][1]);
    const Vec2 right(scene.polylines[1].vectors[0][0], scene.polylines[1].vectors[0][1]);
    EXPECT_NEAR(left.x(), -55.0, 0.5);
    EXPECT_GT((left - right).norm(), 3.2 - 0.02);
    EXPECT_LT((left - right).norm(), 3.8 + 0.02);
    // Inputs and metrics travel with the sample.
    EXPECT_EQ(scene.inputs[0], csv.number(i, csv.column("v_ego")));
    EXPECT_EQ(scene.metrics[1], csv.number(i, csv.column("d_min")));
  }
}

TEST(Run, VehicleSizesTravelIntoTheDatasetAndItsMetrics) {
  TemporaryDirectory dir;
  // acc with a 12 m truck as the Co.
  std::string yaml = readTextFile(test::scenarioFile("acc.yaml"));
  const std::string co = "- id: co\n";
  ASSERT_NE(yaml.find(co), std::string::npos);
  yaml.replace(yaml.find(co), co.size(), co + "      length: 12.0\n      width: 2.55\n");
  const auto scenario = test::writeFile(dir.path() / "acc_truck.yaml", yaml);
  runScenarios(options(scenario, dir.path() / "out", 10));
  const vector::DatasetReader dataset(dir.path() / "out" / "dataset.h5");
  EXPECT_FALSE(dataset.header().vehicleSizesAssumed);
  const auto csv = CsvTable::read(dir.path() / "out" / "concrete.csv");
  const metrics::MetricSet metric_set({"d_min", "ttc_min"}, pipeline::sceneAvailability("generated"), "test");
  for (std::size_t i = 0; i < dataset.size(); ++i) {
    const auto scene = dataset.scene(i);
    EXPECT_EQ(scene.polylines[2].length, 12.0);
    EXPECT_EQ(scene.polylines[2].width, 2.55);
    EXPECT_EQ(scene.polylines[3].length, 5.0);
    // The recorded future scored from the dataset alone gives the simulated d_min: the truck's
    // length comes with the scene (assuming 5 m would add 3.5 m). d_min is the clearance of
    // oriented footprints; a scene's future has positions only, so headings are reconstructed
    // from them and the footprints turn slightly differently (a few cm at these gaps).
    const auto values = pipeline::metricsOfFuture(metric_set, scene, scene.target);
    EXPECT_NEAR(values[0], csv.number(i, csv.column("d_min")), 0.25) << "sample " << i;
  }
}

namespace {

/// Three scenarios of fully_blocking_target.yaml with `kind` as the blocking target, into dir/out.
RunSummary runWithBlockingTarget(const TemporaryDirectory& dir, const std::string& kind) {
  const auto file = dir.path() / (kind + ".yaml");
  test::writeFile(file, test::scenarioVariant("alks/fully_blocking_target.yaml",
                                              "choices: [pedestrian, car, truck, van, bus, motorbike]",
                                              "choices: [" + kind + "]"));
  return runScenarios(options(file, dir.path() / "out", 3));
}

}  // namespace

// A stationary object is a road user SUMO loads and sees like the others (its type has a
// shape SUMO knows), so a scenario with one simulates.
TEST(Run, AStationaryObjectSimulates) {
  TemporaryDirectory dir;
  const auto summary = runWithBlockingTarget(dir, "stationary_object");
  EXPECT_EQ(summary.ok, 3u);
  EXPECT_EQ(summary.failed, 0u);
}

// A bicycle (appended to the road-user table, code 7) rides in the Ego's lane as a blocking
// target: SUMO takes its class, the run completes.
TEST(Run, ABicycleSimulates) {
  TemporaryDirectory dir;
  const auto summary = runWithBlockingTarget(dir, "bicycle");
  EXPECT_EQ(summary.ok, 3u);
  EXPECT_EQ(summary.failed, 0u);
  // The type input's column holds the bicycle's code in every row.
  std::istringstream csv(readTextFile(dir.path() / "out" / "concrete.csv"));
  std::string line;
  std::getline(csv, line);
  const auto split = [](const std::string& text) {
    std::vector<std::string> cells;
    std::istringstream row(text);
    for (std::string cell; std::getline(row, cell, ',');) cells.push_back(cell);
    return cells;
  };
  const auto header = split(line);
  const auto column = std::find(header.begin(), header.end(), "TargetBlocking_Model") - header.begin();
  ASSERT_LT(static_cast<std::size_t>(column), header.size()) << line;
  int rows = 0;
  while (std::getline(csv, line)) {
    EXPECT_EQ(split(line).at(static_cast<std::size_t>(column)), "7") << line;
    ++rows;
  }
  EXPECT_EQ(rows, 3);
}

// The partially blocking target is never alongside the Ego: its lateral clearance is infinite
// in every run, and the summary says so instead of printing NaN as its min, mean and max.
TEST(Run, TheSummaryOfAMetricWithoutFiniteValuesShowsDashes) {
  TemporaryDirectory dir;
  const auto summary =
      runScenarios(options(test::scenarioFile("alks/partially_blocking_target.yaml"), dir.path() / "out", 3));
  const std::string report = summary.report();
  const auto row = report.find("lat_clearance_min");
  ASSERT_NE(row, std::string::npos) << report;
  const std::string line = report.substr(row, report.find('\n', row) - row);
  EXPECT_EQ(line, "lat_clearance_min          -          -          -  m  (+3 x inf)") << report;
  EXPECT_EQ(report.find("nan"), std::string::npos) << report;
}

// --reference: every concrete scenario again with the reference driver as the Ego, both
// outcomes side by side; without it concrete.csv keeps its columns.
TEST(Run, ReferenceRunsEveryScenarioAgainBesideTheSystem) {
  TemporaryDirectory dir;
  auto run_options = options(test::scenarioFile("alks/cut_in_unavoidable.yaml"), dir.path() / "ref", 6);
  run_options.reference = "paper_ego";
  const auto summary = runScenarios(run_options);
  EXPECT_EQ(summary.ok, 6u);
  const auto csv = CsvTable::read(dir.path() / "ref" / "concrete.csv");
  const auto& header = csv.header();
  const auto column = [&](const std::string& name) {
    const auto it = std::find(header.begin(), header.end(), name);
    EXPECT_NE(it, header.end()) << name;
    return static_cast<std::size_t>(std::distance(header.begin(), it));
  };
  const std::size_t d_min = column("d_min");
  const std::size_t reference_d_min = column("reference_d_min");
  const std::size_t criterion = column(kReferenceCriterion);
  EXPECT_EQ(header.back(), kReferenceCriterion);
  std::uint64_t avoided = 0;
  for (std::size_t row = 0; row < csv.rows(); ++row) {
    EXPECT_EQ(csv.cell(row, column("reference_status")), "ok");
    const bool sut = std::stod(csv.cell(row, d_min)) <= 0.0;
    const bool reference = std::stod(csv.cell(row, reference_d_min)) <= 0.0;
    EXPECT_EQ(csv.cell(row, criterion), sut && !reference ? "1" : "0") << row;
    avoided += sut && !reference ? 1 : 0;
  }
  EXPECT_EQ(summary.referenceAvoidsSutCollides, avoided);

  run_options.reference.clear();
  run_options.outputDir = dir.path() / "plain";
  runScenarios(run_options);
  const auto plain = CsvTable::read(dir.path() / "plain" / "concrete.csv");
  EXPECT_EQ(plain.header().back(), "lane_offset_max");
  for (std::size_t row = 0; row < plain.rows(); ++row) {
    EXPECT_EQ(plain.cell(row, d_min), csv.cell(row, d_min));  // the system's outcome is the same
  }
}

TEST(Run, ABadSampleStopsTheRunWithOneLineAndWritesNothing) {
  TemporaryDirectory dir;
  const auto scenario = test::writeFile(dir.path() / "overlap.yaml", R"(
name: overlap
inputs: [{name: g, min: -30, max: 30}]
road: {shape: arc, length: 200, lanes: 2}
vehicles:
  ego: {s: 40, lane: 0, speed: 10, controller: {name: idm}}
  others:
    - {id: a, ds: g, lane: 0, speed: 10}
)");
  try {
    runScenarios(options(scenario, dir.path() / "out", 50));
    FAIL() << "expected a ConfigError";
  } catch (const ConfigError& error) {
    EXPECT_NE(std::string(error.what()).find("overlap.yaml: sample "), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("road user 'a' starts overlapping 'ego'"), std::string::npos)
        << error.what();
  }
  EXPECT_FALSE(fs::exists(dir.path() / "out"));
}
