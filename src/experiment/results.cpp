#include "results.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <limits>
#include <set>
#include <sstream>

#include "vsd/core/csv.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/log.hpp"
#include "vsd/core/seeds.hpp"
#include "vsd/core/statistics.hpp"
#include "vsd/pipeline/provenance.hpp"

namespace fs = std::filesystem;

namespace vsd::experiment {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}  // namespace

double adeOf(const AdeRow& row, const std::string& label) {
  const auto found = row.ade.find(label);
  return found == row.ade.end() ? kNaN : found->second;
}

std::string metres(double value) { return std::isfinite(value) ? fmt::format("{:.2f}", value) : "–"; }

/// "0.57" or, over several seeds, "0.57 ± 0.03" (mean ± sample standard deviation).
std::string adeText(const AdeRow& row, const std::string& label) {
  const auto spread = row.adeStd.find(label);
  if (spread == row.adeStd.end()) return metres(adeOf(row, label));
  return fmt::format("{} ± {}", metres(adeOf(row, label)), metres(spread->second));
}

std::string mixText(const AdeRow& row) {
  std::vector<std::string> parts;
  for (const auto& [label, count] : row.mix) {
    if (count > 0) parts.push_back(fmt::format("{} {}", label, count));
  }
  return fmt::format("{}", fmt::join(parts, " + "));
}

std::string percent(double share) { return std::isfinite(share) ? fmt::format("{:.0f} %", 100.0 * share) : "–"; }

namespace {
/// "51 % (48–54)": a coverage with a 95 % interval (one seed's Wilson interval, or over seeds
/// the span of theirs); the share alone where there is no interval.
std::string coverageSpanText(double share, const std::array<double, 2>& interval) {
  if (!std::isfinite(share) || !std::isfinite(interval[0])) return percent(share);
  return fmt::format("{} ({:.0f}–{:.0f})", percent(share), 100.0 * interval[0], 100.0 * interval[1]);
}
}  // namespace

/// "51 % (48–54)": a coverage with its binomial 95 % confidence interval (Wilson) over the
/// scenes that had an interval.
std::string coverageText(double share, std::size_t scenes) {
  if (!std::isfinite(share) || scenes == 0) return percent(share);
  const auto interval = wilsonInterval(share, scenes);
  return coverageSpanText(share, {interval.low, interval.high});
}

std::string modelDescription(const ModelSpec& model) {
  std::vector<std::string> options;
  for (const auto& [name, value] : model.options) options.push_back(fmt::format("{}={}", name, formatNumber(value)));
  std::string text = options.empty() ? model.decoder : fmt::format("{} ({})", model.decoder, fmt::join(options, ", "));
  return model.frame == "ego" ? text : text + fmt::format(", {} frame", model.frame);
}

namespace {

/// Row `number` if its mix holds exactly `labels` (count > 0), else null.
const AdeRow* paperRow(const std::vector<AdeRow>& rows, int number, const std::set<std::string>& labels) {
  for (const auto& row : rows) {
    if (row.row != number) continue;
    std::set<std::string> present;
    for (const auto& [label, count] : row.mix) {
      if (count > 0) present.insert(label);
    }
    return present == labels ? &row : nullptr;
  }
  return nullptr;
}


enum class Transfer { Generalises, Fails, Between };

Transfer classify(double cross, double in_distribution) {
  if (cross <= kGeneralisesAde && cross <= kGeneralisesFactor * in_distribution) return Transfer::Generalises;
  if (cross >= kFailsAde && cross >= kFailsFactor * in_distribution) return Transfer::Fails;
  return Transfer::Between;
}

const char* transferText(Transfer transfer) {
  switch (transfer) {
    case Transfer::Generalises: return "generalises";
    case Transfer::Fails: return "does not generalise";
    case Transfer::Between: return "in between";
  }
  return "";
}



double stdOf(const AdeRow& row, const std::string& label) {
  const auto spread = row.adeStd.find(label);
  return spread == row.adeStd.end() ? 0.0 : spread->second;
}


std::string paperValue(const std::map<std::string, double>& paper, const std::string& key) {
  const auto found = paper.find(key);
  return found == paper.end() ? std::string() : formatNumber(found->second);
}

std::vector<std::string> labelsOf(const Spec& spec) {
  std::vector<std::string> labels;
  for (const auto& source : spec.sources) labels.push_back(source.label);
  return labels;
}


std::string seedsText(const Spec& spec) {
  std::vector<std::string> parts;
  if (spec.seedCount >= 2 && !spec.seedRows.empty() && spec.models.front().seeds == 0) {
    parts.push_back(fmt::format("rows {} of the main model: seeds {} to {}", fmt::join(spec.seedRows, ", "), spec.seed,
                                spec.seed + static_cast<std::uint64_t>(spec.seedCount) - 1));
  }
  for (const auto& model : spec.models) {
    if (model.seeds >= 2) {
      parts.push_back(fmt::format("every row of {}: seeds {} to {}", model.name, spec.seed,
                                  spec.seed + static_cast<std::uint64_t>(model.seeds) - 1));
    }
  }
  if (parts.empty()) return "";
  return fmt::format(" ({}; mean ± standard deviation)", fmt::join(parts, "; "));
}

/// Whether the test data are sealed (core/seeds.hpp): figures on the validation seed or any
/// seed below the sealed range may have been seen by a configuration choice.
std::string sealedText(const Spec& spec) {
  if (isSealedTestSeed(spec.testSeed)) return "sealed: no configuration was chosen on them";
  return fmt::format("**not sealed**: test seeds start at {}, and configurations were chosen on seed {}",
                     kFirstSealedTestSeed, kValidationDataSeed);
}

}  // namespace

std::string sizesLine(const Spec& spec) {
  return fmt::format(
      "Data per functional scenario: {} training scenarios (seed {}), {} test scenarios (seed {}; {}). "
      "VectorNet: {} optimizer steps, batch {}, peak learning rate {}, seed {}{}, {} thread(s) per training, {} "
      "training(s) at a time.{}",
      spec.trainSamples, spec.trainSeed, spec.testSamples, spec.testSeed, sealedText(spec), spec.steps, spec.batch,
      spec.learningRate, spec.seed, seedsText(spec), spec.threads, spec.parallel,
      spec.quick ? " **--quick sizes: not comparable with the paper.**" : "");
}

namespace {



/// "| first | <labels> | last |" and its separator row; `first` and `last` may hold several
/// columns ("a | b"), `last` none ("").
std::string adeTableHead(const std::vector<std::string>& labels, const std::string& first_columns,
                         const std::string& last_columns) {
  std::string md = "| " + first_columns + " |";
  for (const auto& label : labels) md += " " + label + " |";
  if (!last_columns.empty()) md += " " + last_columns + " |";
  md += "\n|";
  auto count = [](const std::string& columns) {
    return columns.empty() ? 0 : 1 + static_cast<std::size_t>(std::count(columns.begin(), columns.end(), '|'));
  };
  const auto columns = count(first_columns) + labels.size() + count(last_columns);
  for (std::size_t i = 0; i < columns; ++i) md += "---|";
  return md + "\n";
}


/// The spec's models that predict in the MAE table, in spec order (main model first).
std::vector<std::string> maeModelNames(const Spec& spec, const std::vector<MaeRow>& rows) {
  std::vector<std::string> names;
  for (const auto& model : spec.models) {
    const bool present = std::any_of(rows.begin(), rows.end(), [&](const MaeRow& row) {
      return std::any_of(row.vectornet.begin(), row.vectornet.end(),
                         [&](const VectorNetMetricError& error) { return error.model == model.name; });
    });
    if (present) names.push_back(model.name);
  }
  return names;
}

const VectorNetMetricError* errorOf(const MaeRow& row, const std::string& model) {
  for (const auto& error : row.vectornet) {
    if (error.model == model) return &error;
  }
  return nullptr;
}



std::string optionalNumber(double value) { return std::isfinite(value) ? formatNumber(value) : std::string(); }

/// An MAE over seeds for mae.md: "0.232" for one seed, "0.232 ± 0.010" over several, then the
/// paper's value in brackets where `paper_key` names one.
std::string maeText(double mae, double spread, const MaeRow& row, const std::string& paper_key) {
  std::string text = std::isfinite(mae) ? fmt::format("{:.3f}", mae) : "–";
  if (std::isfinite(spread)) text += fmt::format(" ± {:.3f}", spread);
  const auto found = paper_key.empty() ? row.paper.end() : row.paper.find(paper_key);
  return found == row.paper.end() ? text : fmt::format("{} ({:.2f})", text, found->second);
}

/// A model's cell of mae.md: "0.440 ± 0.020 (0.58) bias +0.200; covered 48 % (47–49) / 87 % (86–88)";
/// the main model's also carries the paper's value.
std::string maeCell(const MaeRow& row, const std::string& model, bool main) {
  const auto* error = errorOf(row, model);
  if (error == nullptr) return "";
  std::string cell = maeText(error->mae, error->maeStd, row, main ? "vectornet" : "");
  cell += fmt::format(" bias {:+.3f}", error->bias);
  if (std::isfinite(error->coverage90)) {
    cell += fmt::format("; covered {} / {}", coverageSpanText(error->coverage50, error->coverage50Interval),
                        coverageSpanText(error->coverage90, error->coverage90Interval));
  }
  return cell;
}

/// mae.csv (a row per functional scenario and metric; `vectornet` is the main model's MAE,
/// then per model of the spec its MAE, bias and interval coverage) and mae.md.
std::pair<std::string, std::string> maeFiles(const Spec& spec, const std::vector<MaeRow>& rows) {
  const auto models = maeModelNames(spec, rows);
  std::vector<std::string> head = {"functional_scenario", "metric", "unit", "et", "bnn", "vectornet",
                                   "vectornet_from_true_positions", "bnn_mean_std", "paper_et", "paper_bnn",
                                   "paper_vectornet", "train_rows", "vectornet_test_samples", "et_seconds", "bnn_seconds",
                                   "baseline_seeds", "et_seed_std", "bnn_seed_std"};
  for (const auto& model : models) {
    for (const char* column : {"", "_seed_std", "_seeds", "_bias", "_coverage_50", "_coverage_50_ci95_low",
                               "_coverage_50_ci95_high", "_coverage_90", "_coverage_90_ci95_low",
                               "_coverage_90_ci95_high"}) {
      head.push_back("vectornet_" + model + column);
    }
  }
  std::ostringstream csv;
  CsvWriter writer(csv);
  writer.writeRow(head);
  std::string md =
      "# MAE of evaluation metrics: ours (paper's Table III)\n\n" + sizesLine(spec) +
      fmt::format("\n\nExtra trees and the BNN are trained on the first {} training scenarios' concrete inputs; "
                  "VectorNet's metrics come from its predicted Ego trajectory (docs/models.md: metrics from predicted trajectories; a "
                  "kinematic model's own speeds and accelerations), with every seed's model of the ADE row "
                  "named in the spec, for every model of the spec that trains that row: the MAE (mean ± sample "
                  "standard deviation over the seeds where there are several — the ADE table's seeds column says how "
                  "many; the paper's value in brackets for the main model), the bias (mean of predicted − simulated) "
                  "and, for probabilistic models, the share of simulated values inside the metric's 50 % / 90 % "
                  "interval over {} sampled futures (mean over the seeds), with its binomial 95 % confidence interval "
                  "(Wilson, over the scenes that had an interval; over several seeds from the lowest seed's lower bound "
                  "to the highest seed's upper bound). Extra trees and the BNN are fitted with {} seed(s) (mean ± "
                  "std). 'true positions' is the same computation on the simulated future positions: the error "
                  "of reconstructing the metric from positions alone, a floor for VectorNet's.\n\n",
                  spec.maeSamples, spec.maeDraws, rows.empty() ? std::size_t{1} : rows.front().baselineSeeds) +
      "| scenario | metric | extra trees | BNN | BNN mean std |";
  for (const auto& model : models) md += fmt::format(" VectorNet `{}` |", model);
  md += " true positions | ET / BNN time |\n|";
  for (std::size_t c = 0; c < 7 + models.size(); ++c) md += "---|";
  md += "\n";
  for (const auto& row : rows) {
    const auto* main_error = models.empty() ? nullptr : errorOf(row, models.front());
    std::vector<std::string> cells = {
        row.label, row.metric, row.unit, formatNumber(row.et), formatNumber(row.bnn),
        main_error ? formatNumber(main_error->mae) : "", formatNumber(row.fromTruePositions), formatNumber(row.bnnStd),
        paperValue(row.paper, "et"), paperValue(row.paper, "bnn"), paperValue(row.paper, "vectornet"),
        std::to_string(row.trainRows), main_error ? std::to_string(main_error->samples) : "",
        formatNumber(row.etSeconds), formatNumber(row.bnnSeconds), std::to_string(row.baselineSeeds),
        optionalNumber(row.etSpread), optionalNumber(row.bnnSpread)};
    for (const auto& model : models) {
      const auto* error = errorOf(row, model);
      cells.push_back(error ? formatNumber(error->mae) : "");
      cells.push_back(error ? optionalNumber(error->maeStd) : "");
      cells.push_back(error ? std::to_string(error->seeds) : "");
      cells.push_back(error ? formatNumber(error->bias) : "");
      for (const auto& [coverage, interval] :
           {std::pair{error ? error->coverage50 : kNaN, error ? error->coverage50Interval : std::array{kNaN, kNaN}},
            std::pair{error ? error->coverage90 : kNaN, error ? error->coverage90Interval : std::array{kNaN, kNaN}}}) {
        cells.insert(cells.end(), {optionalNumber(coverage), optionalNumber(interval[0]), optionalNumber(interval[1])});
      }
    }
    writer.writeRow(cells);
    md += fmt::format("| {} | {} [{}] | {} | {} | {:.3f} |", row.label, row.metric, row.unit,
                      maeText(row.et, row.etSpread, row, "et"), maeText(row.bnn, row.bnnSpread, row, "bnn"), row.bnnStd);
    for (std::size_t m = 0; m < models.size(); ++m) md += " " + maeCell(row, models[m], m == 0) + " |";
    md += fmt::format(" {:.3f} | {:.1f} s / {:.1f} s |\n", row.fromTruePositions, row.etSeconds, row.bnnSeconds);
  }
  return {csv.str(), md};
}

/// ade.md: per model of the spec one table in the paper's layout (ours, the paper's in
/// brackets; mean ± standard deviation over seeds where a row has several), then the
/// predictors without training.
std::string adeMarkdown(const Spec& spec, const std::vector<AdeRow>& rows) {
  const auto labels = labelsOf(spec);
  std::string md = "# ADE of the Ego's predicted trajectory (m): ours (paper's Table II)\n\n" + sizesLine(spec) + "\n";
  for (std::size_t m = 0; m < spec.models.size(); ++m) {
    const auto& model = spec.models[m];
    md += fmt::format("\n## {}: decoder {}{}\n\n", model.name, modelDescription(model),
                      m == 0 ? " — the main model (findings, MAE, figures)" : "");
    md += adeTableHead(labels, "row | training mix", "seeds | training");
    for (const auto& row : rows) {
      if (row.model != model.name) continue;
      md += fmt::format("| {} | {} |", row.row, mixText(row));
      for (const auto& label : labels) {
        const auto paper = row.paper.find(label);
        md += " " + adeText(row, label) +
              (paper == row.paper.end() ? std::string() : fmt::format(" ({:.2f})", paper->second)) + " |";
      }
      md += fmt::format(" {} | {:.0f} s, {} epochs |\n", row.seeds.size(), row.trainSeconds, row.epochs);
    }
  }
  if (!spec.predictors.empty()) {
    md += "\n## Predictors without training\n\ncv: constant velocity along the initial heading; ca: constant "
          "acceleration (the last observed one) along it.\n\n";
    md += adeTableHead(labels, "predictor", "");
    for (const auto& row : rows) {
      if (row.row != 0) continue;
      md += "| " + row.model + " |";
      for (const auto& label : labels) md += " " + adeText(row, label) + " |";
      md += "\n";
    }
  }
  return md;
}

/// The rule that classifies a transfer, as the findings state it.
std::string generaliseRule() {
  return fmt::format(
      "ADE on a functional scenario not trained on 'generalises' if <= {} m and <= {}x the in-distribution ADE, "
      "'does not generalise' if >= {} m and >= {}x it",
      kGeneralisesAde, kGeneralisesFactor, kFailsAde, kFailsFactor);
}

/// row 1-3: in-distribution ADE is good on each functional scenario.
Finding findingA(const std::vector<AdeRow>& rows) {
  Finding finding{"a", "Good in-distribution ADE: trained on one functional scenario, VectorNet predicts the Ego well "
                       "on fresh scenarios of the same one.",
                  fmt::format("rows 1 (acc), 2 (lk) and 3 (acc_lk): in-distribution ADE <= {} m each", kGoodAde), "",
                  ""};
  const AdeRow* acc = paperRow(rows, 1, {"acc"});
  const AdeRow* lk = paperRow(rows, 2, {"lk"});
  const AdeRow* acc_lk = paperRow(rows, 3, {"acc_lk"});
  if (!acc || !lk || !acc_lk) {
    finding.verdict = "not checked";
    finding.evidence = "rows 1-3 missing or with another mix";
  } else {
    const double values[] = {adeOf(*acc, "acc"), adeOf(*lk, "lk"), adeOf(*acc_lk, "acc_lk")};
    bool good = true;
    for (const double value : values) good = good && value <= kGoodAde;
    finding.verdict = good ? "holds" : "does not hold";
    finding.evidence = fmt::format("row 1 on acc {} m, row 2 on lk {} m, row 3 on acc_lk {} m", adeText(*acc, "acc"),
                                   adeText(*lk, "lk"), adeText(*acc_lk, "acc_lk"));
  }
  return finding;
}

/// Row 3: trained on ACC&LK, generalises to ACC but not to LK.
Finding findingB(const std::vector<AdeRow>& rows, const std::string& generalise_rule) {
  Finding finding{"b", "Trained on ACC&LK, VectorNet generalises to ACC but not to LK.",
                  "row 3 (acc_lk): " + generalise_rule + " (in-distribution: its ADE on acc_lk)", "", ""};
  if (const AdeRow* row = paperRow(rows, 3, {"acc_lk"})) {
    const double in = adeOf(*row, "acc_lk");
    const auto to_acc = classify(adeOf(*row, "acc"), in);
    const auto to_lk = classify(adeOf(*row, "lk"), in);
    if (to_acc == Transfer::Generalises && to_lk == Transfer::Fails) {
      finding.verdict = "holds";
    } else if (to_acc == Transfer::Fails || to_lk == Transfer::Generalises) {
      finding.verdict = "does not hold";
    } else {
      finding.verdict = "inconclusive";
    }
    finding.evidence = fmt::format("acc_lk {} m; acc {} m ({}); lk {} m ({})", adeText(*row, "acc_lk"),
                                   adeText(*row, "acc"), transferText(to_acc), adeText(*row, "lk"), transferText(to_lk));
  } else {
    finding.verdict = "not checked";
    finding.evidence = "row 3 missing or with another mix";
  }
  return finding;
}

/// Row 4: trained on ACC and LK, does not generalise to ACC&LK.
Finding findingC(const std::vector<AdeRow>& rows, const std::string& generalise_rule) {
  Finding finding{"c", "Trained on ACC and LK (without ACC&LK samples), VectorNet does not generalise to ACC&LK.",
                  "row 4 (acc + lk): " + generalise_rule + " (in-distribution: the larger of its ADEs on acc and lk)",
                  "", ""};
  if (const AdeRow* row = paperRow(rows, 4, {"acc", "lk"})) {
    const double in = std::max(adeOf(*row, "acc"), adeOf(*row, "lk"));
    const auto to_acc_lk = classify(adeOf(*row, "acc_lk"), in);
    finding.verdict = to_acc_lk == Transfer::Fails         ? "holds"
                      : to_acc_lk == Transfer::Generalises ? "does not hold"
                                                           : "inconclusive";
    finding.evidence = fmt::format("acc {} m, lk {} m; acc_lk {} m ({})", adeText(*row, "acc"), adeText(*row, "lk"),
                                   adeText(*row, "acc_lk"), transferText(to_acc_lk));
  } else {
    finding.verdict = "not checked";
    finding.evidence = "row 4 missing or with another mix";
  }
  return finding;
}

/// Rows 9 and 10: adding ACC + LK helps ACC&LK.
Finding findingD(const std::vector<AdeRow>& rows) {
  Finding finding{"d", "Adding 200 ACC&LK samples to ACC + LK predicts ACC&LK better than the 200 ACC&LK samples alone.",
                  "ADE on acc_lk of row 9 (acc + lk + acc_lk 200) < that of row 10 (acc_lk 200)", "", ""};
  const AdeRow* with = paperRow(rows, 9, {"acc", "lk", "acc_lk"});
  const AdeRow* alone = paperRow(rows, 10, {"acc_lk"});
  if (with && alone) {
    const double a = adeOf(*with, "acc_lk");
    const double b = adeOf(*alone, "acc_lk");
    finding.verdict = a < b ? "holds" : "does not hold";
    const double spread = std::max(stdOf(*with, "acc_lk"), stdOf(*alone, "acc_lk"));
    finding.evidence = fmt::format("row 9 {} m vs row 10 {} m; margin {} m", adeText(*with, "acc_lk"),
                                   adeText(*alone, "acc_lk"), metres(b - a)) +
                       (spread > 0.0 ? fmt::format(" = {:.1f}x the larger seed spread", (b - a) / spread) : "");
  } else {
    finding.verdict = "not checked";
    finding.evidence = "rows 9 or 10 missing or with another mix";
  }
  return finding;
}

/// Rows 5 and 6: LK with ACC&LK needs 3000 samples of each.
Finding findingE(const std::vector<AdeRow>& rows) {
  Finding finding{"e", "Combining LK and ACC&LK needs 3000 samples of each: with 2000 each (row 5) they are not "
                       "predicted well, with 3000 each (row 6) they are.",
                  fmt::format("holds if row 6's ADEs on lk and acc_lk are <= {0} m and one of row 5's is above {0} m; "
                              "does not hold if row 5's are both <= {0} m (2000 each suffice)",
                              kGoodAde),
                  "", ""};
  const AdeRow* two = paperRow(rows, 5, {"lk", "acc_lk"});
  const AdeRow* three = paperRow(rows, 6, {"lk", "acc_lk"});
  if (two && three) {
    const bool two_good = adeOf(*two, "lk") <= kGoodAde && adeOf(*two, "acc_lk") <= kGoodAde;
    const bool three_good = adeOf(*three, "lk") <= kGoodAde && adeOf(*three, "acc_lk") <= kGoodAde;
    finding.verdict = two_good ? "does not hold" : three_good ? "holds" : "inconclusive";
    finding.evidence = fmt::format(
        "row 5 lk {} m, acc_lk {} m (acc {} m) vs row 6 lk {} m, acc_lk {} m (acc {} m); row 5's largest margin to "
        "{} m: {} m",
        adeText(*two, "lk"), adeText(*two, "acc_lk"), adeText(*two, "acc"), adeText(*three, "lk"),
        adeText(*three, "acc_lk"), adeText(*three, "acc"), kGoodAde,
        metres(std::max(adeOf(*two, "lk"), adeOf(*two, "acc_lk")) - kGoodAde));
  } else {
    finding.verdict = "not checked";
    finding.evidence = "rows 5 or 6 missing or with another mix";
  }
  return finding;
}

}  // namespace

std::vector<Finding> checkFindings(const std::vector<AdeRow>& rows) {
  const std::string generalise_rule = generaliseRule();
  return {findingA(rows), findingB(rows, generalise_rule), findingC(rows, generalise_rule), findingD(rows), findingE(rows)};
}

std::vector<Finding> checkFindings(const Spec& spec, const std::vector<AdeRow>& rows) {
  const bool paper_rows = std::any_of(spec.ade.begin(), spec.ade.end(), [](const AdeSpec& row) { return row.heldOut.empty(); });
  auto findings = paper_rows ? checkFindings(rows) : std::vector<Finding>{};
  for (auto& finding : heldOutFindings(spec, rows)) findings.push_back(std::move(finding));
  return findings;
}

void writeResults(const Spec& spec, const ExperimentOptions& options, ExperimentSummary& summary,
                  const std::vector<ArtefactRecord>& artefacts, OutputFolder& folder) {
  const auto& out = summary.output;
  const auto labels = labelsOf(spec);
  auto keep = [&](const fs::path& path, const std::string& contents) {
    folder.stageText(fs::relative(path, out), contents);
    summary.files.push_back(path);
  };

  const bool table_rows =
      std::any_of(spec.ade.begin(), spec.ade.end(), [](const AdeSpec& row) { return row.heldOut.empty(); });
  if (table_rows) {  // ade.csv (long format) and ade.md (the paper's layout, one table per model)
    std::vector<AdeRow> rows;  // the leave-one-out rows have their own files
    for (const auto& row : summary.ade) {
      if (row.heldOut.empty()) rows.push_back(row);
    }
    std::ostringstream csv;
    CsvWriter writer(csv);
    writer.writeRow({"model", "row", "mix", "test_label", "ade_m", "ade_std_m", "seeds", "fde_m", "paper_ade_m",
                     "train_seconds", "epochs"});
    for (const auto& row : rows) {
      for (const auto& label : labels) {
        const double ade = row.ade.count(label) ? row.ade.at(label) : kNaN;
        const double fde = row.fde.count(label) ? row.fde.at(label) : kNaN;
        writer.writeRow({row.model, std::to_string(row.row), mixText(row), label, formatNumber(ade),
                         row.adeStd.count(label) ? formatNumber(row.adeStd.at(label)) : "",
                         std::to_string(row.seeds.size()), formatNumber(fde), paperValue(row.paper, label),
                         formatNumber(row.trainSeconds), std::to_string(row.epochs)});
      }
    }
    keep(out / "ade.csv", csv.str());
    keep(out / "ade.md", adeMarkdown(spec, rows));
  }

  if (table_rows) {  // mae.csv and mae.md
    const auto [csv, md] = maeFiles(spec, summary.mae);
    keep(out / "mae.csv", csv);
    keep(out / "mae.md", md);
  }

  if (!spec.leaveOneOut.heldOut.empty()) {  // held_out.csv and held_out.md
    const auto [csv, md] = heldOutFiles(spec, summary);
    keep(out / "held_out.csv", csv);
    keep(out / "held_out.md", md);
  }

  {  // findings.md
    std::string md = fmt::format("# {}, checked on these numbers\n\n{}\n\n",
                                 table_rows ? "The paper's findings" : "Findings of the leave-one-out study", sizesLine(spec));
    for (const auto& finding : summary.findings) {
      md += fmt::format("- **({}) {}** — **{}**: {}.  \n  Rule: {}.\n", finding.id, finding.claim, finding.verdict,
                        finding.evidence, finding.rule);
    }
    keep(out / "findings.md", md);
  }

  // The manifest last (the output folder adds "outputs": every file's SHA-256 and size).
  nlohmann::json manifest;
  manifest["schema"] = "vsd-experiment-results/1";
  manifest["name"] = spec.name;
  manifest["spec"] = spec.file.string();
  manifest["spec_sha256"] = sha256OfFile(spec.file);
  manifest["quick"] = spec.quick;
  pipeline::provenance().addTo(manifest);
  manifest["command_line"] = options.commandLine;
  manifest["finished_utc"] = utcTimestamp();
  manifest["seconds"] = summary.seconds;
  manifest["seeds"] = {{"experiment", spec.seed},
                       {"train_data", spec.trainSeed},
                       {"test_data", spec.testSeed},
                       {"test_data_sealed", isSealedTestSeed(spec.testSeed)},
                       {"validation", "each training's validation split of its training data (early stopping, "
                                      "calibration)"},
                       {"count", spec.seedCount},
                       {"rows", spec.seedRows}};
  for (const auto& model : spec.models) {
    manifest["models"].push_back(
        {{"name", model.name}, {"decoder", model.decoder}, {"options", model.options}, {"rows", model.rows},
         {"seeds", model.seeds}});
  }
  manifest["predictors"] = spec.predictors;
  if (!spec.leaveOneOut.heldOut.empty()) {
    const auto& study = spec.leaveOneOut;
    manifest["leave_one_out"] = {{"held_out", study.heldOut}, {"context", study.context},
                                 {"others", study.others},    {"few_shot", study.fewShot},
                                 {"alone", study.alone},      {"metrics", study.metrics}};
  }
  manifest["sizes"] = {{"train_samples", spec.trainSamples}, {"test_samples", spec.testSamples},
                       {"steps", spec.steps},                {"batch", spec.batch},
                       {"mae_train_rows", spec.maeSamples},  {"threads", spec.threads},
                       {"parallel_trainings", spec.parallel}};
  for (const auto& artefact : artefacts) {
    manifest["artefacts"].push_back({{"path", artefact.path}, {"key_sha256", artefact.keyDigest}, {"reused", artefact.reused}});
  }
  folder.commit(manifest);
  summary.files.push_back(out / "manifest.json");
}

std::string ExperimentSummary::report() const {
  std::string text = fmt::format("experiment written to {}/ in {:.0f} s ({} artefacts built, {} reused from the cache)\n",
                                 output.string(), seconds, artefactsBuilt, artefactsReused);
  text += "\nADE (m), ours (paper):\n";
  for (const auto& row : ade) {
    text += fmt::format("  {:<12} row {:>2}  {:<34}", row.model, row.row, mixText(row));
    for (const auto& [label, value] : row.ade) {
      text += fmt::format("  {} {}", label, adeText(row, label));
      const auto paper = row.paper.find(label);
      if (paper != row.paper.end()) text += fmt::format(" ({:.2f})", paper->second);
    }
    text += "\n";
  }
  if (!mae.empty()) {
    text += "\nMAE of metrics, ours (paper):\n";
    for (const auto& row : mae) {
      text += fmt::format("  {:<7} {:<10} ET {:<22} BNN {:<22}", row.label, row.metric,
                          maeText(row.et, row.etSpread, row, "et"), maeText(row.bnn, row.bnnSpread, row, "bnn"));
      for (std::size_t m = 0; m < row.vectornet.size(); ++m) {
        const auto& error = row.vectornet[m];
        text += fmt::format(" VectorNet {} {}", error.model, maeText(error.mae, error.maeStd, row, m == 0 ? "vectornet" : ""));
      }
      text += fmt::format(" (true positions {:.3f})\n", row.fromTruePositions);
    }
  }
  text += "\nFindings:\n";
  for (const auto& finding : findings) {
    text += fmt::format("  ({}) {}: {} [{}]\n", finding.id, finding.verdict, finding.claim, finding.evidence);
  }
  text += "\nFiles:\n";
  for (const auto& file : files) text += "  " + file.string() + "\n";
  return text;
}

}  // namespace vsd::experiment
