// Faults of code we do not control — an Ego controller plugin that crashes,
// aborts, calls exit(0) or hangs, libsumo crashing in a step — are contained in
// worker processes: the affected scenarios (or Egos) fail with the reason, the
// rest goes on with exactly the results it would have had.

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <map>

#include "test_support.hpp"
#include "vsd/core/csv.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/fault.hpp"
#include "vsd/pipeline/map_export.hpp"
#include "vsd/pipeline/run.hpp"
#include "vsd/vector/dataset.hpp"

using namespace vsd;
using namespace vsd::pipeline;
namespace fs = std::filesystem;

namespace {

fs::path misbehavingPlugin() { return test::binaryDir() / "plugins" / "libvsd_misbehaving_egos.so"; }

/// acc_lk driven by a misbehaving controller (tests/plugins/misbehaving_egos.c) with `params`.
fs::path misbehavingScenario(const fs::path& dir, const std::string& controller, const std::string& params) {
  const std::string text = test::scenarioVariant(
      "acc_lk.yaml",
      "name: paper_ego                     # time-gap P-controller + lane keeping\n      params: {time_gap: 2.0, "
      "set_speed: v_ego}",
      fmt::format("name: {}\n      library: {}\n      params: {{{}}}", controller, misbehavingPlugin().string(), params));
  return test::writeFile(dir / (controller + ".yaml"), text);
}

RunOptions runOptions(const fs::path& scenario, const fs::path& out, int jobs) {
  RunOptions options;
  options.scenarioFile = scenario;
  options.outputDir = out;
  options.samples = 10;
  options.batch = 5;
  options.seed = 5;
  options.jobs = jobs;
  // Short, so that a hang costs little; long enough that a crash is not taken
  // for a hang when the test machine is loaded.
  options.watchdog.stepTimeout = 1.0;
  return options;
}

struct Row {
  std::string status;
  std::string failure;
  std::vector<std::string> rest;  ///< inputs and metrics
  bool operator==(const Row& other) const {
    return status == other.status && failure == other.failure && rest == other.rest;
  }
};

std::map<std::string, Row> rowsOf(const fs::path& out) {
  const auto csv = CsvTable::read(out / "concrete.csv");
  std::map<std::string, Row> rows;
  for (std::size_t r = 0; r < csv.rows(); ++r) {
    Row row{csv.cell(r, csv.column("status")), csv.cell(r, csv.column("failure")), {}};
    for (std::size_t c = csv.column("failure") + 1; c < csv.header().size(); ++c) row.rest.push_back(csv.cell(r, c));
    rows[csv.cell(r, csv.column("sample"))] = row;
  }
  return rows;
}

}  // namespace

TEST(Faults, CrashesExitsAndHangsOfAPluginFailOnlyTheirScenariosWhateverTheJobs) {
  TemporaryDirectory dir;
  // v_ego in (12, 13.2]: segfault, (13.2, 14]: abort, (14, 14.4]: exit(0), above: endless loop; all at t = 1 s.
  // Seed 5's six samples hold each kind once and two without a fault (v_ego 11.9 and 11.3),
  // one in each of the two batches.
  const auto faulty = misbehavingScenario(
      dir.path(), "misbehaving_ego", "kind: (v_ego > 12) + (v_ego > 13.2) + (v_ego > 14) + (v_ego > 14.4), at: 1.0");
  auto options = [&](const fs::path& scenario, const std::string& out, int jobs) {
    auto result = runOptions(scenario, dir.path() / out, jobs);
    result.samples = 6;
    result.batch = 3;
    return result;
  };
  const auto one_job = runScenarios(options(faulty, "jobs1", 1));
  const auto two_jobs = runScenarios(options(faulty, "jobs2", 2));
  runScenarios(options(misbehavingScenario(dir.path() / "clean", "misbehaving_ego", "kind: 0"), "clean", 1));
  const auto rows = rowsOf(dir.path() / "jobs1");
  const auto clean = rowsOf(dir.path() / "clean");
  EXPECT_EQ(rowsOf(dir.path() / "jobs2"), rows);  // the same failures and results with two workers
  const std::vector<std::string> reasons = {
      "", "Ego controller crashed (signal 11, Segmentation fault) at t = 1.0 s",
      "Ego controller crashed (signal 6, Aborted) at t = 1.0 s",
      "Ego controller ended the process (exit code 0) at t = 1.0 s",
      "Ego controller did not return within 1 s (watchdog, --step-timeout) at t = 1.0 s"};
  std::map<int, int> struck;
  ASSERT_EQ(rows.size(), 6u);
  for (const auto& [sample, row] : rows) {
    const double v_ego = std::stod(clean.at(sample).rest.at(4));  // inputs a0..a3, v_ego, ...
    const int kind = (v_ego > 12) + (v_ego > 13.2) + (v_ego > 14) + (v_ego > 14.4);
    ++struck[kind];
    if (kind == 0) {
      EXPECT_EQ(row, clean.at(sample)) << "sample " << sample;  // untouched by the others' faults
    } else {
      EXPECT_EQ(row.status, "failed") << sample;
      EXPECT_EQ(row.failure, reasons[static_cast<std::size_t>(kind)]) << sample;
    }
  }
  for (int kind = 1; kind <= 4; ++kind) EXPECT_GE(struck[kind], 1) << "no scenario with fault kind " << kind;
  EXPECT_GE(struck[0], 1) << "no scenario without a fault";
  EXPECT_EQ(one_job.failed, static_cast<std::uint64_t>(6 - struck[0]));
  EXPECT_EQ(one_job.workerRestarts, static_cast<int>(one_job.failed));
  EXPECT_GE(two_jobs.workerRestarts, 1);
  EXPECT_NE(one_job.report().find("restarted after a crash, exit or hang"), std::string::npos);
  EXPECT_TRUE(vector::validateDataset(dir.path() / "jobs1").ok());
}

TEST(Faults, APluginCrashingInCreateAndOneCrashingEverywhere) {
  TemporaryDirectory dir;
  // Scenarios with a fast Ego crash while their controller is created.
  auto options = runOptions(misbehavingScenario(dir.path(), "crashing_ego", "fault: v_ego > 14, at: -1"),
                            dir.path() / "out", 1);
  options.samples = 6;
  options.watchdog.stepTimeout = 10.0;  // no hang here: no timeout may be mistaken for the crash
  const auto first = runScenarios(options);
  EXPECT_GE(first.failed, 2u);
  EXPECT_GE(first.ok, 2u);
  for (const auto& [sample, row] : rowsOf(dir.path() / "out")) {
    if (row.status == "failed") {
      EXPECT_EQ(row.failure, "Ego controller crashed (signal 11, Segmentation fault) at t = 0.0 s");
    }
  }
  const auto everywhere = misbehavingScenario(dir.path() / "all", "crashing_ego", "at: -1");
  options.scenarioFile = everywhere;
  options.samples = 2;
  try {
    runScenarios(options);
    FAIL() << "expected SumoError";
  } catch (const SumoError& error) {
    EXPECT_NE(std::string(error.what()).find("every concrete scenario failed (e.g. Ego controller crashed (signal 11"),
              std::string::npos)
        << error.what();
  }
  EXPECT_EQ(rowsOf(dir.path() / "out").size(), 6u);  // the earlier run's outputs are kept
}

TEST(Faults, ALibsumoCrashInASharedStepIsIsolatedToItsScenario) {
  TemporaryDirectory dir;
  ::setenv("VSD_FAULT", "abort@sumo.step-with:4", 1);  // libsumo "asserts" whenever sample 4 is simulated
  reloadFaultInjection();
  auto options = runOptions(test::scenarioFile("acc_lk.yaml"), dir.path() / "out", 1);
  options.samples = 5;  // one batch: the five scenarios share every libsumo step
  const auto summary = runScenarios(options);
  ::unsetenv("VSD_FAULT");
  reloadFaultInjection();
  EXPECT_EQ(summary.failed, 1u);
  const auto rows = rowsOf(dir.path() / "out");
  EXPECT_EQ(rows.at("4").status, "failed");
  EXPECT_NE(rows.at("4").failure.find("libsumo crashed (signal 6, Aborted) in a simulation step at t = 0.0 s "
                                      "(isolated to this scenario)"),
            std::string::npos)
      << rows.at("4").failure;
  options.outputDir = dir.path() / "clean";
  runScenarios(options);
  const auto clean = rowsOf(dir.path() / "clean");
  for (const auto& [sample, row] : rows) {
    if (sample != "4") {
      EXPECT_EQ(row.rest, clean.at(sample).rest) << sample;
    }
  }
}

TEST(Faults, AClosedLoopEgoWhosePluginExitsIsTakenOutAndTheExportGoesOn) {
  TemporaryDirectory dir;
  auto export_with = [&](const std::string& controller, const std::string& name) {
    ExportOptions options;
    options.openDrive = test::sourceDir() / "sumo_nets" / "opendrive_curve" / "curve.xodr";
    options.source.routes = {test::sourceDir() / "sumo_nets" / "opendrive_curve" / "curve.rou.xml"};
    options.output = dir.path() / name;
    options.end = 60.0;
    options.egos = "vtype:truck";
    options.closedLoop = true;
    options.controller = controller;
    options.controllerLibrary = misbehavingPlugin();
    options.controllerParams = {{"at", 30.0}};
    options.watchdog.stepTimeout = 10.0;  // no hang here
    return exportMap(options);
  };
  // failing_ego reports its fault (an ordinary error, handled in the worker);
  // exiting_ego ends the worker process at the same moment: same dataset.
  const auto reported = export_with("failing_ego", "reported.h5");
  const auto exited = export_with("exiting_ego", "exited.h5");
  ASSERT_FALSE(reported.failedEgos.empty());
  ASSERT_EQ(exited.failedEgos.size(), reported.failedEgos.size());
  for (std::size_t i = 0; i < exited.failedEgos.size(); ++i) {
    EXPECT_EQ(exited.failedEgos[i].id, reported.failedEgos[i].id);
    EXPECT_DOUBLE_EQ(exited.failedEgos[i].time, reported.failedEgos[i].time);
    EXPECT_NE(exited.failedEgos[i].reason.find("Ego controller ended the process (exit code 0)"), std::string::npos)
        << exited.failedEgos[i].reason;
  }
  EXPECT_GT(exited.samples, 0u);
  EXPECT_EQ(exited.samples, reported.samples);
  EXPECT_EQ(sha256OfFile(dir.path() / "exited.h5"), sha256OfFile(dir.path() / "reported.h5"));
  EXPECT_NE(exited.report().find("Egos taken out because their controller failed"), std::string::npos);
}

// Fail fast (RunOptions::maxFailures, docs/cli.md): a plugin that fails every scenario the
// same way stops the run after the first few, naming the reason - a hanging one after a
// few watchdog periods, not one per scenario - and nothing is written.
TEST(Faults, ARunWhoseFirstScenariosAllFailTheSameWayStopsEarly) {
  TemporaryDirectory dir;
  for (const std::string controller : {"failing_ego", "hanging_ego"}) {
    auto options = runOptions(misbehavingScenario(dir.path(), controller, "at: 0.4"), dir.path() / controller, 1);
    options.samples = 40;
    options.maxFailures = 3;
    options.watchdog.stepTimeout = 0.5;
    try {
      runScenarios(options);
      FAIL() << controller << ": expected SumoError";
    } catch (const SumoError& error) {
      const std::string message = error.what();
      EXPECT_EQ(message.rfind("the first 3 concrete scenarios all failed the same way: ", 0), 0u) << message;
      EXPECT_NE(message.find("Ego controller"), std::string::npos) << message;
      EXPECT_NE(message.find("--max-failures 0 runs every scenario"), std::string::npos) << message;
    }
    EXPECT_FALSE(fs::exists(dir.path() / controller / "manifest.json")) << controller;
  }
  // Scenarios that fail for different reasons, or a first one that completes, do not stop it.
  auto mixed = runOptions(misbehavingScenario(dir.path() / "mixed", "misbehaving_ego",
                                              "kind: (v_ego > 12) + (v_ego > 14)"),
                          dir.path() / "mixed", 1);
  mixed.maxFailures = 2;
  mixed.watchdog.stepTimeout = 10.0;
  EXPECT_EQ(runScenarios(mixed).samples, 10u);
  // --max-failures 0: every scenario runs.
  auto all = runOptions(misbehavingScenario(dir.path() / "all", "failing_ego", "at: 0.4"), dir.path() / "all", 1);
  all.maxFailures = 0;
  try {
    runScenarios(all);
    FAIL() << "expected SumoError";
  } catch (const SumoError& error) {
    EXPECT_EQ(std::string(error.what()).rfind("every concrete scenario failed", 0), 0u) << error.what();
  }
}
