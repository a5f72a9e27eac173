#pragma once
// The outputs of `vsd-sumo deviations` (internal to the compare module): deviations.csv's
// rows and the report's content.

#include <string>
#include <utility>
#include <vector>

#include "vsd/compare/deviations.hpp"
#include "vsd/report/deviation_report.hpp"

namespace vsd::compare {

/// deviations.csv: one row per recorded scene (docs/deviations.md lists the columns).
std::vector<std::string> csvHeader(const DeviationResult& result);
/// `rank`: 1 for the most surprising flagged scene, 0 for a scene not flagged.
std::vector<std::string> csvRow(const DeviationResult& result, const SceneDeviation& scene, std::size_t rank);

/// The report: groups, the first `drawn_scenes.size()` ranked scenes drawn (their scenes
/// in rank order), the flagged and out-of-distribution lists, the tail probabilities.
report::DeviationReport buildReport(const DeviationSummary& summary, const std::vector<vector::VectorizedScene>& drawn_scenes,
                                    std::vector<std::pair<std::string, std::string>> provenance);

}  // namespace vsd::compare
