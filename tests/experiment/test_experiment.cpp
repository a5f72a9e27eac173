// `vsd-sumo experiment`: the paper's pipeline at --quick sizes end to end, its cache
// (a re-run reuses everything; a removed or half-written artefact is rebuilt with its
// dependants and nothing else), the findings' rules, and bad specs.
#include <gtest/gtest.h>

#include <cmath>
#include <regex>
#include <set>
#include <sstream>

#include "../../src/experiment/cache.hpp"
#include "../../src/experiment/results.hpp"
#include "test_support.hpp"
#include "vsd/core/csv.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"

namespace fs = std::filesystem;
using namespace vsd;
using namespace vsd::experiment;

namespace {

std::vector<std::string> splitLines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream stream(text);
  for (std::string line; std::getline(stream, line);) lines.push_back(line);
  return lines;
}

ProcessResult runExperimentCli(const std::vector<std::string>& args, const fs::path& work) {
  std::vector<std::string> argv = {test::vsdSumo().string(), "experiment"};
  argv.insert(argv.end(), args.begin(), args.end());
  return test::run(argv, work);
}

std::size_t builtCount(const std::string& output) {
  static const std::regex pattern(R"(\((\d+) artefacts built, (\d+) reused)");
  std::smatch match;
  if (!std::regex_search(output, match, pattern)) return 999;
  return std::stoul(match[1].str());
}

/// ade.csv as "model row label" -> ADE.
std::map<std::string, double> adeValues(const fs::path& csv) {
  const auto table = CsvTable::read(csv);
  std::map<std::string, double> values;
  for (std::size_t r = 0; r < table.rows(); ++r) {
    values[table.cell(r, table.column("model")) + " " + table.cell(r, table.column("row")) + " " +
           table.cell(r, table.column("test_label"))] = table.number(r, table.column("ade_m"));
  }
  return values;
}

AdeRow row(int number, std::map<std::string, std::size_t> mix, std::map<std::string, double> ade) {
  AdeRow result;
  result.row = number;
  result.mix = std::move(mix);
  result.ade = std::move(ade);
  return result;
}

}  // namespace

TEST(Experiment, QuickRunProducesTheTablesFiguresAndManifestAndCachesArtefacts) {
  TemporaryDirectory dir;
  const auto out = dir.path() / "quick";
  const auto spec = test::sourceDir() / "scenarios" / "experiments" / "paper.yaml";
  const auto first = runExperimentCli({spec.string(), "--quick", "--out", out.string()}, dir.path());
  ASSERT_EQ(first.exitCode, 0) << first.output;

  // Ten rows of the main model, row 3 (quick.repeat_rows) also with the residual, the kinematic
  // decoder and in the lane frame, and the two predictors without training, each on three test
  // sets: every ADE finite and positive.
  const auto ade = adeValues(out / "ade.csv");
  ASSERT_EQ(ade.size(), (10u + 3u + 2u) * 3u);
  for (const auto& [key, value] : ade) EXPECT_TRUE(std::isfinite(value) && value > 0.0) << key;
  const auto ade_table = CsvTable::read(out / "ade.csv");
  EXPECT_EQ(ade_table.cell(0, ade_table.column("paper_ade_m")), "0.37");
  // In-distribution beats out-of-distribution even at quick sizes: ACC-only on LK is far off.
  EXPECT_LT(ade.at("no_residual 1 acc"), ade.at("no_residual 1 lk"));
  EXPECT_LT(ade.at("no_residual 2 lk"), ade.at("no_residual 2 acc"));
  EXPECT_TRUE(ade.count("residual 3 acc_lk") && ade.count("kinematic 3 lk") && ade.count("lane 3 acc") &&
              ade.count("cv 0 lk") && ade.count("ca 0 acc"));
  // Row 3 (a row carrying findings) over three seeds: mean with a spread; row 1 over one.
  for (std::size_t r = 0; r < ade_table.rows(); ++r) {
    const auto row = ade_table.cell(r, ade_table.column("row"));
    if (ade_table.cell(r, ade_table.column("model")) != "no_residual" || (row != "3" && row != "1")) continue;
    EXPECT_EQ(ade_table.cell(r, ade_table.column("seeds")), row == "3" ? "3" : "1");
    const auto spread = ade_table.cell(r, ade_table.column("ade_std_m"));
    if (row == "3") {
      EXPECT_GT(std::stod(spread), 0.0) << "different seeds train different models";
    } else {
      EXPECT_EQ(spread, "");
    }
  }
  // paper.yaml gives the kinematic model its own three seeds; --quick trains them once.
  for (std::size_t r = 0; r < ade_table.rows(); ++r) {
    if (ade_table.cell(r, ade_table.column("model")) == "kinematic") {
      EXPECT_EQ(ade_table.cell(r, ade_table.column("seeds")), "1");
    }
  }
  const auto ade_md = readTextFile(out / "ade.md");
  EXPECT_NE(ade_md.find("## residual: decoder offsets (residual=1)"), std::string::npos) << ade_md;
  EXPECT_NE(ade_md.find("## lane: decoder offsets (residual=0), lane frame"), std::string::npos) << ade_md;
  EXPECT_NE(ade_md.find(" ± "), std::string::npos) << ade_md;
  EXPECT_NE(ade_md.find("| cv |"), std::string::npos) << ade_md;
  // Every Markdown table is well formed: its separator has a column per header cell and every
  // row has as many cells (a table that does not is shown as text).
  for (const auto& file : {"ade.md", "mae.md"}) {
    const auto lines = splitLines(readTextFile(out / file));
    for (std::size_t i = 1; i < lines.size(); ++i) {
      if (lines[i].rfind("|---", 0) != 0) continue;
      const auto columns = std::count(lines[i - 1].begin(), lines[i - 1].end(), '|');
      EXPECT_EQ(std::count(lines[i].begin(), lines[i].end(), '|'), columns) << file << ": " << lines[i - 1];
      for (std::size_t r = i + 1; r < lines.size() && lines[r].rfind("|", 0) == 0; ++r) {
        EXPECT_EQ(std::count(lines[r].begin(), lines[r].end(), '|'), columns) << file << ": " << lines[r];
      }
    }
  }

  const auto mae = CsvTable::read(out / "mae.csv");
  ASSERT_EQ(mae.rows(), 6u);  // acc: a_min, d_min; lk: p_lat_max; acc_lk: all three
  for (std::size_t r = 0; r < mae.rows(); ++r) {
    for (const char* column : {"et", "bnn", "vectornet", "vectornet_from_true_positions", "bnn_mean_std"}) {
      const double value = mae.number(r, mae.column(column));
      EXPECT_TRUE(std::isfinite(value) && value >= 0.0) << column << " row " << r;
    }
    // Positions reproduce p_lat_max exactly (datasets store float32: about 1e-5 m at 100 m).
    // d_min is the clearance of oriented footprints, whose headings a future of positions
    // only approximates: a few cm (measured 0.023 / 0.040 m on the quick run).
    // Every model that trains the row predicting the scenario has a column; only the
    // probabilistic one (kinematic, row 3: acc_lk) has interval coverage, between 0 and 1
    // and larger for the wider interval.
    const bool acc_lk = mae.cell(r, mae.column("functional_scenario")) == "acc_lk";
    EXPECT_EQ(mae.cell(r, mae.column("vectornet_no_residual_coverage_90")), "");
    EXPECT_EQ(mae.cell(r, mae.column("vectornet_kinematic")) != "", acc_lk) << "row " << r;
    EXPECT_EQ(mae.cell(r, mae.column("vectornet_lane")) != "", acc_lk) << "row " << r;
    // The MAE of a row trained with several seeds is their mean with a spread (acc_lk: row 3,
    // quick.repeat_rows); a row of one seed has none. The baselines are fitted with as many
    // seeds as the rows that carry findings, and different seeds fit different models.
    EXPECT_EQ(mae.cell(r, mae.column("vectornet_no_residual_seeds")), acc_lk ? "3" : "1") << "row " << r;
    if (acc_lk) {
      EXPECT_GT(mae.number(r, mae.column("vectornet_no_residual_seed_std")), 0.0) << "row " << r;
    } else {
      EXPECT_EQ(mae.cell(r, mae.column("vectornet_no_residual_seed_std")), "") << "row " << r;
    }
    EXPECT_EQ(mae.cell(r, mae.column("baseline_seeds")), "3");
    EXPECT_GT(mae.number(r, mae.column("et_seed_std")), 0.0) << "row " << r;
    EXPECT_GT(mae.number(r, mae.column("bnn_seed_std")), 0.0) << "row " << r;
    if (acc_lk) {
      const double covered50 = mae.number(r, mae.column("vectornet_kinematic_coverage_50"));
      const double covered90 = mae.number(r, mae.column("vectornet_kinematic_coverage_90"));
      EXPECT_TRUE(covered50 >= 0.0 && covered50 <= covered90 && covered90 <= 1.0) << covered50 << " " << covered90;
      EXPECT_EQ(mae.cell(r, mae.column("vectornet_lane_coverage_90")), "");
    }
    const std::string metric = mae.cell(r, mae.column("metric"));
    if (metric == "p_lat_max") {
      EXPECT_LT(mae.number(r, mae.column("vectornet_from_true_positions")), 1e-4);
    }
    if (metric == "d_min") {
      EXPECT_LT(mae.number(r, mae.column("vectornet_from_true_positions")), 0.1);
    }
  }
  for (const char* figure : {"fig6_trained_on_all_three", "fig7_trained_on_acc_lk", "fig8_trained_on_acc_and_lk"}) {
    const auto svg = readTextFile(out / "figures" / (std::string(figure) + ".svg"));
    EXPECT_EQ(svg.rfind("<svg", 0), 0u) << figure;
    EXPECT_NE(svg.find("VectorNet prediction"), std::string::npos) << figure;
    EXPECT_EQ(std::count(svg.begin(), svg.end(), '\n') > 50, true) << figure;
  }
  const auto findings = readTextFile(out / "findings.md");
  for (const char* id : {"(a)", "(b)", "(c)", "(d)", "(e)"}) EXPECT_NE(findings.find(id), std::string::npos);
  const auto manifest = readTextFile(out / "manifest.json");
  EXPECT_NE(manifest.find("\"quick\": true"), std::string::npos);
  EXPECT_NE(manifest.find("\"sumo_version\""), std::string::npos);

  // A re-run reuses everything and gives the same numbers.
  const auto second = runExperimentCli({spec.string(), "--quick", "--out", out.string()}, dir.path());
  ASSERT_EQ(second.exitCode, 0) << second.output;
  EXPECT_EQ(builtCount(second.output), 0u) << second.output;
  EXPECT_EQ(adeValues(out / "ade.csv"), ade);

  // Artefacts left half-written by an interrupted run (no key) are rebuilt: row 10's model (the
  // quickest to train: 20 samples) and its evaluation. Downstream keys name what an artefact
  // was built from (data, mix, decoder, seed), not its bytes, so nothing else is redone. Same
  // seed and threads: the same ADEs again.
  const auto row10_model = out / "cache" / "models" / "no_residual" / "row10_seed1";
  fs::remove(ArtefactCache::keyFile(row10_model));
  test::writeFile(row10_model / "model.pt", "truncated");
  fs::remove(ArtefactCache::keyFile(out / "cache" / "eval" / "no_residual" / "row10_seed1"));
  const auto third = runExperimentCli({spec.string(), "--quick", "--out", out.string()}, dir.path());
  ASSERT_EQ(third.exitCode, 0) << third.output;
  EXPECT_EQ(builtCount(third.output), 2u) << third.output;
  EXPECT_NE(third.output.find("no_residual row 10 seed 1 model"), std::string::npos) << third.output;
  EXPECT_EQ(adeValues(out / "ade.csv"), ade);

  // Existing run folders can stand in for simulated data, but must hold the right scenario.
  const auto runs = out / "cache" / "data";
  const auto wrong = test::writeFile(dir.path() / "wrong_runs.yaml", fmt::format(R"(schema: vsd-experiment/1
name: wrong
scenarios:
  acc: {{train: {0}/lk_train, test: {0}/lk_test}}
ade:
  - {{row: 1, mix: {{acc: 20}}}}
)",
                                                                                   runs.string()));
  const auto wrong_result = runExperimentCli({wrong.string(), "--out", (dir.path() / "wrong").string()}, dir.path());
  EXPECT_EQ(wrong_result.exitCode, 1);
  EXPECT_NE(wrong_result.output.find("holds functional scenario 'lk', expected 'acc'"), std::string::npos)
      << wrong_result.output;
  EXPECT_FALSE(fs::exists(dir.path() / "wrong"));
}

TEST(Experiment, BadSpecsGiveOneLineNamingFileFieldAndValue) {
  TemporaryDirectory dir;
  const auto scenarios = test::sourceDir() / "scenarios";
  const std::string head = fmt::format("schema: vsd-experiment/1\nname: bad\nscenarios:\n  acc: {{scenario: {}}}\n",
                                       (scenarios / "acc.yaml").string());
  const std::string two = head + fmt::format("  lk: {{scenario: {}}}\n", (scenarios / "lk.yaml").string());
  struct Case {
    std::string name;
    std::string yaml;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {"missing_scenario", "schema: vsd-experiment/1\nname: bad\nscenarios:\n  acc: {scenario: nowhere.yaml}\nade: []\n",
       "nowhere.yaml' does not exist (a logical scenario file)"},
      {"missing_run", "schema: vsd-experiment/1\nname: bad\nscenarios:\n  acc: {train: no/run, test: no/run}\nade: []\n",
       "no/run' is not a run folder of vsd-sumo run (no dataset.h5)"},
      {"unknown_label", head + "ade:\n  - {row: 1, mix: {acc: 20, lkk: 20}}\n",
       "ade[0].mix.lkk: unknown functional scenario 'lkk' (defined under scenarios: acc)"},
      {"unknown_metric",
       head + "ade:\n  - {row: 1, mix: {acc: 20}}\nmae:\n  vectornet_rows: {acc: 1}\n  metrics: {acc: {a_max: {}}}\n",
       "mae.metrics.acc.a_max: unknown metric 'a_max'"},
      {"unknown_row", head + "ade:\n  - {row: 1, mix: {acc: 20}}\nfigures:\n  - {name: f, row: 7}\n",
       "figures[0].row: no ade row 7"},
      {"unknown_key", head + "ade: []\ntrainig: {steps: 10}\n", "unknown key 'trainig'"},
      {"too_many", head + "data: {train_samples: 100}\nade:\n  - {row: 1, mix: {acc: 200}}\n",
       "ade[0].mix.acc: 200 samples, but data.train_samples is 100"},
      {"wrong_label",
       fmt::format("schema: vsd-experiment/1\nname: bad\nscenarios:\n  acc: {{scenario: {}}}\nade: []\n",
                   (scenarios / "lk.yaml").string()),
       "describes functional scenario 'lk', expected 'acc'"},
      {"no_quick", head + "ade:\n  - {row: 1, mix: {acc: 20}}\n", "quick: missing"},
      {"unknown_predictor", head + "ade:\n  - {row: 1, mix: {acc: 20}}\npredictors: [cv, kalman]\n",
       "predictors[1]: unknown predictor 'kalman' (known: cv, ca)"},
      {"unknown_decoder_option",
       head + "ade:\n  - {row: 1, mix: {acc: 20}}\nmodels:\n  - {name: m, decoder: offsets, options: {residul: 0}}\n",
       "models[0]"},
      {"main_model_rows",
       head + "ade:\n  - {row: 1, mix: {acc: 20}}\nmodels:\n  - {name: m, rows: [1]}\n",
       "models[0].rows: the first model is the main one and trains every row"},
      {"unknown_seed_row", head + "ade:\n  - {row: 1, mix: {acc: 20}}\nseeds: {count: 3, rows: [1, 4]}\n",
       "seeds.rows[1]: no ade row 4"},
      {"model_seeds_zero", head + "ade:\n  - {row: 1, mix: {acc: 20}}\nmodels:\n  - {name: m, seeds: 0}\n",
       "models[0].seeds"},
      {"preset_and_decoder",
       head + "ade:\n  - {row: 1, mix: {acc: 20}}\nmodels:\n  - {name: m, preset: paper, decoder: kinematic}\n",
       "models[0].decoder: given with a preset, which sets it"},
      {"unknown_preset", head + "ade:\n  - {row: 1, mix: {acc: 20}}\nmodels:\n  - {name: m, preset: best}\n",
       "unknown preset 'best' (known: recommended, paper)"},
      {"no_ade_no_study", head, "ade: expected a list of training mixes (or a leave_one_out section)"},
      {"held_out_in_context", two + "leave_one_out: {context: [acc], held_out: [lk, acc]}\n",
       "leave_one_out.held_out[1]: 'acc' is in leave_one_out.context"},
      {"held_out_unknown", two + "leave_one_out: {held_out: [acc_lk]}\n",
       "leave_one_out.held_out[0]: unknown functional scenario 'acc_lk' (defined under scenarios: acc, lk)"},
      {"alone_not_more", two + "leave_one_out: {few_shot: 200, alone: 200}\n",
       "leave_one_out.alone: 200 is not more than few_shot (200)"},
      {"others_beyond_pool", two + "data: {train_samples: 100}\nleave_one_out: {others: 500}\n",
       "leave_one_out.others"},
      {"all_context", two + "leave_one_out: {context: [acc, lk]}\n",
       "leave_one_out: no functional scenario left to hold out (all are context)"},
      {"study_unknown_metric", two + "leave_one_out: {metrics: [d_minimum]}\n",
       "leave_one_out.metrics[0]: unknown metric 'd_minimum'"},
  };
  for (const auto& c : cases) {
    const auto file = test::writeFile(dir.path() / (c.name + ".yaml"), c.yaml);
    const auto out = dir.path() / ("out_" + c.name);
    std::vector<std::string> args = {file.string(), "--out", out.string()};
    if (c.name == "no_quick") args.push_back("--quick");
    const auto result = runExperimentCli(args, dir.path());
    EXPECT_EQ(result.exitCode, 1) << c.name << ": " << result.output;
    EXPECT_EQ(std::count(result.output.begin(), result.output.end(), '\n'), 1) << c.name << ": " << result.output;
    EXPECT_NE(result.output.find(c.expected), std::string::npos) << c.name << ": " << result.output;
    EXPECT_NE(result.output.find(file.string()), std::string::npos) << c.name << ": " << result.output;
    EXPECT_FALSE(fs::exists(out)) << c.name << ": output left behind";
  }
}

// Issue 25 item 1 at toy sizes: each held-out scenario gets its four trainings, is evaluated on
// its own test set only, the baselines learn from its own inputs only, and the finding states
// what the numbers say.
TEST(Experiment, LeaveOneOutHoldsEachScenarioOutAndComparesFewOwnSamplesWithManyAlone) {
  TemporaryDirectory dir;
  const auto scenarios = test::sourceDir() / "scenarios";
  const auto spec = test::writeFile(dir.path() / "loso.yaml", fmt::format(R"(schema: vsd-experiment/1
name: loso
scenarios:
  acc: {{scenario: {0}/acc.yaml}}
  lk: {{scenario: {0}/lk.yaml}}
  acc_lk: {{scenario: {0}/acc_lk.yaml}}
data: {{train_samples: 60, test_samples: 20, test_seed: 1001}}
training: {{steps: 8, threads: 1, parallel: 2}}
models:
  - {{name: kin, preset: recommended}}
leave_one_out: {{context: [acc], others: 20, few_shot: 10, alone: 40, metrics: [a_min, d_min, p_lat_max]}}
mae: {{draws: 4, extra_trees: {{trees: 5}}, bnn: {{epochs: 5}}}}
)",
                                                                       scenarios.string()));
  const auto out = dir.path() / "out";
  const auto result = runExperimentCli({spec.string(), "--out", out.string()}, dir.path());
  ASSERT_EQ(result.exitCode, 0) << result.output;
  // Without an `ade` section there is no paper table to write.
  EXPECT_FALSE(fs::exists(out / "ade.csv"));
  EXPECT_FALSE(fs::exists(out / "mae.csv"));

  const auto table = CsvTable::read(out / "held_out.csv");
  std::map<std::string, std::string> mix;   // "held_out training" -> mix of the ADE row
  std::map<std::string, double> ade;        // "held_out training" -> ADE
  std::set<std::string> baseline_trainings;
  std::set<std::string> metrics_of_lk;
  for (std::size_t r = 0; r < table.rows(); ++r) {
    const auto held_out = table.cell(r, table.column("held_out"));
    const auto training = table.cell(r, table.column("training"));
    const auto model = table.cell(r, table.column("model"));
    const auto quantity = table.cell(r, table.column("quantity"));
    if (quantity == "ade") {
      mix[held_out + " " + training] = table.cell(r, table.column("mix"));
      ade[held_out + " " + training] = table.number(r, table.column("value"));
    } else if (model == "et" || model == "bnn") {
      baseline_trainings.insert(training);
    } else if (held_out == "lk") {
      metrics_of_lk.insert(quantity);
    }
  }
  // acc is context: never held out. Each held-out scenario: four trainings with the spec's counts.
  EXPECT_EQ(mix.count("acc others"), 0U);
  EXPECT_EQ(mix["lk others"], "acc 20 + acc_lk 20");
  EXPECT_EQ(mix["lk others_and_few_own"], "acc 20 + acc_lk 20 + lk 10");
  EXPECT_EQ(mix["lk few_own"], "lk 10");
  EXPECT_EQ(mix["lk all_own"], "lk 40");
  EXPECT_EQ(mix["acc_lk others"], "acc 20 + lk 20");
  EXPECT_EQ(mix["acc_lk all_own"], "acc_lk 40");
  // The baselines have only the scenario's own samples to learn from.
  EXPECT_EQ(baseline_trainings, (std::set<std::string>{"few_own", "all_own"}));
  // Metrics where the held-out data store them: lk has no leader, so no d_min.
  EXPECT_EQ(metrics_of_lk, (std::set<std::string>{"a_min", "p_lat_max"}));

  // A held-out row is evaluated on its own test set only.
  const auto errors = readTextFile(out / "cache" / "eval" / "kin" / "row1001_seed1" / "errors.json");
  EXPECT_NE(errors.find("\"lk\""), std::string::npos) << errors;
  EXPECT_EQ(errors.find("\"acc_lk\""), std::string::npos) << errors;

  // One finding per held-out scenario, its verdict the comparison of its two ADEs.
  const auto findings = readTextFile(out / "findings.md");
  for (const std::string label : {"lk", "acc_lk"}) {
    const bool holds = ade[label + " others_and_few_own"] <= ade[label + " all_own"];
    const std::string expected = fmt::format("predict {} no worse than 40 own samples alone (the paper's rows 9 and 10)** — **{}**",
                                             label, holds ? "holds" : "does not hold");
    EXPECT_NE(findings.find(expected), std::string::npos) << findings;
  }
  const auto held_out_md = readTextFile(out / "held_out.md");
  EXPECT_NE(held_out_md.find("| held out | others (20 each) | others + 10 own | 10 own | 40 own |"), std::string::npos)
      << held_out_md;
  EXPECT_NE(readTextFile(out / "manifest.json").find("\"leave_one_out\""), std::string::npos);
}

TEST(Experiment, CacheKeysAreExactAndClearingRemovesTheKeyFirst) {
  TemporaryDirectory dir;
  const ArtefactCache cache(dir.path());
  const auto folder = cache.folder("models/row1");
  CacheKey key("model");
  key.add("mix", "acc=2000").add("seed", 1);
  EXPECT_FALSE(cache.valid(folder, key));
  cache.clear(folder);
  test::writeFile(folder / "model.pt", "weights");
  EXPECT_FALSE(cache.valid(folder, key)) << "no key yet: an unfinished artefact";
  cache.commit(folder, key);
  EXPECT_TRUE(cache.valid(folder, key));
  CacheKey other("model");
  other.add("mix", "acc=2000").add("seed", 2);
  EXPECT_FALSE(cache.valid(folder, other));
  EXPECT_NE(key.digest(), other.digest());
  cache.clear(folder);
  EXPECT_FALSE(fs::exists(ArtefactCache::keyFile(folder)));
  EXPECT_TRUE(fs::is_directory(folder) && fs::is_empty(folder));
}

TEST(Experiment, FindingsFollowTheirThresholds) {
  // The paper's own Table II: (a)-(d) all hold.
  std::vector<AdeRow> paper = {
      row(1, {{"acc", 2000}}, {{"acc", 0.37}, {"lk", 12.47}, {"acc_lk", 8.96}}),
      row(2, {{"lk", 2000}}, {{"acc", 2.40}, {"lk", 0.40}, {"acc_lk", 6.48}}),
      row(3, {{"acc_lk", 2000}}, {{"acc", 0.43}, {"lk", 14.86}, {"acc_lk", 0.52}}),
      row(4, {{"acc", 2000}, {"lk", 2000}}, {{"acc", 0.39}, {"lk", 0.41}, {"acc_lk", 4.69}}),
      row(9, {{"acc", 2000}, {"lk", 2000}, {"acc_lk", 200}}, {{"acc", 0.41}, {"lk", 0.42}, {"acc_lk", 0.83}}),
      row(10, {{"acc_lk", 200}}, {{"acc", 0.88}, {"lk", 9.95}, {"acc_lk", 1.13}}),
      row(5, {{"lk", 2000}, {"acc_lk", 2000}}, {{"acc", 1.58}, {"lk", 0.97}, {"acc_lk", 1.73}}),
      row(6, {{"lk", 3000}, {"acc_lk", 3000}}, {{"acc", 0.45}, {"lk", 0.46}, {"acc_lk", 0.54}}),
  };
  auto findings = checkFindings(paper);
  ASSERT_EQ(findings.size(), 5u);
  for (const auto& finding : findings) EXPECT_EQ(finding.verdict, "holds") << finding.id << ": " << finding.evidence;

  // An in-distribution ADE above 0.6 m: (a) does not hold.
  paper[2].ade["acc_lk"] = 0.65;
  findings = checkFindings(paper);
  EXPECT_EQ(findings[0].verdict, "does not hold");
  // ACC&LK -> ACC at 1.5 m is neither generalising (<= 1 m) nor failing (>= 2 m).
  paper[2].ade["acc"] = 1.5;
  EXPECT_EQ(checkFindings(paper)[1].verdict, "inconclusive");
  // ACC + LK -> ACC&LK at 0.6 m generalises: (c) does not hold.
  paper[3].ade["acc_lk"] = 0.6;
  EXPECT_EQ(checkFindings(paper)[2].verdict, "does not hold");
  // Row 9 worse than row 10: (d) does not hold. A row with another mix is not checked.
  paper[4].ade["acc_lk"] = 1.2;
  EXPECT_EQ(checkFindings(paper)[3].verdict, "does not hold");
  paper[5].mix = {{"acc", 200}};
  EXPECT_EQ(checkFindings(paper)[3].verdict, "not checked");
  // With several seeds the evidence shows mean ± spread and the margin in spreads.
  paper[4].ade["acc_lk"] = 0.57;
  paper[4].adeStd["acc_lk"] = 0.05;
  paper[5].mix = {{"acc_lk", 200}};
  paper[5].adeStd["acc_lk"] = 0.1;
  findings = checkFindings(paper);
  EXPECT_EQ(findings[3].verdict, "holds");
  EXPECT_NE(findings[3].evidence.find("0.57 ± 0.05"), std::string::npos) << findings[3].evidence;
  EXPECT_NE(findings[3].evidence.find("margin 0.56 m = 5.6x the larger seed spread"), std::string::npos)
      << findings[3].evidence;
  // (e): 2000 samples each already good on lk and acc_lk: the claim does not hold.
  paper[6].ade["lk"] = 0.5;
  paper[6].ade["acc_lk"] = 0.55;
  EXPECT_EQ(checkFindings(paper)[4].verdict, "does not hold");
  // Neither 2000 nor 3000 each good: inconclusive.
  paper[6].ade["lk"] = 0.9;
  paper[7].ade["lk"] = 0.8;
  EXPECT_EQ(checkFindings(paper)[4].verdict, "inconclusive");
}
