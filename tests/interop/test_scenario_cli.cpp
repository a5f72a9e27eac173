// `vsd-sumo scenario export | distribution` and `vsd-sumo run FILE.xosc` as a user runs
// them: export the critical scenarios of a run, re-simulate one, and the one-line
// errors for bad input (issue 16).

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "test_support.hpp"
#include "vsd/core/csv.hpp"
#include "vsd/core/files.hpp"

using namespace vsd;
using ::testing::HasSubstr;
namespace fs = std::filesystem;

namespace {

ProcessResult vsdSumo(const std::vector<std::string>& args, const fs::path& work) {
  std::vector<std::string> argv = {test::vsdSumo().string(), "--quiet"};
  argv.insert(argv.end(), args.begin(), args.end());
  return test::run(argv, work);
}

/// stderr only (stdout discarded): a user-facing error must be exactly one line.
ProcessResult errorsOf(const std::vector<std::string>& args, const fs::path& work) {
  std::string command = test::vsdSumo().string() + " --quiet";
  for (const auto& arg : args) command += " '" + arg + "'";
  return test::run({"sh", "-c", command + " >/dev/null"}, work);
}

void expectOneLineError(const ProcessResult& result, const std::string& expected, int exit_code = 1) {
  EXPECT_EQ(result.exitCode, exit_code) << result.output;
  EXPECT_EQ(std::count(result.output.begin(), result.output.end(), '\n'), 1) << result.output;
  EXPECT_THAT(result.output, HasSubstr(expected));
}

/// acc.yaml with a criterion most scenarios fail (so that `--only failures` has work).
fs::path accWithCriterion(const fs::path& dir, const std::string& criterion) {
  return test::writeFile(dir / "acc_close.yaml", test::scenarioVariant("acc.yaml", "fail_if: d_min < 2", criterion));
}

}  // namespace

TEST(ScenarioCli, CriticalScenariosOfARunExportAndReSimulate) {
  TemporaryDirectory dir("vsd-scenario-cli");
  const auto scenario = accWithCriterion(dir.path(), "fail_if: d_min < 12");
  const auto run = dir.path() / "run";
  ASSERT_EQ(vsdSumo({"run", scenario.string(), "--samples", "30", "--seed", "4", "--out", run.string()}, dir.path()).exitCode, 0);
  const auto exported = dir.path() / "xosc";
  const auto result = vsdSumo({"scenario", "export", run.string(), "--only", "failures", "--format", "openscenario",
                               "--out", exported.string()},
                              dir.path());
  ASSERT_EQ(result.exitCode, 0) << result.output;

  // Exactly the scenarios whose simulated d_min fails the criterion.
  const auto table = CsvTable::read(run / "concrete.csv");
  std::vector<std::size_t> critical;
  for (std::size_t row = 0; row < table.rows(); ++row) {
    if (table.number(row, table.column("d_min")) < 12) critical.push_back(row);
  }
  ASSERT_FALSE(critical.empty());
  ASSERT_LT(critical.size(), table.rows());
  for (std::size_t row = 0; row < table.rows(); ++row) {
    const auto stem = fmt::format("acc_{:06}", static_cast<int>(table.number(row, table.column("sample"))));
    const bool is_critical = std::find(critical.begin(), critical.end(), row) != critical.end();
    EXPECT_EQ(fs::exists(exported / (stem + ".xosc")), is_critical) << stem;
    EXPECT_EQ(fs::exists(exported / (stem + ".xodr")), is_critical) << stem;
  }
  EXPECT_TRUE(fs::exists(exported / "vsd_controllers.xosc"));
  EXPECT_TRUE(fs::exists(exported / "manifest.json"));

  // Back in: one exported scenario re-simulated gives the run's metrics.
  const std::size_t row = critical.front();
  const auto sample = static_cast<int>(table.number(row, table.column("sample")));
  const auto again = dir.path() / "again";
  const auto rerun = vsdSumo({"run", (exported / fmt::format("acc_{:06}.xosc", sample)).string(), "--out", again.string()},
                             dir.path());
  ASSERT_EQ(rerun.exitCode, 0) << rerun.output;
  const auto copy = CsvTable::read(again / "concrete.csv");
  ASSERT_EQ(copy.rows(), 1u);
  EXPECT_EQ(copy.number(0, copy.column("sample")), sample);
  for (const char* metric : {"a_min", "d_min", "ttc_min", "thw_min"}) {
    const double original = table.number(row, table.column(metric));
    const double repeated = copy.number(0, copy.column(metric));
    if (std::isinf(original)) EXPECT_TRUE(std::isinf(repeated)) << metric;
    else EXPECT_NEAR(repeated, original, 0.01) << metric;
  }
}

TEST(ScenarioCli, DistributionListsWhatOpenScenarioCannotExpress) {
  TemporaryDirectory dir("vsd-scenario-distribution");
  const auto file = dir.path() / "acc_lk.dist.xosc";
  const auto result = vsdSumo({"scenario", "distribution", test::scenarioFile("acc_lk.yaml").string(), "--out",
                               file.string(), "--samples", "20", "--seed", "3"},
                              dir.path());
  ASSERT_EQ(result.exitCode, 0) << result.output;
  const std::string text = readTextFile(file);
  EXPECT_THAT(text, HasSubstr(R"(<Stochastic numberOfTestRuns="20" randomSeed="3">)"));
  EXPECT_THAT(text, HasSubstr(R"(<StochasticDistribution parameterName="v_ego">)"));
  EXPECT_THAT(text, HasSubstr(R"(<Range lowerLimit="8" upperLimit="16" />)"));
  EXPECT_THAT(text, ::testing::Not(HasSubstr(R"(parameterName="x_co")")));
  EXPECT_THAT(text, HasSubstr("x_co: dependent range [-50 + v_ego, -50 + 2*v_ego]"));
  EXPECT_THAT(result.output, HasSubstr("x_co: dependent range"));

  const auto grid = dir.path() / "acc_lk.grid.xosc";
  ASSERT_EQ(vsdSumo({"scenario", "distribution", test::scenarioFile("acc_lk.yaml").string(), "--out", grid.string(),
                     "--grid", "5"},
                    dir.path())
                .exitCode,
            0);
  EXPECT_THAT(readTextFile(grid), HasSubstr(R"(<DistributionRange stepWidth="2">)"));  // v_ego: 8 .. 16 in 5 points
}

TEST(ScenarioCli, BadInputIsOneLineAndLeavesNothingBehind) {
  TemporaryDirectory dir("vsd-scenario-bad");
  const auto scenario = accWithCriterion(dir.path(), "fail_if: d_min < 12");
  const auto run = dir.path() / "run";
  ASSERT_EQ(vsdSumo({"run", scenario.string(), "--samples", "3", "--out", run.string()}, dir.path()).exitCode, 0);
  const auto out = dir.path() / "xosc";

  // --only failures on a scenario without criteria.
  const auto plain = test::writeFile(dir.path() / "no_criteria.yaml",
                                     test::scenarioVariant("acc.yaml", "criteria:\n  - {name: close_approach, fail_if: d_min < 2}", ""));
  const auto plain_run = dir.path() / "plain_run";
  ASSERT_EQ(vsdSumo({"run", plain.string(), "--samples", "2", "--out", plain_run.string()}, dir.path()).exitCode, 0);
  expectOneLineError(errorsOf({"scenario", "export", plain_run.string(), "--only", "failures", "--out", out.string()}, dir.path()),
                     "--only failures: " + plain.string() + " defines no criteria");
  EXPECT_FALSE(fs::exists(out));

  // An existing output folder is not replaced without --force.
  test::writeFile(out / "notes.txt", "mine");
  expectOneLineError(errorsOf({"scenario", "export", run.string(), "--out", out.string()}, dir.path()),
                     "the folder exists");
  fs::remove_all(out);

  // A run folder without the scenario file it was made from.
  fs::rename(scenario, dir.path() / "moved.yaml");
  expectOneLineError(errorsOf({"scenario", "export", run.string(), "--out", out.string()}, dir.path()),
                     (run / "manifest.json").string() + ": scenario_file '" + scenario.string() + "' does not exist");
  // ... or with a scenario file that changed since.
  test::writeFile(scenario, readTextFile(dir.path() / "moved.yaml") + "\n# edited\n");
  expectOneLineError(errorsOf({"scenario", "export", run.string(), "--out", out.string()}, dir.path()),
                     "has changed since the run");
  EXPECT_FALSE(fs::exists(out));

  // Beyond the paper's kind of scenario the files would carry another one (measured: a cut-in
  // without its lane change, road users 30 m off on an arc road).
  const std::string paper_road = "road: {x_range: [-55, 55], lanes: 2}\n";
  const std::string with_actions =
      paper_road + "vehicles:\n  ego: {x: -50, lane: 0, speed: 10, controller: {name: idm}}\n  others:\n"
                   "    - {id: a, x: -20, lane: 1, speed: 8,\n"
                   "       actions: [{id: over, lane_change: {lanes: -1, duration: 3}}]}\n";
  const std::string by_s = paper_road + "vehicles:\n  ego: {s: 5, lane: 0, speed: 10, controller: {name: idm}}\n";
  const std::string oncoming =
      paper_road + "vehicles:\n  ego: {x: -50, lane: 0, speed: 10, controller: {name: idm}}\n  others:\n"
                   "    - {id: a, x: 20, lane: 1, speed: 8, direction: against}\n";
  const std::string late =
      paper_road + "vehicles:\n  ego: {x: -50, lane: 0, speed: 10, controller: {name: idm, active_from: 3}}\n";
  const std::string piled =
      paper_road + "vehicles:\n  ego: {x: -50, lane: 0, speed: 10, controller: {name: idm}}\n  others:\n"
                   "    - {id: a, x: 20, lane: 1, speed: 0, may_start_overlapping: true}\n";
  const std::vector<std::pair<fs::path, std::string>> refused = {
      {test::sourceDir() / "scenarios" / "alks" / "free_driving.yaml", "road.shape: an arc or polyline road"},
      {test::writeFile(dir.path() / "by_s.yaml", "name: by_s\n" + by_s), "'ego' placed by s, ds or gap rather than x"},
      {test::writeFile(dir.path() / "actions.yaml", "name: actions\n" + with_actions),
       "action 'over' of 'a': actions and their triggers are not written"},
      {test::writeFile(dir.path() / "oncoming.yaml", "name: oncoming\n" + oncoming),
       "'a' drives against the road (direction: against)"},
      {test::writeFile(dir.path() / "late.yaml", "name: late\n" + late),
       "controller.active_from 3: the Ego's scripted phase is not written"},
      {test::writeFile(dir.path() / "piled.yaml", "name: piled\n" + piled),
       "'a' may start overlapping others (may_start_overlapping: true), which is not written"}};
  for (const auto& [file, message] : refused) {
    expectOneLineError(errorsOf({"scenario", "export", file.string(), "--samples", "1", "--out", out.string()},
                                dir.path()),
                       message);
    expectOneLineError(errorsOf({"scenario", "export", file.string(), "--samples", "1", "--out", out.string()},
                                dir.path()),
                       "the OpenSCENARIO export carries the paper's kind of scenario only");
    EXPECT_FALSE(fs::exists(out));
  }
}

TEST(ScenarioCli, RunRefusesOpenScenarioFilesItCannotSimulate) {
  TemporaryDirectory dir("vsd-run-xosc-bad");
  const auto exported = dir.path() / "xosc";
  ASSERT_EQ(vsdSumo({"scenario", "export", test::scenarioFile("acc.yaml").string(), "--samples", "1", "--out",
                     exported.string()},
                    dir.path())
                .exitCode,
            0);
  const auto xosc = exported / "acc_000000.xosc";
  const auto xodr = exported / "acc_000000.xodr";

  // An element outside the supported subset: named with its line.
  std::string text = readTextFile(xosc);
  const auto at = text.find("<Private entityRef=\"co\">");
  ASSERT_NE(at, std::string::npos);
  const auto line = 1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n');
  text.insert(at, "<GlobalAction><EnvironmentAction/></GlobalAction>\n        ");
  const auto weather = test::writeFile(exported / "weather.xosc", text);
  expectOneLineError(errorsOf({"run", weather.string(), "--out", (dir.path() / "o1").string()}, dir.path()),
                     fmt::format("weather.xosc:{}: element <GlobalAction> is outside the supported subset", line));

  // A road SUMO's netconvert rejects.
  std::string road = readTextFile(xodr);
  const auto length = road.find("length=\"", road.find("<road "));
  road.replace(length, road.find('"', length + 8) - length + 1, "length=\"bogus\"");
  test::writeFile(xodr, road);
  expectOneLineError(errorsOf({"run", xosc.string(), "--out", (dir.path() / "o2").string()}, dir.path()),
                     "netconvert rejects " + xodr.string());

  // Flags that the file fixes: a usage error (exit code 2, docs/cli.md).
  expectOneLineError(errorsOf({"run", xosc.string(), "--samples", "5"}, dir.path()), "--samples", 2);
  EXPECT_FALSE(fs::exists(dir.path() / "o1"));
  EXPECT_FALSE(fs::exists(dir.path() / "o2"));
}

// The ASAM schemas are not redistributed here; point VSD_ASAM_SCHEMA_DIR at a copy (e.g.
// esmini's resources/schema) to validate exported files with xmllint.
TEST(ScenarioCli, ExportsValidateAgainstTheAsamSchemas) {
  const char* schemas = std::getenv("VSD_ASAM_SCHEMA_DIR");
  if (schemas == nullptr || *schemas == '\0') GTEST_SKIP() << "VSD_ASAM_SCHEMA_DIR is not set";
  TemporaryDirectory dir("vsd-asam");
  const auto out = dir.path() / "xosc";
  ASSERT_EQ(vsdSumo({"scenario", "export", test::scenarioFile("acc_lk.yaml").string(), "--samples", "2", "--out",
                     out.string()},
                    dir.path())
                .exitCode,
            0);
  ASSERT_EQ(vsdSumo({"scenario", "distribution", test::scenarioFile("acc_lk.yaml").string(), "--out",
                     (out / "dist.xosc").string()},
                    dir.path())
                .exitCode,
            0);
  for (const auto& entry : fs::directory_iterator(out)) {
    const auto extension = entry.path().extension();
    if (extension != ".xosc" && extension != ".xodr") continue;
    const fs::path schema = fs::path(schemas) / (extension == ".xosc" ? "OpenSCENARIOv1.2.xsd"
                                                                       : "OpenDRIVE_1.6/opendrive_16_core.xsd");
    const auto result = test::run({"xmllint", "--noout", "--schema", schema.string(), entry.path().string()}, dir.path());
    EXPECT_EQ(result.exitCode, 0) << result.output;
  }
}
