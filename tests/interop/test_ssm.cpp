// Criticality measures cross-checked against SUMO's SSM device (issue 16): the same
// vehicles at the same instants, replayed with tools/replay_fcd.py (following on a
// lane), and SUMO's own vehicles on a crossing (post-encroachment time).

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <libsumo/libsumo.h>
#include <pugixml.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

#include "test_support.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/metrics/metrics.hpp"
#include "vsd/pipeline/run.hpp"
#include "vsd/sim/sumo_session.hpp"

using namespace vsd;
namespace fs = std::filesystem;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// One SSM time series by time (s, rounded to ms); NaN where SSM writes NA.
using Series = std::map<long, double>;
long millis(double seconds) { return std::lround(seconds * 1000.0); }

Series parseSeries(const pugi::xml_node& parent, const char* name) {
  Series series;
  std::istringstream times(parent.child("timeSpan").attribute("values").value());
  std::istringstream values(parent.child(name).attribute("values").value());
  std::string time;
  std::string value;
  while (times >> time && values >> value) series[millis(std::stod(time))] = value == "NA" ? kNaN : std::stod(value);
  return series;
}

/// SSM's series of the device on `ego` against `foe`: TTC and DRAC from the conflict, SGAP and TGAP from the global measures.
std::map<std::string, Series> ssmSeries(const pugi::xml_document& log, const std::string& ego, const std::string& foe) {
  std::map<std::string, Series> result;
  for (const pugi::xml_node& node : log.child("SSMLog").children()) {
    if (std::string(node.attribute("ego").value()) != ego) continue;
    if (std::string(node.name()) == "conflict" && std::string(node.attribute("foe").value()) == foe) {
      result["TTC"] = parseSeries(node, "TTCSpan");
      result["DRAC"] = parseSeries(node, "DRACSpan");
    } else if (std::string(node.name()) == "globalMeasures") {
      result["SGAP"] = parseSeries(node, "SGAPSpan");
      result["TGAP"] = parseSeries(node, "TGAPSpan");
    }
  }
  return result;
}

/// The trace with only instant k valid: every metric then measures that instant.
Trace atInstant(const Trace& trace, std::size_t k) {
  Trace single = trace;
  for (auto& track : single.vehicles) {
    for (std::size_t j = 0; j < track.valid.size(); ++j) track.valid[j] = j == k ? track.valid[j] : 0;
  }
  return single;
}

struct Replayed {
  std::vector<pipeline::ScenarioOutcome> outcomes;
  pugi::xml_document ssm;
};

/// Runs `scenario` with FCD output (6 decimals, so the replay is exact), replays batch 0
/// with SSM devices on every vehicle and returns the outcomes and SSM's log.
void runAndReplay(const std::string& scenario, std::uint64_t samples, const fs::path& work, Replayed& replayed) {
  const auto file = test::writeFile(work / (scenario + ".yaml"),
                                    readTextFile(test::scenarioFile(scenario + ".yaml")) +
                                        "\nsumo:\n  sumo_options: [\"--precision\", \"6\"]\n");
  pipeline::RunOptions options;
  options.scenarioFile = file;
  options.outputDir = work / "run";
  options.samples = samples;
  options.seed = 5;
  options.fcd = true;
  pipeline::runScenarios(options, [&](const pipeline::ScenarioOutcome& outcome) { replayed.outcomes.push_back(outcome); });
  const fs::path log = work / "ssm.xml";
  const auto result = test::run({test::python(), (test::sourceDir() / "tools" / "replay_fcd.py").string(),
                                 options.outputDir.string(), "--check", "--sumo-option",
                                 "--precision 6 --device.ssm.probability 1 --device.ssm.measures 'TTC DRAC SGAP TGAP' "
                                 "--device.ssm.thresholds '1000 0 1000 1000' --device.ssm.trajectories true "
                                 "--device.ssm.range 500 --device.ssm.extratime 0 --device.ssm.file " +
                                     log.string()},
                                work);
  ASSERT_EQ(result.exitCode, 0) << result.output;
  ASSERT_TRUE(replayed.ssm.load_file(log.c_str())) << log;
}

/// Metric values at every instant of an outcome, by metric name.
std::map<std::string, std::vector<double>> metricsPerInstant(const pipeline::ScenarioOutcome& outcome,
                                                             const std::vector<std::string>& names) {
  const metrics::MetricSet set(names, {true, true, true}, "test");
  const Polyline& lane = outcome.lanes.at(static_cast<std::size_t>(outcome.egoLane)).centre;
  std::map<std::string, std::vector<double>> values;
  for (std::size_t k = 0; k < outcome.trace.instants(); ++k) {
    const Trace single = atInstant(outcome.trace, k);
    const auto row = set.evaluate({single, lane});
    for (std::size_t m = 0; m < names.size(); ++m) values[names[m]].push_back(row[m]);
  }
  return values;
}

double ssmAt(const std::map<std::string, Series>& series, const std::string& measure, double time) {
  const auto it = series.find(measure);
  if (it == series.end()) return kNaN;
  const auto value = it->second.find(millis(time));
  return value == it->second.end() ? kNaN : value->second;
}

}  // namespace

// The lane variants use SSM's convention (gap along the Ego's lane between bumpers, scalar
// speed difference): they agree with SSM at every instant up to its output precision.
// The straight-line measures differ by convention; on a curved road their gap is the chord.
TEST(SsmCrossCheck, FollowingOnCurvedRoadsMatchesSsmAtEveryInstant) {
  TemporaryDirectory work("vsd-ssm-acc-lk");
  Replayed replayed;
  runAndReplay("acc_lk", 20, work.path(), replayed);
  const std::vector<std::string> names = {"gap_min_lane", "ttc_min_lane", "thw_min_lane", "drac_max_lane", "d_lon_min"};
  std::size_t compared = 0;
  for (const auto& outcome : replayed.outcomes) {
    ASSERT_TRUE(outcome.ok()) << outcome.failure;
    const auto ssm = ssmSeries(replayed.ssm, fmt::format("s{}.ego", outcome.index), fmt::format("s{}.co", outcome.index));
    const auto ours = metricsPerInstant(outcome, names);
    for (std::size_t k = 0; k < outcome.trace.instants(); ++k) {
      const double time = static_cast<double>(k) * outcome.trace.step;
      const std::string where = fmt::format("sample {} t = {:.1f} s", outcome.index, time);
      const double sgap = ssmAt(ssm, "SGAP", time);
      if (std::isnan(sgap)) continue;
      ++compared;
      EXPECT_NEAR(ours.at("gap_min_lane")[k], sgap, 0.01) << where;
      if (outcome.trace.ego().states[k].speed > 0.1) {  // headway needs a moving Ego
        EXPECT_NEAR(ours.at("thw_min_lane")[k], ssmAt(ssm, "TGAP", time), 0.01) << where;
      }
      const double ttc = ssmAt(ssm, "TTC", time);
      if (!std::isnan(ttc) && ttc < 10.0) {
        EXPECT_NEAR(ours.at("ttc_min_lane")[k], ttc, 0.01) << where;
      }
      const double drac = ssmAt(ssm, "DRAC", time);
      if (!std::isnan(drac)) {
        EXPECT_NEAR(ours.at("drac_max_lane")[k], drac, 0.01) << where;
      }
      // The straight gap between centres is nearly a chord of the lane: longer only by what
      // lateral offsets on the outside of a bend add (<= 0.1 m), and within 0.25 m where the
      // vehicles are close (<= 10 m).
      EXPECT_LE(ours.at("d_lon_min")[k], sgap + 0.1) << where;
      if (sgap <= 10.0) {
        EXPECT_NEAR(ours.at("d_lon_min")[k], sgap, 0.25) << where;
      }
    }
  }
  EXPECT_GT(compared, 400u);
}

// On straight roads (acc, whose lane still zigzags by the centre noise) the straight-line
// measures agree with SSM's within the tolerances the README states.
TEST(SsmCrossCheck, StraightLineMeasuresAgreeWithSsmOnStraightRoads) {
  TemporaryDirectory work("vsd-ssm-acc");
  Replayed replayed;
  runAndReplay("acc", 20, work.path(), replayed);
  const std::vector<std::string> names = {"d_lon_min", "ttc_min", "drac_max"};
  const metrics::MetricSet set(names, {true, true, true}, "test");
  std::vector<double> ttc_differences;
  for (const auto& outcome : replayed.outcomes) {
    const auto ssm = ssmSeries(replayed.ssm, fmt::format("s{}.ego", outcome.index), fmt::format("s{}.co", outcome.index));
    const auto values = set.evaluate({outcome.trace, outcome.lanes.at(0).centre});
    double min_sgap = std::numeric_limits<double>::infinity();
    double min_ttc = std::numeric_limits<double>::infinity();
    double max_drac = 0.0;
    for (const auto& [time, value] : ssm.at("SGAP")) min_sgap = std::isnan(value) ? min_sgap : std::min(min_sgap, value);
    for (const auto& [time, value] : ssm.at("TTC")) min_ttc = std::isnan(value) ? min_ttc : std::min(min_ttc, value);
    for (const auto& [time, value] : ssm.at("DRAC")) max_drac = std::isnan(value) ? max_drac : std::max(max_drac, value);
    const std::string where = fmt::format("sample {}", outcome.index);
    EXPECT_NEAR(values[0], min_sgap, 0.25) << where;
    if (min_ttc < 10.0) {  // projected vs scalar speeds: a relative difference
      EXPECT_NEAR(values[1], min_ttc, 0.12 * min_ttc) << where;
      ttc_differences.push_back(std::abs(values[1] - min_ttc));
    }
    EXPECT_NEAR(values[2], max_drac, 0.05) << where;
  }
  ASSERT_GT(ttc_differences.size(), 5u);
  std::nth_element(ttc_differences.begin(), ttc_differences.begin() + ttc_differences.size() / 2, ttc_differences.end());
  EXPECT_LE(ttc_differences[ttc_differences.size() / 2], 0.1) << "median TTC difference";
}

namespace {

/// A four-arm priority junction at the origin, arms 200 m long, one 3.2 m lane each.
fs::path crossingNetwork(const fs::path& work) {
  test::writeFile(work / "cross.nod.xml", R"(<nodes>
  <node id="c" x="0" y="0" type="priority"/>
  <node id="w" x="-200" y="0"/> <node id="e" x="200" y="0"/>
  <node id="s" x="0" y="-200"/> <node id="n" x="0" y="200"/>
</nodes>)");
  test::writeFile(work / "cross.edg.xml", R"(<edges>
  <edge id="wc" from="w" to="c" priority="2" numLanes="1" width="3.2" speed="30"/>
  <edge id="ce" from="c" to="e" priority="2" numLanes="1" width="3.2" speed="30"/>
  <edge id="sc" from="s" to="c" priority="1" numLanes="1" width="3.2" speed="30"/>
  <edge id="cn" from="c" to="n" priority="1" numLanes="1" width="3.2" speed="30"/>
</edges>)");
  const fs::path net = work / "cross.net.xml";
  const auto result = test::run({"netconvert", "--node-files", (work / "cross.nod.xml").string(), "--edge-files",
                                 (work / "cross.edg.xml").string(), "--output-file", net.string(), "--no-turnarounds",
                                 "true"},
                                work);
  if (result.exitCode != 0) throw std::runtime_error(result.output);
  return net;
}

void recordState(VehicleTrack& track, std::size_t k, const std::string& id) {
  const auto front = libsumo::Vehicle::getPosition(id);
  const double heading = headingFromSumoAngle(libsumo::Vehicle::getAngle(id));
  const Vec2 centre = Vec2(front.x, front.y) - 0.5 * track.length * headingVector(heading);
  track.states[k] = {centre.x(), centre.y(), heading, libsumo::Vehicle::getSpeed(id), 0.0};
  track.valid[k] = 1;
}

struct Crossing {
  double speedA = 10.0;  ///< m/s, west -> east
  double speedB = 10.0;  ///< m/s, south -> north
  double startB = 150.0; ///< m, B's depart position on its arm (A departs at 150 m)
};

/// SSM's PET and the trace of A (Ego) and B crossing the junction at constant speeds.
std::pair<double, Trace> simulateCrossing(const fs::path& net, const Crossing& crossing, const fs::path& work) {
  // One log per simulation: SUMO keeps its output devices by file name for the whole process.
  static int simulations = 0;
  const fs::path log = work / fmt::format("ssm_pet_{}.xml", simulations++);
  constexpr double kStep = 0.2;
  constexpr std::size_t kInstants = 101;
  Trace trace;
  trace.step = kStep;
  trace.vehicles.resize(2);
  for (auto& track : trace.vehicles) {
    track.length = 5.0;
    track.width = 1.8;
    track.states.resize(kInstants);
    track.valid.assign(kInstants, 0);
  }
  {
    sim::SumoSession session({"--net-file", net.string(), "--step-length", fmt::format("{}", kStep), "--precision", "6",
                              "--collision.action", "none", "--xml-validation", "never", "--device.ssm.probability",
                              "1", "--device.ssm.measures", "PET", "--device.ssm.thresholds", "100",
                              "--device.ssm.range", "200", "--device.ssm.extratime", "20", "--device.ssm.file",
                              log.string()});
    libsumo::Route::add("we", {"wc", "ce"});
    libsumo::Route::add("sn", {"sc", "cn"});
    const std::vector<std::tuple<std::string, std::string, double, double>> vehicles = {
        {"a", "we", 150.0, crossing.speedA}, {"b", "sn", crossing.startB, crossing.speedB}};
    for (const auto& [id, route, position, speed] : vehicles) {
      libsumo::Vehicle::add(id, route, "DEFAULT_VEHTYPE", "now", "0", fmt::format("{}", position), fmt::format("{}", speed));
      libsumo::Vehicle::setSpeedMode(id, 0);  // ignores right of way: both drive through
      libsumo::Vehicle::setSpeed(id, speed);
    }
    for (std::size_t k = 0; k < kInstants; ++k) {
      session.step();
      const auto alive = libsumo::Vehicle::getIDList();
      for (std::size_t v = 0; v < 2; ++v) {
        const std::string id = v == 0 ? "a" : "b";
        if (std::find(alive.begin(), alive.end(), id) != alive.end()) recordState(trace.vehicles[v], k, id);
      }
    }
  }
  pugi::xml_document document;
  if (!document.load_file(log.c_str())) throw std::runtime_error("no SSM log " + log.string());
  double pet = std::numeric_limits<double>::infinity();
  for (const pugi::xml_node& conflict : document.child("SSMLog").children("conflict")) {
    const std::string value = conflict.child("PET").attribute("value").value();
    if (!value.empty() && value != "NA") pet = std::min(pet, std::stod(value));
  }
  return {pet, trace};
}

}  // namespace

// PET on a crossing: SSM's conflict area is the other vehicle's width around the
// crossing point, entered with the front and left with the rear; pet_min uses the same
// area (width / sin of the crossing angle - equal at right angles) on the recorded paths.
TEST(SsmCrossCheck, PostEncroachmentTimeOnACrossingMatchesSsm) {
  TemporaryDirectory work("vsd-ssm-pet");
  const fs::path net = crossingNetwork(work.path());
  const metrics::MetricSet set({"pet_min"}, {true, false, false}, "test");
  const Polyline no_lane;
  for (const Crossing& crossing :
       {Crossing{12.0, 8.0, 150.0}, Crossing{9.0, 14.0, 100.0}, Crossing{10.0, 10.0, 120.0}, Crossing{15.0, 5.0, 170.0}}) {
    const auto [ssm_pet, trace] = simulateCrossing(net, crossing, work.path());
    const double pet = set.evaluate({trace, no_lane})[0];
    const std::string where = fmt::format("speeds {} / {} m/s, B from {} m", crossing.speedA, crossing.speedB, crossing.startB);
    ASSERT_TRUE(std::isfinite(ssm_pet)) << where;
    EXPECT_GT(ssm_pet, 0.2) << where;
    EXPECT_NEAR(pet, ssm_pet, 0.01) << where;
  }
}
