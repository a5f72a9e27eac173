#include "vsd/sim/activity.hpp"

#include <algorithm>
#include <chrono>
#include <cstring>

namespace vsd {

namespace {
// One record per process, like the process's pid: installed by the worker pool
// in a freshly forked worker, absent everywhere else.
ActivityRecord* g_record = nullptr;

std::int64_t nowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}
}  // namespace

const char* activityName(Activity activity) {
  switch (activity) {
    case Activity::Idle: return "idle";
    case Activity::Netconvert: return "netconvert";
    case Activity::SumoLoad: return "libsumo loading the simulation";
    case Activity::SumoVehicles: return "libsumo handling the scenario's vehicles";
    case Activity::SumoStep: return "libsumo simulation step";
    case Activity::Controller: return "Ego controller";
  }
  return "unknown";
}

ActivityRecord::Snapshot ActivityRecord::snapshot() const {
  Snapshot copy;
  copy.activity = static_cast<Activity>(activity.load());
  copy.seconds = static_cast<double>(nowNs() - sinceNs.load()) * 1e-9;
  copy.subject = subject.load();
  copy.time = time.load();
  copy.unit = unit.load();
  copy.marker = marker.load();
  copy.label.assign(label, strnlen(label, sizeof(label)));
  return copy;
}

void setActivityRecord(ActivityRecord* record) { g_record = record; }

void reportActivity(Activity activity) {
  if (!g_record) return;
  g_record->sinceNs.store(nowNs(), std::memory_order_relaxed);
  g_record->activity.store(static_cast<int>(activity), std::memory_order_release);
}

void reportSubject(std::int64_t subject, const std::string& label) {
  if (!g_record) return;
  const std::size_t size = std::min(label.size(), sizeof(g_record->label) - 1);
  std::memcpy(g_record->label, label.data(), size);
  g_record->label[size] = '\0';
  g_record->subject.store(subject, std::memory_order_release);
}

void reportSimulationTime(double time) {
  if (g_record) g_record->time.store(time, std::memory_order_relaxed);
}

void reportUnit(std::int64_t unit) {
  if (g_record) g_record->unit.store(unit, std::memory_order_release);
}

void reportMarker(std::int64_t marker) {
  if (g_record) g_record->marker.store(marker, std::memory_order_release);
}

ActivityScope::ActivityScope(Activity activity)
    : previous_(g_record ? static_cast<Activity>(g_record->activity.load()) : Activity::Idle) {
  reportActivity(activity);
}

ActivityScope::~ActivityScope() { reportActivity(previous_); }

}  // namespace vsd
