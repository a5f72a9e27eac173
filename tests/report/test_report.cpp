// Comparison statistics, comparison.csv and the HTML report (also rendered in a real
// browser: headless Chromium).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <regex>
#include <set>

#include "../../src/report/charts.hpp"
#include "test_support.hpp"
#include "vsd/core/csv.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/svg.hpp"
#include "vsd/report/comparison.hpp"

using namespace vsd;
using namespace vsd::report;
namespace fs = std::filesystem;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// 40 scenarios: d_min predicted = simulated +-0.5 m alternately (MAE 0.5, bias 0);
/// a_min predicted 0.2 too low everywhere (bias -0.2); ttc_min infinite on both sides in
/// every 4th scenario, infinite only in the prediction in scenario 1; scenario 39 failed.
Comparison syntheticComparison() {
  Comparison c;
  c.title = "acc_lk, 40 fresh scenarios";
  c.inputNames = {"v_ego"};
  c.metricNames = {"d_min", "a_min", "ttc_min"};
  c.metricUnits = {"m", "m/s^2", "s"};
  c.criteria = {{"close_approach", "d_min < 2"}};
  for (int i = 0; i < 40; ++i) {
    ComparedScenario s;
    s.sample = static_cast<std::uint64_t>(i);
    s.label = "acc_lk";
    s.inputs = {8.0 + 0.1 * i};
    s.ade = 0.1 * i;
    s.fde = 0.2 * i;
    const double d_min = 0.25 * i;  // 0 .. 9.75 m
    const double d_pred = d_min + (i % 2 == 0 ? 0.5 : -0.5);
    const double ttc = i % 4 == 0 ? kInf : 3.0;
    const double ttc_pred = i == 1 ? kInf : ttc;
    s.reference = {d_min, -2.0, ttc};
    s.predicted = {d_pred, -2.2, ttc_pred};
    s.fromReferencePositions = {d_min, -2.05, ttc};
    s.referenceFails = {d_min < 2 ? 1 : 0};
    s.predictedFails = {d_pred < 2 ? 1 : 0};
    if (i == 39) s.failure = "SUMO removed vehicle 'co' at t = 3.2 s (reached the end of its road)";
    c.scenarios.push_back(s);
  }
  c.timings = {{"vectorize", 0.05}, {"predict", 0.02}, {"simulate", 1.5}};
  c.provenance = {{"model file", "models/m.pt"}, {"seed", "99"}};
  c.notes = {"a note"};
  return c;
}

std::string sceneSvgStub() {
  SvgCanvas canvas(Vec2(-55, -5), Vec2(55, 5), 600, 0, true);
  canvas.polyline({Vec2(-55, 0), Vec2(55, 1)}, "#9a9a9a", 1.0);
  canvas.textPx(10, 18, "scene drawing", 12, "#222222");
  return canvas.str();
}

}  // namespace

TEST(ReportStatistics, MaeBiasInfinitiesAndConfusionCounts) {
  const auto c = syntheticComparison();
  const auto s = computeStatistics(c);
  EXPECT_EQ(s.compared, 39u);
  EXPECT_EQ(s.failed, 1u);
  ASSERT_EQ(s.metrics.size(), 3u);
  EXPECT_EQ(s.metrics[0].pairs, 39u);
  EXPECT_NEAR(s.metrics[0].mae, 0.5, 1e-12);
  EXPECT_NEAR(s.metrics[0].bias, 0.5 / 39.0, 1e-12);  // 20 of +0.5, 19 of -0.5
  EXPECT_NEAR(*s.metrics[0].floorMae, 0.0, 1e-12);
  EXPECT_NEAR(s.metrics[1].bias, -0.2, 1e-12);
  EXPECT_NEAR(*s.metrics[1].floorMae, 0.05, 1e-12);
  // ttc_min: scenarios 0, 4, ..., 36 infinite on both sides (10), scenario 1 on one side only.
  EXPECT_EQ(s.metrics[2].bothInfinite, 10u);
  EXPECT_EQ(s.metrics[2].finitenessMismatch, 1u);
  EXPECT_EQ(s.metrics[2].pairs, 28u);
  EXPECT_NEAR(s.metrics[2].mae, 0.0, 1e-12);
  // d_min < 2: reference fails for i = 0..7; prediction for even i <= 4 (d + 0.5 < 2) and odd i <= 9.
  ASSERT_EQ(s.criteria.size(), 1u);
  const auto& criterion = s.criteria[0];
  EXPECT_EQ(criterion.bothFail, 7u);    // 0, 1, 2, 3, 4, 5, 7
  EXPECT_EQ(criterion.missed, 1u);      // 6
  EXPECT_EQ(criterion.falseAlarm, 1u);  // 9
  EXPECT_EQ(criterion.bothPass, 30u);
  EXPECT_NEAR(criterion.agreement(), 37.0 / 39.0, 1e-12);
  EXPECT_NEAR(criterion.recall(), 7.0 / 8.0, 1e-12);
  // ADE 0.0 .. 3.8 m over the 39 compared scenarios.
  EXPECT_NEAR(s.ade.mean, 1.9, 1e-9);
  EXPECT_NEAR(s.ade.median, 1.9, 1e-9);
  EXPECT_NEAR(s.ade.max, 3.8, 1e-9);
  EXPECT_NEAR(s.ade.p90, 0.9 * 3.8, 1e-9);
}

TEST(ReportStatistics, IntervalCoverageAndTheErrorOfTheDrawsMedian) {
  auto c = syntheticComparison();
  c.draws = 32;
  for (std::size_t i = 0; i < c.scenarios.size(); ++i) {
    auto& s = c.scenarios[i];
    // a_min (reference -2.0): the draws' median 0.1 too high in half of the scenarios and
    // 0.3 too low in the other; the reference inside the central 40 % interval (inside the
    // 50 % one) or only inside the 94 % one (inside neither).
    const bool high = i % 2 == 0;
    const double median = high ? -1.9 : -2.3;
    const double level = high ? 0.4 : 0.94;
    s.intervals = {MetricInterval{}, MetricInterval{32, median - 1, median - 0.5, median, median + 0.5, median + 1, level},
                   MetricInterval{}};
  }
  const auto s = computeStatistics(c);
  const auto& a_min = s.metrics[1];
  EXPECT_EQ(a_min.intervalPairs, 39u);  // scenario 39 failed
  EXPECT_NEAR(a_min.coverage50, 20.0 / 39.0, 1e-12);
  EXPECT_NEAR(a_min.coverage90, 20.0 / 39.0, 1e-12);
  EXPECT_NEAR(a_min.meanWidth90, 2.0, 1e-12);
  EXPECT_NEAR(a_min.medianDrawMae, (20 * 0.1 + 19 * 0.3) / 39.0, 1e-12);
  EXPECT_EQ(s.metrics[0].intervalPairs, 0u);  // no draws: no interval statistics
  EXPECT_NE(textSummary(c, s).find("their median: MAE 0.197 m/s^2"), std::string::npos) << textSummary(c, s);
}

TEST(ReportStatistics, DescribeIgnoresNonFiniteValues) {
  const auto d = describe({1.0, kNaN, 3.0, kInf, 2.0});
  EXPECT_EQ(d.count, 3u);
  EXPECT_DOUBLE_EQ(d.mean, 2.0);
  EXPECT_DOUBLE_EQ(d.median, 2.0);
  EXPECT_TRUE(std::isnan(describe({}).mean));
}

TEST(ReportCsv, OneRowPerScenarioWithPredictedSimulatedAndError) {
  TemporaryDirectory dir;
  const auto c = syntheticComparison();
  writeComparisonCsv(c, dir.path() / "comparison.csv");
  const auto table = CsvTable::read(dir.path() / "comparison.csv");
  ASSERT_EQ(table.rows(), 40u);
  for (const char* column : {"sample", "status", "failure", "v_ego", "ade_m", "fde_m", "d_min_predicted_m",
                             "d_min_simulated_m", "d_min_error_m", "a_min_error_m_s2", "close_approach_predicted_fail",
                             "close_approach_simulated_fail"}) {
    EXPECT_TRUE(table.findColumn(column).has_value()) << column;
  }
  EXPECT_DOUBLE_EQ(table.number(2, table.column("d_min_error_m")), 0.5);
  EXPECT_EQ(table.cell(1, table.column("ttc_min_predicted_s")), "inf");
  EXPECT_EQ(table.cell(1, table.column("ttc_min_error_s")), "");
  EXPECT_EQ(table.cell(39, table.column("status")), "failed");
  EXPECT_EQ(table.cell(39, table.column("ade_m")), "");
  EXPECT_EQ(table.cell(6, table.column("close_approach_simulated_fail")), "1");
  EXPECT_EQ(table.cell(6, table.column("close_approach_predicted_fail")), "0");
}

TEST(ReportCharts, TicksAreRoundAndCoverTheRange) {
  EXPECT_EQ(niceTicks(0.0, 10.0, 5), (std::vector<double>{0, 2, 4, 6, 8, 10}));
  const auto ticks = niceTicks(-0.37, 1.42, 4);
  ASSERT_GE(ticks.size(), 3u);
  EXPECT_NEAR(ticks.front(), 0.0, 1e-12);
  EXPECT_NEAR(ticks[1] - ticks[0], 0.5, 1e-12);
  const auto svg = histogramSvg({1.0, 2.0, 2.5, kNaN}, "ADE", "m");
  EXPECT_NE(svg.find("n = 3"), std::string::npos);
  EXPECT_NE(scatterSvg({}, {}, "d_min", "x", "y").find("no scenario with both values finite"), std::string::npos);
}

TEST(ReportHtml, SelfContainedWithTheSummaryFirst) {
  const auto c = syntheticComparison();
  const auto html = renderHtmlReport(c, computeStatistics(c), {{17, "caption of sample 17", sceneSvgStub()}});
  EXPECT_EQ(html.rfind("<!DOCTYPE html>", 0), 0u);
  const auto summary = html.find("id=\"summary\"");
  ASSERT_NE(summary, std::string::npos);
  for (const char* later : {"id=\"scatter\"", "id=\"errors\"", "id=\"worst\"", "id=\"failures\"", "id=\"scenarios\"",
                            "id=\"provenance\""}) {
    const auto at = html.find(later);
    ASSERT_NE(at, std::string::npos) << later;
    EXPECT_GT(at, summary) << later;
  }
  // Offline: nothing is fetched (SVG's xmlns is a name, not a request).
  for (const std::regex& external : {std::regex(R"((src|href)\s*=\s*["']?(https?:)?//)"), std::regex("@import"),
                                    std::regex(R"(url\()")}) {
    EXPECT_FALSE(std::regex_search(html, external));
  }
  EXPECT_NE(html.find("caption of sample 17"), std::string::npos);
  EXPECT_NE(html.find("SUMO removed vehicle &#39;co&#39;"), std::string::npos);  // the failed scenario is listed
  EXPECT_NE(html.find("models/m.pt"), std::string::npos);
  EXPECT_NE(html.find("simulating took 75.0&times; as long as predicting"), std::string::npos);  // 1.5 s / 0.02 s
  auto slow_model = c;
  slow_model.timings = {{"predict", 0.9}, {"simulate", 0.6}};
  EXPECT_NE(renderHtmlReport(slow_model, computeStatistics(slow_model), {}).find(
                "predicting took 1.5&times; as long as simulating"),
            std::string::npos);
  EXPECT_NE(html.find("the model flags 7 of 8 critical scenarios (1 missed, 1 false alarm)"), std::string::npos);
  // one scatter and one error histogram per metric, ADE and FDE histograms
  std::size_t svgs = 0;
  for (auto at = html.find("<svg"); at != std::string::npos; at = html.find("<svg", at + 1)) ++svgs;
  EXPECT_EQ(svgs, 3u + 2u + 3u + 1u);
}

// Renders the report in headless Chromium: the page must not be blank, must raise no
// JavaScript error, and its script must have run (sortable tables marked ready).
TEST(ReportHtml, RendersInHeadlessChromiumWithoutJavaScriptErrors) {
  if (!fs::exists("/usr/bin/chromium")) GTEST_SKIP() << "chromium is not installed (tools/setup.sh installs it)";
  TemporaryDirectory dir;
  const auto c = syntheticComparison();
  const auto page = dir.path() / "index.html";
  writeTextFileAtomically(page, renderHtmlReport(c, computeStatistics(c), {{17, "caption", sceneSvgStub()}}));
  // Chromium's own scratch (org.chromium.Chromium.*) goes inside the test's folder, not /tmp.
  fs::create_directories(dir.path() / "tmp");
  const std::vector<std::string> common = {"/usr/bin/env", "TMPDIR=" + (dir.path() / "tmp").string(),
                                           "/usr/bin/chromium", "--headless", "--no-sandbox", "--disable-gpu",
                                           "--no-first-run", "--disable-background-networking",
                                           "--disable-component-update", "--disable-sync", "--enable-logging=stderr",
                                           "--v=0", "--user-data-dir=" + (dir.path() / "profile").string()};
  auto screenshot_args = common;
  screenshot_args.insert(screenshot_args.end(), {"--window-size=1280,1600",
                                                 "--screenshot=" + (dir.path() / "shot.png").string(),
                                                 "file://" + page.string()});
  const auto shot = test::run(screenshot_args, dir.path());
  ASSERT_TRUE(fs::exists(dir.path() / "shot.png")) << shot.output;
  for (const char* error : {"Uncaught", "SyntaxError", "ReferenceError", "TypeError"}) {
    EXPECT_EQ(shot.output.find(error), std::string::npos) << shot.output;
  }
  auto dom_args = common;
  dom_args.insert(dom_args.end(), {"--dump-dom", "file://" + page.string()});
  const auto dom = test::run(dom_args, dir.path());
  EXPECT_NE(dom.output.find("data-sortable=\"ready\""), std::string::npos) << "the report's script did not run";
  for (const char* error : {"Uncaught", "SyntaxError", "ReferenceError", "TypeError"}) {
    EXPECT_EQ(dom.output.find(error), std::string::npos) << dom.output.substr(0, 2000);
  }
  // Not blank: a good share of the pixels differ from the background, in more than one colour.
  const auto check = test::run({test::python(), "-c", R"(
import sys
from PIL import Image
image = Image.open(sys.argv[1]).convert('RGB')
pixels = list(image.getdata())
non_white = sum(1 for p in pixels if p != (255, 255, 255))
colours = len(set(pixels))
print(f'{image.size[0]}x{image.size[1]} non_white={non_white / len(pixels):.4f} colours={colours}')
sys.exit(0 if non_white / len(pixels) > 0.02 and colours > 20 else 1)
)", (dir.path() / "shot.png").string()}, dir.path());
  EXPECT_EQ(check.exitCode, 0) << check.output;
}

// The reliability diagram tells every metric of a report apart (up to twelve by colour).
TEST(ReportCharts, ReliabilityCurvesOfTenMetricsHaveTenColours) {
  std::vector<std::pair<std::string, std::vector<double>>> curves;
  for (int m = 0; m < 10; ++m) curves.emplace_back("metric" + std::to_string(m), std::vector<double>{0.1, 0.5, 0.9});
  const auto svg = reliabilitySvg({0.1, 0.5, 0.9}, curves, "reliability");
  std::set<std::string> colours;
  const std::regex stroke(R"re(<polyline [^>]*stroke="(#[0-9a-f]{6})")re");
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), stroke); it != std::sregex_iterator(); ++it) {
    colours.insert((*it)[1].str());
  }
  colours.erase("#888888");  // the dashed diagonal
  EXPECT_EQ(colours.size(), 10u) << svg;
}

// Scene drawings (equal-aspect canvases in metres) carry a scale bar of a round length.
TEST(ReportCharts, SceneDrawingsHaveAScaleBar) {
  const auto svg = sceneSvgStub();  // 110 m over 600 px
  EXPECT_NE(svg.find("class=\"scale-bar\""), std::string::npos) << svg;
  EXPECT_NE(svg.find(">20 m</text>"), std::string::npos) << svg;
  // Charts (free aspect) have none.
  EXPECT_EQ(histogramSvg({1.0, 2.0}, "ADE", "m").find("scale-bar"), std::string::npos);
}

TEST(ReportHtml, WarningsComeFirst) {
  auto c = syntheticComparison();
  c.warnings = {"the model never trained on label 'acc_lk'"};
  const auto html = renderHtmlReport(c, computeStatistics(c), {});
  const auto warning = html.find("<p class=\"warning\">Warning: the model never trained on label &#39;acc_lk&#39;");
  ASSERT_NE(warning, std::string::npos);
  EXPECT_LT(warning, html.find("id=\"summary\""));
  EXPECT_NE(textSummary(c, computeStatistics(c)).find("warning: the model never trained"), std::string::npos);
}

// At 1,400 px nothing scrolls the page sideways: wide tables scroll in their own box.
TEST(ReportHtml, NoPageWideHorizontalScrollAt1400Pixels) {
  if (!fs::exists("/usr/bin/chromium")) GTEST_SKIP() << "chromium is not installed (tools/setup.sh installs it)";
  TemporaryDirectory dir;
  auto c = syntheticComparison();
  for (int m = 0; m < 8; ++m) {  // a wide scenario table: 2 columns per metric
    c.metricNames.push_back("long_metric_name_" + std::to_string(m));
    c.metricUnits.push_back("m/s^2");
    for (auto& s : c.scenarios) {
      s.predicted.push_back(1.0);
      s.reference.push_back(1.0);
      s.fromReferencePositions.push_back(1.0);
    }
  }
  c.provenance.push_back({"command line", std::string(400, 'x')});
  std::string html = renderHtmlReport(c, computeStatistics(c), {{17, "caption", sceneSvgStub()}});
  // Measured in the page: the document's width against the window's.
  html.replace(html.rfind("</body>"), 7,
               "<script>var d = document.createElement('div'); d.setAttribute('data-widths', "
               "document.documentElement.scrollWidth + ' ' + window.innerWidth); document.body.appendChild(d);"
               "</script></body>");  // at the end: the captured output is the dump's tail
  const auto page = dir.path() / "report.html";
  writeTextFileAtomically(page, html);
  const auto dom = test::run({"/usr/bin/chromium", "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
                              "--hide-scrollbars", "--window-size=1400,900",
                              "--user-data-dir=" + (dir.path() / "profile").string(), "--dump-dom",
                              "file://" + page.string()},
                             dir.path());
  std::smatch widths;
  const std::string output = dom.output;
  ASSERT_TRUE(std::regex_search(output, widths, std::regex(R"re(data-widths="([0-9]+) ([0-9]+)")re")))
      << output.substr(output.size() > 2000 ? output.size() - 2000 : 0);
  EXPECT_LE(std::stoi(widths[1].str()), std::stoi(widths[2].str())) << "the page scrolls sideways";
  EXPECT_EQ(std::stoi(widths[2].str()), 1400);
}
