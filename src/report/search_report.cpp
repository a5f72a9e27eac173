#include "vsd/report/search_report.hpp"

#include <fmt/format.h>

#include <cmath>
#include <sstream>

#include "charts.hpp"
#include "vsd/core/svg.hpp"
#include "vsd/report/numbers.hpp"

namespace vsd::report {

namespace {

std::string html(const std::string& text) { return escapeXml(text); }

/// A share as a percentage with `decimals` (those its interval makes meaningful).
std::string percent(double share, int decimals) {
  return std::isfinite(share) ? fmt::format("{:.{}f}&nbsp;%", 100.0 * share, decimals) : "&ndash;";
}

void curveSection(std::ostringstream& out, const SearchReport& report) {
  std::vector<std::pair<std::string, std::vector<std::pair<double, double>>>> curves;
  for (const auto& curve : report.curves) curves.emplace_back(curve.name, curve.points);
  out << "<section id=\"learning\"><h2>Learning curves</h2>\n<div class=\"grid\"><figure>"
      << lineChartSvg(curves, "critical scenarios found", "executions", "critical scenarios")
      << "<figcaption>Critical scenarios found against executions (SUMO simulations), one line per "
         "search.</figcaption></figure></div></section>\n";
}

void rateSection(std::ostringstream& out, const SearchReport& report) {
  out << "<section id=\"rate\"><h2>P(criterion) under the logical scenario's distribution</h2>\n<table>\n"
         "<tr><th>estimate</th><th>method</th><th>executions</th><th>P</th><th>95&nbsp;% low</th>"
         "<th>95&nbsp;% high</th><th>interval width</th></tr>\n";
  for (const auto& row : report.rates) {
    const int decimals = decimalsFor(100.0 * (row.high - row.low));
    out << fmt::format("<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n",
                       html(row.name), html(row.method), row.executions, percent(row.estimate, decimals),
                       percent(row.low, decimals), percent(row.high, decimals), percent(row.high - row.low, decimals));
  }
  out << "</table></section>\n";
}

}  // namespace

std::string renderSearchReport(const SearchReport& report) {
  std::ostringstream out;
  out << reportHead("search", report.title);
  out << fmt::format("<header><h1>Search: {}</h1>\n", html(report.title));
  for (const auto& line : report.summary) out << fmt::format("<p class=\"lead\">{}</p>\n", html(line));
  out << "</header>\n";
  curveSection(out, report);
  rateSection(out, report);
  out << provenanceSection(report.provenance);
  out << "</body>\n</html>\n";
  return out.str();
}

}  // namespace vsd::report
