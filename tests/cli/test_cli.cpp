// The vsd-sumo executable as a user runs it: exit codes, one-line errors,
// outputs readable from Python, replay of FCD output.
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>

#include <algorithm>
#include <regex>

#include "test_support.hpp"
#include "vsd/vector/dataset.hpp"

using namespace vsd;
namespace fs = std::filesystem;

namespace {

std::size_t lineCount(const std::string& text) {
  return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
}

/// Runs vsd-sumo with stderr only (stdout discarded) to check error output.
ProcessResult runForErrors(const std::vector<std::string>& args, const fs::path& work) {
  std::string command = test::vsdSumo().string() + " --quiet";
  for (const auto& arg : args) command += " '" + arg + "'";
  return test::run({"sh", "-c", command + " >/dev/null"}, work);
}

}  // namespace

TEST(Cli, HelpListsSubcommandsAndRunOptions) {
  TemporaryDirectory dir;
  const auto top = test::run({test::vsdSumo().string(), "--help"}, dir.path());
  EXPECT_EQ(top.exitCode, 0);
  EXPECT_NE(top.output.find("run"), std::string::npos);
  const auto run = test::run({test::vsdSumo().string(), "run", "--help"}, dir.path());
  EXPECT_EQ(run.exitCode, 0);
  for (const char* option : {"--samples", "--seed", "--out", "--jobs", "--net-batch", "--keep-nets", "--fcd", "--max-failures", "--force"}) {
    EXPECT_NE(run.output.find(option), std::string::npos) << option;
  }
}

// -q and -v are global options; they work before and after the subcommand.
TEST(Cli, QuietAndVerboseWorkBeforeAndAfterTheSubcommand) {
  TemporaryDirectory dir;
  const auto scenario = test::scenarioFile("lk.yaml").string();
  const auto before = test::run({test::vsdSumo().string(), "-q", "run", scenario, "--samples", "5", "--out",
                                 (dir.path() / "a").string()}, dir.path());
  const auto after = test::run({test::vsdSumo().string(), "run", scenario, "--samples", "5", "--out",
                                (dir.path() / "b").string(), "-q"}, dir.path());
  const auto loud = test::run({test::vsdSumo().string(), "run", scenario, "--samples", "5", "--out",
                               (dir.path() / "c").string(), "-v"}, dir.path());
  for (const auto* result : {&before, &after, &loud}) ASSERT_EQ(result->exitCode, 0) << result->output;
  EXPECT_EQ(before.output.find("run lk: 5/5"), std::string::npos) << before.output;  // no progress
  EXPECT_EQ(after.output.find("run lk: 5/5"), std::string::npos) << after.output;
  EXPECT_NE(loud.output.find("debug: batch 0"), std::string::npos) << loud.output;
}

TEST(Cli, RunPrintsASummaryAndWritesTheOutputs) {
  TemporaryDirectory dir;
  const auto out = dir.path() / "out";
  const auto result = test::run({test::vsdSumo().string(), "run", test::scenarioFile("acc_lk.yaml").string(),
                                 "--samples", "30", "--seed", "3", "--out", out.string(), "--jobs", "2"},
                                dir.path());
  ASSERT_EQ(result.exitCode, 0) << result.output;
  EXPECT_NE(result.output.find("acc_lk: 30 concrete scenarios (seed 3)"), std::string::npos) << result.output;
  EXPECT_NE(result.output.find("completed 30, failed 0"), std::string::npos) << result.output;
  EXPECT_TRUE(std::regex_search(result.output, std::regex("d_min +[-0-9.]+ +[-0-9.]+ +[-0-9.]+ +m")))
      << result.output;
  // Not a terminal: progress comes as plain lines.
  EXPECT_NE(result.output.find("run acc_lk: 30/30 scenarios"), std::string::npos) << result.output;
  for (const char* file : {"concrete.csv", "traces.h5", "manifest.json"}) EXPECT_TRUE(fs::exists(out / file)) << file;

  // The documented trace schema, read with h5py.
  const auto python = test::writeFile(dir.path() / "read.py", R"(
import sys, h5py, numpy as np
with h5py.File(sys.argv[1], "r") as f:
    assert f.attrs["schema"] == "vsd-traces/2", f.attrs["schema"]
    assert f.attrs["functional_scenario"] == "acc_lk"
    assert list(f["vehicle_ids"].asstr()[:]) == ["ego", "co"]
    assert list(f["fields"].asstr()[:]) == ["x", "y", "heading", "speed", "accel"]
    states = f["states"][:]
    assert states.shape == (30, 2, 26, 5), states.shape
    assert np.all(f["valid"][:] == 1) and np.all(f["ok"][:] == 1)
    assert np.allclose(states[:, 0, 0, 0], -50.0)
    assert list(f["sample"][:]) == list(range(30))
print("ok")
)");
  const auto read = test::run({test::python(), python.string(), (out / "traces.h5").string()}, dir.path());
  EXPECT_EQ(read.exitCode, 0) << read.output;
}

TEST(Cli, BadInputGivesOneLineNamingTheProblemAndNoOutput) {
  TemporaryDirectory dir;
  struct Case {
    std::string name;
    std::string yaml;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {"malformed", "name: x\ninputs: [ {name: a, min: 1\n", "malformed YAML"},
      {"unknown_key", test::scenarioVariant("acc.yaml", "  lanes: 1\n", "  lanes: 1\n  colour: red\n"),
       "road.colour: unknown key 'colour'"},
      {"min_max", test::scenarioVariant("acc.yaml", "min: -8,          max: -1", "min: -1,          max: -8"),
       "min -1 > max -8"},
      {"unknown_input", test::scenarioVariant("acc.yaml", "v_ego - 4", "v_egoo - 4"), "unknown name 'v_egoo'"},
      {"negative_duration", test::scenarioVariant("acc.yaml", "duration: 5.0", "duration: -1"), "time.duration"},
      {"unknown_controller", test::scenarioVariant("acc.yaml", "name: paper_ego", "name: tesla_fsd"),
       "unknown controller 'tesla_fsd' (available: alks, fsm, idm, keep_lane, paper_ego, r157_reference_driver, "
       "time_gap_p)"},
      {"missing_library",
       test::scenarioVariant("acc.yaml", "name: paper_ego", "name: mine\n      library: /nonexistent/libmine.so"),
       "controller library '/nonexistent/libmine.so' does not exist"},
      {"netconvert",
       test::scenarioVariant("acc.yaml", "criteria:", "sumo: {netconvert_options: [--default.lanewidth, \"-1\"]}\ncriteria:"),
       "netconvert failed"},
  };
  for (const auto& c : cases) {
    const auto file = test::writeFile(dir.path() / (c.name + ".yaml"), c.yaml);
    const auto out = dir.path() / ("out_" + c.name);
    const auto result = runForErrors({"run", file.string(), "--samples", "5", "--out", out.string()}, dir.path());
    EXPECT_EQ(result.exitCode, 1) << c.name << ": " << result.output;
    EXPECT_EQ(lineCount(result.output), 1u) << c.name << ": " << result.output;
    EXPECT_NE(result.output.find(c.expected), std::string::npos) << c.name << ": " << result.output;
    EXPECT_NE(result.output.find("vsd-sumo: error:"), std::string::npos) << c.name;
    EXPECT_TRUE(!fs::exists(out) || fs::is_empty(out)) << c.name << ": output left behind";
  }
  // A missing scenario file and a bad flag are usage errors (exit code 2, docs/cli.md).
  const auto missing = runForErrors({"run", (dir.path() / "nope.yaml").string()}, dir.path());
  EXPECT_EQ(missing.exitCode, 2);
  EXPECT_NE(missing.output.find("nope.yaml"), std::string::npos);
  const auto flag = runForErrors({"run", test::scenarioFile("acc.yaml").string(), "--jobs", "0"}, dir.path());
  EXPECT_EQ(flag.exitCode, 2);
  EXPECT_NE(flag.output.find("--jobs: got '0'"), std::string::npos) << flag.output;
}

TEST(Cli, FcdOutputReplaysInSumo) {
  TemporaryDirectory dir;
  const auto out = dir.path() / "out";
  const auto result = test::run({test::vsdSumo().string(), "--quiet", "run", test::scenarioFile("acc_lk.yaml").string(),
                                 "--samples", "8", "--net-batch", "4", "--fcd", "--out", out.string()},
                                dir.path());
  ASSERT_EQ(result.exitCode, 0) << result.output;
  const auto replay = test::run(
      {test::python(), (test::sourceDir() / "tools" / "replay_fcd.py").string(), out.string(), "--batch", "1", "--check"},
      dir.path());
  EXPECT_EQ(replay.exitCode, 0) << replay.output;
  EXPECT_NE(replay.output.find("replayed 8 vehicles over 26 steps"), std::string::npos) << replay.output;
}

TEST(Cli, DatasetsFromRunAndExportValidateAndLoadInPython) {
  TemporaryDirectory dir;
  const auto run_out = dir.path() / "acc_lk";
  ASSERT_EQ(test::run({test::vsdSumo().string(), "--quiet", "run", test::scenarioFile("acc_lk.yaml").string(),
                       "--samples", "12", "--out", run_out.string()},
                      dir.path())
                .exitCode,
            0);
  const auto map = dir.path() / "od.h5";
  const auto exported = test::run(
      {test::vsdSumo().string(), "--quiet", "export", "--opendrive",
       (test::sourceDir() / "sumo_nets/opendrive_curve/curve.xodr").string(), "--routes",
       (test::sourceDir() / "sumo_nets/opendrive_curve/curve.rou.xml").string(), "--out", map.string(), "--end", "40"},
      dir.path());
  ASSERT_EQ(exported.exitCode, 0) << exported.output;
  EXPECT_NE(exported.output.find("bytes per sample"), std::string::npos) << exported.output;

  const auto validate = test::run({test::vsdSumo().string(), "dataset", "validate", run_out.string(), map.string()},
                                  dir.path());
  EXPECT_EQ(validate.exitCode, 0) << validate.output;
  EXPECT_NE(validate.output.find("dataset.h5: valid (12 samples)"), std::string::npos) << validate.output;

  const auto info = test::run({test::vsdSumo().string(), "dataset", "info", map.string()}, dir.path());
  EXPECT_EQ(info.exitCode, 0);
  for (const char* text : {"schema vsd-dataset/3", "kind map", "curve.xodr", "bytes per sample", "timestamp"}) {
    EXPECT_NE(info.output.find(text), std::string::npos) << text << "\n" << info.output;
  }
  const auto svg = dir.path() / "s3.svg";
  const auto show = test::run(
      {test::vsdSumo().string(), "dataset", "show", run_out.string(), "--sample", "3", "--svg", svg.string()}, dir.path());
  EXPECT_EQ(show.exitCode, 0) << show.output;
  EXPECT_NE(show.output.find("v_ego ="), std::string::npos);
  const auto drawing = readTextFile(svg);
  EXPECT_NE(drawing.find("<svg"), std::string::npos);
  EXPECT_NE(drawing.find("5 s"), std::string::npos);  // Co timestamps as in the paper's figure

  // The Python reader in tools/ validates both and agrees with the C++ reader.
  const auto reader = (test::sourceDir() / "tools" / "vsd_dataset.py").string();
  for (const auto& path : {run_out, map}) {
    const auto result = test::run({test::python(), reader, "validate", path.string()}, dir.path());
    EXPECT_EQ(result.exitCode, 0) << result.output;
  }
  const auto compare = test::writeFile(dir.path() / "compare.py", R"(
import json, subprocess, sys
sys.path.insert(0, sys.argv[1])
from vsd_dataset import Dataset
ds = Dataset(sys.argv[2])
s = ds.sample(3)
ego = s["polylines"][s["ego_polyline"]]["vectors"][-1]
print(json.dumps({"n": len(ds), "polylines": len(s["polylines"]), "vectors": sum(len(p["vectors"]) for p in s["polylines"]),
                  "ego": [round(float(v), 4) for v in ego[:4]], "v_ego": s["inputs"]["v_ego"],
                  "sizes": [[p["length"], p["width"]] for p in s["polylines"]]}))
)");
  const auto py = test::run({test::python(), compare.string(), (test::sourceDir() / "tools").string(), run_out.string()},
                            dir.path());
  ASSERT_EQ(py.exitCode, 0) << py.output;
  EXPECT_NE(py.output.find("\"n\": 12, \"polylines\": 4, \"vectors\": 74"), std::string::npos) << py.output;
  EXPECT_NE(py.output.find("\"ego\": [-50.0,"), std::string::npos) << py.output;
  // Lanes have no size; the Co and the Ego carry the scenario's 5 m x 1.8 m.
  EXPECT_NE(py.output.find("\"sizes\": [[0.0, 0.0], [0.0, 0.0], [5.0, 1.8], [5.0, 1.8]]"),
            std::string::npos) << py.output;
}

TEST(Cli, ExportAndDatasetBadInputGiveOneLine) {
  TemporaryDirectory dir;
  const auto garbage = test::writeFile(dir.path() / "garbage.h5", "definitely not HDF5");
  const auto info = runForErrors({"dataset", "info", garbage.string()}, dir.path());
  EXPECT_EQ(info.exitCode, 1);
  EXPECT_EQ(lineCount(info.output), 1u) << info.output;
  EXPECT_NE(info.output.find("garbage.h5: not an HDF5 file"), std::string::npos) << info.output;

  const auto validate = test::run({test::vsdSumo().string(), "dataset", "validate", garbage.string()}, dir.path());
  EXPECT_EQ(validate.exitCode, 1);
  EXPECT_NE(validate.output.find("INVALID"), std::string::npos);

  const auto out = dir.path() / "x.h5";
  const auto ghost = runForErrors({"export", "--opendrive", (test::sourceDir() / "sumo_nets/opendrive_curve/curve.xodr").string(),
                                   "--routes", (test::sourceDir() / "sumo_nets/opendrive_curve/curve.rou.xml").string(),
                                   "--out", out.string(), "--egos", "ghost", "--end", "30"},
                                  dir.path());
  EXPECT_EQ(ghost.exitCode, 1);
  EXPECT_EQ(lineCount(ghost.output), 1u) << ghost.output;
  EXPECT_NE(ghost.output.find("vehicle 'ghost' never appears"), std::string::npos) << ghost.output;
  EXPECT_FALSE(fs::exists(out));
  const auto no_map = runForErrors({"export", "--out", out.string()}, dir.path());
  EXPECT_EQ(no_map.exitCode, 1);
  EXPECT_NE(no_map.output.find("no map given"), std::string::npos) << no_map.output;
}

/// `run acc.yaml --samples 30` into `out`: the training data of the small CLI trainings.
int runThirtyAcc(const fs::path& work, const fs::path& out) {
  return test::run({test::vsdSumo().string(), "--quiet", "run", test::scenarioFile("acc.yaml").string(), "--samples",
                    "30", "--out", out.string()},
                   work)
      .exitCode;
}

// issue 26: the configuration the docs report is one name away, and a preset cannot be
// contradicted by --decoder or --frame.
TEST(Cli, TrainPresetGivesTheDocumentedConfiguration) {
  TemporaryDirectory dir;
  const auto data = dir.path() / "acc";
  ASSERT_EQ(runThirtyAcc(dir.path(), data), 0);
  const auto model = dir.path() / "p.pt";
  const std::vector<std::string> train = {test::vsdSumo().string(), "train", "--data", data.string(), "--out",
                                          model.string(), "--steps", "10", "--minibatch", "8", "--hidden", "8",
                                          "--global-width", "8", "--decoder-hidden", "16", "--preset", "recommended"};
  const auto trained = test::run(train, dir.path());
  ASSERT_EQ(trained.exitCode, 0) << trained.output;
  EXPECT_NE(trained.output.find("trained VectorNet (kinematic decoder)"), std::string::npos) << trained.output;
  EXPECT_NE(trained.output.find("calibrated " + model.string()), std::string::npos) << trained.output;
  // The model file's description (stored uncompressed in its archive) names frame and options.
  std::ifstream file(model, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  EXPECT_NE(bytes.find("\"frame\":\"lane\""), std::string::npos);
  EXPECT_NE(bytes.find("\"accel_weight\":10.0"), std::string::npos);
  for (const char* flag : {"--decoder", "--frame"}) {
    auto contradicted = train;
    contradicted.insert(contradicted.end(), {flag, std::string(flag) == "--frame" ? "ego" : "offsets"});
    const auto refused = test::run(contradicted, dir.path());
    EXPECT_EQ(refused.exitCode, 2) << refused.output;
    EXPECT_NE(refused.output.find("excludes --preset"), std::string::npos) << refused.output;
  }
}

TEST(Cli, TrainPredictEvaluate) {
  TemporaryDirectory dir;
  const auto data = dir.path() / "acc";
  ASSERT_EQ(runThirtyAcc(dir.path(), data), 0);
  const auto model = dir.path() / "models" / "m.pt";
  const auto trained = test::run({test::vsdSumo().string(), "train", "--data", data.string(), "--mix", "acc=30", "--out",
                                  model.string(), "--steps", "30", "--minibatch", "8", "--hidden", "8", "--global-width",
                                  "8", "--decoder-hidden", "16", "--decoder", "kinematic", "--decoder-option",
                                  "max_decel=8"},
                                 dir.path());
  ASSERT_EQ(trained.exitCode, 0) << trained.output;
  EXPECT_NE(trained.output.find("epoch   1/8: train loss"), std::string::npos) << trained.output;
  EXPECT_NE(trained.output.find("NLL"), std::string::npos) << trained.output;
  EXPECT_NE(trained.output.find("samples/s"), std::string::npos);
  EXPECT_NE(trained.output.find("trained VectorNet (kinematic decoder): best validation ADE"), std::string::npos)
      << trained.output;
  EXPECT_NE(trained.output.find("acc 27/3"), std::string::npos) << trained.output;  // 90 % / 10 %

  const auto csv = dir.path() / "eval.csv";
  const auto evaluated = test::run(
      {test::vsdSumo().string(), "evaluate", "--model", model.string(), "--data", data.string(), "--csv", csv.string()},
      dir.path());
  ASSERT_EQ(evaluated.exitCode, 0) << evaluated.output;
  EXPECT_NE(evaluated.output.find("ADE [m]"), std::string::npos);
  EXPECT_NE(evaluated.output.find("NLL [nats]"), std::string::npos);
  EXPECT_NE(evaluated.output.find("share inside the predicted 50 % / 90 % region"), std::string::npos) << evaluated.output;
  EXPECT_NE(evaluated.output.find("scenes/s"), std::string::npos);
  EXPECT_EQ(readTextFile(csv).rfind("label,samples,ade_m,fde_m,nll,nll_1s,nll_3s,nll_5s,coverage50_1s,coverage90_1s,", 0),
            0u)
      << readTextFile(csv);
  // The constant-velocity predictor needs no model file.
  const auto cv = test::run({test::vsdSumo().string(), "evaluate", "--model", "cv", "--data", data.string()}, dir.path());
  ASSERT_EQ(cv.exitCode, 0) << cv.output;
  EXPECT_NE(cv.output.find("cv (no training)"), std::string::npos) << cv.output;

  const auto predictions = dir.path() / "pred.h5";
  const auto predicted = test::run({test::vsdSumo().string(), "predict", "--model", model.string(), "--data",
                                    data.string(), "--out", predictions.string(), "--futures", "4"},
                                   dir.path());
  ASSERT_EQ(predicted.exitCode, 0) << predicted.output;
  const auto check = test::writeFile(dir.path() / "check.py", R"(
import sys, h5py, numpy as np
with h5py.File(sys.argv[1], "r") as f:
    assert f.attrs["schema"] == "vsd-predictions/3"
    assert f.attrs["predictor"] == "kinematic" and f.attrs["samples"] == 4
    p, t, v = f["predictions"][:], f["targets"][:], f["target_valid"][:]
    assert p.shape == (30, 25, 2) and t.shape == (30, 25, 2) and v.all()
    ade = np.linalg.norm(p - t, axis=-1).mean(axis=1)
    assert np.allclose(ade, f["ade"][:], atol=1e-9)
    assert list(f["labels"].asstr()[:]) == ["acc"]
    assert f["sample_positions"].shape == (30, 4, 25, 2)
    assert f["position_covariance"].shape == (30, 25, 2, 2)
    # Uncalibrated model: the regions' radii are the Gaussian's (-2 ln(1 - level)).
    assert np.allclose(f["position_region_radius2"][:], [-2 * np.log(0.5), -2 * np.log(0.1)])
    speed, accel = f["predicted_speed"][:], f["predicted_accel"][:]
    assert (speed >= 0).all() and (accel >= -8 - 1e-3).all()
    # Metrics of the most likely future and their intervals over the 4 draws, by the metric code.
    names = list(f["metric_names"].asstr()[:])
    point, intervals = f["metrics_predicted"][:], f["metric_intervals"][:]
    assert "a_min" in names and "d_min" in names, names
    assert point.shape == (30, len(names)) and intervals.shape == (30, len(names), 5)
    a = names.index("a_min")
    assert np.allclose(point[:, a], accel.min(axis=1), atol=1e-4)  # the model's own accelerations
    assert np.isfinite(intervals[:, a]).all()
    assert (np.diff(intervals[:, a], axis=-1) >= 0).all()  # 5 <= 25 <= 50 <= 75 <= 95 %
print("ok")
)");
  const auto read = test::run({test::python(), check.string(), predictions.string()}, dir.path());
  EXPECT_EQ(read.exitCode, 0) << read.output;
  for (const std::string samples : {"-2", "0"}) {  // 0 would draw nothing: refused like a negative count
    const auto no_samples = runForErrors({"predict", "--model", model.string(), "--data", data.string(), "--out",
                                          (dir.path() / "p.h5").string(), "--futures", samples},
                                         dir.path());
    EXPECT_EQ(no_samples.exitCode, 2);  // a flag's value: a usage error
    EXPECT_EQ(lineCount(no_samples.output), 1u) << no_samples.output;
    EXPECT_NE(no_samples.output.find("--futures: got '" + samples + "', expected"), std::string::npos) << no_samples.output;
    EXPECT_FALSE(fs::exists(dir.path() / "p.h5"));
  }
  const auto no_decoder = runForErrors({"train", "--data", data.string(), "--out", (dir.path() / "x.pt").string(),
                                        "--decoder", "lstm"},
                                       dir.path());
  EXPECT_EQ(no_decoder.exitCode, 1);
  EXPECT_EQ(lineCount(no_decoder.output), 1u) << no_decoder.output;
  EXPECT_NE(no_decoder.output.find("unknown decoder 'lstm' (known: offsets, kinematic)"), std::string::npos)
      << no_decoder.output;

  // Bad input: one line, exit 1.
  const auto empty_mix = runForErrors({"train", "--data", data.string(), "--mix", "acc=0", "--out",
                                       (dir.path() / "x.pt").string()},
                                      dir.path());
  EXPECT_EQ(empty_mix.exitCode, 1);
  EXPECT_EQ(lineCount(empty_mix.output), 1u) << empty_mix.output;
  EXPECT_NE(empty_mix.output.find("the mix is empty"), std::string::npos);
  const auto too_many = runForErrors({"train", "--data", data.string(), "--mix", "acc=31", "--out",
                                      (dir.path() / "x.pt").string()},
                                     dir.path());
  EXPECT_NE(too_many.output.find("holds only 30 samples"), std::string::npos) << too_many.output;
  const auto garbage = test::writeFile(dir.path() / "garbage.pt", "zzz");
  const auto corrupt = runForErrors({"evaluate", "--model", garbage.string(), "--data", data.string()}, dir.path());
  EXPECT_EQ(corrupt.exitCode, 1);
  EXPECT_EQ(lineCount(corrupt.output), 1u) << corrupt.output;
  EXPECT_NE(corrupt.output.find("not a vsd-sumo model file"), std::string::npos);
  EXPECT_FALSE(fs::exists(dir.path() / "x.pt"));

  // A dataset without samples has no ADE (not 0.000): refused.
  const auto empty = dir.path() / "empty.h5";
  {
    vector::DatasetWriter writer(empty, vector::DatasetReader(data / "dataset.h5").header());
    writer.close();
  }
  for (const auto& command : std::vector<std::vector<std::string>>{
           {"evaluate", "--model", model.string(), "--data", empty.string()},
           {"compare", "--model", model.string(), "--data", empty.string(), "--out", (dir.path() / "r").string()},
           {"predict", "--model", model.string(), "--data", empty.string(), "--out", (dir.path() / "p0.h5").string()}}) {
    const auto refused = runForErrors(command, dir.path());
    EXPECT_EQ(refused.exitCode, 1) << command[0] << ": " << refused.output;
    EXPECT_EQ(lineCount(refused.output), 1u) << refused.output;
    EXPECT_NE(refused.output.find("empty.h5"), std::string::npos) << refused.output;
  }
  EXPECT_FALSE(fs::exists(dir.path() / "r"));
  EXPECT_FALSE(fs::exists(dir.path() / "p0.h5"));

  // An existing folder where a file is expected is refused by the output policy before the
  // work starts (docs/output-policy.md): a folder is never replaced by a file.
  const auto folder = dir.path() / "a_folder";
  fs::create_directories(folder);
  for (const auto& command : std::vector<std::vector<std::string>>{
           {"train", "--data", data.string(), "--out", folder.string(), "--steps", "3"},
           {"predict", "--model", model.string(), "--data", data.string(), "--out", folder.string()},
           {"evaluate", "--model", model.string(), "--data", data.string(), "--csv", folder.string()}}) {
    const auto refused = runForErrors(command, dir.path());
    EXPECT_EQ(refused.exitCode, 1) << command[0] << ": " << refused.output;
    EXPECT_EQ(lineCount(refused.output), 1u) << refused.output;
    EXPECT_NE(refused.output.find("a_folder: exists and is a folder vsd-sumo did not write"), std::string::npos)
        << command[0] << ": " << refused.output;
  }
  EXPECT_TRUE(fs::is_empty(folder));
}

// Numbers from flags are checked where they enter: no wrap-around of negative values
// into unsigned ones, no infinities, no absurd sizes that allocate or run forever.
TEST(Cli, NumbersFromFlagsAreCheckedWhereTheyEnter) {
  TemporaryDirectory dir;
  const auto out = dir.path() / "out";
  const std::string acc = test::scenarioFile("acc.yaml").string();
  const std::string xodr = (test::sourceDir() / "sumo_nets/opendrive_curve/curve.xodr").string();
  const std::string routes = (test::sourceDir() / "sumo_nets/opendrive_curve/curve.rou.xml").string();
  struct Case {
    std::vector<std::string> args;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {{"run", acc, "--seed", "-1"}, "--seed: got '-1', expected a whole number 0 .. 18446744073709551615"},
      {{"run", acc, "--first-sample", "-5"}, "--first-sample: got '-5', expected a whole number"},
      {{"run", acc, "--first-sample", "1125899906842620"}, "--first-sample: got '1125899906842620'"},
      {{"run", acc, "--samples", "0x10"}, "--samples: got '0x10'"},
      {{"run", acc, "--jobs", "99999999999"}, "--jobs: got '99999999999', expected a whole number -2147483648"},
      {{"run", acc, "--compression", "12"}, "--compression: got '12', expected a deflate level 0 .. 9"},
      {{"export", "--opendrive", xodr, "--routes", routes, "--radius", "inf"},
       "--radius: got 'inf', expected a finite decimal number"},
      {{"export", "--opendrive", xodr, "--routes", routes, "--radius", "1e9"}, "expected a radius in (0, 1000] m"},
      {{"export", "--opendrive", xodr, "--routes", routes, "--step", "1e-9"}, "--step: got '1e-09'"},
      {{"export", "--opendrive", xodr, "--routes", routes, "--horizon", "1e6"}, "at most 1000 steps"},
      {{"export", "--opendrive", xodr, "--routes", routes, "--begin", "-5"}, "--begin: got '-5', expected a time"},
      {{"export", "--opendrive", xodr, "--routes", routes, "--controller-param", "time_gap=nan"},
       "--controller-param: got 'time_gap=nan'"},
      {{"train", "--data", out.string(), "--lr", "nan"}, "--lr: got 'nan', expected a finite decimal number"},
      {{"compare", acc, "--model", "m.pt", "--worst", "-1"}, "--worst: got '-1'"},
      {{"dataset", "show", out.string(), "--sample", "-1"}, "--sample: got '-1'"},
  };
  for (const auto& c : cases) {
    auto args = c.args;
    if (args[0] == "run" || args[0] == "export") args.insert(args.end(), {"--out", (out / args[0]).string()});
    if (args[0] == "train") args.insert(args.end(), {"--out", (out / "m.pt").string()});
    const auto result = runForErrors(args, dir.path());
    EXPECT_EQ(result.exitCode, 2) << c.expected << ": " << result.output;  // a flag's value: a usage error
    EXPECT_EQ(lineCount(result.output), 1u) << result.output;
    EXPECT_NE(result.output.find(c.expected), std::string::npos) << result.output;
    EXPECT_EQ(result.output.find("internal error"), std::string::npos) << result.output;
  }
  EXPECT_FALSE(fs::exists(out));
}
