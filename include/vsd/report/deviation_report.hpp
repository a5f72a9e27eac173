#pragma once
// The HTML report of `vsd-sumo deviations`: recorded Ego behaviour the model did not
// expect, grouped by what deviates, the most surprising scenes drawn (predicted 90 %
// region against the recorded path), scenes out of the model's distribution apart, and
// the distribution of the scenes' tail probabilities. Self-contained (inline CSS and SVG),
// like the comparison report. The compare module fills it (compare/deviations.hpp).

#include <string>
#include <utility>
#include <vector>

#include "vsd/report/comparison.hpp"

namespace vsd::report {

/// A table of formatted cells (the first column left-aligned).
struct TextTable {
  std::string id;       ///< HTML id of its section
  std::string heading;
  std::string intro;    ///< a sentence under the heading (plain text)
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
};

struct DeviationReport {
  std::string title;                   ///< e.g. "field.h5 with m.pt at level 0.05"
  std::vector<std::string> summary;    ///< lead lines (plain text)
  std::vector<std::string> warnings;   ///< shown first, in red
  std::vector<std::string> notes;      ///< how to read it (plain text)
  std::vector<double> pValues;         ///< of every scored scene: the histogram
  double level = 0.05;
  std::vector<TextTable> groups;       ///< what deviates (before the drawings)
  std::vector<SceneDrawing> drawings;  ///< the most surprising scenes
  std::vector<TextTable> lists;        ///< flagged scenes, out-of-distribution scenes
  std::vector<std::pair<std::string, std::string>> provenance;
};

/// The complete HTML document.
std::string renderDeviationReport(const DeviationReport& report);

}  // namespace vsd::report
