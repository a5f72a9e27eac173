#include "vsd/bench/process_bench.hpp"

#include <fmt/format.h>

#include "vsd/core/files.hpp"
#include "vsd/vector/dataset.hpp"

namespace fs = std::filesystem;

namespace vsd::bench {

namespace {

MapExportMeasurement measureMapExport(const MapExportBenchOptions& options, double end, int compression,
                                      const fs::path& work) {
  const fs::path out = work / "bench.h5";
  const auto result = options.tool
                          .run({"export", options.map.string(), "--out", out.string(), "--egos", options.egos,
                                "--end", fmt::format("{}", end), "--compression", std::to_string(compression)},
                               work)
                          .result;
  const vector::DatasetReader reader(out);
  const auto samples = static_cast<double>(reader.size());
  MapExportMeasurement measured{end, compression, samples, result.seconds,
                                static_cast<double>(fs::file_size(out)) / samples, result.maxRssKiB};
  fs::remove(out);
  return measured;
}

}  // namespace

MapExportBenchResult runMapExportBench(const MapExportBenchOptions& options) {
  TemporaryDirectory work("vsd-bench");
  MapExportBenchResult result;
  for (const int compression : {1, 0}) {
    result.modes.push_back(measureMapExport(options, options.end, compression, work.path()));
  }
  for (const double end : options.memoryEnds) result.memory.push_back(measureMapExport(options, end, 1, work.path()));
  return result;
}

std::vector<CompareMeasurement> runCompareBench(const CompareBenchOptions& options) {
  TemporaryDirectory work("vsd-bench-compare");
  std::vector<CompareMeasurement> measured;
  for (const auto samples : options.samples) {
    const fs::path out = work.path() / fmt::format("compare_{}", samples);
    const auto result = options.tool
                            .run({"compare", options.scenario.string(), "--model", options.model.string(),
                                  "--samples", std::to_string(samples), "--seed", "99", "--jobs",
                                  std::to_string(options.jobs), "--out", out.string()},
                                 work.path())
                            .result;
    measured.push_back({samples, result.seconds,
                        static_cast<double>(fs::file_size(out / "report.html")) / (1024.0 * 1024.0),
                        result.maxRssKiB});
  }
  return measured;
}

}  // namespace vsd::bench
