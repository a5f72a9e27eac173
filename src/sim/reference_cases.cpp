#include "vsd/sim/reference_cases.hpp"

#include <fmt/format.h>

#include <cmath>

namespace vsd::sim {

namespace {

constexpr double kGravity = 9.81;  ///< m/s^2, the regulation's g as the reference driver uses it
constexpr double kKmh = 1.0 / 3.6;

const char* const kTable1 =
    "UN R157 (E/ECE/TRANS/505/Rev.3/Add.156) Annex 4 Appendix 3 Table 1; 01 series Annex 3 Table 1";
const char* const kAsam = "ASAM OSC-ALKS-scenarios, Scenarios/ALKS_Scenario_4.4_{}_TEMPLATE.xosc";
const char* const kParagraph5252 = "UN R157 paragraph 5.2.5.2";

/// The eyes of the human driver models: 100 m ahead (esmini's ALKS_R157SM reference driver
/// looks as far), the neighbouring lanes beside.
ObjectSensor humanEyes() {
  ObjectSensor sensor;
  sensor.forwardRange = 100.0;
  return sensor;
}

CutIn cutIn(double ego_kmh, double target_kmh, double gap, double lateral_speed, int from_lane) {
  CutIn cut_in;
  cut_in.egoSpeed = ego_kmh * kKmh;
  cut_in.targetSpeed = target_kmh * kKmh;
  cut_in.gap = gap;
  cut_in.lateralSpeed = lateral_speed;
  cut_in.fromLane = from_lane;
  return cut_in;
}

/// Table 1's timeline at lateral speed `vy` from `side`: a 60 km/h Ego, a 40 km/h car whose
/// gap leaves a time to collision of 1.5 s (critical) when the risk evaluation ends.
void addTimelineCases(std::vector<DocumentedCase>& cases, double vy, int side) {
  CutIn cut_in = cutIn(60.0, 40.0, 0.0, vy, side);
  cut_in.sensor = humanEyes();
  const double perceived = cutInTimeAtDeviation(cut_in, 0.375);
  const double evaluated = perceived + 0.4;
  cut_in.gap = (cut_in.egoSpeed - cut_in.targetSpeed) * (evaluated + 1.5);
  const double onset = evaluated + 0.75;
  const std::string where = fmt::format("vy{:.1f}{}", vy, side > 0 ? "" : "_right");
  DocumentedCase onset_case{"table1.onset." + where, kTable1,
                            fmt::format("perception when the cut-in's centre is 0.375 m off its lane ({:.4f} s), "
                                        "braking 0.4 s + 0.75 s later ({:.4f} s)",
                                        perceived, onset),
                            "r157_reference_driver", cut_in, DocumentedCase::Check::BrakeOnset, onset, 0.0};
  cases.push_back(onset_case);
  const double wrapped = cut_in.laneWidth / vy;  // equal widths: a full wrap once it is on the Ego's lane centre
  const bool before = wrapped <= onset;
  if (!before && wrapped < onset + 0.6) return;  // the cap changes while rising: no single row applies
  const double g = before ? 0.85 : 0.774;
  DocumentedCase full{"table1.full_decel." + where, kTable1,
                      fmt::format("the deceleration rises to {} g in 0.6 s{} ({:.4f} s)", g,
                                  before ? " (after full wrap)" : "", onset + 0.6),
                      "r157_reference_driver", cut_in, DocumentedCase::Check::FullDecel, onset + 0.6, g * kGravity};
  cases.push_back(full);
}

void addAsamCases(std::vector<DocumentedCase>& cases) {
  // The templates: Ego 60 km/h, the cut-in vehicle 20 km/h slower in the lane to the right
  // (RelativeLaneId -1), starting when the gap falls to dx0 = 30 m at Vy = 2 m/s / 10 m at 3 m/s.
  CutIn avoidable = cutIn(60.0, 40.0, 30.0, 2.0, -1);
  avoidable.sensor = humanEyes();
  cases.push_back({"asam.4.4_1", fmt::format(kAsam, "1_CutInNoCollision"),
                   "CutInNoCollision (dx0 30 m, Vy 2 m/s): no collision", "r157_reference_driver", avoidable,
                   DocumentedCase::Check::Avoids, 0.0, 0.0});
  CutIn unavoidable = cutIn(60.0, 40.0, 10.0, 3.0, -1);
  unavoidable.sensor = humanEyes();
  cases.push_back({"asam.4.4_2", fmt::format(kAsam, "2_CutInUnavoidableCollision"),
                   "CutInUnavoidableCollision (dx0 10 m, Vy 3 m/s): a collision", "r157_reference_driver", unavoidable,
                   DocumentedCase::Check::Collides, 0.0, 0.0});
}

/// Paragraph 5.2.5.2: TTC at lane intrusion (the cut-in's side 0.3 m inside the Ego's lane)
/// above v_rel / 12 + 0.35 s, the lateral movement visible for 0.72 s or more before.
void addParagraph5252Cases(std::vector<DocumentedCase>& cases) {
  const double car_width = roadUserKind(RoadUserType::Car).width;
  for (double ego : {30.0, 40.0, 50.0, 60.0}) {
    for (double slower : {10.0, 20.0, 30.0}) {
      if (ego - slower < 10.0) continue;
      for (double vy : {0.5, 1.0, 1.5}) {
        for (double margin : {0.05, 0.5}) {
          CutIn cut_in = cutIn(ego, ego - slower, 0.0, vy, 1);
          const double v_rel = cut_in.egoSpeed - cut_in.targetSpeed;
          const double intrusion = (0.5 * cut_in.laneWidth + 0.3 - 0.5 * car_width) / vy;  // s, >= 0.72 s here
          const double ttc = v_rel / 12.0 + 0.35 + margin;
          cut_in.gap = v_rel * (ttc + intrusion);
          cases.push_back({fmt::format("r157.5.2.5.2.v{:.0f}.dv{:.0f}.vy{:.1f}.m{:.2f}", ego, slower, vy, margin),
                           kParagraph5252,
                           fmt::format("TTC at lane intrusion {:.2f} s > {:.2f} s: the ALKS avoids a collision", ttc,
                                       ttc - margin),
                           "alks", cut_in, DocumentedCase::Check::Avoids, 0.0, 0.0});
        }
      }
    }
  }
}

std::unique_ptr<EgoController> makeFresh(const ControllerRegistry& registry, const std::string& name) {
  auto controller = registry.create(name);
  controller->init(ControllerParams({}, "bench reference: " + name));
  controller->reset();
  return controller;
}

std::string describe(const CutInOutcome& outcome) {
  if (outcome.collision) {
    return fmt::format("collision at {:.2f} s, {:.2f} m/s closing", outcome.collisionTime, outcome.impactSpeed);
  }
  return fmt::format("no collision, min clearance {:.2f} m", outcome.minClearance);
}

}  // namespace

std::vector<DocumentedCase> documentedCases() {
  std::vector<DocumentedCase> cases;
  for (double vy : {0.5, 1.0, 1.5, 2.0, 3.0}) addTimelineCases(cases, vy, 1);
  addTimelineCases(cases, 1.0, -1);
  addAsamCases(cases);
  addParagraph5252Cases(cases);
  return cases;
}

CaseResult runDocumentedCase(const ControllerRegistry& registry, const DocumentedCase& documented) {
  auto controller = makeFresh(registry, documented.controller);
  CaseResult result;
  result.documented = documented;
  result.outcome = simulateCutIn(*controller, documented.cutIn, documented.decel);
  const CutInOutcome& outcome = result.outcome;
  const double step = documented.cutIn.step;
  switch (documented.check) {
    case DocumentedCase::Check::Avoids:
      result.pass = !outcome.collision;
      result.measured = describe(outcome);
      break;
    case DocumentedCase::Check::Collides:
      result.pass = outcome.collision;
      result.measured = describe(outcome);
      break;
    case DocumentedCase::Check::BrakeOnset:
      // The first braking step holds the onset: it starts at most one step before it.
      result.pass = outcome.brakeOnset <= documented.expected + 1e-9 && outcome.brakeOnset > documented.expected - step - 1e-9;
      result.measured = fmt::format("braking from the step starting at {:.2f} s", outcome.brakeOnset);
      break;
    case DocumentedCase::Check::FullDecel:
      result.pass = std::abs(outcome.decelMarkTime - documented.expected) <= step + 1e-9;
      result.measured = fmt::format("{:.2f} m/s^2 from the step starting at {:.2f} s", documented.decel,
                                    outcome.decelMarkTime);
      break;
  }
  return result;
}

const std::vector<std::string>& gridControllers() {
  static const std::vector<std::string> kControllers{"r157_reference_driver", "fsm", "alks"};
  return kControllers;
}

std::vector<GridResult> runGrid(const ControllerRegistry& registry) {
  std::vector<GridResult> grid;
  for (int ego = 20; ego <= 60; ego += 10) {           // km/h
    for (int slower = 10; slower <= 50 && ego - slower >= 10; slower += 10) {  // km/h
      for (int gap = 0; gap <= 60; gap += 10) {        // m
        for (int vy = 1; vy <= 6; ++vy) {              // 0.5 m/s
          GridResult cell;
          cell.cutIn = cutIn(ego, ego - slower, gap, 0.5 * vy, 1);
          for (const auto& name : gridControllers()) {
            CutIn cut_in = cell.cutIn;
            if (name != "alks") cut_in.sensor = humanEyes();
            auto controller = makeFresh(registry, name);
            cell.outcomes.push_back(simulateCutIn(*controller, cut_in));
          }
          grid.push_back(cell);
        }
      }
    }
  }
  return grid;
}

}  // namespace vsd::sim
