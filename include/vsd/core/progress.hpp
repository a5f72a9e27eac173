#pragma once
// Progress on long work: a bar redrawn in place on a terminal, plain periodic
// lines otherwise (CI logs, pipes), nothing when disabled (--quiet, tests).

#include <chrono>
#include <cstdio>
#include <string>

namespace vsd {

class Progress {
 public:
  /// `unit` names what is counted ("scenarios", "samples"); total may be 0 if unknown.
  Progress(std::string label, std::size_t total, std::string unit);
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;
  ~Progress();

  void advance(std::size_t count = 1);
  /// Prints the final line (once); called by the destructor if not called before.
  void finish();

  /// Process-wide switch (the CLI's --quiet); default on.
  static void setEnabled(bool enabled);

 private:
  void draw(bool final_line);

  std::string label_;
  std::string unit_;
  std::size_t total_;
  std::size_t done_ = 0;
  bool terminal_;
  bool finished_ = false;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point lastDraw_;
};

/// Seconds since `start` as a double.
double secondsSince(std::chrono::steady_clock::time_point start);

}  // namespace vsd
