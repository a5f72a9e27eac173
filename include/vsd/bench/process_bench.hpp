#pragma once
// Benchmarks of whole `vsd-sumo` commands as separate processes: `bench export` (map ->
// dataset: throughput, size, peak memory), `bench compare` (prediction + simulation +
// report: wall time, report size, peak memory) and `bench train` (data-parallel training:
// N ranks x 1 thread vs 1 process x N threads, with the same data, seed and global batch).

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "vsd/bench/measure.hpp"

namespace vsd::bench {

struct MapExportBenchOptions {
  std::filesystem::path map = "/usr/share/sumo/tools/game/A10KW.sumocfg";
  double end = 300.0;                         ///< simulated seconds
  std::string egos = "all";
  std::vector<double> memoryEnds = {100.0, 400.0};  ///< simulated seconds of the memory runs
  Tool tool;
};

struct MapExportMeasurement {
  double end = 0.0;  ///< simulated seconds
  int compression = 1;
  double samples = 0.0;
  double seconds = 0.0;
  double bytesPerSample = 0.0;
  long maxRssKiB = 0;
};

struct MapExportBenchResult {
  std::vector<MapExportMeasurement> modes;   ///< compression 1 and 0 at options.end
  std::vector<MapExportMeasurement> memory;  ///< compression 1 at each of options.memoryEnds
};

MapExportBenchResult runMapExportBench(const MapExportBenchOptions& options);

struct CompareBenchOptions {
  std::filesystem::path model;
  std::filesystem::path scenario = kDefaultScenario;
  std::vector<std::uint64_t> samples = {500, 5000};
  int jobs = 1;
  Tool tool;
};

struct CompareMeasurement {
  std::uint64_t samples = 0;
  double seconds = 0.0;
  double reportMiB = 0.0;
  long maxRssKiB = 0;
};

std::vector<CompareMeasurement> runCompareBench(const CompareBenchOptions& options);

struct TrainBenchOptions {
  std::filesystem::path scenario = kDefaultScenario;
  std::filesystem::path work;  ///< keeps data and models (data reused when present); empty: a temporary folder
  std::uint64_t samples = 2000;
  int steps = 200;
  int batch = 64;
  int ranks = 2;
  int port = 29650;  ///< MASTER_PORT of the ranks' rendezvous on 127.0.0.1
  Tool tool;
};

struct TrainMeasurement {
  double samplesPerSecond = 0.0;
  double allreduceShare = 0.0;  ///< of the training steps' wall time
  double validationAde = 0.0;   ///< m
  double seconds = 0.0;         ///< wall time of the whole process(es)
};

struct TrainBenchResult {
  TrainMeasurement oneProcess;  ///< 1 process x `ranks` threads
  TrainMeasurement ranks;       ///< `ranks` processes x 1 thread
};

TrainBenchResult runTrainBench(const TrainBenchOptions& options);

}  // namespace vsd::bench
