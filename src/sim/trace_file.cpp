#include "vsd/sim/trace_file.hpp"

#include <fmt/format.h>

#include "vsd/core/error.hpp"
#include "vsd/core/hdf5.hpp"
#include "vsd/core/log.hpp"

namespace vsd::sim {

namespace {
constexpr hsize_t kChunkRows = 256;
constexpr int kDeflateLevel = 1;  // fast; traces compress ~2x
}  // namespace

struct TraceFileWriter::Impl {
  H5::H5File file;
  std::size_t vehicles = 0;
  std::size_t instants = 0;
  h5::Appendable<std::int64_t> sample;
  h5::Appendable<std::uint8_t> ok;
  h5::Appendable<double> states;
  h5::Appendable<std::uint8_t> valid;
  h5::Appendable<double> sampleLength;
  h5::Appendable<double> sampleWidth;
  h5::Appendable<std::int8_t> sampleType;
  std::size_t buffered = 0;
  bool open = true;
  std::filesystem::path name;  ///< the file as messages name it (its final name)

  void flush() {
    try {
      h5::flushAll(sample, ok, states, valid, sampleLength, sampleWidth, sampleType);
    } catch (const H5::Exception& error) {
      failed(error);
    }
    buffered = 0;
  }
  [[noreturn]] void failed(const H5::Exception& error) const {
    throw IoError(fmt::format("{}: writing the trace file failed: {}", name.string(), h5::errorCause(error)));
  }
};

TraceFileWriter::TraceFileWriter(const std::filesystem::path& path, const std::string& functional_scenario, double step,
                                 std::size_t instants, const std::vector<std::string>& vehicle_ids,
                                 const std::vector<double>& vehicle_lengths, const std::vector<double>& vehicle_widths,
                                 const std::filesystem::path& name_in_messages)
    : impl_(std::make_unique<Impl>()) {
  h5::silenceErrorStack();
  impl_->name = name_in_messages.empty() ? path : name_in_messages;
  try {
    impl_->file = H5::H5File(path.string(), H5F_ACC_TRUNC);
    impl_->vehicles = vehicle_ids.size();
    impl_->instants = instants;
    H5::Group root = impl_->file.openGroup("/");
    h5::writeAttribute(root, "schema", std::string(kTraceSchema));
    h5::writeAttribute(root, "functional_scenario", functional_scenario);
    h5::writeAttribute(root, "step", step);
    h5::writeAttribute(root, "instants", static_cast<std::int64_t>(instants));
    h5::writeAttribute(root, "tool_version", toolVersion());
    h5::writeStrings(root, "vehicle_ids", vehicle_ids);
    h5::writeStrings(root, "fields", {"x", "y", "heading", "speed", "accel"});
    h5::Appendable<double> lengths(root, "vehicle_length", {}, vehicle_ids.size(), 0);
    lengths.append(vehicle_lengths.data(), vehicle_lengths.size());
    h5::Appendable<double> widths(root, "vehicle_width", {}, vehicle_ids.size(), 0);
    widths.append(vehicle_widths.data(), vehicle_widths.size());
    const hsize_t v = impl_->vehicles;
    const hsize_t t = impl_->instants;
    impl_->sample = h5::Appendable<std::int64_t>(root, "sample", {}, kChunkRows, kDeflateLevel);
    impl_->ok = h5::Appendable<std::uint8_t>(root, "ok", {}, kChunkRows, kDeflateLevel);
    impl_->states = h5::Appendable<double>(root, "states", {v, t, kTraceFields}, kChunkRows, kDeflateLevel);
    impl_->valid = h5::Appendable<std::uint8_t>(root, "valid", {v, t}, kChunkRows, kDeflateLevel);
    impl_->sampleLength = h5::Appendable<double>(root, "sample_vehicle_length", {v}, kChunkRows, kDeflateLevel);
    impl_->sampleWidth = h5::Appendable<double>(root, "sample_vehicle_width", {v}, kChunkRows, kDeflateLevel);
    impl_->sampleType = h5::Appendable<std::int8_t>(root, "sample_vehicle_type", {v}, kChunkRows, kDeflateLevel);
  } catch (const H5::Exception& error) {
    throw IoError(fmt::format("{}: cannot create trace file: {}", impl_->name.string(), h5::errorCause(error)));
  }
}

TraceFileWriter::~TraceFileWriter() {
  try {
    close();
  } catch (const std::exception& error) {
    spdlog::warn("closing trace file failed: {}", error.what());
  }
}

void TraceFileWriter::append(std::uint64_t sample, const Trace& trace, bool ok) {
  if (trace.vehicles.size() != impl_->vehicles) {
    throw Error(fmt::format("internal: trace of sample {} has {} vehicles, the trace file {}", sample,
                            trace.vehicles.size(), impl_->vehicles));
  }
  impl_->sample.push(static_cast<std::int64_t>(sample));
  impl_->ok.push(ok ? 1 : 0);
  for (const auto& track : trace.vehicles) {
    impl_->sampleLength.push(track.length);
    impl_->sampleWidth.push(track.width);
    impl_->sampleType.push(static_cast<std::int8_t>(track.type));
    for (std::size_t k = 0; k < impl_->instants; ++k) {
      const bool present = k < track.states.size();
      const VehicleState state = present ? track.states[k] : VehicleState{};
      impl_->states.push({state.x, state.y, state.heading, state.speed, state.accel});
      impl_->valid.push(present ? track.valid[k] : std::uint8_t{0});
    }
  }
  if (++impl_->buffered >= kChunkRows) impl_->flush();
}

void TraceFileWriter::close() {
  if (!impl_ || !impl_->open) return;
  impl_->open = false;
  impl_->flush();
  try {
    impl_->file.close();
  } catch (const H5::Exception& error) {
    impl_->failed(error);
  }
}

struct TraceFileReader::Impl {
  std::filesystem::path path;
  H5::H5File file;
  std::string functionalScenario;
  double step = 0.0;
  std::size_t instants = 0;
  std::vector<std::string> vehicleIds;
  std::vector<double> lengths;
  std::vector<double> widths;
  bool perSample = false;  ///< vsd-traces/2: sizes and types per sample
  H5::DataSet sampleLength;
  H5::DataSet sampleWidth;
  H5::DataSet sampleType;
  std::vector<std::int64_t> samples;
  std::vector<std::uint8_t> ok;
  H5::DataSet states;
  H5::DataSet valid;
};

TraceFileReader::TraceFileReader(const std::filesystem::path& path) : impl_(std::make_unique<Impl>()) {
  h5::silenceErrorStack();
  impl_->path = path;
  if (!std::filesystem::exists(path)) throw DatasetError(path.string() + ": trace file does not exist");
  try {
    impl_->file = H5::H5File(path.string(), H5F_ACC_RDONLY);
  } catch (const H5::Exception&) {
    throw DatasetError(path.string() + ": not an HDF5 file (corrupt or foreign)");
  }
  try {
    H5::Group root = impl_->file.openGroup("/");
    if (!h5::hasAttribute(root, "schema")) throw DatasetError(path.string() + ": not a vsd-sumo trace file (no schema)");
    const auto schema = h5::readStringAttribute(root, "schema");
    if (schema != kTraceSchema && schema != kTraceSchemaVersion1) {
      throw DatasetError(fmt::format("{}: trace schema '{}' is not supported (expected '{}' or '{}')", path.string(),
                                     schema, kTraceSchema, kTraceSchemaVersion1));
    }
    impl_->perSample = schema == kTraceSchema;
    if (impl_->perSample) {
      impl_->sampleLength = root.openDataSet("sample_vehicle_length");
      impl_->sampleWidth = root.openDataSet("sample_vehicle_width");
      impl_->sampleType = root.openDataSet("sample_vehicle_type");
    }
    impl_->functionalScenario = h5::readStringAttribute(root, "functional_scenario");
    impl_->step = h5::readDoubleAttribute(root, "step");
    impl_->instants = static_cast<std::size_t>(h5::readIntAttribute(root, "instants"));
    impl_->vehicleIds = h5::readStrings(root, "vehicle_ids");
    impl_->lengths = h5::readAll<double>(root.openDataSet("vehicle_length"));
    impl_->widths = h5::readAll<double>(root.openDataSet("vehicle_width"));
    impl_->samples = h5::readAll<std::int64_t>(root.openDataSet("sample"));
    impl_->ok = h5::readAll<std::uint8_t>(root.openDataSet("ok"));
    impl_->states = root.openDataSet("states");
    impl_->valid = root.openDataSet("valid");
    checkShapes();
  } catch (const H5::Exception& error) {
    throw DatasetError(fmt::format("{}: damaged trace file: {}", path.string(), h5::errorCause(error)));
  }
}

void TraceFileReader::checkShapes() const {
  // trace() indexes /states by the vehicle list and `instants`: they must agree.
  const auto& d = *impl_;
  const hsize_t n = d.samples.size();
  const hsize_t v = d.vehicleIds.size();
  const auto t = static_cast<hsize_t>(d.instants);
  h5::checkStoredSize(d.states);
  h5::checkStoredSize(d.valid);
  const bool ok = d.ok.size() == n && d.lengths.size() == v && d.widths.size() == v &&
                  h5::shapeOf(d.states) == std::vector<hsize_t>{n, v, t, kTraceFields} &&
                  h5::shapeOf(d.valid) == std::vector<hsize_t>{n, v, t};
  const bool sizes_ok = !d.perSample || (h5::shapeOf(d.sampleLength) == std::vector<hsize_t>{n, v} &&
                                          h5::shapeOf(d.sampleWidth) == std::vector<hsize_t>{n, v} &&
                                          h5::shapeOf(d.sampleType) == std::vector<hsize_t>{n, v});
  if (!ok || !sizes_ok) {
    throw DatasetError(fmt::format("{}: damaged trace file: array shapes do not match {} samples x {} vehicles x {} "
                                   "instants",
                                   d.path.string(), n, v, t));
  }
}

TraceFileReader::~TraceFileReader() = default;

std::size_t TraceFileReader::size() const { return impl_->samples.size(); }
const std::string& TraceFileReader::functionalScenario() const { return impl_->functionalScenario; }
double TraceFileReader::step() const { return impl_->step; }
const std::vector<std::string>& TraceFileReader::vehicleIds() const { return impl_->vehicleIds; }
const std::vector<double>& TraceFileReader::vehicleLengths() const { return impl_->lengths; }
const std::vector<double>& TraceFileReader::vehicleWidths() const { return impl_->widths; }
std::uint64_t TraceFileReader::sample(std::size_t row) const { return static_cast<std::uint64_t>(impl_->samples.at(row)); }
bool TraceFileReader::ok(std::size_t row) const { return impl_->ok.at(row) != 0; }

Trace TraceFileReader::trace(std::size_t row) const {
  if (row >= size()) throw DatasetError(fmt::format("{}: row {} out of range (size {})", impl_->path.string(), row, size()));
  const auto states = h5::readRows<double>(impl_->states, row, 1);
  const auto valid = h5::readRows<std::uint8_t>(impl_->valid, row, 1);
  const auto lengths = impl_->perSample ? h5::readRows<double>(impl_->sampleLength, row, 1) : impl_->lengths;
  const auto widths = impl_->perSample ? h5::readRows<double>(impl_->sampleWidth, row, 1) : impl_->widths;
  const auto types = impl_->perSample ? h5::readRows<std::int8_t>(impl_->sampleType, row, 1)
                                      : std::vector<std::int8_t>(impl_->vehicleIds.size(), 0);
  Trace trace;
  trace.step = impl_->step;
  const std::size_t t = impl_->instants;
  for (std::size_t v = 0; v < impl_->vehicleIds.size(); ++v) {
    VehicleTrack track;
    track.id = impl_->vehicleIds[v];
    track.role = v == 0 ? VehicleRole::Ego : VehicleRole::Other;
    track.length = lengths[v];
    track.width = widths[v];
    if (types[v] < 0 || static_cast<std::size_t>(types[v]) >= roadUserKinds().size()) {
      throw DatasetError(fmt::format("{}: damaged trace file: sample row {} vehicle {} has road-user type {}",
                                     impl_->path.string(), row, v, types[v]));
    }
    track.type = static_cast<RoadUserType>(types[v]);
    for (std::size_t k = 0; k < t; ++k) {
      const double* s = &states[(v * t + k) * kTraceFields];
      track.states.push_back({s[0], s[1], s[2], s[3], s[4]});
      track.valid.push_back(valid[v * t + k]);
    }
    trace.vehicles.push_back(std::move(track));
  }
  return trace;
}

}  // namespace vsd::sim
