// writeReferenceReport: results/reference_driver/ - the documented cases, the comparison
// grid and a summary, written as one output set.

#include <fmt/format.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>

#include "vsd/core/csv.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/log.hpp"
#include "vsd/sim/reference_cases.hpp"

namespace vsd::sim {

namespace {

const char* checkName(DocumentedCase::Check check) {
  switch (check) {
    case DocumentedCase::Check::Avoids: return "avoids";
    case DocumentedCase::Check::Collides: return "collides";
    case DocumentedCase::Check::BrakeOnset: return "brake_onset";
    case DocumentedCase::Check::FullDecel: return "full_decel";
  }
  return "";
}

/// Without the last digits of a round trip (km/h -> m/s -> km/h) or of a sum of steps.
double rounded(double value) { return std::round(value * 1e6) / 1e6; }
double kmh(double speed) { return rounded(speed * 3.6); }

std::vector<std::string> cutInCells(const CutIn& cut_in) {
  return {formatNumber(kmh(cut_in.egoSpeed)), formatNumber(kmh(cut_in.targetSpeed)), formatNumber(cut_in.gap),
          formatNumber(cut_in.lateralSpeed), std::to_string(cut_in.fromLane)};
}

std::string casesCsv(const std::vector<CaseResult>& cases) {
  std::ostringstream text;
  CsvWriter csv(text);
  csv.writeRow({"id", "source", "statement", "controller", "ego_kmh", "target_kmh", "dx0_m", "vy_mps", "from_lane",
                "check", "expected_s", "measured", "verdict"});
  for (const auto& result : cases) {
    const auto& documented = result.documented;
    std::vector<std::string> row{documented.id, documented.source, documented.statement, documented.controller};
    for (auto& cell : cutInCells(documented.cutIn)) row.push_back(std::move(cell));
    const bool timed = documented.check == DocumentedCase::Check::BrakeOnset ||
                       documented.check == DocumentedCase::Check::FullDecel;
    row.insert(row.end(), {checkName(documented.check), timed ? formatNumber(documented.expected) : "", result.measured,
                           result.pass ? "right" : "wrong"});
    csv.writeRow(row);
  }
  return text.str();
}

std::string gridCsv(const std::vector<GridResult>& grid) {
  std::ostringstream text;
  CsvWriter csv(text);
  std::vector<std::string> header{"ego_kmh", "target_kmh", "dx0_m", "vy_mps", "from_lane"};
  for (const auto& name : gridControllers()) {
    for (const char* column : {"collision", "min_clearance_m", "brake_onset_s", "max_decel_mps2"}) {
      header.push_back(name + "." + column);
    }
  }
  csv.writeRow(header);
  for (const auto& cell : grid) {
    auto row = cutInCells(cell.cutIn);
    for (const auto& outcome : cell.outcomes) {
      row.insert(row.end(), {outcome.collision ? "1" : "0", formatNumber(outcome.minClearance),
                             formatNumber(rounded(outcome.brakeOnset)), formatNumber(outcome.maxDecel)});
    }
    csv.writeRow(row);
  }
  return text.str();
}

std::string casesSummary(const std::vector<CaseResult>& cases) {
  std::string text;
  int right = 0;
  for (const auto& result : cases) right += result.pass ? 1 : 0;
  text += fmt::format("## Documented cases: {} of {} on the right side\n\n", right, cases.size());
  text += "| case | source | statement | controller | measured | verdict |\n|---|---|---|---|---|---|\n";
  for (const auto& result : cases) {
    const auto& documented = result.documented;
    text += fmt::format("| `{}` | {} | {} | `{}` | {} | {} |\n", documented.id, documented.source, documented.statement,
                        documented.controller, result.measured, result.pass ? "right" : "**wrong**");
  }
  return text;
}

std::string gridSummary(const std::vector<GridResult>& grid) {
  const auto& names = gridControllers();
  std::string text = fmt::format(
      "\n## Comparison grid: {} cut-ins (ASAM's 4.4 variation ranges, from the left)\n\n"
      "| controller | collisions | collisions the reference driver avoids |\n|---|---|---|\n",
      grid.size());
  for (std::size_t c = 0; c < names.size(); ++c) {
    int collisions = 0;
    int beyond_reference = 0;
    for (const auto& cell : grid) {
      collisions += cell.outcomes[c].collision ? 1 : 0;
      beyond_reference += cell.outcomes[c].collision && !cell.outcomes[0].collision ? 1 : 0;
    }
    text += fmt::format("| `{}` | {} | {} |\n", names[c], collisions, beyond_reference);
  }
  text +=
      "\nUN R157's pass criterion: the system under test (`alks`) avoids a collision wherever the reference "
      "driver does - the last column counts the cut-ins where it does not.\n";
  return text;
}

}  // namespace

int writeReferenceReport(const std::filesystem::path& folder, const std::vector<CaseResult>& cases,
                         const std::vector<GridResult>& grid, const std::string& command, const std::string& invocation) {
  OutputFolder output(folder);
  output.stageText("cases.csv", casesCsv(cases));
  output.stageText("grid.csv", gridCsv(grid));
  std::string readme = fmt::format(
      "# The reference driver against the regulation's statements\n\nMade by `{}` with vsd-sumo {} (kinematic "
      "cut-ins, src/sim/cut_in_harness.cpp, step 0.01 s; docs/controllers.md explains the models and the "
      "sources).\n\n",
      command, toolVersion());
  readme += casesSummary(cases) + gridSummary(grid);
  output.stageText("README.md", readme);
  output.commit(nlohmann::json{{"command", invocation}, {"version", toolVersion()}});
  int wrong = 0;
  for (const auto& result : cases) wrong += result.pass ? 0 : 1;
  return wrong;
}

}  // namespace vsd::sim
