#include "vsd/core/progress.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>

namespace vsd {

namespace {
std::atomic<bool> g_progress_enabled{true};

std::string formatDuration(double seconds) {
  if (!(seconds >= 0.0) || seconds > 1e7) return "?";
  const auto total = static_cast<long>(seconds + 0.5);
  if (total >= 3600) return fmt::format("{}h{:02}m", total / 3600, (total % 3600) / 60);
  if (total >= 60) return fmt::format("{}m{:02}s", total / 60, total % 60);
  return fmt::format("{}s", total);
}
}  // namespace

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void Progress::setEnabled(bool enabled) { g_progress_enabled = enabled; }

Progress::Progress(std::string label, std::size_t total, std::string unit)
    : label_(std::move(label)),
      unit_(std::move(unit)),
      total_(total),
      terminal_(::isatty(STDERR_FILENO) != 0),
      start_(std::chrono::steady_clock::now()),
      lastDraw_(start_) {}

Progress::~Progress() { finish(); }

void Progress::advance(std::size_t count) {
  done_ += count;
  const auto now = std::chrono::steady_clock::now();
  // Terminals get ~10 redraws/s; logs get a line every 5 s.
  const auto interval = terminal_ ? std::chrono::milliseconds(100) : std::chrono::milliseconds(5000);
  if (now - lastDraw_ >= interval) {
    lastDraw_ = now;
    draw(false);
  }
}

void Progress::finish() {
  if (finished_) return;
  finished_ = true;
  if (done_ > 0) draw(true);
}

void Progress::draw(bool final_line) {
  if (!g_progress_enabled) return;
  const double elapsed = secondsSince(start_);
  const double rate = elapsed > 0.0 ? static_cast<double>(done_) / elapsed : 0.0;
  std::string text;
  if (total_ > 0) {
    const double fraction = std::min(1.0, static_cast<double>(done_) / static_cast<double>(total_));
    const double remaining = rate > 0.0 ? static_cast<double>(total_ - std::min(done_, total_)) / rate : -1.0;
    if (terminal_) {
      constexpr int kWidth = 30;
      const int filled = static_cast<int>(fraction * kWidth);
      text = fmt::format("{} [{}{}] {}/{} {} {:.0f}/s {}", label_, std::string(static_cast<std::size_t>(filled), '#'),
                         std::string(static_cast<std::size_t>(kWidth - filled), '.'), done_, total_, unit_, rate,
                         final_line ? formatDuration(elapsed) : "ETA " + formatDuration(remaining));
    } else {
      text = fmt::format("{}: {}/{} {} ({:.0f}%), {:.0f}/s, {}", label_, done_, total_, unit_, 100.0 * fraction, rate,
                         final_line ? "took " + formatDuration(elapsed) : "ETA " + formatDuration(remaining));
    }
  } else {
    text = fmt::format("{}: {} {}, {:.0f}/s, {}", label_, done_, unit_, rate, formatDuration(elapsed));
  }
  if (terminal_) {
    std::fprintf(stderr, "\r\033[K%s%s", text.c_str(), final_line ? "\n" : "");
  } else {
    std::fprintf(stderr, "%s\n", text.c_str());
  }
  std::fflush(stderr);
}

}  // namespace vsd
