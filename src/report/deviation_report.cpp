#include "vsd/report/deviation_report.hpp"

#include <fmt/format.h>

#include <sstream>

#include "charts.hpp"
#include "vsd/core/svg.hpp"

namespace vsd::report {

namespace {

std::string html(const std::string& text) { return escapeXml(text); }

void tableSection(std::ostringstream& out, const TextTable& table) {
  out << fmt::format("<section id=\"{}\"><h2>{}</h2>\n", html(table.id), html(table.heading));
  if (!table.intro.empty()) out << fmt::format("<p class=\"muted\">{}</p>\n", html(table.intro));
  if (table.rows.empty()) {
    out << "<p>None.</p></section>\n";
    return;
  }
  out << "<div class=\"scroll\"><table>\n<tr>";
  for (const auto& cell : table.header) out << "<th>" << html(cell) << "</th>";
  out << "</tr>\n";
  for (const auto& row : table.rows) {
    out << "<tr>";
    for (const auto& cell : row) out << "<td>" << html(cell) << "</td>";
    out << "</tr>\n";
  }
  out << "</table></div></section>\n";
}

void drawingSection(std::ostringstream& out, const std::vector<SceneDrawing>& drawings) {
  if (drawings.empty()) return;
  out << fmt::format("<section id=\"drawings\"><h2>The {} most surprising scenes</h2>\n<div class=\"grid\">\n",
                     drawings.size());
  for (const auto& drawing : drawings) {
    out << fmt::format("<figure id=\"scene-{}\">\n{}\n<figcaption>{}</figcaption></figure>\n", drawing.sample,
                       drawing.svg, html(drawing.caption));
  }
  out << "</div></section>\n";
}

void pValueSection(std::ostringstream& out, const DeviationReport& report) {
  if (report.pValues.empty()) return;
  out << "<section id=\"p-values\"><h2>Tail probabilities of the scored scenes</h2>\n<div class=\"grid\"><figure>"
      << histogramSvg(report.pValues, "scene tail probability p", "p", 20, report.level)
      << fmt::format("<figcaption>Where the recorded behaviour is like the tests' (and the model calibrated), p is "
                     "uniform on [0, 1] and a share {:g} of the scenes falls below the level (marker); a pile-up at "
                     "small p is behaviour the tests did not predict.</figcaption></figure></div></section>\n",
                     report.level);
}

}  // namespace

std::string renderDeviationReport(const DeviationReport& report) {
  std::ostringstream out;
  out << reportHead("deviations", report.title);
  out << fmt::format("<header><h1>Deviations: {}</h1>\n", html(report.title));
  for (const auto& warning : report.warnings) out << fmt::format("<p class=\"warning\">{}</p>\n", html(warning));
  for (const auto& line : report.summary) out << fmt::format("<p class=\"lead\">{}</p>\n", html(line));
  for (const auto& note : report.notes) out << fmt::format("<p class=\"muted\">{}</p>\n", html(note));
  out << "</header>\n";
  for (const auto& table : report.groups) tableSection(out, table);
  drawingSection(out, report.drawings);
  pValueSection(out, report);
  for (const auto& table : report.lists) tableSection(out, table);
  out << provenanceSection(report.provenance);
  out << "</body>\n</html>\n";
  return out.str();
}

}  // namespace vsd::report
