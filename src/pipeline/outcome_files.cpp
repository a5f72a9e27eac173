#include "vsd/pipeline/outcome_files.hpp"

#include <limits>

#include "vsd/core/files.hpp"
#include "vsd/core/progress.hpp"
#include "vsd/pipeline/scenes.hpp"

namespace fs = std::filesystem;

namespace vsd::pipeline {

OutcomeFiles::OutcomeFiles(const scenario::LogicalScenario& logical, const std::vector<std::string>& metric_names,
                           int compression, const fs::path& traces, const fs::path& dataset,
                           const fs::path& traces_name, const fs::path& dataset_name)
    : logical_(logical), scenarioSha256_(sha256OfFile(logical.sourceFile)) {
  // Sizes per file where they are fixed; NaN where the type (and so the size) is drawn per sample.
  const auto size_of = [](const scenario::VehicleSpec& vehicle, double size, bool given) {
    return vehicle.typeCode && !given ? std::numeric_limits<double>::quiet_NaN() : size;
  };
  std::vector<std::string> ids = {logical_.ego.id};
  std::vector<double> lengths = {size_of(logical_.ego, logical_.ego.length, logical_.ego.lengthGiven)};
  std::vector<double> widths = {size_of(logical_.ego, logical_.ego.width, logical_.ego.widthGiven)};
  std::vector<RoadUserType> types = {logical_.ego.type};
  for (const auto& other : logical_.others) {
    ids.push_back(other.id);
    lengths.push_back(size_of(other, other.length, other.lengthGiven));
    widths.push_back(size_of(other, other.width, other.widthGiven));
    types.push_back(other.type);
  }
  traces_.emplace(traces, logical_.name, logical_.step, static_cast<std::size_t>(logical_.steps()) + 1, ids, lengths,
                  widths, traces_name);
  vector::DatasetHeader dataset_header;
  dataset_header.kind = "generated";
  dataset_header.step = logical_.step;
  dataset_header.horizon = logical_.steps();
  dataset_header.inputNames = logical_.inputNames();
  dataset_header.metricNames = metric_names;
  dataset_header.compression = compression;
  dataset_.emplace(dataset, dataset_header, dataset_name);
  emptyTrace_.step = logical_.step;
  for (std::size_t v = 0; v < ids.size(); ++v) {
    VehicleTrack track;
    track.id = ids[v];
    track.length = lengths[v];
    track.width = widths[v];
    track.type = types[v];
    emptyTrace_.vehicles.push_back(track);
  }
}

void OutcomeFiles::write(const ScenarioOutcome& outcome) {
  // A scenario that failed before simulation has no trace: store an all-invalid one.
  traces_->append(outcome.index, outcome.trace.vehicles.empty() ? emptyTrace_ : outcome.trace, outcome.ok());
  // A failed run has no complete future of the Ego: it cannot be a training sample.
  if (outcome.ok()) dataset_->append(sceneOf(outcome));
}

vector::VectorizedScene OutcomeFiles::sceneOf(const ScenarioOutcome& outcome) const {
  auto scene = simulatedScene(logical_, outcome);
  scene.provenance = {logical_.sourceFile.string(), scenarioSha256_, logical_.ego.id, 0.0};
  return scene;
}

void OutcomeFiles::close() {
  traces_->close();
  traces_.reset();
  dataset_->close();
  dataset_.reset();
}

void concatenateTraces(const std::vector<fs::path>& files, const fs::path& target) {
  std::optional<sim::TraceFileWriter> writer;
  for (const auto& file : files) {
    const sim::TraceFileReader reader(file);
    for (std::size_t row = 0; row < reader.size(); ++row) {
      const Trace trace = reader.trace(row);
      if (!writer) {  // the file's own sizes: NaN where they are drawn per sample, as one process writes them
        writer.emplace(target, reader.functionalScenario(), reader.step(), trace.instants(), reader.vehicleIds(),
                       reader.vehicleLengths(), reader.vehicleWidths());
      }
      writer->append(reader.sample(row), trace, reader.ok(row));
    }
  }
  if (writer) writer->close();
}

void concatenateDatasets(const std::vector<fs::path>& files, const fs::path& target, int compression) {
  std::optional<vector::DatasetWriter> writer;
  Progress progress("merge datasets", files.size(), "files");
  for (const auto& file : files) {
    const vector::DatasetReader reader(file);
    if (!writer) {
      vector::DatasetHeader header = reader.header();
      header.compression = compression;
      writer.emplace(target, header);
    }
    for (std::size_t i = 0; i < reader.size(); ++i) writer->appendCopy(reader, i);
    progress.advance(1);
  }
  progress.finish();
  if (writer) writer->close();
}

}  // namespace vsd::pipeline
