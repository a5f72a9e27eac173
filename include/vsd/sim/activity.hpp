#pragma once
// What a worker process is doing right now, written into memory that its
// supervising parent shares (pipeline::WorkerPool maps it). The parent's
// watchdog reads how long the current activity has lasted, and after the worker
// died it reads what the worker was doing — whose Ego controller, which SUMO
// step — to record the fault against the right scenario or Ego.
//
// Without an installed record (the default, e.g. in the parent) every call is a
// no-op. Reporting costs a few atomic stores and one steady-clock read.

#include <atomic>
#include <cstdint>
#include <string>

namespace vsd {

enum class Activity : int {
  Idle = 0,    ///< between units of work, or sending results (not watched)
  Netconvert,  ///< waiting for netconvert
  SumoLoad,    ///< libsumo loads a simulation
  SumoVehicles,  ///< libsumo calls for one scenario's vehicles: adding, observing, placing the Ego (subject set)
  SumoStep,    ///< one libsumo simulation step
  Controller,  ///< inside an Ego controller (subject set): create, reset or step
};

/// "controller", "SUMO step", ... (for failure messages).
const char* activityName(Activity activity);

/// The shared record. Lives in a MAP_SHARED mapping; only lock-free atomics and
/// a character buffer (read by the parent only while the writer is stopped).
struct ActivityRecord {
  std::atomic<int> activity{0};
  std::atomic<std::int64_t> sinceNs{0};   ///< steady clock when the activity began
  std::atomic<std::int64_t> subject{-1};  ///< concrete scenario (sample index), -1: none
  std::atomic<double> time{0.0};          ///< simulation time, s
  std::atomic<std::int64_t> unit{-1};     ///< the unit of work within a job (e.g. a group of scenarios simulated together)
  std::atomic<std::int64_t> marker{-1};   ///< free for the body (e.g. the last batch whose network is ready)
  char label[128] = {};                   ///< e.g. the Ego id of a map export

  /// A copy of the fields (label as a string).
  struct Snapshot {
    Activity activity = Activity::Idle;
    double seconds = 0.0;  ///< how long it has lasted
    std::int64_t subject = -1;
    double time = 0.0;
    std::int64_t unit = -1;
    std::int64_t marker = -1;
    std::string label;
  };
  Snapshot snapshot() const;
};

/// Installs the record this process reports into (nullptr: none).
void setActivityRecord(ActivityRecord* record);
/// Starts `activity` now.
void reportActivity(Activity activity);
/// Sets the subject (sample index, -1 for none) and label (e.g. an Ego id) of what follows.
void reportSubject(std::int64_t subject, const std::string& label = {});
/// Sets the simulation time (s).
void reportSimulationTime(double time);
/// Sets the unit of work.
void reportUnit(std::int64_t unit);
/// Sets the marker.
void reportMarker(std::int64_t marker);

/// Reports `activity` for its lifetime, then the one before it.
class ActivityScope {
 public:
  explicit ActivityScope(Activity activity);
  ActivityScope(const ActivityScope&) = delete;
  ActivityScope& operator=(const ActivityScope&) = delete;
  ~ActivityScope();

 private:
  Activity previous_;
};

}  // namespace vsd
