#include "vsd/vector/dataset.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <tuple>
#include <unordered_map>

#include "vsd/core/csv.hpp"
#include "vsd/core/error.hpp"
#include "vsd/run_folder/shards.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/hdf5.hpp"
#include "vsd/core/log.hpp"
#include "vsd/core/numbers.hpp"

namespace fs = std::filesystem;

namespace vsd::vector {

namespace {

constexpr hsize_t kChunkSamples = 256;
constexpr hsize_t kChunkVectors = 8192;
constexpr int kDeflate = 4;  // small per-sample and per-polyline arrays

std::string joinedFeatureNames() {
  std::string names;
  for (std::size_t f = 0; f < kFeatures; ++f) names += (f == 0 ? "" : ",") + std::string(kFeatureNames[f]);
  return names;
}

/// Index of `value` in a growing string table.
class StringTable {
 public:
  std::int32_t index(const std::string& value) {
    const auto [it, inserted] = lookup_.emplace(value, static_cast<std::int32_t>(values_.size()));
    if (inserted) values_.push_back(value);
    return it->second;
  }
  const std::vector<std::string>& values() const { return values_; }

 private:
  std::unordered_map<std::string, std::int32_t> lookup_;
  std::vector<std::string> values_;
};

/// One sample as a dataset stores it: inline vectors and targets as float32 relative to
/// the origin. Writing goes through this form, so a sample copied from another file
/// (DatasetWriter::appendCopy) is stored bit for bit as it was.
struct StoredSample {
  double originX = 0.0;
  double originY = 0.0;
  std::int32_t egoPolyline = 0;
  std::vector<std::int8_t> polylineType;
  std::vector<std::uint8_t> polylineShared;
  std::vector<std::int64_t> sharedStart;  ///< per polyline; used where shared
  std::vector<std::int32_t> polylineVectorCount;
  std::vector<double> polylineLength;     ///< m, per polyline (0 for lanes)
  std::vector<double> polylineWidth;
  std::vector<std::int8_t> polylineRoadUser;  ///< RoadUserType code per polyline (-1 for lanes)
  std::vector<float> vectors;             ///< inline vectors, kFeatures per vector
  std::vector<std::uint8_t> vectorValid;
  std::string label;
  std::int64_t index = 0;
  std::string source;
  std::string sourceSha256;
  std::string egoId;
  double t0 = 0.0;
  std::vector<float> targets;             ///< 2 per step
  std::vector<std::uint8_t> targetValid;
  std::vector<double> inputs;
  std::vector<double> metrics;
};

/// `scene` in stored form; `share` = the file has a shared lane pool.
StoredSample storedSample(const VectorizedScene& scene, bool share) {
  StoredSample stored;
  const Vec2 origin = scene.egoInitialState().position();
  stored.originX = origin.x();
  stored.originY = origin.y();
  stored.egoPolyline = static_cast<std::int32_t>(scene.egoPolyline);
  for (const auto& polyline : scene.polylines) {
    const bool shared = polyline.sharedStart >= 0 && share;
    stored.polylineType.push_back(static_cast<std::int8_t>(polyline.type));
    stored.polylineShared.push_back(shared ? 1 : 0);
    stored.sharedStart.push_back(shared ? polyline.sharedStart : -1);
    stored.polylineVectorCount.push_back(static_cast<std::int32_t>(polyline.vectors.size()));
    stored.polylineLength.push_back(polyline.length);
    stored.polylineWidth.push_back(polyline.width);
    stored.polylineRoadUser.push_back(polyline.type == ObjectType::LaneBoundary
                                          ? std::int8_t{-1}
                                          : static_cast<std::int8_t>(polyline.roadUser));
    if (shared) continue;
    for (std::size_t v = 0; v < polyline.vectors.size(); ++v) {
      const auto& f = polyline.vectors[v];
      stored.vectors.insert(stored.vectors.end(),
                            {static_cast<float>(f[0] - origin.x()), static_cast<float>(f[1] - origin.y()),
                             static_cast<float>(f[2] - origin.x()), static_cast<float>(f[3] - origin.y()),
                             static_cast<float>(f[4]), static_cast<float>(f[5]), static_cast<float>(f[6])});
      stored.vectorValid.push_back(polyline.valid[v]);
    }
  }
  stored.label = scene.label;
  stored.index = static_cast<std::int64_t>(scene.sample);
  stored.source = scene.provenance.source;
  stored.sourceSha256 = scene.provenance.sourceSha256;
  stored.egoId = scene.provenance.egoId;
  stored.t0 = scene.provenance.t0;
  for (std::size_t k = 0; k < scene.target.size(); ++k) {
    stored.targets.push_back(static_cast<float>(scene.target[k].x() - origin.x()));
    stored.targets.push_back(static_cast<float>(scene.target[k].y() - origin.y()));
    stored.targetValid.push_back(scene.targetValid[k]);
  }
  stored.inputs = scene.inputs;
  stored.metrics = scene.metrics;
  return stored;
}

}  // namespace

// --- writer --------------------------------------------------------------------------------

struct DatasetWriter::Impl {
  H5::H5File file;
  DatasetHeader header;
  bool open = true;
  std::size_t samples = 0;
  std::int64_t vectorsWritten = 0;
  std::int64_t polylinesWritten = 0;

  h5::Appendable<float> vectors;
  h5::Appendable<std::uint8_t> vectorValid;
  h5::Appendable<double> sharedVectors;
  std::size_t sharedSize = 0;
  h5::Appendable<std::int8_t> polylineType;
  h5::Appendable<std::uint8_t> polylineShared;
  h5::Appendable<std::int64_t> polylineVectorStart;
  h5::Appendable<std::int32_t> polylineVectorCount;
  h5::Appendable<double> polylineLength;
  h5::Appendable<double> polylineWidth;
  h5::Appendable<std::int8_t> polylineRoadUser;
  h5::Appendable<std::int64_t> samplePolylineStart;
  h5::Appendable<std::int32_t> samplePolylineCount;
  h5::Appendable<std::int32_t> sampleEgoPolyline;
  h5::Appendable<double> sampleOrigin;
  h5::Appendable<std::int32_t> sampleLabel;
  h5::Appendable<std::int64_t> sampleIndex;
  h5::Appendable<std::int32_t> sampleSource;
  h5::Appendable<std::int32_t> sampleEgo;
  h5::Appendable<double> sampleT0;
  h5::Appendable<float> targets;
  h5::Appendable<std::uint8_t> targetValid;
  std::optional<h5::Appendable<double>> inputs;
  std::optional<h5::Appendable<double>> metrics;

  std::size_t buffered = 0;  ///< samples pushed since the last flush
  fs::path name;             ///< the file as messages name it (its final name, not the temporary one)

  [[noreturn]] void failed(const H5::Exception& error) const {
    throw IoError(fmt::format("{}: writing the dataset failed: {}", name.string(), h5::errorCause(error)));
  }

  StringTable labels;
  StringTable sources;
  std::unordered_map<std::int32_t, std::string> sourceSha;
  StringTable egoIds;

  void push(const StoredSample& stored) {
    samplePolylineStart.push(polylinesWritten);
    samplePolylineCount.push(static_cast<std::int32_t>(stored.polylineType.size()));
    sampleEgoPolyline.push(stored.egoPolyline);
    sampleOrigin.push({stored.originX, stored.originY});
    for (std::size_t p = 0; p < stored.polylineType.size(); ++p) {
      polylineType.push(stored.polylineType[p]);
      polylineVectorCount.push(stored.polylineVectorCount[p]);
      polylineLength.push(stored.polylineLength[p]);
      polylineWidth.push(stored.polylineWidth[p]);
      polylineRoadUser.push(stored.polylineRoadUser[p]);
      polylineShared.push(stored.polylineShared[p]);
      if (stored.polylineShared[p]) {
        polylineVectorStart.push(stored.sharedStart[p]);
      } else {
        polylineVectorStart.push(vectorsWritten);
        vectorsWritten += stored.polylineVectorCount[p];
      }
    }
    polylinesWritten += static_cast<std::int64_t>(stored.polylineType.size());
    vectors.push(stored.vectors.begin(), stored.vectors.end());
    vectorValid.push(stored.vectorValid.begin(), stored.vectorValid.end());
    sampleLabel.push(labels.index(stored.label));
    sampleIndex.push(stored.index);
    const std::int32_t source = sources.index(stored.source);
    sourceSha.emplace(source, stored.sourceSha256);
    sampleSource.push(source);
    sampleEgo.push(egoIds.index(stored.egoId));
    sampleT0.push(stored.t0);
    targets.push(stored.targets.begin(), stored.targets.end());
    targetValid.push(stored.targetValid.begin(), stored.targetValid.end());
    if (inputs) inputs->push(stored.inputs.begin(), stored.inputs.end());
    if (metrics) metrics->push(stored.metrics.begin(), stored.metrics.end());
    ++samples;
    if (++buffered >= kChunkSamples) {
      try {
        flush();
      } catch (const H5::Exception& error) {
        failed(error);
      }
    }
  }

  void flush() {
    h5::flushAll(vectors, vectorValid, polylineType, polylineShared, polylineVectorStart, polylineVectorCount,
                 polylineLength, polylineWidth, polylineRoadUser, samplePolylineStart, samplePolylineCount, sampleEgoPolyline,
                 sampleOrigin, sampleLabel, sampleIndex, sampleSource, sampleEgo, sampleT0, targets, targetValid);
    if (inputs) inputs->flush();
    if (metrics) metrics->flush();
    buffered = 0;
  }
};

DatasetWriter::DatasetWriter(const fs::path& path, DatasetHeader header, const fs::path& name_in_messages)
    : impl_(std::make_unique<Impl>()) {
  h5::silenceErrorStack();
  impl_->name = name_in_messages.empty() ? path : name_in_messages;
  impl_->header = std::move(header);
  const auto& h = impl_->header;
  // The bounds every reader checks (kMinStep .. kMaxStep, kMaxWindowSteps) hold before the
  // file is created: arrays sized by them fail here in one line, not in HDF5.
  if (!(h.step >= kMinStep && h.step <= kMaxStep) || h.horizon < 1 || h.horizon > kMaxWindowSteps || h.history < 0 ||
      h.history > kMaxWindowSteps) {
    throw DatasetError(fmt::format("{}: cannot hold step {} s, horizon {} and history {} steps (expected {} .. {} s and "
                                   "at most {} steps)",
                                   impl_->name.string(), h.step, h.horizon, h.history, kMinStep, kMaxStep,
                                   kMaxWindowSteps));
  }
  if (h.compression < 0 || h.compression > 9) {
    throw ConfigError::field("command line", "--compression", std::to_string(h.compression), "a deflate level 0..9");
  }
  try {
    impl_->file = H5::H5File(path.string(), H5F_ACC_TRUNC);
    H5::Group root = impl_->file.openGroup("/");
    h5::writeAttribute(root, "schema", std::string(kDatasetSchema));
    h5::writeAttribute(root, "feature_version", static_cast<std::int64_t>(kFeatureVersion));
    h5::writeAttribute(root, "features", joinedFeatureNames());
    h5::writeAttribute(root, "kind", h.kind);
    h5::writeAttribute(root, "step", h.step);
    h5::writeAttribute(root, "horizon", static_cast<std::int64_t>(h.horizon));
    h5::writeAttribute(root, "history", static_cast<std::int64_t>(h.history));
    h5::writeAttribute(root, "tool_version", toolVersion());
    h5::writeStrings(root, "input_names", h.inputNames);
    h5::writeStrings(root, "metric_names", h.metricNames);
    const auto horizon = static_cast<hsize_t>(h.horizon);
    impl_->vectors = h5::Appendable<float>(root, "vectors", {kFeatures}, kChunkVectors, h.compression);
    impl_->vectorValid = h5::Appendable<std::uint8_t>(root, "vector_valid", {}, kChunkVectors, h.compression);
    impl_->sharedVectors = h5::Appendable<double>(root, "shared_vectors", {kFeatures}, kChunkVectors, kDeflate);
    impl_->polylineType = h5::Appendable<std::int8_t>(root, "polyline_type", {}, kChunkVectors, kDeflate);
    impl_->polylineShared = h5::Appendable<std::uint8_t>(root, "polyline_shared", {}, kChunkVectors, kDeflate);
    impl_->polylineVectorStart = h5::Appendable<std::int64_t>(root, "polyline_vector_start", {}, kChunkVectors, kDeflate);
    impl_->polylineVectorCount = h5::Appendable<std::int32_t>(root, "polyline_vector_count", {}, kChunkVectors, kDeflate);
    impl_->polylineLength = h5::Appendable<double>(root, "polyline_length", {}, kChunkVectors, kDeflate);
    impl_->polylineWidth = h5::Appendable<double>(root, "polyline_width", {}, kChunkVectors, kDeflate);
    impl_->polylineRoadUser = h5::Appendable<std::int8_t>(root, "polyline_road_user", {}, kChunkVectors, kDeflate);
    impl_->samplePolylineStart = h5::Appendable<std::int64_t>(root, "sample_polyline_start", {}, kChunkSamples, kDeflate);
    impl_->samplePolylineCount = h5::Appendable<std::int32_t>(root, "sample_polyline_count", {}, kChunkSamples, kDeflate);
    impl_->sampleEgoPolyline = h5::Appendable<std::int32_t>(root, "sample_ego_polyline", {}, kChunkSamples, kDeflate);
    impl_->sampleOrigin = h5::Appendable<double>(root, "sample_origin", {2}, kChunkSamples, kDeflate);
    impl_->sampleLabel = h5::Appendable<std::int32_t>(root, "sample_label", {}, kChunkSamples, kDeflate);
    impl_->sampleIndex = h5::Appendable<std::int64_t>(root, "sample_index", {}, kChunkSamples, kDeflate);
    impl_->sampleSource = h5::Appendable<std::int32_t>(root, "sample_source", {}, kChunkSamples, kDeflate);
    impl_->sampleEgo = h5::Appendable<std::int32_t>(root, "sample_ego", {}, kChunkSamples, kDeflate);
    impl_->sampleT0 = h5::Appendable<double>(root, "sample_t0", {}, kChunkSamples, kDeflate);
    impl_->targets = h5::Appendable<float>(root, "targets", {horizon, 2}, kChunkSamples, kDeflate);
    impl_->targetValid = h5::Appendable<std::uint8_t>(root, "target_valid", {horizon}, kChunkSamples, kDeflate);
    if (!h.inputNames.empty()) {
      impl_->inputs.emplace(root, "inputs", std::vector<hsize_t>{h.inputNames.size()}, kChunkSamples, kDeflate);
    }
    if (!h.metricNames.empty()) {
      impl_->metrics.emplace(root, "metrics", std::vector<hsize_t>{h.metricNames.size()}, kChunkSamples, kDeflate);
    }
  } catch (const H5::Exception& error) {
    throw IoError(fmt::format("{}: cannot create dataset: {}", impl_->name.string(), h5::errorCause(error)));
  }
}

DatasetWriter::~DatasetWriter() {
  try {
    close();
  } catch (const std::exception& error) {
    spdlog::warn("closing dataset failed: {}", error.what());
  }
}

std::size_t DatasetWriter::size() const { return impl_->samples; }

void DatasetWriter::setSharedVectors(const std::vector<Feature>& pool) {
  if (impl_->samples > 0 || impl_->sharedSize > 0) throw Error("internal: setSharedVectors() after append()");
  std::vector<double> flat;
  flat.reserve(pool.size() * kFeatures);
  for (const auto& feature : pool) flat.insert(flat.end(), feature.begin(), feature.end());
  try {
    impl_->sharedVectors.append(flat);
  } catch (const H5::Exception& error) {
    impl_->failed(error);
  }
  impl_->sharedSize = pool.size();
}

void DatasetWriter::append(const VectorizedScene& scene) {
  auto& d = *impl_;
  if (!d.open) throw Error("internal: append() to a closed dataset");
  if (scene.target.size() != static_cast<std::size_t>(d.header.horizon)) {
    throw Error(fmt::format("internal: scene with {} target steps in a dataset with horizon {}", scene.target.size(),
                            d.header.horizon));
  }
  if (scene.inputs.size() != d.header.inputNames.size() || scene.metrics.size() != d.header.metricNames.size()) {
    throw Error("internal: scene inputs/metrics do not match the dataset's columns");
  }
  d.push(storedSample(scene, d.sharedSize > 0));
}

void DatasetWriter::close() {
  if (!impl_ || !impl_->open) return;
  auto& d = *impl_;
  d.open = false;
  try {
    d.flush();
    H5::Group root = d.file.openGroup("/");
    h5::writeStrings(root, "labels", d.labels.values());
    h5::writeStrings(root, "sources", d.sources.values());
    std::vector<std::string> shas;
    for (std::size_t s = 0; s < d.sources.values().size(); ++s) shas.push_back(d.sourceSha[static_cast<std::int32_t>(s)]);
    h5::writeStrings(root, "source_sha256", shas);
    h5::writeStrings(root, "ego_ids", d.egoIds.values());
    d.file.close();
  } catch (const H5::Exception& error) {
    d.failed(error);
  }
}

// --- reader --------------------------------------------------------------------------------

struct DatasetReader::Impl {
  fs::path path;
  H5::H5File file;
  DatasetHeader header;
  std::string toolVersion;
  std::vector<std::string> labels;
  std::vector<std::string> sources;
  std::vector<std::string> sourceSha;
  std::vector<std::string> egoIds;
  // Per-sample index arrays (read eagerly: small).
  std::vector<std::int64_t> samplePolylineStart;
  std::vector<std::int32_t> samplePolylineCount;
  std::vector<std::int32_t> sampleEgoPolyline;
  std::vector<double> sampleOrigin;
  std::vector<std::int32_t> sampleLabel;
  std::vector<std::int64_t> sampleIndex;
  std::vector<std::int32_t> sampleSource;
  std::vector<std::int32_t> sampleEgo;
  std::vector<double> sampleT0;
  // Read per sample.
  H5::DataSet vectors, vectorValid, polylineType, polylineShared, polylineVectorStart, polylineVectorCount, targets,
      targetValid;
  std::optional<H5::DataSet> polylineLength, polylineWidth;  ///< absent in version-1 files
  std::optional<H5::DataSet> polylineRoadUser;               ///< absent in version-1 and -2 files
  std::vector<double> sharedVectors;  ///< the map's lane vectors (read eagerly: small)
  std::optional<H5::DataSet> inputs, metrics;

  /// What the reader was reading when HDF5 failed (named in the message).
  std::string reading;

  [[noreturn]] void fail(const std::string& problem) const {
    throw DatasetError(fmt::format("{}: {}", path.string(), problem));
  }

  void readHeader(const H5::Group& root);
  void openArrays(const H5::Group& root);
  /// The arrays of the file's version, by name (inputs / metrics only where stored).
  std::map<std::string, H5::DataSet> openAll(const H5::Group& root);
  /// Fails unless every array's shape follows from the header and the index arrays.
  void checkShapes(const std::map<std::string, H5::DataSet>& arrays) const;
  void readIndex(const H5::Group& root);
  void checkIndex() const;
  std::pair<hsize_t, hsize_t> inlineVectorRange(std::size_t sample, const std::vector<std::uint8_t>& shared,
                                                const std::vector<std::int64_t>& starts,
                                                const std::vector<std::int32_t>& counts) const;
  /// Lengths and widths of polylines [first, first + count) (m): stored in version 2,
  /// assumed for the vehicles of version-1 files.
  std::pair<std::vector<double>, std::vector<double>> polylineSizes(const std::vector<std::int8_t>& types,
                                                                    hsize_t first, hsize_t count) const {
    std::pair<std::vector<double>, std::vector<double>> sizes;
    if (polylineLength) {
      sizes.first = h5::readRows<double>(*polylineLength, first, count);
      sizes.second = h5::readRows<double>(*polylineWidth, first, count);
      return sizes;
    }
    const RoadUserKind& car = roadUserKind(RoadUserType::Car);
    for (auto type : types) {
      const bool vehicle = type != static_cast<std::int8_t>(ObjectType::LaneBoundary);
      sizes.first.push_back(vehicle ? car.length : 0.0);
      sizes.second.push_back(vehicle ? car.width : 0.0);
    }
    return sizes;
  }
  /// Road-user kinds of polylines [first, first + count): stored in version 3, cars for the
  /// vehicles of older files; -1 for lanes. Checked against the table.
  std::vector<std::int8_t> polylineRoadUsers(const std::vector<std::int8_t>& types, hsize_t first, hsize_t count) const {
    std::vector<std::int8_t> kinds;
    if (polylineRoadUser) {
      kinds = h5::readRows<std::int8_t>(*polylineRoadUser, first, count);
    } else {
      for (auto type : types) kinds.push_back(type == static_cast<std::int8_t>(ObjectType::LaneBoundary) ? -1 : 0);
    }
    for (std::size_t p = 0; p < kinds.size(); ++p) {
      const bool lane = types[p] == static_cast<std::int8_t>(ObjectType::LaneBoundary);
      if (lane ? kinds[p] != -1 : kinds[p] < 0 || static_cast<std::size_t>(kinds[p]) >= roadUserKinds().size()) {
        fail(fmt::format("array 'polyline_road_user': polyline {} has road-user kind {} (expected {})", first + p,
                         kinds[p], lane ? "-1 for a lane boundary" : "a code of " + roadUserTypeList()));
      }
    }
    return kinds;
  }

  /// Sample `i` exactly as stored.
  StoredSample stored(std::size_t i) const;
};

StoredSample DatasetReader::Impl::stored(std::size_t i) const {
  if (i >= sampleLabel.size()) fail(fmt::format("sample {} out of range (the dataset has {})", i, sampleLabel.size()));
  StoredSample stored;
  try {
    const auto first_polyline = static_cast<hsize_t>(samplePolylineStart[i]);
    const auto polylines = static_cast<hsize_t>(samplePolylineCount[i]);
    stored.polylineType = h5::readRows<std::int8_t>(polylineType, first_polyline, polylines);
    stored.polylineShared = h5::readRows<std::uint8_t>(polylineShared, first_polyline, polylines);
    stored.sharedStart = h5::readRows<std::int64_t>(polylineVectorStart, first_polyline, polylines);
    stored.polylineVectorCount = h5::readRows<std::int32_t>(polylineVectorCount, first_polyline, polylines);
    std::tie(stored.polylineLength, stored.polylineWidth) =
        polylineSizes(stored.polylineType, first_polyline, polylines);
    stored.polylineRoadUser = polylineRoadUsers(stored.polylineType, first_polyline, polylines);
    const auto [first_vector, vector_count] =
        inlineVectorRange(i, stored.polylineShared, stored.sharedStart, stored.polylineVectorCount);
    stored.vectors = h5::readRows<float>(vectors, first_vector, vector_count);
    stored.vectorValid = h5::readRows<std::uint8_t>(vectorValid, first_vector, vector_count);
    stored.targets = h5::readRows<float>(targets, i, 1);
    stored.targetValid = h5::readRows<std::uint8_t>(targetValid, i, 1);
    if (inputs) stored.inputs = h5::readRows<double>(*inputs, i, 1);
    if (metrics) stored.metrics = h5::readRows<double>(*metrics, i, 1);
  } catch (const H5::Exception& error) {
    fail(fmt::format("cannot read sample {}: {}", i, h5::errorCause(error)));
  }
  stored.originX = sampleOrigin[2 * i];
  stored.originY = sampleOrigin[2 * i + 1];
  stored.egoPolyline = sampleEgoPolyline[i];
  stored.label = labels.at(static_cast<std::size_t>(sampleLabel[i]));
  stored.index = sampleIndex[i];
  const auto source = static_cast<std::size_t>(sampleSource[i]);
  if (source < sources.size()) {
    stored.source = sources[source];
    stored.sourceSha256 = source < sourceSha.size() ? sourceSha[source] : "";
  }
  const auto ego = static_cast<std::size_t>(sampleEgo[i]);
  if (ego < egoIds.size()) stored.egoId = egoIds[ego];
  stored.t0 = sampleT0[i];
  return stored;
}

void DatasetWriter::appendCopy(const DatasetReader& source, std::size_t sample) {
  auto& d = *impl_;
  if (!d.open) throw Error("internal: appendCopy() to a closed dataset");
  const auto& header = source.header();
  if (header.kind != d.header.kind || header.step != d.header.step || header.horizon != d.header.horizon ||
      header.history != d.header.history || header.inputNames != d.header.inputNames ||
      header.metricNames != d.header.metricNames) {
    throw DatasetError(fmt::format("{}: its header (kind, step, horizon, history, inputs, metrics) differs from the "
                                   "dataset being written",
                                   source.path().string()));
  }
  if (source.impl_->sharedVectors.size() != d.sharedSize * kFeatures) {
    throw DatasetError(fmt::format("{}: its shared lane vectors differ from the dataset being written",
                                   source.path().string()));
  }
  d.push(source.impl_->stored(sample));
}

/// First row and count of a sample's own (inline) vectors in /vectors, which the
/// writer stores contiguously; checked against the array before anything is read.
std::pair<hsize_t, hsize_t> DatasetReader::Impl::inlineVectorRange(std::size_t sample,
                                                                  const std::vector<std::uint8_t>& shared,
                                                                  const std::vector<std::int64_t>& starts,
                                                                  const std::vector<std::int32_t>& counts) const {
  const auto total = static_cast<std::int64_t>(h5::shapeOf(vectors).front());
  std::int64_t first = -1;
  std::int64_t next = 0;
  for (std::size_t p = 0; p < shared.size(); ++p) {
    if (counts[p] < 0 || shared[p] > 1) {
      fail(fmt::format("sample {} polyline {}: {} vectors, shared flag {}", sample, p, counts[p], shared[p]));
    }
    if (shared[p]) continue;
    if (first < 0) first = next = starts[p];
    if (starts[p] != next || next < 0 || counts[p] > total - next) {
      fail(fmt::format("sample {} polyline {}: vectors {} .. {} are not the sample's next rows of the {} in "
                       "/vectors",
                       sample, p, starts[p], starts[p] + counts[p], total));
    }
    next += counts[p];
  }
  if (first < 0) return {0, 0};
  return {static_cast<hsize_t>(first), static_cast<hsize_t>(next - first)};
}

void DatasetReader::Impl::readHeader(const H5::Group& root) {
  reading = "attributes";
  if (!h5::hasAttribute(root, "schema")) fail("not a vsd-sumo dataset (no 'schema' attribute)");
  const auto schema = h5::readStringAttribute(root, "schema");
  if (schema != kDatasetSchema && schema != kDatasetSchemaVersion2 && schema != kDatasetSchemaVersion1) {
    fail(fmt::format("dataset schema '{}' is not supported by this version (expected '{}', '{}' or '{}')", schema,
                     kDatasetSchema, kDatasetSchemaVersion2, kDatasetSchemaVersion1));
  }
  header.vehicleSizesAssumed = schema == kDatasetSchemaVersion1;
  header.roadUsersAssumed = schema != kDatasetSchema;
  const auto features = h5::readIntAttribute(root, "feature_version");
  if (features != kFeatureVersion) {
    fail(fmt::format("feature version {} is not supported (expected {})", features, kFeatureVersion));
  }
  header.kind = h5::readStringAttribute(root, "kind");
  header.step = h5::readDoubleAttribute(root, "step");
  const auto horizon = h5::readIntAttribute(root, "horizon");
  const auto history = h5::readIntAttribute(root, "history");
  toolVersion = h5::readStringAttribute(root, "tool_version");
  // The time base sizes every per-sample array and tensor: bounded before use.
  if (header.kind != "generated" && header.kind != "map") {
    fail(fmt::format("attribute 'kind': got '{}', expected 'generated' or 'map'", header.kind));
  }
  if (!(header.step >= kMinStep && header.step <= kMaxStep)) {
    fail(fmt::format("attribute 'step': got {}, expected {} .. {} s", header.step, kMinStep, kMaxStep));
  }
  if (horizon < 1 || horizon > kMaxWindowSteps) {
    fail(fmt::format("attribute 'horizon': got {}, expected 1 .. {} steps", horizon, kMaxWindowSteps));
  }
  if (history < 0 || history > kMaxWindowSteps) {
    fail(fmt::format("attribute 'history': got {}, expected 0 .. {} steps", history, kMaxWindowSteps));
  }
  header.horizon = static_cast<int>(horizon);
  header.history = static_cast<int>(history);
}

std::map<std::string, H5::DataSet> DatasetReader::Impl::openAll(const H5::Group& root) {
  const auto open = [&](const char* name) {
    reading = name;
    H5::DataSet dataset = root.openDataSet(name);
    h5::checkStoredSize(dataset);
    return dataset;
  };
  for (const char* table : {"labels", "input_names", "metric_names", "sources", "source_sha256", "ego_ids"}) open(table);
  std::map<std::string, H5::DataSet> result;
  for (const char* name : {"sample_polyline_start", "sample_polyline_count", "sample_ego_polyline", "sample_origin",
                           "sample_label", "sample_index", "sample_source", "sample_ego", "sample_t0", "vectors",
                           "vector_valid", "polyline_type", "polyline_shared", "shared_vectors",
                           "polyline_vector_start", "polyline_vector_count", "targets", "target_valid"}) {
    result.emplace(name, open(name));
  }
  for (const char* name : {"inputs", "metrics"}) {
    if (root.nameExists(name)) result.emplace(name, open(name));
  }
  if (!header.vehicleSizesAssumed) {
    for (const char* name : {"polyline_length", "polyline_width"}) result.emplace(name, open(name));
  }
  if (!header.roadUsersAssumed) result.emplace("polyline_road_user", open("polyline_road_user"));
  return result;
}

void DatasetReader::Impl::checkShapes(const std::map<std::string, H5::DataSet>& arrays) const {
  const auto rows = [](const H5::DataSet& dataset) {
    const auto shape = h5::shapeOf(dataset);
    return shape.empty() ? hsize_t{0} : shape[0];
  };
  // Every array's shape follows from N samples, P polylines, V inline and S shared
  // vectors, F horizon steps and the I inputs / M metrics named in the header.
  const hsize_t n = rows(arrays.at("sample_label"));
  const hsize_t p = rows(arrays.at("polyline_type"));
  const hsize_t v = rows(arrays.at("vectors"));
  const hsize_t shared = rows(arrays.at("shared_vectors"));
  const auto f = static_cast<hsize_t>(header.horizon);
  const std::vector<std::pair<std::string, std::vector<hsize_t>>> expected = {
      {"sample_polyline_start", {n}}, {"sample_polyline_count", {n}}, {"sample_ego_polyline", {n}},
      {"sample_origin", {n, 2}},      {"sample_label", {n}},          {"sample_index", {n}},
      {"sample_source", {n}},         {"sample_ego", {n}},            {"sample_t0", {n}},
      {"vectors", {v, kFeatures}},    {"vector_valid", {v}},          {"polyline_type", {p}},
      {"polyline_shared", {p}},       {"shared_vectors", {shared, kFeatures}},
      {"polyline_vector_start", {p}}, {"polyline_vector_count", {p}}, {"targets", {n, f, 2}},
      {"target_valid", {n, f}},       {"inputs", {n, header.inputNames.size()}},
      {"metrics", {n, header.metricNames.size()}}, {"polyline_length", {p}}, {"polyline_width", {p}},
      {"polyline_road_user", {p}}};
  for (const auto& [name, shape] : expected) {
    const bool sizes = name == "polyline_length" || name == "polyline_width";
    if (sizes && header.vehicleSizesAssumed) continue;  // version 1 stores none
    if (name == "polyline_road_user" && header.roadUsersAssumed) continue;  // versions 1 and 2 store none
    const auto it = arrays.find(name);
    if (it == arrays.end()) {
      // inputs/metrics are left out when the header names none.
      if (shape.back() == 0) continue;
      fail(fmt::format("array '{}' is missing ({} columns are named)", name, shape.back()));
    }
    const auto actual = h5::shapeOf(it->second);
    if (actual != shape) {
      fail(fmt::format("array '{}' has shape [{}], expected [{}] (from {} samples, {} polylines, {} vectors, horizon "
                       "{})",
                       name, fmt::join(actual, ", "), fmt::join(shape, ", "), n, p, v, f));
    }
  }
}

void DatasetReader::Impl::openArrays(const H5::Group& root) {
  const auto arrays = openAll(root);
  reading = "input_names";
  header.inputNames = h5::readStrings(root, "input_names");
  reading = "metric_names";
  header.metricNames = h5::readStrings(root, "metric_names");
  checkShapes(arrays);
  vectors = arrays.at("vectors");
  vectorValid = arrays.at("vector_valid");
  polylineType = arrays.at("polyline_type");
  polylineShared = arrays.at("polyline_shared");
  polylineVectorStart = arrays.at("polyline_vector_start");
  polylineVectorCount = arrays.at("polyline_vector_count");
  targets = arrays.at("targets");
  targetValid = arrays.at("target_valid");
  if (arrays.count("inputs")) inputs = arrays.at("inputs");
  if (arrays.count("metrics")) metrics = arrays.at("metrics");
  if (!header.vehicleSizesAssumed) {
    polylineLength = arrays.at("polyline_length");
    polylineWidth = arrays.at("polyline_width");
  }
  if (!header.roadUsersAssumed) polylineRoadUser = arrays.at("polyline_road_user");
}

void DatasetReader::Impl::readIndex(const H5::Group& root) {
  const auto strings = [&](const char* name) {
    reading = name;
    return h5::readStrings(root, name);
  };
  labels = strings("labels");
  sources = strings("sources");
  sourceSha = strings("source_sha256");
  egoIds = strings("ego_ids");
  const auto all = [&](const char* name, auto& values) {
    reading = name;
    values = h5::readAll<typename std::decay_t<decltype(values)>::value_type>(root.openDataSet(name));
  };
  all("sample_polyline_start", samplePolylineStart);
  all("sample_polyline_count", samplePolylineCount);
  all("sample_ego_polyline", sampleEgoPolyline);
  all("sample_origin", sampleOrigin);
  all("sample_label", sampleLabel);
  all("sample_index", sampleIndex);
  all("sample_source", sampleSource);
  all("sample_ego", sampleEgo);
  all("sample_t0", sampleT0);
  all("shared_vectors", sharedVectors);
}

void DatasetReader::Impl::checkIndex() const {
  const std::size_t n = sampleLabel.size();
  const auto polylines = static_cast<std::int64_t>(h5::shapeOf(polylineType).front());
  const auto in_table = [](std::int32_t index, std::size_t size) {
    return index >= 0 && static_cast<std::size_t>(index) < size;
  };
  for (std::size_t i = 0; i < n; ++i) {
    const std::int64_t first = samplePolylineStart[i];
    const std::int32_t count = samplePolylineCount[i];
    if (first < 0 || count < 1 || first > polylines - count) {
      fail(fmt::format("sample {}: polylines {} .. {} outside the {} polylines of the file", i, first,
                       first + count, polylines));
    }
    if (sampleEgoPolyline[i] < 0 || sampleEgoPolyline[i] >= count) {
      fail(fmt::format("sample {}: Ego polyline {} of {}", i, sampleEgoPolyline[i], count));
    }
    if (!in_table(sampleLabel[i], labels.size())) {
      fail(fmt::format("sample {} refers to label #{} of {}", i, sampleLabel[i], labels.size()));
    }
    if (!in_table(sampleSource[i], sources.size()) || !in_table(sampleEgo[i], egoIds.size())) {
      fail(fmt::format("sample {} refers to source #{} of {} / Ego id #{} of {}", i, sampleSource[i], sources.size(),
                       sampleEgo[i], egoIds.size()));
    }
    if (!std::isfinite(sampleOrigin[2 * i]) || !std::isfinite(sampleOrigin[2 * i + 1]) || !std::isfinite(sampleT0[i])) {
      fail(fmt::format("sample {}: non-finite origin or t0", i));
    }
  }
}

DatasetReader::DatasetReader(const fs::path& path) : impl_(std::make_unique<Impl>()) {
  h5::silenceErrorStack();
  auto& d = *impl_;
  d.path = path;
  if (!fs::exists(path)) d.fail("dataset does not exist");
  if (fs::is_directory(path)) d.fail("is a folder (expected a dataset .h5 file, or a run folder with dataset.h5)");
  try {
    d.file = H5::H5File(path.string(), H5F_ACC_RDONLY);
  } catch (const H5::Exception&) {
    d.fail("not an HDF5 file (corrupt, truncated or foreign)");
  }
  try {
    const H5::Group root = d.file.openGroup("/");
    d.readHeader(root);
    d.openArrays(root);
    d.readIndex(root);
  } catch (const H5::Exception& error) {
    d.fail(fmt::format("damaged dataset: cannot read '{}': {}", d.reading, h5::errorCause(error)));
  }
  d.checkIndex();
  if (d.header.vehicleSizesAssumed) {
    spdlog::warn("{}: a {} file stores no vehicle sizes; assuming a car's {} m x {} m for every vehicle", path.string(),
                 kDatasetSchemaVersion1, roadUserKind(RoadUserType::Car).length, roadUserKind(RoadUserType::Car).width);
  }
}

DatasetReader::~DatasetReader() = default;

const fs::path& DatasetReader::path() const { return impl_->path; }
const DatasetHeader& DatasetReader::header() const { return impl_->header; }
const std::string& DatasetReader::toolVersion() const { return impl_->toolVersion; }
std::size_t DatasetReader::size() const { return impl_->sampleLabel.size(); }
const std::vector<std::string>& DatasetReader::labels() const { return impl_->labels; }
const std::string& DatasetReader::label(std::size_t sample) const {
  return impl_->labels[static_cast<std::size_t>(impl_->sampleLabel.at(sample))];
}

std::vector<std::size_t> DatasetReader::samplesWithLabel(const std::string& wanted) const {
  std::vector<std::size_t> result;
  for (std::size_t i = 0; i < size(); ++i) {
    if (label(i) == wanted) result.push_back(i);
  }
  return result;
}

std::vector<DatasetReader::SampleRecord> DatasetReader::records() const {
  const auto& d = *impl_;
  const std::size_t inputs_per_sample = d.header.inputNames.size();
  std::vector<double> inputs;
  if (d.inputs && inputs_per_sample > 0 && size() > 0) {
    try {
      inputs = h5::readRows<double>(*d.inputs, 0, size());
    } catch (const H5::Exception& error) {
      d.fail(fmt::format("cannot read /inputs: {}", h5::errorCause(error)));
    }
  }
  std::vector<SampleRecord> records(size());
  for (std::size_t i = 0; i < size(); ++i) {
    records[i].sample = static_cast<std::uint64_t>(d.sampleIndex[i]);
    records[i].sourceSha256 = d.sourceSha.at(static_cast<std::size_t>(d.sampleSource[i]));
    if (!inputs.empty()) {
      const auto first = inputs.begin() + static_cast<std::ptrdiff_t>(i * inputs_per_sample);
      records[i].inputs.assign(first, first + static_cast<std::ptrdiff_t>(inputs_per_sample));
    }
  }
  return records;
}

VectorizedScene DatasetReader::scene(std::size_t sample) const {
  const auto& d = *impl_;
  if (sample >= size()) d.fail(fmt::format("sample {} out of range (the dataset has {})", sample, size()));
  VectorizedScene scene;
  try {
    const auto first_polyline = static_cast<hsize_t>(d.samplePolylineStart[sample]);
    const auto polylines = static_cast<hsize_t>(d.samplePolylineCount[sample]);
    const auto types = h5::readRows<std::int8_t>(d.polylineType, first_polyline, polylines);
    const auto shared = h5::readRows<std::uint8_t>(d.polylineShared, first_polyline, polylines);
    const auto starts = h5::readRows<std::int64_t>(d.polylineVectorStart, first_polyline, polylines);
    const auto counts = h5::readRows<std::int32_t>(d.polylineVectorCount, first_polyline, polylines);
    const auto sizes = d.polylineSizes(types, first_polyline, polylines);
    const auto road_users = d.polylineRoadUsers(types, first_polyline, polylines);
    const auto [first_vector, vector_count] = d.inlineVectorRange(sample, shared, starts, counts);
    const auto raw = h5::readRows<float>(d.vectors, first_vector, vector_count);
    const auto valid = h5::readRows<std::uint8_t>(d.vectorValid, first_vector, vector_count);
    const double ox = d.sampleOrigin[2 * sample];
    const double oy = d.sampleOrigin[2 * sample + 1];
    const std::size_t pool_size = d.sharedVectors.size() / kFeatures;
    std::size_t v = 0;
    for (hsize_t p = 0; p < polylines; ++p) {
      ScenePolyline polyline;
      polyline.type = static_cast<ObjectType>(types[p]);
      polyline.length = sizes.first[p];
      polyline.width = sizes.second[p];
      if (road_users[p] >= 0) polyline.roadUser = static_cast<RoadUserType>(road_users[p]);
      if (shared[p]) {
        const auto start = static_cast<std::size_t>(starts[p]);
        const auto count = static_cast<std::size_t>(counts[p]);
        if (starts[p] < 0 || start + count > pool_size) {
          d.fail(fmt::format("sample {} polyline {} refers to shared vectors {}..{} of {}", sample, p, start,
                             start + count, pool_size));
        }
        polyline.sharedStart = starts[p];
        for (std::size_t i = 0; i < count; ++i) {
          Feature feature;
          std::copy_n(&d.sharedVectors[(start + i) * kFeatures], kFeatures, feature.begin());
          feature[5] = static_cast<double>(p);
          polyline.vectors.push_back(feature);
        }
        polyline.valid.assign(count, 1);
        scene.polylines.push_back(std::move(polyline));
        continue;
      }
      for (std::int32_t i = 0; i < counts[p]; ++i, ++v) {
        const float* f = &raw[v * kFeatures];
        const auto d64 = [&](std::size_t feature) { return static_cast<double>(f[feature]); };
        polyline.vectors.push_back({d64(0) + ox, d64(1) + oy, d64(2) + ox, d64(3) + oy, d64(4), d64(5), d64(6)});
        polyline.valid.push_back(valid[v]);
      }
      scene.polylines.push_back(std::move(polyline));
    }
    const auto target = h5::readRows<float>(d.targets, sample, 1);
    scene.targetValid = h5::readRows<std::uint8_t>(d.targetValid, sample, 1);
    for (std::size_t k = 0; k + 1 < target.size(); k += 2) {
      scene.target.emplace_back(static_cast<double>(target[k]) + ox, static_cast<double>(target[k + 1]) + oy);
    }
    if (d.inputs) scene.inputs = h5::readRows<double>(*d.inputs, sample, 1);
    if (d.metrics) scene.metrics = h5::readRows<double>(*d.metrics, sample, 1);
  } catch (const H5::Exception& error) {
    d.fail(fmt::format("cannot read sample {}: {}", sample, error.getDetailMsg()));
  }
  scene.label = label(sample);
  scene.sample = static_cast<std::uint64_t>(d.sampleIndex[sample]);
  scene.step = d.header.step;
  scene.egoPolyline = static_cast<std::size_t>(d.sampleEgoPolyline[sample]);
  const auto source = static_cast<std::size_t>(d.sampleSource[sample]);
  if (source < d.sources.size()) {
    scene.provenance.source = d.sources[source];
    scene.provenance.sourceSha256 = source < d.sourceSha.size() ? d.sourceSha[source] : "";
  }
  const auto ego = static_cast<std::size_t>(d.sampleEgo[sample]);
  if (ego < d.egoIds.size()) scene.provenance.egoId = d.egoIds[ego];
  scene.provenance.t0 = d.sampleT0[sample];
  return scene;
}

// --- validation and summaries -----------------------------------------------------------------

namespace {

void checkScene(const VectorizedScene& scene, std::size_t sample, const DatasetHeader& header,
                std::vector<std::string>& problems) {
  auto problem = [&](const std::string& text) {
    if (problems.size() < 50) problems.push_back(fmt::format("sample {}: {}", sample, text));
  };
  if (scene.polylines.empty()) return problem("no polylines");
  if (scene.egoPolyline >= scene.polylines.size()) return problem("Ego polyline index out of range");
  std::size_t egos = 0;
  const double max_time = header.horizon * header.step + 1e-4;
  const double min_time = -header.history * header.step - 1e-4;
  for (std::size_t p = 0; p < scene.polylines.size(); ++p) {
    const auto& polyline = scene.polylines[p];
    const int type = static_cast<int>(polyline.type);
    if (type < 1 || type > 3) problem(fmt::format("polyline {} has object type {}", p, type));
    if (polyline.type == ObjectType::Ego) ++egos;
    if (polyline.vectors.empty()) problem(fmt::format("polyline {} has no vectors", p));
    const bool vehicle = polyline.type != ObjectType::LaneBoundary;
    if (vehicle && !(polyline.length > 0.0 && polyline.width > 0.0 && polyline.length < 100.0 && polyline.width < 20.0)) {
      problem(fmt::format("vehicle polyline {}: size {} m x {} m (expected 0 < length < 100, 0 < width < 20)", p,
                          polyline.length, polyline.width));
    }
    for (std::size_t v = 0; v < polyline.vectors.size(); ++v) {
      const auto& f = polyline.vectors[v];
      if (static_cast<int>(f[4]) != type) problem(fmt::format("polyline {} vector {}: object_type {}", p, v, f[4]));
      if (static_cast<std::size_t>(f[5]) != p) problem(fmt::format("polyline {} vector {}: polyline_id {}", p, v, f[5]));
      if (polyline.valid[v] == 0) continue;
      for (std::size_t i = 0; i < 4; ++i) {
        if (!std::isfinite(f[i])) problem(fmt::format("polyline {} vector {}: non-finite coordinate", p, v));
      }
      if (polyline.type == ObjectType::LaneBoundary && f[6] != 0.0) {
        problem(fmt::format("lane polyline {} vector {}: timestamp {} (expected 0)", p, v, f[6]));
      }
      if (!(f[6] >= min_time && f[6] <= max_time)) {
        problem(fmt::format("polyline {} vector {}: timestamp {} outside [{}, {}] s", p, v, f[6], min_time, max_time));
      }
    }
  }
  if (egos != 1) problem(fmt::format("{} Ego polylines (expected 1)", egos));
  const auto& ego = scene.polylines[scene.egoPolyline];
  if (ego.type != ObjectType::Ego) problem("the Ego polyline index points to a non-Ego polyline");
  if (!ego.vectors.empty() && (ego.vectors.back()[6] != 0.0 || ego.valid.back() == 0)) {
    problem("the Ego polyline does not end with a valid initial vector at t = 0");
  }
  if (scene.target.size() != static_cast<std::size_t>(header.horizon)) problem("target length differs from the horizon");
  for (std::size_t k = 0; k < scene.target.size(); ++k) {
    if (scene.targetValid[k] && !scene.target[k].allFinite()) problem(fmt::format("target {} is not finite", k));
  }
}

}  // namespace

namespace {

/// A run folder: its manifest (sizes and SHA-256) first. A file inside a folder
/// whose manifest lists it: that entry.
std::vector<std::string> outputFolderProblems(const fs::path& path) {
  if (fs::is_directory(path)) {
    auto problems = checkOutputFolder(path, /*hashes=*/true);
    if (problems.empty() && !readManifestOutputs(path).count("dataset.h5")) {
      problems.push_back(fmt::format("{}: the folder's manifest lists no dataset.h5 (not a run folder)", path.string()));
    }
    return problems;
  }
  const fs::path folder = path.parent_path().empty() ? fs::path(".") : path.parent_path();
  if (!fs::exists(folder / "manifest.json")) return {};
  std::map<std::string, ManifestEntry> entries;
  try {
    entries = readManifestOutputs(folder);
  } catch (const DatasetError&) {
    return {};  // a manifest of something else (not an output folder of ours)
  }
  const auto entry = entries.find(path.filename().string());
  if (entry == entries.end()) return {};
  std::error_code ec;
  if (fs::file_size(path, ec) != entry->second.bytes || sha256OfFile(path) != entry->second.sha256) {
    return {fmt::format("{}: size or SHA-256 differs from {} (changed or truncated after it was written)",
                        path.string(), (folder / "manifest.json").string())};
  }
  return {};
}

}  // namespace

namespace {

/// One row of concrete.csv as the record check needs it.
struct ConcreteRow {
  bool ok = false;
  std::vector<double> inputs;
};

bool sameNumbers(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!(a[i] == b[i] || (std::isnan(a[i]) && std::isnan(b[i])))) return false;
  }
  return true;
}

/// concrete.csv's rows by sample index, each row's seed checked against the manifest's.
std::map<std::uint64_t, ConcreteRow> concreteRows(const CsvTable& csv, const nlohmann::json& manifest,
                                                  const std::vector<std::string>& input_names,
                                                  std::vector<std::string>& problems) {
  const std::size_t sample_column = csv.column("sample");
  const std::size_t seed_column = csv.column("seed");
  const std::size_t status_column = csv.column("status");
  std::vector<std::size_t> input_columns;
  for (const auto& name : input_names) input_columns.push_back(csv.column(name));
  const std::string seed = manifest.contains("seed") ? manifest.at("seed").dump() : std::string();
  std::map<std::uint64_t, ConcreteRow> rows;
  for (std::size_t r = 0; r < csv.rows(); ++r) {
    if (!seed.empty() && csv.cell(r, seed_column) != seed) {
      problems.push_back(fmt::format("{}: row {} has seed {}, the manifest says {} (made by another run, or the "
                                     "manifest was edited)",
                                     csv.path().string(), r + 1, csv.cell(r, seed_column), seed));
      return rows;
    }
    const std::uint64_t sample = parseUnsigned(csv.cell(r, sample_column), std::numeric_limits<std::uint64_t>::max(),
                                               fmt::format("{}: row {}", csv.path().string(), r + 1), "sample");
    ConcreteRow row;
    row.ok = csv.cell(r, status_column) == "ok";
    for (const std::size_t column : input_columns) row.inputs.push_back(csv.number(r, column));
    if (!rows.emplace(sample, std::move(row)).second) {
      problems.push_back(fmt::format("{}: sample {} is listed twice", csv.path().string(), sample));
      return rows;
    }
  }
  return rows;
}

/// The manifest's sample range (a run or shard: first_sample, samples) against concrete.csv.
void checkSampleRange(const nlohmann::json& manifest, const std::map<std::uint64_t, ConcreteRow>& rows,
                      const fs::path& csv, std::vector<std::string>& problems) {
  const nlohmann::json& range = manifest.contains("shard") ? manifest.at("shard") : manifest;
  if (!range.contains("first_sample") || !range.contains("samples")) return;
  const auto first = range.at("first_sample").get<std::uint64_t>();
  const auto count = range.at("samples").get<std::uint64_t>();
  const bool inside = rows.empty() || (rows.begin()->first >= first && rows.rbegin()->first - first < count);
  if (rows.size() != count || !inside) {
    problems.push_back(fmt::format("{}: {} rows (samples {} .. {}), the manifest says samples {} .. {}", csv.string(),
                                   rows.size(), rows.empty() ? 0 : rows.begin()->first,
                                   rows.empty() ? 0 : rows.rbegin()->first, first, first + count - 1));
  }
}

}  // namespace

std::vector<std::string> runFolderRecordProblems(const fs::path& folder) {
  if (!fs::exists(folder / "concrete.csv") || !fs::exists(folder / "dataset.h5")) return {};
  std::vector<std::string> problems;
  try {
    const nlohmann::json manifest = readManifest(folder);
    const DatasetReader reader(folder / "dataset.h5");
    const CsvTable csv = CsvTable::read(folder / "concrete.csv");
    const auto rows = concreteRows(csv, manifest, reader.header().inputNames, problems);
    if (!problems.empty()) return problems;
    checkSampleRange(manifest, rows, csv.path(), problems);
    const std::string scenario_sha = manifest.value("scenario_sha256", std::string());
    std::size_t completed = 0;
    for (const auto& [sample, row] : rows) completed += row.ok ? 1 : 0;
    for (const auto& record : reader.records()) {
      const auto row = rows.find(record.sample);
      if (row == rows.end() || !row->second.ok) {
        problems.push_back(fmt::format("{}: sample {} is not a completed scenario of {} (joined from another run's "
                                       "files?)",
                                       reader.path().string(), record.sample, csv.path().string()));
      } else if (!sameNumbers(record.inputs, row->second.inputs)) {
        problems.push_back(fmt::format("{}: sample {}'s inputs differ from {}'s (made by another run: another seed "
                                       "or scenario)",
                                       reader.path().string(), record.sample, csv.path().string()));
      } else if (!scenario_sha.empty() && record.sourceSha256 != scenario_sha) {
        problems.push_back(fmt::format("{}: sample {} was made from a scenario file with SHA-256 {:.12}, the "
                                       "manifest's has {:.12}",
                                       reader.path().string(), record.sample, record.sourceSha256, scenario_sha));
      }
      if (!problems.empty()) return problems;
    }
    if (reader.size() != completed) {
      problems.push_back(fmt::format("{}: {} samples, but {} lists {} completed scenarios", reader.path().string(),
                                     reader.size(), csv.path().string(), completed));
    }
  } catch (const nlohmann::json::exception& error) {
    problems.push_back(fmt::format("{}: damaged manifest: {}", (folder / "manifest.json").string(), error.what()));
  } catch (const Error& error) {
    problems.push_back(error.what());
  }
  return problems;
}

DatasetValidation validateDataset(const fs::path& path) {
  DatasetValidation result;
  result.path = fs::is_directory(path) ? path / "dataset.h5" : path;
  result.problems = outputFolderProblems(path);
  if (result.problems.empty() && fs::is_directory(path)) result.problems = runFolderRecordProblems(path);
  if (!result.problems.empty()) return result;
  try {
    const DatasetReader reader(result.path);
    result.samples = reader.size();
    for (std::size_t i = 0; i < reader.size(); ++i) {
      checkScene(reader.scene(i), i, reader.header(), result.problems);
    }
  } catch (const Error& error) {
    result.problems.push_back(error.what());
  }
  return result;
}

DatasetSummary summarizeDataset(const fs::path& path) {
  const DatasetReader reader(path);
  DatasetSummary summary;
  summary.path = path;
  summary.schema = reader.header().vehicleSizesAssumed ? kDatasetSchemaVersion1
                   : reader.header().roadUsersAssumed  ? kDatasetSchemaVersion2
                                                       : kDatasetSchema;
  summary.header = reader.header();
  summary.samples = reader.size();
  summary.bytes = fs::file_size(path);
  summary.toolVersion = reader.toolVersion();
  summary.featureMin.fill(std::numeric_limits<double>::infinity());
  summary.featureMax.fill(-std::numeric_limits<double>::infinity());
  std::size_t vectors = 0;
  std::size_t polylines = 0;
  std::map<std::string, bool> sources;
  for (std::size_t i = 0; i < reader.size(); ++i) {
    const auto scene = reader.scene(i);
    ++summary.samplesPerLabel[scene.label];
    sources[scene.provenance.source] = true;
    polylines += scene.polylines.size();
    for (const auto& polyline : scene.polylines) {
      for (std::size_t v = 0; v < polyline.vectors.size(); ++v) {
        ++vectors;
        if (!polyline.valid[v]) continue;
        for (std::size_t f = 0; f < kFeatures; ++f) {
          summary.featureMin[f] = std::min(summary.featureMin[f], polyline.vectors[v][f]);
          summary.featureMax[f] = std::max(summary.featureMax[f], polyline.vectors[v][f]);
        }
      }
    }
  }
  for (const auto& [source, present] : sources) summary.sources.push_back(source);
  if (summary.samples > 0) {
    summary.vectorsPerSample = static_cast<double>(vectors) / static_cast<double>(summary.samples);
    summary.polylinesPerSample = static_cast<double>(polylines) / static_cast<double>(summary.samples);
  }
  return summary;
}

std::string DatasetSummary::report() const {
  std::string text = fmt::format("{}\n  schema {} (features v{}: {}), kind {}, written by vsd-sumo {}\n", path.string(),
                                 schema, kFeatureVersion, joinedFeatureNames(), header.kind, toolVersion);
  text += fmt::format("  samples {}, step {} s, horizon {} steps, history {} steps\n", samples, header.step,
                      header.horizon, header.history);
  for (const auto& [label, count] : samplesPerLabel) text += fmt::format("    {:<20} {:>8} samples\n", label, count);
  text += fmt::format("  {:.1f} polylines and {:.1f} vectors per sample; {} bytes on disk = {:.0f} bytes per sample\n",
                      polylinesPerSample, vectorsPerSample, bytes,
                      samples > 0 ? static_cast<double>(bytes) / static_cast<double>(samples) : 0.0);
  if (!header.inputNames.empty()) text += fmt::format("  inputs: {}\n", fmt::join(header.inputNames, ", "));
  if (!header.metricNames.empty()) text += fmt::format("  metrics: {}\n", fmt::join(header.metricNames, ", "));
  text += "  provenance:\n";
  for (const auto& source : sources) text += fmt::format("    {}\n", source);
  if (samples > 0) {
    text += "  feature ranges (valid vectors):\n";
    for (std::size_t f = 0; f < kFeatures; ++f) {
      text += fmt::format("    {:<12} {:>12.3f} {:>12.3f}\n", kFeatureNames[f], featureMin[f], featureMax[f]);
    }
  }
  return text;
}

// --- collections -------------------------------------------------------------------------------

fs::path resolveDatasetPath(const fs::path& path) {
  if (!fs::is_directory(path)) return path;
  // A run folder is one unit: only a complete one (its manifest and sizes agree) is read.
  requireCompleteOutputFolder(path, /*hashes=*/false);
  if (!readManifestOutputs(path).count("dataset.h5")) {
    throw DatasetError(fmt::format("{}: the folder's manifest lists no dataset.h5 (not a run folder)", path.string()));
  }
  return path / "dataset.h5";
}

std::vector<fs::path> datasetFiles(const fs::path& path) {
  if (!fs::is_directory(path) || fs::exists(path / "dataset.h5") || !hasShards(path)) return {resolveDatasetPath(path)};
  std::vector<fs::path> files;
  for (const auto& shard : readShardSet(path)) files.push_back(shard.folder / "dataset.h5");
  return files;
}

void DatasetCollection::add(const fs::path& path_or_run_folder) {
  for (const auto& file : datasetFiles(path_or_run_folder)) readers_.push_back(std::make_unique<DatasetReader>(file));
}

std::vector<DatasetCollection::SampleRef> DatasetCollection::all() const {
  std::vector<SampleRef> refs;
  for (std::size_t f = 0; f < readers_.size(); ++f) {
    for (std::size_t i = 0; i < readers_[f]->size(); ++i) refs.push_back({f, i});
  }
  return refs;
}

std::vector<DatasetCollection::SampleRef> DatasetCollection::withLabel(const std::string& label) const {
  std::vector<SampleRef> refs;
  for (std::size_t f = 0; f < readers_.size(); ++f) {
    for (std::size_t i : readers_[f]->samplesWithLabel(label)) refs.push_back({f, i});
  }
  return refs;
}

std::map<std::string, std::size_t> DatasetCollection::labelCounts() const {
  std::map<std::string, std::size_t> counts;
  for (const auto& reader : readers_) {
    for (std::size_t i = 0; i < reader->size(); ++i) ++counts[reader->label(i)];
  }
  return counts;
}

}  // namespace vsd::vector
