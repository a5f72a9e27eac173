#pragma once
// The cut-ins whose outcome a source states, run in the kinematic harness
// (cut_in_harness.hpp), and the regulation's comparison grid: what `vsd-sumo bench
// reference` computes and writes to results/reference_driver/.
//
// Documented cases (each names its source; docs/controllers.md quotes them):
//   - UN R157 Annex 4 Appendix 3, Table 1 (01 series: Annex 3, Table 1): the competent and
//     careful driver starts braking 0.4 s + 0.75 s after the risk perception point (the
//     cut-in vehicle's centre 0.375 m off its lane's centre) and reaches 0.774 g 0.6 s later
//     (0.85 g once the cut-in vehicle fully wraps the Ego) - r157_reference_driver's brake
//     onset and full deceleration, at several lateral speeds, from either side;
//   - ASAM OSC-ALKS-scenarios 4.4_1 "CutInNoCollision" and 4.4_2 "CutInUnavoidableCollision"
//     (the templates' parameters): the reference driver avoids the first and collides in
//     the second;
//   - UN R157 paragraph 5.2.5.2: an ALKS avoids every cut-in of a slower vehicle whose
//     lateral movement was visible for at least 0.72 s and whose TTC at lane intrusion
//     exceeds v_rel / (2 * 6 m/s^2) + 0.35 s - the `alks` controller on a grid of them.

#include <filesystem>
#include <string>
#include <vector>

#include "vsd/sim/controller.hpp"
#include "vsd/sim/cut_in_harness.hpp"

namespace vsd::sim {

struct DocumentedCase {
  enum class Check {
    Avoids,        ///< no collision
    Collides,      ///< a collision
    BrakeOnset,    ///< braking starts at `expected` s (within one step)
    FullDecel,     ///< the deceleration reaches `decel` at `expected` s (within one step)
  };
  std::string id;
  std::string source;      ///< the document and its paragraph, table or file
  std::string statement;   ///< what it states about this case
  std::string controller;  ///< registry name of the controller checked
  CutIn cutIn;
  Check check = Check::Avoids;
  double expected = 0.0;  ///< s (BrakeOnset, FullDecel)
  double decel = 0.0;     ///< m/s^2 (FullDecel)
};

struct CaseResult {
  DocumentedCase documented;
  CutInOutcome outcome;
  bool pass = false;
  std::string measured;  ///< what the harness measured, in words
};

/// Every documented case, in a fixed order.
std::vector<DocumentedCase> documentedCases();

/// Runs `documented` with a fresh controller of `registry`.
CaseResult runDocumentedCase(const ControllerRegistry& registry, const DocumentedCase& documented);

/// One cell of the comparison grid: ASAM's variation of 4.4 (cut-in) - Ego speed 20 ... 60
/// km/h, the cut-in vehicle 10 ... 50 km/h slower (never below 10 km/h), dx0 0 ... 60 m,
/// lateral speed 0.5 ... 3 m/s, from the left - with each compared controller.
struct GridResult {
  CutIn cutIn;
  std::vector<CutInOutcome> outcomes;  ///< in the order of gridControllers()
};

/// The controllers the grid compares: r157_reference_driver, fsm, alks.
const std::vector<std::string>& gridControllers();

std::vector<GridResult> runGrid(const ControllerRegistry& registry);

/// Writes cases.csv, grid.csv and README.md (the summary, naming `command` and the tool's
/// version) to `folder` as one output set (OutputFolder: manifest last, with the full
/// `invocation`). Returns the number of documented cases on the wrong side.
int writeReferenceReport(const std::filesystem::path& folder, const std::vector<CaseResult>& cases,
                         const std::vector<GridResult>& grid, const std::string& command, const std::string& invocation);

}  // namespace vsd::sim
