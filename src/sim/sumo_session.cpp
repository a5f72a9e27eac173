#include "vsd/sim/sumo_session.hpp"

#include <fmt/format.h>
#include <libsumo/libsumo.h>
#include <unistd.h>

#include <cstdio>
#include <iostream>
#include <set>
#include <sstream>

#include "vsd/sim/activity.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/fault.hpp"
#include "vsd/road/network.hpp"

namespace vsd::sim {

namespace {
// libsumo's simulation is process-global; this mirrors that fact (it is not a registry).
bool g_session_open = false;

/// The input files among SUMO arguments ("map.sumocfg", "a.net.xml, b.rou.xml"), for messages.
std::string inputsOf(const std::vector<std::string>& arguments) {
  static const std::set<std::string> kFileOptions = {"-c", "--configuration-file", "-n", "--net-file", "-r",
                                                     "--route-files", "-a", "--additional-files"};
  std::vector<std::string> files;
  for (std::size_t i = 0; i + 1 < arguments.size(); ++i) {
    if (kFileOptions.count(arguments[i])) files.push_back(arguments[i + 1]);
  }
  return files.empty() ? fmt::format("{}", fmt::join(arguments, " ")) : fmt::format("{}", fmt::join(files, ", "));
}

}  // namespace

/// SUMO writes the reason of a failure to stderr ("Error: Departure speed for vehicle
/// ... is too high ...") and then throws an exception that says only "Process Error" or
/// the like. While libsumo runs, stderr goes to a private temporary file; what SUMO
/// wrote there becomes part of the one-line error. Anything else (warnings) is passed on
/// to stderr unchanged when the call succeeds, and dropped when it fails: the error is
/// then the one line the user sees.
class SumoSession::ErrorCapture {
 public:
  ErrorCapture() : file_(std::tmpfile()) {}
  ~ErrorCapture() {
    if (file_ != nullptr) std::fclose(file_);
  }
  ErrorCapture(const ErrorCapture&) = delete;
  ErrorCapture& operator=(const ErrorCapture&) = delete;

  /// Redirects stderr for the lifetime of the returned guard.
  class Guard {
   public:
    explicit Guard(ErrorCapture& capture) : capture_(capture) {
      if (capture_.file_ == nullptr) return;
      std::cerr.flush();
      std::fflush(stderr);
      start_ = ::lseek(::fileno(capture_.file_), 0, SEEK_END);
      saved_ = ::dup(STDERR_FILENO);
      if (saved_ >= 0) ::dup2(::fileno(capture_.file_), STDERR_FILENO);
    }
    ~Guard() {
      if (saved_ < 0) return;
      std::cerr.flush();
      std::fflush(stderr);
      ::dup2(saved_, STDERR_FILENO);
      ::close(saved_);
      capture_.collect(start_);
    }
    Guard(const Guard&) = delete;
    Guard& operator=(const Guard&) = delete;

   private:
    ErrorCapture& capture_;
    int saved_ = -1;
    off_t start_ = 0;
  };

  /// SUMO's error lines since the last call (without "Error: "), joined by "; "; empty
  /// if none. The other lines are passed on to stderr if `succeeded`, else dropped.
  std::string take(bool succeeded) {
    if (succeeded && !passed_.empty()) std::cerr << passed_ << std::flush;
    passed_.clear();
    std::string joined;
    for (const auto& line : errors_) joined += (joined.empty() ? "" : "; ") + line;
    errors_.clear();
    return joined;
  }

 private:
  /// Reads what was written from `start`, keeps error lines, passes the rest on.
  void collect(off_t start) {
    const int fd = ::fileno(file_);
    const off_t end = ::lseek(fd, 0, SEEK_END);
    if (end <= start) return;
    std::string text(static_cast<std::size_t>(end - start), '\0');
    const ssize_t got = ::pread(fd, text.data(), text.size(), start);
    text.resize(got > 0 ? static_cast<std::size_t>(got) : 0);
    std::istringstream lines(text);
    for (std::string line; std::getline(lines, line);) {
      if (line.rfind("Error: ", 0) == 0) errors_.push_back(line.substr(7));
      else if (line.rfind("Quitting (on error)", 0) != 0 && !line.empty()) passed_ += line + "\n";
    }
    if (end > (1 << 20)) ::ftruncate(fd, 0);  // a long simulation's output does not accumulate in the file
  }

  std::FILE* file_;
  std::vector<std::string> errors_;
  std::string passed_;
};

SumoSession::SumoSession(const std::vector<std::string>& arguments)
    : inputs_(inputsOf(arguments)), capture_(std::make_unique<ErrorCapture>()) {
  if (g_session_open) throw SumoError("internal: a libsumo simulation is already open in this process");
  road::ensureSumoHome();
  std::vector<std::string> args = {"--no-step-log", "true", "--duration-log.disable", "true", "--no-warnings", "true",
                                   "--verbose", "false"};
  args.insert(args.end(), arguments.begin(), arguments.end());
  faultPoint("sumo.load");
  const ActivityScope loading(Activity::SumoLoad);
  std::string failure;
  try {
    const ErrorCapture::Guard capturing(*capture_);
    libsumo::Simulation::load(args);
  } catch (const std::exception& error) {
    failure = error.what();
  }
  const bool loaded = failure.empty() && libsumo::Simulation::isLoaded();
  const std::string reasons = capture_->take(loaded);
  if (!loaded) {
    throw SumoError(fmt::format("SUMO could not load {}: {}", inputs_,
                                !reasons.empty() ? reasons : failure.empty() ? "no reason given" : failure));
  }
  open_ = true;
  g_session_open = true;
  reportSimulationTime(time());
}

SumoSession::~SumoSession() {
  if (!open_) return;
  try {
    libsumo::Simulation::close();
  } catch (const std::exception&) {
    // Closing must not throw from a destructor; SUMO reports nothing useful here.
  }
  g_session_open = false;
}

void SumoSession::step() {
  faultPoint("sumo.step");
  const double now = time();
  reportSimulationTime(now);  // what a crash inside the step is reported at: SUMO's own clock
  const ActivityScope stepping(Activity::SumoStep);
  std::string failure;
  try {
    const ErrorCapture::Guard capturing(*capture_);
    libsumo::Simulation::step();
  } catch (const std::exception& error) {
    failure = error.what();
  }
  const std::string reasons = capture_->take(failure.empty());
  if (!failure.empty()) {
    throw SumoError(fmt::format("SUMO failed at t = {} s (simulating {}): {}", now, inputs_,
                                reasons.empty() ? failure : reasons));
  }
}

double SumoSession::time() const { return libsumo::Simulation::getTime(); }

std::string SumoSession::version() { return libsumo::Simulation::getVersion().second; }

LaneGeometry fetchLane(const std::string& lane_id, const Vec2& offset) {
  LaneGeometry lane;
  lane.id = lane_id;
  const auto shape = libsumo::Lane::getShape(lane_id);
  lane.centre.reserve(shape.value.size());
  for (const auto& point : shape.value) lane.centre.emplace_back(point.x - offset.x(), point.y - offset.y());
  lane.width = libsumo::Lane::getWidth(lane_id);
  return lane;
}

}  // namespace vsd::sim
