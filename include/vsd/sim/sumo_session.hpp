#pragma once
// RAII around a libsumo simulation. libsumo holds one simulation per process:
// opening a second session while one is open throws SumoError.
//
// This header keeps libsumo's own headers out of other modules.

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "vsd/core/geometry.hpp"

namespace vsd::sim {

class SumoSession {
 public:
  /// Loads a simulation with the given SUMO command-line arguments (without
  /// the program name), e.g. {"-n", "net.net.xml", "--step-length", "0.2"}.
  /// Quiet defaults (no step log, no warnings on stdout) are prepended.
  /// Throws SumoError "SUMO could not load <input files>: <SUMO's own error lines>"
  /// if loading fails (SUMO's stderr is read for the reason, not shown).
  explicit SumoSession(const std::vector<std::string>& arguments);
  SumoSession(const SumoSession&) = delete;
  SumoSession& operator=(const SumoSession&) = delete;
  ~SumoSession();

  /// Advances one step; throws SumoError "SUMO failed at t = <simulation time> s
  /// (simulating <input files>): <SUMO's own error lines>".
  void step();
  /// Simulation time in s.
  double time() const;

  /// "Eclipse SUMO sumo Version 1.15.0" (from libsumo, no simulation needed).
  static std::string version();

 private:
  class ErrorCapture;
  std::string inputs_;  ///< the input files, for messages
  std::unique_ptr<ErrorCapture> capture_;
  bool open_ = false;
};

/// Lane `lane_id`'s shape and width from the loaded SUMO network, shifted by -offset.
LaneGeometry fetchLane(const std::string& lane_id, const Vec2& offset);

}  // namespace vsd::sim
