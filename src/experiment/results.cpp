#include "results.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <ctime>
#include <limits>
#include <set>
#include <sstream>

#include "vsd/core/csv.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/log.hpp"
#include "vsd/sim/sumo_session.hpp"

namespace fs = std::filesystem;

namespace vsd::experiment {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

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

double adeOf(const AdeRow& row, const std::string& label) {
  const auto found = row.ade.find(label);
  return found == row.ade.end() ? kNaN : found->second;
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

std::string metres(double value) { return std::isfinite(value) ? fmt::format("{:.2f}", value) : "–"; }

std::string mixText(const AdeRow& row) {
  std::vector<std::string> parts;
  for (const auto& [label, count] : row.mix) {
    if (count > 0) parts.push_back(fmt::format("{} {}", label, count));
  }
  return fmt::format("{}", fmt::join(parts, " + "));
}

std::string paperValue(const std::map<std::string, double>& paper, const std::string& key) {
  const auto found = paper.find(key);
  return found == paper.end() ? std::string() : formatNumber(found->second);
}

std::string withPaper(double ours, const std::map<std::string, double>& paper, const std::string& key,
                      int decimals = 2) {
  const std::string value = std::isfinite(ours) ? fmt::format("{:.{}f}", ours, decimals) : "–";
  const auto found = paper.find(key);
  return found == paper.end() ? value : fmt::format("{} ({:.2f})", value, found->second);
}

std::vector<std::string> labelsOf(const Spec& spec) {
  std::vector<std::string> labels;
  for (const auto& source : spec.sources) labels.push_back(source.label);
  return labels;
}


std::string sizesLine(const Spec& spec) {
  return fmt::format(
      "Data per functional scenario: {} training scenarios (seed {}), {} test scenarios (seed {}). "
      "VectorNet: {} optimizer steps, batch {}, peak learning rate {}, seed {}, {} threads.{}",
      spec.trainSamples, spec.trainSeed, spec.testSamples, spec.testSeed, spec.steps, spec.batch, spec.learningRate,
      spec.seed, spec.threads, spec.quick ? " **--quick sizes: not comparable with the paper.**" : "");
}

}  // namespace

std::vector<Finding> checkFindings(const std::vector<AdeRow>& rows) {
  std::vector<Finding> findings;
  const std::string generalise_rule = fmt::format(
      "ADE on a functional scenario not trained on 'generalises' if <= {} m and <= {}x the in-distribution ADE, "
      "'does not generalise' if >= {} m and >= {}x it",
      kGeneralisesAde, kGeneralisesFactor, kFailsAde, kFailsFactor);

  {
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
      finding.evidence = fmt::format("row 1 on acc {} m, row 2 on lk {} m, row 3 on acc_lk {} m", metres(values[0]),
                                     metres(values[1]), metres(values[2]));
    }
    findings.push_back(finding);
  }
  {
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
      finding.evidence = fmt::format("acc_lk {} m; acc {} m ({}); lk {} m ({})", metres(in), metres(adeOf(*row, "acc")),
                                     transferText(to_acc), metres(adeOf(*row, "lk")), transferText(to_lk));
    } else {
      finding.verdict = "not checked";
      finding.evidence = "row 3 missing or with another mix";
    }
    findings.push_back(finding);
  }
  {
    Finding finding{"c", "Trained on ACC and LK (without ACC&LK samples), VectorNet does not generalise to ACC&LK.",
                    "row 4 (acc + lk): " + generalise_rule + " (in-distribution: the larger of its ADEs on acc and lk)",
                    "", ""};
    if (const AdeRow* row = paperRow(rows, 4, {"acc", "lk"})) {
      const double in = std::max(adeOf(*row, "acc"), adeOf(*row, "lk"));
      const auto to_acc_lk = classify(adeOf(*row, "acc_lk"), in);
      finding.verdict = to_acc_lk == Transfer::Fails         ? "holds"
                        : to_acc_lk == Transfer::Generalises ? "does not hold"
                                                             : "inconclusive";
      finding.evidence = fmt::format("acc {} m, lk {} m; acc_lk {} m ({})", metres(adeOf(*row, "acc")),
                                     metres(adeOf(*row, "lk")), metres(adeOf(*row, "acc_lk")), transferText(to_acc_lk));
    } else {
      finding.verdict = "not checked";
      finding.evidence = "row 4 missing or with another mix";
    }
    findings.push_back(finding);
  }
  {
    Finding finding{"d", "Adding 200 ACC&LK samples to ACC + LK predicts ACC&LK better than the 200 ACC&LK samples alone.",
                    "ADE on acc_lk of row 9 (acc + lk + acc_lk 200) < that of row 10 (acc_lk 200)", "", ""};
    const AdeRow* with = paperRow(rows, 9, {"acc", "lk", "acc_lk"});
    const AdeRow* alone = paperRow(rows, 10, {"acc_lk"});
    if (with && alone) {
      const double a = adeOf(*with, "acc_lk");
      const double b = adeOf(*alone, "acc_lk");
      finding.verdict = a < b ? "holds" : "does not hold";
      finding.evidence = fmt::format("row 9 {} m vs row 10 {} m", metres(a), metres(b));
    } else {
      finding.verdict = "not checked";
      finding.evidence = "rows 9 or 10 missing or with another mix";
    }
    findings.push_back(finding);
  }
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

  {  // ade.csv (long format) and ade.md (the paper's layout)
    std::ostringstream csv;
    CsvWriter writer(csv);
    writer.writeRow({"row", "mix", "test_label", "ade_m", "fde_m", "paper_ade_m", "train_seconds", "epochs"});
    std::string md = "# ADE of the Ego's predicted trajectory (m): ours (paper's Table II)\n\n" + sizesLine(spec) +
                     "\n\n| row | training mix |";
    for (const auto& label : labels) md += " " + label + " |";
    md += " training |\n|---|---|";
    for (std::size_t i = 0; i < labels.size(); ++i) md += "---|";
    md += "---|\n";
    for (const auto& row : summary.ade) {
      md += fmt::format("| {} | {} |", row.row, mixText(row));
      for (const auto& label : labels) {
        const double ade = row.ade.count(label) ? row.ade.at(label) : kNaN;
        const double fde = row.fde.count(label) ? row.fde.at(label) : kNaN;
        md += " " + withPaper(ade, row.paper, label) + " |";
        writer.writeRow({std::to_string(row.row), mixText(row), label, formatNumber(ade), formatNumber(fde),
                         paperValue(row.paper, label), formatNumber(row.trainSeconds), std::to_string(row.epochs)});
      }
      md += fmt::format(" {:.0f} s, {} epochs |\n", row.trainSeconds, row.epochs);
    }
    keep(out / "ade.csv", csv.str());
    keep(out / "ade.md", md);
  }

  {  // mae.csv and mae.md
    std::ostringstream csv;
    CsvWriter writer(csv);
    writer.writeRow({"functional_scenario", "metric", "unit", "et", "bnn", "vectornet", "vectornet_from_true_positions",
                     "bnn_mean_std", "paper_et", "paper_bnn", "paper_vectornet", "train_rows", "vectornet_test_samples",
                     "et_seconds", "bnn_seconds"});
    std::string md =
        "# MAE of evaluation metrics: ours (paper's Table III)\n\n" + sizesLine(spec) +
        fmt::format("\n\nExtra trees and the BNN are trained on the first {} training scenarios' concrete inputs; "
                    "VectorNet's metrics come from its predicted Ego trajectory (README: metrics from predictions), "
                    "with the model of the ADE row named in the spec. 'true positions' is the same computation on the "
                    "simulated future positions: the error of reconstructing the metric from positions alone, a floor "
                    "for VectorNet's.\n\n",
                    spec.maeSamples) +
        "| scenario | metric | extra trees | BNN | BNN mean std | VectorNet | true positions | ET / BNN time |\n"
        "|---|---|---|---|---|---|---|---|\n";
    for (const auto& row : summary.mae) {
      writer.writeRow({row.label, row.metric, row.unit, formatNumber(row.et), formatNumber(row.bnn),
                       formatNumber(row.vectornet), formatNumber(row.fromTruePositions), formatNumber(row.bnnStd),
                       paperValue(row.paper, "et"), paperValue(row.paper, "bnn"), paperValue(row.paper, "vectornet"),
                       std::to_string(row.trainRows), std::to_string(row.testSamples), formatNumber(row.etSeconds),
                       formatNumber(row.bnnSeconds)});
      md += fmt::format("| {} | {} [{}] | {} | {} | {:.3f} | {} | {:.3f} | {:.1f} s / {:.1f} s |\n", row.label, row.metric,
                        row.unit, withPaper(row.et, row.paper, "et", 3), withPaper(row.bnn, row.paper, "bnn", 3),
                        row.bnnStd, withPaper(row.vectornet, row.paper, "vectornet", 3), row.fromTruePositions,
                        row.etSeconds, row.bnnSeconds);
    }
    keep(out / "mae.csv", csv.str());
    keep(out / "mae.md", md);
  }

  {  // findings.md
    std::string md = "# The paper's findings, checked on these numbers\n\n" + sizesLine(spec) + "\n\n";
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
  manifest["tool_version"] = toolVersion();
  manifest["sumo_version"] = sim::SumoSession::version();
  manifest["command_line"] = options.commandLine;
  manifest["finished_utc"] = utcTimestamp();
  manifest["seconds"] = summary.seconds;
  manifest["seeds"] = {{"experiment", spec.seed}, {"train_data", spec.trainSeed}, {"test_data", spec.testSeed}};
  manifest["sizes"] = {{"train_samples", spec.trainSamples}, {"test_samples", spec.testSamples},
                       {"steps", spec.steps},                {"batch", spec.batch},
                       {"mae_train_rows", spec.maeSamples},  {"threads", spec.threads}};
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
    text += fmt::format("  row {:>2}  {:<34}", row.row, mixText(row));
    for (const auto& [label, value] : row.ade) text += fmt::format("  {} {}", label, withPaper(value, row.paper, label));
    text += "\n";
  }
  if (!mae.empty()) {
    text += "\nMAE of metrics, ours (paper):\n";
    for (const auto& row : mae) {
      text += fmt::format("  {:<7} {:<10} ET {:<14} BNN {:<14} VectorNet {:<14} (true positions {:.3f})\n", row.label,
                          row.metric, withPaper(row.et, row.paper, "et", 3), withPaper(row.bnn, row.paper, "bnn", 3),
                          withPaper(row.vectornet, row.paper, "vectornet", 3), row.fromTruePositions);
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
