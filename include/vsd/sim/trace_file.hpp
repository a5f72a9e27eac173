#pragma once
// traces.h5: the full traces of every vehicle of every concrete scenario of a
// run. Schema "vsd-traces/2" (see README, "Trace file"; /1 files, without the per-sample
// sizes and types, are still read: every road user a car of the file's sizes):
//
//   /            attrs: schema, functional_scenario, step [s], instants, tool_version
//   /vehicle_ids       [V] strings, vehicle 0 = the Ego
//   /vehicle_length    [V] float64, m (NaN where a road user's type, and so its size, is drawn per sample)
//   /vehicle_width     [V] float64, m
//   /sample_vehicle_length, /sample_vehicle_width [N, V] float64, m: each sample's sizes
//   /sample_vehicle_type [N, V] int8: each sample's road-user types (core/road_user.hpp codes)
//   /fields            [5] strings: x, y, heading, speed, accel
//   /sample            [N] int64, sample index of the run
//   /ok                [N] uint8, 1 = the run completed
//   /states            [N, V, T, 5] float64, scenario frame, vehicle centre, SI units
//   /valid             [N, V, T] uint8, 1 = the vehicle existed at that instant
//
// Written streaming (rows are buffered and appended in chunks).

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "vsd/core/trace.hpp"

namespace vsd::sim {

inline constexpr const char* kTraceSchema = "vsd-traces/2";
inline constexpr const char* kTraceSchemaVersion1 = "vsd-traces/1";
inline constexpr std::size_t kTraceFields = 5;

class TraceFileWriter {
 public:
  /// Creates the file at `path` (callers pass a temporary path and rename on success;
  /// `name_in_messages`, e.g. the final path, is what errors name). Throws IoError
  /// naming the file, the array and the cause.
  TraceFileWriter(const std::filesystem::path& path, const std::string& functional_scenario, double step,
                  std::size_t instants, const std::vector<std::string>& vehicle_ids,
                  const std::vector<double>& vehicle_lengths, const std::vector<double>& vehicle_widths,
                  const std::filesystem::path& name_in_messages = {});
  TraceFileWriter(const TraceFileWriter&) = delete;
  TraceFileWriter& operator=(const TraceFileWriter&) = delete;
  ~TraceFileWriter();

  /// Appends one scenario. The trace must have the file's vehicles and instants.
  void append(std::uint64_t sample, const Trace& trace, bool ok);
  /// Flushes buffered rows and closes the file.
  void close();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

class TraceFileReader {
 public:
  /// Opens and checks a trace file; throws DatasetError naming the file and the problem.
  explicit TraceFileReader(const std::filesystem::path& path);
  ~TraceFileReader();
  TraceFileReader(const TraceFileReader&) = delete;
  TraceFileReader& operator=(const TraceFileReader&) = delete;

  std::size_t size() const;
  const std::string& functionalScenario() const;
  double step() const;
  const std::vector<std::string>& vehicleIds() const;
  /// m, per vehicle: the file's fixed sizes (`vehicle_length`/`vehicle_width`); NaN where
  /// the size is drawn per sample (then each trace carries its own).
  const std::vector<double>& vehicleLengths() const;
  const std::vector<double>& vehicleWidths() const;
  std::uint64_t sample(std::size_t row) const;
  bool ok(std::size_t row) const;
  Trace trace(std::size_t row) const;

 private:
  void checkShapes() const;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace vsd::sim
