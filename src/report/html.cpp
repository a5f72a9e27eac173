// The self-contained HTML comparison report: summary first, then charts, the worst
// scenarios, failures, every scenario (sortable) and provenance. Everything is inline
// (CSS, SVG, a few lines of JavaScript for sorting): the file works offline, attached
// to a ticket or opened from a shared drive.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>

#include "charts.hpp"
#include "vsd/core/csv.hpp"
#include "vsd/core/svg.hpp"
#include "vsd/report/comparison.hpp"

namespace vsd::report {

namespace {

/// Scenarios listed in the sortable table (worst ADE first); all of them are in comparison.csv.
constexpr std::size_t kMaxTableRows = 500;

std::string html(const std::string& text) { return escapeXml(text); }

std::string number(double value, int decimals = 3) {
  if (std::isnan(value)) return "&ndash;";
  if (std::isinf(value)) return value > 0 ? "&infin;" : "&minus;&infin;";
  return fmt::format("{:.{}f}", value, decimals);
}

std::string percent(double share) { return std::isnan(share) ? "&ndash;" : fmt::format("{:.1f}&nbsp;%", 100.0 * share); }

/// A table cell that sorts by its exact value.
std::string numberCell(double value, int decimals = 3) {
  const std::string sort_value = std::isnan(value) ? "" : std::isinf(value) ? (value > 0 ? "Infinity" : "-Infinity")
                                                                            : formatNumber(value);
  return fmt::format("<td data-value=\"{}\">{}</td>", sort_value, number(value, decimals));
}

constexpr const char* kStyle = R"css(
:root { color-scheme: light; }
body { font-family: "DejaVu Sans", "Liberation Sans", Arial, sans-serif; margin: 24px auto; max-width: 1180px;
       padding: 0 16px; color: #1f2328; background: #ffffff; line-height: 1.4; }
h1 { font-size: 1.55em; margin-bottom: 0.2em; }
h2 { font-size: 1.2em; margin-top: 1.8em; border-bottom: 1px solid #d0d7de; padding-bottom: 0.2em; }
p.lead { font-size: 1.05em; margin-top: 0.3em; }
table { border-collapse: collapse; margin: 0.6em 0 1em; font-size: 0.92em; }
th, td { border: 1px solid #d0d7de; padding: 3px 8px; text-align: right; }
th { background: #f3f5f7; }
td:first-child, th:first-child { text-align: left; }
table.sortable th { cursor: pointer; user-select: none; }
table.sortable th[aria-sort="ascending"]::after { content: " \25B2"; }
table.sortable th[aria-sort="descending"]::after { content: " \25BC"; }
.grid { display: flex; flex-wrap: wrap; gap: 10px; }
.grid svg { border: 1px solid #eaeef2; background: #fff; }
figure { margin: 0 0 18px; max-width: 560px; }
figcaption { font-size: 0.9em; color: #444; margin-top: 2px; }
.muted { color: #57606a; font-size: 0.9em; }
.warn { color: #b42318; }
p.warning { color: #b42318; background: #fff4f2; border: 1px solid #f3c2b8; padding: 6px 10px; }
/* Wide tables scroll inside their own box: the page never scrolls sideways. */
.scroll, section { overflow-x: auto; max-width: 100%; }
td code { overflow-wrap: anywhere; }
code { background: #f3f5f7; padding: 0 3px; }
)css";

constexpr const char* kScript = R"js(
(function () {
  'use strict';
  function key(cell) {
    var value = cell.getAttribute('data-value');
    return value === null ? cell.textContent : value;
  }
  document.querySelectorAll('table.sortable').forEach(function (table) {
    var headers = table.tHead.rows[0].cells;
    Array.prototype.forEach.call(headers, function (header, column) {
      header.addEventListener('click', function () {
        var body = table.tBodies[0];
        var rows = Array.prototype.slice.call(body.rows);
        var ascending = header.getAttribute('aria-sort') !== 'ascending';
        rows.sort(function (a, b) {
          var x = key(a.cells[column]), y = key(b.cells[column]);
          var nx = parseFloat(x), ny = parseFloat(y);
          var order = (isNaN(nx) || isNaN(ny)) ? x.localeCompare(y) : (nx < ny ? -1 : nx > ny ? 1 : 0);
          return ascending ? order : -order;
        });
        Array.prototype.forEach.call(headers, function (h) { h.removeAttribute('aria-sort'); });
        header.setAttribute('aria-sort', ascending ? 'ascending' : 'descending');
        rows.forEach(function (row) { body.appendChild(row); });
      });
    });
    table.setAttribute('data-sortable', 'ready');
  });
})();
)js";

std::string timingText(const Comparison& comparison) {
  std::string text;
  double predict = 0.0;
  double simulate = 0.0;
  for (const auto& [stage, seconds] : comparison.timings) {
    text += fmt::format("{}{} {:.2f}&nbsp;s", text.empty() ? "" : ", ", html(stage), seconds);
    if (stage == "predict") predict = seconds;
    if (stage == "simulate") simulate = seconds;
  }
  if (predict > 0.0 && simulate > 0.0) {
    // The ratio with a decimal and the slower stage named, so 0.45 s against 0.65 s does not read "1x less".
    text += simulate >= predict
                ? fmt::format(" &mdash; simulating took {:.1f}&times; as long as predicting", simulate / predict)
                : fmt::format(" &mdash; predicting took {:.1f}&times; as long as simulating", predict / simulate);
  }
  return text;
}

/// The sentence a reader sees first.
std::string leadSentence(const Comparison& comparison, const ComparisonStatistics& s) {
  std::string lead = fmt::format("{} scenarios compared", s.compared);
  if (s.failed > 0) lead += fmt::format(" (<span class=\"warn\">{} without a {} reference</span>)", s.failed,
                                        html(comparison.referenceName));
  lead += fmt::format(". Median ADE {} m, 90&nbsp;% of scenarios below {} m.", number(s.ade.median, 2),
                      number(s.ade.p90, 2));
  for (const auto& c : s.criteria) {
    const std::size_t critical = c.bothFail + c.missed;
    lead += fmt::format(" Criterion <code>{}</code>: the model flags {} of {} critical scenarios ({} missed, {} false "
                        "alarm{}).",
                        html(c.expression), c.bothFail, critical, c.missed, c.falseAlarm, c.falseAlarm == 1 ? "" : "s");
  }
  return lead;
}

void summarySection(std::ostringstream& out, const Comparison& comparison, const ComparisonStatistics& s) {
  const std::string& ref = comparison.referenceName;
  out << "<section id=\"summary\"><h2>Summary</h2>\n<table>\n";
  out << "<tr><th>quantity</th><th>mean</th><th>median</th><th>p90</th><th>max</th><th>scenarios</th></tr>\n";
  for (const auto& [name, d] : {std::pair<std::string, Distribution>{"ADE (m)", s.ade}, {"FDE (m)", s.fde}}) {
    out << fmt::format("<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n", name,
                       number(d.mean), number(d.median), number(d.p90), number(d.max), d.count);
  }
  out << "</table>\n";
  if (!s.metrics.empty()) {
    const bool any_floor = std::any_of(s.metrics.begin(), s.metrics.end(), [](const auto& m) { return m.floorMae.has_value(); });
    out << fmt::format("<table>\n<tr><th>metric</th><th>unit</th><th>MAE</th><th>median |error|</th><th>bias "
                       "(predicted &minus; {})</th><th>p90 |error|</th><th>pairs</th><th>both &infin;</th><th>finite on one side only</th>{}</tr>\n",
                       html(ref), any_floor ? fmt::format("<th>MAE from {} positions</th>", html(ref)) : "");
    for (const auto& m : s.metrics) {
      out << fmt::format("<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td>"
                         "<td>{}</td>{}</tr>\n",
                         html(m.name), html(m.unit), number(m.mae), number(m.medianAbsoluteError), number(m.bias),
                         number(m.p90AbsoluteError), m.pairs,
                         m.bothInfinite, m.finitenessMismatch,
                         any_floor ? fmt::format("<td>{}</td>", m.floorMae ? number(*m.floorMae) : "&ndash;") : "");
    }
    out << "</table>\n";
    if (any_floor) {
      out << fmt::format("<p class=\"muted\">\"MAE from {0} positions\" feeds the {0} Ego positions through the same "
                         "code as the prediction (speeds and accelerations reconstructed from positions): the part of "
                         "the MAE that is not the model's.</p>\n",
                         html(ref));
    }
  }
  if (!s.criteria.empty()) {
    out << fmt::format("<table>\n<tr><th>criterion</th><th>fails if</th><th>both fail</th><th>false alarm (only "
                       "predicted fails)</th><th>missed (only {} fails)</th><th>both pass</th><th>undefined</th>"
                       "<th>agreement</th><th>critical found</th></tr>\n",
                       html(ref));
    for (const auto& c : s.criteria) {
      out << fmt::format("<tr><td>{}</td><td><code>{}</code></td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td>"
                         "<td>{}</td><td>{}</td></tr>\n",
                         html(c.name), html(c.expression), c.bothFail, c.falseAlarm, c.missed, c.bothPass, c.undefined,
                         percent(c.agreement()), percent(c.recall()));
    }
    out << "</table>\n";
  }
  if (!comparison.timings.empty()) out << "<p>Time: " << timingText(comparison) << ".</p>\n";
  for (const auto& note : comparison.notes) out << "<p class=\"muted\">" << html(note) << "</p>\n";
  out << "</section>\n";
}

std::vector<double> column(const Comparison& comparison, std::size_t metric, bool predicted) {
  std::vector<double> values;
  for (const auto& scenario : comparison.scenarios) {
    if (!scenario.ok()) continue;
    values.push_back(predicted ? scenario.predicted.at(metric) : scenario.reference.at(metric));
  }
  return values;
}

void chartSections(std::ostringstream& out, const Comparison& comparison) {
  const std::string& ref = comparison.referenceName;
  if (!comparison.metricNames.empty()) {
    out << fmt::format("<section id=\"scatter\"><h2>Metrics: predicted vs {}</h2>\n<p class=\"muted\">One point per "
                       "scenario; on the dashed diagonal the prediction is exact.</p>\n<div class=\"grid\">\n",
                       html(ref));
    for (std::size_t m = 0; m < comparison.metricNames.size(); ++m) {
      const std::string unit = m < comparison.metricUnits.size() ? comparison.metricUnits[m] : "";
      const auto& name = comparison.metricNames[m];
      out << scatterSvg(column(comparison, m, false), column(comparison, m, true), name,
                        fmt::format("{} {} ({})", ref, name, unit), fmt::format("predicted {} ({})", name, unit));
    }
    out << "</div></section>\n";
  }
  out << "<section id=\"errors\"><h2>Error distributions</h2>\n<div class=\"grid\">\n";
  std::vector<double> ades;
  std::vector<double> fdes;
  for (const auto& scenario : comparison.scenarios) {
    if (!scenario.ok()) continue;
    ades.push_back(scenario.ade);
    fdes.push_back(scenario.fde);
  }
  out << histogramSvg(ades, "ADE", "average displacement error (m)");
  out << histogramSvg(fdes, "FDE", "final displacement error (m)");
  for (std::size_t m = 0; m < comparison.metricNames.size(); ++m) {
    const auto predicted = column(comparison, m, true);
    const auto reference = column(comparison, m, false);
    std::vector<double> errors(predicted.size());
    for (std::size_t i = 0; i < predicted.size(); ++i) errors[i] = predicted[i] - reference[i];
    const std::string unit = m < comparison.metricUnits.size() ? comparison.metricUnits[m] : "";
    out << histogramSvg(errors, comparison.metricNames[m] + " error",
                        fmt::format("predicted - {} ({})", ref, unit), 30, /*marker=*/0.0);
  }
  out << "</div></section>\n";
}

/// Intervals of the sampled futures: coverage per metric, the reliability diagram, and
/// which criterion verdicts the futures agree on.
void calibrationSection(std::ostringstream& out, const Comparison& comparison, const ComparisonStatistics& s) {
  if (comparison.draws <= 0) return;
  const std::string& ref = comparison.referenceName;
  out << fmt::format("<section id=\"calibration\"><h2>Uncertainty: {} sampled futures per scenario</h2>\n"
                     "<p class=\"muted\">Every metric is computed on every sampled future by the same code as the "
                     "prediction; the intervals are quantiles of those values. A well calibrated model has the {} "
                     "value inside its 50&nbsp;% interval in half of the scenarios and inside its 90&nbsp;% interval "
                     "in nine of ten.</p>\n<table>\n<tr><th>metric</th><th>unit</th><th>scenarios</th>"
                     "<th>in 50&nbsp;% interval</th><th>in 90&nbsp;% interval</th><th>mean width of the 90&nbsp;% "
                     "interval</th></tr>\n",
                     comparison.draws, html(ref));
  std::vector<std::pair<std::string, std::vector<double>>> curves;
  for (const auto& m : s.metrics) {
    if (m.intervalPairs == 0) continue;
    out << fmt::format("<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n", html(m.name),
                       html(m.unit), m.intervalPairs, percent(m.coverage50), percent(m.coverage90),
                       number(m.meanWidth90));
    curves.emplace_back(m.name, m.reliability);
  }
  out << "</table>\n<div class=\"grid\">\n"
      << reliabilitySvg(kReliabilityLevels, curves, "Reliability of the metric intervals") << "</div>\n";
  if (!s.criteria.empty()) {
    out << fmt::format("<table>\n<tr><th>criterion</th><th>confident verdicts (&ge;&nbsp;{0:.0f}&nbsp;% of the futures "
                       "agree)</th><th>of them wrong</th><th>uncertain verdicts</th><th>of them wrong for the most "
                       "likely future</th></tr>\n",
                       100.0 * comparison.confidence);
    for (const auto& c : s.criteria) {
      out << fmt::format("<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n", html(c.name),
                         c.confident, c.confidentWrong, c.uncertain, c.uncertainPointWrong);
    }
    out << fmt::format("</table>\n<p class=\"muted\">Uncertain verdicts are the scenarios worth simulating; "
                       "<code>comparison.csv</code> lists each scenario's share of failing futures "
                       "(<code>&lt;criterion&gt;_fail_share</code>).</p>\n");
  }
  out << "</section>\n";
}

void worstSection(std::ostringstream& out, const std::vector<SceneDrawing>& worst) {
  if (worst.empty()) return;
  out << fmt::format("<section id=\"worst\"><h2>The {} scenarios with the largest ADE</h2>\n<div class=\"grid\">\n",
                     worst.size());
  for (const auto& drawing : worst) {
    out << fmt::format("<figure id=\"scenario-{}\">\n{}\n<figcaption>{}</figcaption></figure>\n", drawing.sample,
                       drawing.svg, html(drawing.caption));
  }
  out << "</div></section>\n";
}

void failureSection(std::ostringstream& out, const Comparison& comparison) {
  std::vector<const ComparedScenario*> failed;
  for (const auto& scenario : comparison.scenarios) {
    if (!scenario.ok()) failed.push_back(&scenario);
  }
  if (failed.empty()) return;
  out << fmt::format("<section id=\"failures\"><h2 class=\"warn\">{} scenarios without a {} reference</h2>\n"
                     "<p class=\"muted\">Left out of every number above.</p>\n<table>\n<tr><th>sample</th><th>reason</th>"
                     "</tr>\n",
                     failed.size(), html(comparison.referenceName));
  for (const auto* scenario : failed) {
    out << fmt::format("<tr><td>{}</td><td style=\"text-align:left\">{}</td></tr>\n", scenario->sample,
                       html(scenario->failure));
  }
  out << "</table></section>\n";
}

void scenarioTable(std::ostringstream& out, const Comparison& comparison) {
  std::vector<const ComparedScenario*> rows;
  for (const auto& scenario : comparison.scenarios) {
    if (scenario.ok()) rows.push_back(&scenario);
  }
  std::stable_sort(rows.begin(), rows.end(), [](const auto* a, const auto* b) { return a->ade > b->ade; });
  const std::size_t shown = std::min(rows.size(), kMaxTableRows);
  out << "<section id=\"scenarios\"><h2>Scenarios</h2>\n<p class=\"muted\">";
  if (shown < rows.size()) out << fmt::format("The {} with the largest ADE of {}; ", shown, rows.size());
  out << "every scenario is in <code>comparison.csv</code>. Click a column to sort.</p>\n";
  out << "<div class=\"scroll\"><table class=\"sortable\"><thead><tr><th>sample</th><th>label</th><th>ADE (m)</th>"
         "<th>FDE (m)</th>";
  for (std::size_t m = 0; m < comparison.metricNames.size(); ++m) {
    const std::string unit = m < comparison.metricUnits.size() && !comparison.metricUnits[m].empty()
                                 ? " (" + html(comparison.metricUnits[m]) + ")"
                                 : std::string();
    const auto& name = html(comparison.metricNames[m]);
    out << fmt::format("<th>{0} predicted{2}</th><th>{0} {1}{2}</th>", name, html(comparison.referenceName), unit);
  }
  out << "</tr></thead>\n<tbody>\n";
  for (std::size_t r = 0; r < shown; ++r) {
    const auto& scenario = *rows[r];
    out << fmt::format("<tr><td data-value=\"{0}\">{0}</td><td>{1}</td>", scenario.sample, html(scenario.label))
        << numberCell(scenario.ade) << numberCell(scenario.fde);
    for (std::size_t m = 0; m < comparison.metricNames.size(); ++m) {
      out << numberCell(scenario.predicted.at(m)) << numberCell(scenario.reference.at(m));
    }
    out << "</tr>\n";
  }
  out << "</tbody></table></div></section>\n";
}

}  // namespace

std::string provenanceSection(const std::vector<std::pair<std::string, std::string>>& provenance) {
  std::ostringstream out;
  out << "<section id=\"provenance\"><h2>Provenance</h2>\n<table>\n";
  for (const auto& [key, value] : provenance) {
    out << fmt::format("<tr><td>{}</td><td style=\"text-align:left\"><code>{}</code></td></tr>\n", html(key), html(value));
  }
  out << "</table></section>\n";
  return out.str();
}

std::string reportHead(const std::string& kind, const std::string& title) {
  return fmt::format("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
                     "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
                     "<title>vsd-sumo {}: {}</title>\n<style>{}</style>\n</head>\n<body>\n",
                     kind, html(title), kStyle);
}

std::string renderHtmlReport(const Comparison& comparison, const ComparisonStatistics& statistics,
                             const std::vector<SceneDrawing>& worst) {
  std::ostringstream out;
  out << reportHead("comparison", comparison.title);
  out << fmt::format("<header><h1>Predicted vs {}: {}</h1>\n<p class=\"lead\">{}</p>\n",
                     html(comparison.referenceName), html(comparison.title), leadSentence(comparison, statistics));
  for (const auto& warning : comparison.warnings) out << "<p class=\"warning\">Warning: " << html(warning) << "</p>\n";
  out << "</header>\n";
  summarySection(out, comparison, statistics);
  calibrationSection(out, comparison, statistics);
  chartSections(out, comparison);
  worstSection(out, worst);
  failureSection(out, comparison);
  scenarioTable(out, comparison);
  out << provenanceSection(comparison.provenance);
  out << "<script>" << kScript << "</script>\n</body>\n</html>\n";
  return out.str();
}

}  // namespace vsd::report
