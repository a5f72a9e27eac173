// The leave-one-out study's results (spec `leave_one_out`, docs/results.md "Leave one
// functional scenario out"): per held-out functional scenario the ADE and metric errors of
// the four trainings of the main model, the regression baselines on its own inputs, and
// whether its few own samples added to the others' data do as well as all its own alone.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "results.hpp"
#include "vsd/core/csv.hpp"

namespace vsd::experiment {

namespace {

/// The main model's row of `held_out` trained as `training`, or null.
const AdeRow* heldOutRow(const std::vector<AdeRow>& rows, const std::string& model, const std::string& held_out,
                         HeldOutTraining training) {
  for (const auto& row : rows) {
    if (row.model == model && row.heldOut == held_out && row.training == heldOutTrainingId(training)) return &row;
  }
  return nullptr;
}

double heldOutAde(const std::vector<AdeRow>& rows, const std::string& model, const std::string& held_out,
                  HeldOutTraining training) {
  const auto* row = heldOutRow(rows, model, held_out, training);
  return row == nullptr ? std::nan("") : adeOf(*row, held_out);
}

std::string heldOutAdeText(const std::vector<AdeRow>& rows, const std::string& model, const std::string& held_out,
                           HeldOutTraining training) {
  const auto* row = heldOutRow(rows, model, held_out, training);
  return row == nullptr ? "–" : adeText(*row, held_out);
}

/// Column heads of the four trainings with the study's sizes, e.g. "200 own".
std::string trainingTitle(const LeaveOneOutSpec& study, HeldOutTraining training) {
  switch (training) {
    case HeldOutTraining::Others: return fmt::format("others ({} each)", study.others);
    case HeldOutTraining::OthersAndFewOwn: return fmt::format("others + {} own", study.fewShot);
    case HeldOutTraining::FewOwn: return fmt::format("{} own", study.fewShot);
    case HeldOutTraining::AllOwn: return fmt::format("{} own", study.alone);
  }
  return "?";
}

std::string tableHead(const std::vector<std::string>& columns) {
  std::string md = "|";
  for (const auto& column : columns) md += " " + column + " |";
  md += "\n|";
  for (std::size_t i = 0; i < columns.size(); ++i) md += "---|";
  return md + "\n";
}

std::string adeTable(const Spec& spec, const ExperimentSummary& summary, const std::vector<Finding>& findings) {
  const auto& study = spec.leaveOneOut;
  const auto& main = spec.models.front().name;
  std::vector<std::string> columns = {"held out"};
  for (const auto training : kHeldOutTrainings) columns.push_back(trainingTitle(study, training));
  for (const auto& predictor : spec.predictors) columns.push_back(predictor);
  columns.push_back(fmt::format("others + {} own ≤ {} own", study.fewShot, study.alone));
  std::string md = tableHead(columns);
  for (const auto& label : study.heldOut) {
    md += "| " + label + " |";
    for (const auto training : kHeldOutTrainings) md += " " + heldOutAdeText(summary.ade, main, label, training) + " |";
    for (const auto& predictor : spec.predictors) {
      for (const auto& row : summary.ade) {
        if (row.model == predictor && row.row == 0) md += " " + adeText(row, label) + " |";
      }
    }
    const auto finding = std::find_if(findings.begin(), findings.end(), [&](const Finding& f) { return f.id == label; });
    md += " " + (finding == findings.end() ? std::string("–") : finding->verdict) + " |\n";
  }
  return md;
}

/// "0.412 (90 %: 88 % (85–91))": a metric's MAE and, for a probabilistic model, the coverage
/// of its 90 % intervals.
std::string errorCell(const VectorNetMetricError& error) {
  std::string cell = fmt::format("{:.3f}", error.mae);
  if (std::isfinite(error.coverage90)) cell += fmt::format(" (90 %: {})", coverageText(error.coverage90, error.intervalSamples));
  return cell;
}

std::string baselineCell(const std::map<std::size_t, double>& errors, std::size_t rows) {
  const auto found = errors.find(rows);
  return found == errors.end() ? "–" : fmt::format("{:.3f}", found->second);
}

std::string metricTable(const Spec& spec, const ExperimentSummary& summary) {
  const auto& study = spec.leaveOneOut;
  std::vector<std::string> columns = {"held out", "metric"};
  for (const auto training : kHeldOutTrainings) columns.push_back("VectorNet " + trainingTitle(study, training));
  for (const char* baseline : {"extra trees", "BNN"}) {
    for (const auto rows : {study.fewShot, study.alone}) columns.push_back(fmt::format("{} {} own", baseline, rows));
  }
  std::string md = tableHead(columns);
  for (const auto& metric : summary.heldOut) {
    md += fmt::format("| {} | {} ({}) |", metric.label, metric.metric, metric.unit);
    for (const auto& error : metric.vectornet) md += " " + errorCell(error) + " |";
    for (const auto* errors : {&metric.et, &metric.bnn}) {
      for (const auto rows : {study.fewShot, study.alone}) md += " " + baselineCell(*errors, rows) + " |";
    }
    md += "\n";
  }
  return md;
}

std::string heldOutCsv(const Spec& spec, const ExperimentSummary& summary) {
  std::ostringstream csv;
  CsvWriter writer(csv);
  writer.writeRow({"held_out", "training", "model", "quantity", "unit", "value", "std", "seeds", "coverage50",
                   "coverage90", "interval_samples", "samples", "mix"});
  const auto optional = [](double value) { return std::isfinite(value) ? formatNumber(value) : std::string(); };
  for (const auto& row : summary.ade) {
    const bool predictor = row.row == 0;
    if (row.heldOut.empty() && !predictor) continue;
    for (const auto& label : spec.leaveOneOut.heldOut) {
      if (!predictor && row.heldOut != label) continue;
      const auto spread = row.adeStd.find(label);
      writer.writeRow({label, predictor ? "none" : row.training, row.model, "ade", "m", optional(adeOf(row, label)),
                       spread == row.adeStd.end() ? "" : formatNumber(spread->second), std::to_string(row.seeds.size()),
                       "", "", "", "", mixText(row)});
    }
  }
  for (const auto& metric : summary.heldOut) {
    for (const auto& error : metric.vectornet) {
      writer.writeRow({metric.label, error.model, spec.models.front().name, metric.metric, metric.unit,
                       optional(error.mae), "", "1", optional(error.coverage50), optional(error.coverage90),
                       std::to_string(error.intervalSamples), std::to_string(error.samples), ""});
    }
    for (const auto& [name, errors] : {std::pair{"et", &metric.et}, std::pair{"bnn", &metric.bnn}}) {
      for (const auto& [rows, mae] : *errors) {
        writer.writeRow({metric.label, rows == spec.leaveOneOut.fewShot ? "few_own" : "all_own", name, metric.metric,
                         metric.unit, optional(mae), "", "1", "", "", "", "", fmt::format("{} {}", metric.label, rows)});
      }
    }
  }
  return csv.str();
}

}  // namespace

std::vector<Finding> heldOutFindings(const Spec& spec, const std::vector<AdeRow>& main_rows) {
  const auto& study = spec.leaveOneOut;
  std::vector<Finding> findings;
  if (main_rows.empty()) return findings;
  const auto& model = main_rows.front().model;
  for (const auto& label : study.heldOut) {
    Finding finding;
    finding.id = label;
    finding.claim = fmt::format(
        "{} own samples added to the other functional scenarios' data predict {} no worse than {} own samples alone "
        "(the paper's rows 9 and 10)",
        study.fewShot, label, study.alone);
    finding.rule = fmt::format("holds if the ADE of 'others + {0} own' <= the ADE of '{1} own' on {2}'s test set "
                               "(means over the seeds)",
                               study.fewShot, study.alone, label);
    const double transfer = heldOutAde(main_rows, model, label, HeldOutTraining::OthersAndFewOwn);
    const double own = heldOutAde(main_rows, model, label, HeldOutTraining::AllOwn);
    if (!std::isfinite(transfer) || !std::isfinite(own)) {
      finding.verdict = "not checked";
      finding.evidence = "a row is missing";
    } else {
      finding.verdict = transfer <= own ? "holds" : "does not hold";
      finding.evidence = fmt::format(
          "ADE others only {}, others + {} own {}, {} own {}, {} own {} m",
          heldOutAdeText(main_rows, model, label, HeldOutTraining::Others), study.fewShot,
          heldOutAdeText(main_rows, model, label, HeldOutTraining::OthersAndFewOwn), study.fewShot,
          heldOutAdeText(main_rows, model, label, HeldOutTraining::FewOwn), study.alone,
          heldOutAdeText(main_rows, model, label, HeldOutTraining::AllOwn));
    }
    findings.push_back(std::move(finding));
  }
  return findings;
}

std::pair<std::string, std::string> heldOutFiles(const Spec& spec, const ExperimentSummary& summary) {
  const auto& study = spec.leaveOneOut;
  const auto& main = spec.models.front();
  std::string md = "# Leave one functional scenario out\n\n" + sizesLine(spec) + "\n\n";
  md += fmt::format(
      "Each held-out functional scenario is predicted by four trainings of {} (decoder {}): on every other functional "
      "scenario ({} samples each{}), on the same plus {} of its own (the paper's row 9), on {} of its own alone "
      "(row 10), and on {} of its own alone. Extra trees and the BNN learn from a scenario's own concrete inputs, so "
      "they are fitted on its own {} and {} samples only: with none of its own they have nothing to predict from.\n",
      main.name, modelDescription(main), study.others,
      study.context.empty() ? "" : fmt::format("; always among them: {}", fmt::join(study.context, ", ")),
      study.fewShot, study.fewShot, study.alone, study.fewShot, study.alone);
  std::vector<Finding> held_out_findings;
  for (const auto& finding : summary.findings) {
    if (std::find(study.heldOut.begin(), study.heldOut.end(), finding.id) != study.heldOut.end()) {
      held_out_findings.push_back(finding);
    }
  }
  md += "\n## ADE of the Ego's predicted trajectory on the held-out scenario's test set (m)\n\n";
  md += adeTable(spec, summary, held_out_findings);
  if (!summary.heldOut.empty()) {
    md += "\n## MAE of metrics on the held-out scenario's test set\n\nVectorNet: the metric computed from the most "
          "likely predicted future; in brackets the share of simulated values inside the 90 % interval of its "
          "sampled futures (95 % confidence interval).\n\n";
    md += metricTable(spec, summary);
  }
  return {heldOutCsv(spec, summary), md};
}

}  // namespace vsd::experiment
