// The output policy (docs/output-policy.md), command by command, as a user meets it:
// a refused output is one line, exit code 1, and the existing file is byte-identical;
// a re-run replaces its own output; --force replaces another subject's.
#include <gtest/gtest.h>

#include "test_support.hpp"

using namespace vsd;
namespace fs = std::filesystem;

namespace {

ProcessResult runVsd(const std::vector<std::string>& args, const fs::path& work) {
  std::vector<std::string> argv = {test::vsdSumo().string(), "--quiet"};
  argv.insert(argv.end(), args.begin(), args.end());
  return test::run(argv, work);
}

/// The last line of a command's output (its error line).
std::string lastLine(const std::string& output) {
  auto text = output;
  while (!text.empty() && text.back() == '\n') text.pop_back();
  return text.substr(text.rfind('\n') == std::string::npos ? 0 : text.rfind('\n') + 1);
}

/// Runs a command that must be refused: exit code 1, `expected` in the one error line,
/// and `kept` unchanged.
void expectRefused(const std::vector<std::string>& args, const fs::path& work, const std::string& expected,
                   const fs::path& kept) {
  const std::string before = fs::is_regular_file(kept) ? readTextFile(kept) : std::string();
  const auto result = runVsd(args, work);
  EXPECT_EQ(result.exitCode, 1) << result.output;
  EXPECT_NE(lastLine(result.output).find(expected), std::string::npos) << result.output;
  EXPECT_EQ(lastLine(result.output).rfind("vsd-sumo: error: ", 0), 0u) << result.output;
  if (fs::is_regular_file(kept)) {
    EXPECT_EQ(readTextFile(kept), before) << kept << " changed";
  }
}

fs::path runFolder(const std::string& scenario, const fs::path& out, const std::string& samples = "6") {
  const auto result = runVsd({"run", test::scenarioFile(scenario + ".yaml").string(), "--samples", samples, "--out",
                           out.string()},
                          out.parent_path());
  if (result.exitCode != 0) throw std::runtime_error(result.output);
  return out;
}

std::vector<std::string> trainArgs(const fs::path& data, const fs::path& out) {
  return {"train", "--data", data.string(), "--out", out.string(), "--steps", "4", "--minibatch", "4",
          "--hidden", "8", "--global-width", "8", "--decoder-hidden", "8"};
}

}  // namespace

TEST(OutputPolicy, RunReplacesItsOwnFolderAndNeedsForceForAnotherScenario) {
  TemporaryDirectory dir;
  const auto out = runFolder("acc", dir.path() / "out");
  const auto manifest = out / "manifest.json";
  ASSERT_EQ(runVsd({"run", test::scenarioFile("acc.yaml").string(), "--samples", "5", "--out", out.string()}, dir.path())
                .exitCode,
            0);  // a re-run of the same scenario
  expectRefused({"run", test::scenarioFile("lk.yaml").string(), "--samples", "5", "--out", out.string()}, dir.path(),
                "--out " + out.string() + ": holds a run folder of acc, not of lk; pass --force to replace it",
                manifest);
  const auto forced = runVsd({"run", test::scenarioFile("lk.yaml").string(), "--samples", "5", "--out", out.string(),
                           "--force"},
                          dir.path());
  ASSERT_EQ(forced.exitCode, 0) << forced.output;
  EXPECT_NE(readTextFile(manifest).find("\"functional_scenario\": \"lk\""), std::string::npos);
}

TEST(OutputPolicy, RunNeverReplacesAUsersFileOrFolder) {
  TemporaryDirectory dir;
  // A user's own concrete.csv that no manifest lists.
  const auto mine = test::writeFile(dir.path() / "mine" / "concrete.csv", "my,own\n1,2\n");
  expectRefused({"run", test::scenarioFile("acc.yaml").string(), "--samples", "5", "--out", mine.parent_path().string(),
                 "--force"},
                dir.path(), "concrete.csv there was not written by vsd-sumo (no manifest.json lists it)", mine);
  // A file where a folder should be, and a folder of another kind.
  const auto notes = test::writeFile(dir.path() / "notes.txt", "notes\n");
  expectRefused({"run", test::scenarioFile("acc.yaml").string(), "--samples", "5", "--out", notes.string()}, dir.path(),
                "exists and is a file vsd-sumo did not write, not a run folder", notes);
  // Notes next to a run's outputs stay where they are.
  const auto out = runFolder("acc", dir.path() / "out");
  const auto kept = test::writeFile(out / "notes.txt", "kept\n");
  ASSERT_EQ(runVsd({"run", test::scenarioFile("acc.yaml").string(), "--samples", "5", "--out", out.string()}, dir.path())
                .exitCode,
            0);
  EXPECT_EQ(readTextFile(kept), "kept\n");
}

TEST(OutputPolicy, ModelCommandsRefuseInputsOtherKindsAndFilesOfARunFolder) {
  TemporaryDirectory dir;
  const auto acc = runFolder("acc", dir.path() / "acc", "12");
  const auto model = dir.path() / "m.pt";
  // train: the run's CSV is not a model file, and belongs to the run folder.
  expectRefused(trainArgs(acc, acc / "concrete.csv"), dir.path(),
                "is part of the run folder " + acc.string(), acc / "concrete.csv");
  const auto notes = test::writeFile(dir.path() / "notes.pt", "not a model\n");
  expectRefused(trainArgs(acc, notes), dir.path(), "exists and is a file vsd-sumo did not write, not a model file",
                notes);
  const auto trained = runVsd(trainArgs(acc, model), dir.path());
  ASSERT_EQ(trained.exitCode, 0) << trained.output;
  EXPECT_FALSE(fs::exists(model.string() + ".last")) << "a finished training leaves no resume state behind";
  ASSERT_EQ(runVsd(trainArgs(acc, model), dir.path()).exitCode, 0);  // the same labels: replaced

  // A model trained on other labels needs --force.
  const auto lk = runFolder("lk", dir.path() / "lk", "12");
  expectRefused(trainArgs(lk, model), dir.path(), "holds a model file of labels acc, not of labels lk", model);
  auto forced = trainArgs(lk, model);
  forced.push_back("--force");
  ASSERT_EQ(runVsd(forced, dir.path()).exitCode, 0);

  // predict: its own model, the training data and the run folder's files are refused.
  const std::vector<std::string> predict = {"predict", "--model", model.string(), "--data", lk.string(), "--out"};
  auto with = [&](const fs::path& out) {
    auto args = predict;
    args.push_back(out.string());
    return args;
  };
  expectRefused(with(model), dir.path(), "is also this command's input (--model)", model);
  expectRefused(with(lk / "dataset.h5"), dir.path(), "is also this command's input (--data)", lk / "dataset.h5");
  expectRefused(with(lk / "traces.h5"), dir.path(), "is part of the run folder", lk / "traces.h5");
  const auto predictions = dir.path() / "p.h5";
  ASSERT_EQ(runVsd(with(predictions), dir.path()).exitCode, 0);
  ASSERT_EQ(runVsd(with(predictions), dir.path()).exitCode, 0);  // the same model and data: replaced
  expectRefused({"predict", "--model", "cv", "--data", lk.string(), "--out", predictions.string()}, dir.path(),
                "holds a predictions file of " + model.string(), predictions);

  // evaluate --csv: a model is not a table.
  expectRefused({"evaluate", "--model", model.string(), "--data", lk.string(), "--csv", model.string()}, dir.path(),
                "is also this command's input (--model)", model);
  expectRefused({"evaluate", "--model", "cv", "--data", lk.string(), "--csv", predictions.string()}, dir.path(),
                "exists and is a predictions file written by vsd-sumo, not an evaluation table", predictions);
  const auto table = dir.path() / "e.csv";
  ASSERT_EQ(runVsd({"evaluate", "--model", "cv", "--data", lk.string(), "--csv", table.string()}, dir.path()).exitCode, 0);
  ASSERT_EQ(runVsd({"evaluate", "--model", "cv", "--data", lk.string(), "--csv", table.string()}, dir.path()).exitCode, 0);

  // compare: a model trained on lk scoring acc scenarios says so.
  const auto report = dir.path() / "report";
  const auto compared =
      test::run({test::vsdSumo().string(), "compare", test::scenarioFile("acc.yaml").string(), "--model",
                 model.string(), "--samples", "4", "--futures", "0", "--out", report.string()},
                dir.path());
  ASSERT_EQ(compared.exitCode, 0) << compared.output;
  EXPECT_NE(compared.output.find("the model never trained on label 'acc' (it trained on lk)"), std::string::npos)
      << compared.output;
  EXPECT_NE(readTextFile(report / "report.html").find("class=\"warning\""), std::string::npos);
  EXPECT_FALSE(fs::exists(report / "index.html"));
}

TEST(OutputPolicy, FolderCommandsRefuseFoldersOfAnotherKind) {
  TemporaryDirectory dir;
  const auto acc = runFolder("acc", dir.path() / "acc");
  const auto manifest = acc / "manifest.json";
  const std::string another_kind = "exists and is a run folder written by vsd-sumo, not a";
  expectRefused({"compare", test::scenarioFile("acc.yaml").string(), "--model", "cv", "--samples", "3", "--out",
                 acc.string(), "--force"},
                dir.path(), another_kind + " comparison report folder", manifest);
  expectRefused({"search", test::scenarioFile("acc.yaml").string(), "--criterion", "d_min < 2", "--budget", "10",
                 "--out", acc.string(), "--force"},
                dir.path(), another_kind + " search folder", manifest);
  expectRefused({"scenario", "export", test::scenarioFile("acc.yaml").string(), "--samples", "2", "--out", acc.string(),
                 "--force"},
                dir.path(), another_kind + " scenario export folder", manifest);
  expectRefused({"experiment", (test::sourceDir() / "scenarios" / "experiments" / "paper.yaml").string(), "--quick",
                 "--out", acc.string(), "--force"},
                dir.path(), another_kind + "n experiment results folder", manifest);

  // compare re-runs replace their own report; another scenario's needs --force.
  const auto report = dir.path() / "report";
  const std::vector<std::string> compare = {"compare", test::scenarioFile("acc.yaml").string(), "--model", "cv",
                                            "--samples", "3", "--out", report.string()};
  ASSERT_EQ(runVsd(compare, dir.path()).exitCode, 0);
  ASSERT_EQ(runVsd(compare, dir.path()).exitCode, 0);
  expectRefused({"compare", test::scenarioFile("lk.yaml").string(), "--model", "cv", "--samples", "3", "--out",
                 report.string()},
                dir.path(), "holds a comparison report folder of acc with cv, not of lk with cv; pass --force",
                report / "manifest.json");

  // scenario export: the same scenario again, then another one.
  const auto exported = dir.path() / "xosc";
  const std::vector<std::string> export_acc = {"scenario", "export", test::scenarioFile("acc.yaml").string(),
                                               "--samples", "2", "--out", exported.string()};
  ASSERT_EQ(runVsd(export_acc, dir.path()).exitCode, 0);
  ASSERT_EQ(runVsd(export_acc, dir.path()).exitCode, 0);
  expectRefused({"scenario", "export", test::scenarioFile("lk.yaml").string(), "--samples", "2", "--out",
                 exported.string()},
                dir.path(), "holds a scenario export folder of acc, not of lk", exported / "manifest.json");
}

TEST(OutputPolicy, SingleFileCommandsRefuseFilesOfARunFolder) {
  TemporaryDirectory dir;
  const auto acc = runFolder("acc", dir.path() / "acc");
  expectRefused({"export", "--opendrive", (test::sourceDir() / "sumo_nets/opendrive_curve/curve.xodr").string(),
                 "--routes", (test::sourceDir() / "sumo_nets/opendrive_curve/curve.rou.xml").string(), "--out",
                 (acc / "dataset.h5").string(), "--end", "20", "--force"},
                dir.path(), "is part of the run folder", acc / "dataset.h5");
  expectRefused({"scenario", "distribution", test::scenarioFile("acc.yaml").string(), "--out",
                 (acc / "concrete.csv").string()},
                dir.path(), "is part of the run folder", acc / "concrete.csv");
  expectRefused({"dataset", "show", acc.string(), "--svg", (acc / "concrete.csv").string()}, dir.path(),
                "is part of the run folder", acc / "concrete.csv");
  expectRefused({"baseline", "--data", acc.string(), "--test", acc.string(), "--targets", "d_min", "--out",
                 (acc / "concrete.csv").string()},
                dir.path(), "is also this command's input (--data)", acc / "concrete.csv");
  // merge into a folder holding another scenario's run.
  const auto sweep = dir.path() / "sweep";
  ASSERT_EQ(runVsd({"run", test::scenarioFile("lk.yaml").string(), "--samples", "4", "--shard", "0/1", "--out",
                 sweep.string()},
                dir.path())
                .exitCode,
            0);
  expectRefused({"merge", sweep.string(), "--out", acc.string()}, dir.path(),
                "holds a run folder of acc, not of lk; pass --force", acc / "manifest.json");
  ASSERT_EQ(runVsd({"merge", sweep.string()}, dir.path()).exitCode, 0);
}

TEST(OutputPolicy, SearchResumesItsOwnFolderAndStartsAfreshOnlyWithForce) {
  TemporaryDirectory dir;
  const auto out = dir.path() / "search";
  const std::vector<std::string> search = {"search", test::scenarioFile("acc.yaml").string(), "--criterion",
                                           "d_min < 2", "--surrogate", "random", "--budget", "8", "--initial", "4",
                                           "--round", "4", "--out", out.string()};
  ASSERT_EQ(runVsd(search, dir.path()).exitCode, 0);
  const auto again = runVsd(search, dir.path());
  ASSERT_EQ(again.exitCode, 0) << again.output;
  expectRefused({"search", test::scenarioFile("acc.yaml").string(), "--criterion", "a_min < -6", "--surrogate",
                 "random", "--budget", "8", "--initial", "4", "--round", "4", "--out", out.string()},
                dir.path(), "holds a search folder of acc: d_min < 2, not of acc: a_min < -6; pass --force",
                out / "manifest.json");
  const auto forced = runVsd({"search", test::scenarioFile("acc.yaml").string(), "--criterion", "a_min < -6",
                           "--surrogate", "random", "--budget", "8", "--initial", "4", "--round", "4", "--out",
                           out.string(), "--force"},
                          dir.path());
  ASSERT_EQ(forced.exitCode, 0) << forced.output;
  EXPECT_NE(readTextFile(out / "manifest.json").find("a_min < -6"), std::string::npos);
}
