#pragma once
// Datasets of vectorized scenes (HDF5, schema "vsd-dataset/3", documented in
// the README): written streaming (memory flat in the number of samples), read
// per sample, validated, summarised, and combined across files without copying.
//
// Layout (N samples, P polylines, V vectors in total; ragged arrays with offsets):
//   /                      attrs: schema, feature_version, features, kind, step [s],
//                          horizon [steps], history [steps], tool_version
//   /labels [L], /input_names [I], /metric_names [M], /sources [S], /source_sha256 [S]   strings
//   /vectors [V, 7] float32        features, x/y relative to the sample origin
//   /vector_valid [V] uint8
//   /shared_vectors [S, 7] float64 lane-boundary vectors of a map, stored once (absolute coordinates)
//   /polyline_type [P] int8, /polyline_shared [P] uint8 (1: vectors in /shared_vectors),
//   /polyline_vector_start [P] int64 (into /vectors or /shared_vectors), /polyline_vector_count [P] int32
//   /polyline_length [P], /polyline_width [P] float64   vehicle size (m; 0 for lane boundaries)
//   /polyline_road_user [P] int8   road-user kind of vehicle polylines (core/road_user.hpp codes; -1 for lanes)
//   /sample_polyline_start [N] int64, /sample_polyline_count [N] int32, /sample_ego_polyline [N] int32
//   /sample_origin [N, 2] float64  (the Ego's initial position)
//   /sample_label [N] int32, /sample_index [N] int64, /sample_source [N] int32,
//   /sample_ego_id [N] string, /sample_t0 [N] float64
//   /targets [N, F, 2] float32 (relative to the origin), /target_valid [N, F] uint8
//   /inputs [N, I] float64 (only if I > 0), /metrics [N, M] float64 (only if M > 0)

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "vsd/core/road_user.hpp"
#include "vsd/vector/scene.hpp"

namespace vsd::vector {

inline constexpr const char* kDatasetSchema = "vsd-dataset/3";
/// Older schemas, still read. Version 2 stores no road-user kinds: every vehicle is read as
/// a car. Version 1 stores no vehicle sizes either: readers assume a car's (the road-user
/// table's) for every vehicle and say so.
inline constexpr const char* kDatasetSchemaVersion2 = "vsd-dataset/2";
inline constexpr const char* kDatasetSchemaVersion1 = "vsd-dataset/1";
/// m, what version-1 files are read with: a car's size from the road-user table.
inline const double kAssumedVehicleLength = roadUserKind(RoadUserType::Car).length;
inline const double kAssumedVehicleWidth = roadUserKind(RoadUserType::Car).width;

/// What every sample of a file shares.
struct DatasetHeader {
  std::string kind = "generated";  ///< "generated" (vsd-sumo run) or "map" (vsd-sumo export)
  double step = 0.0;               ///< s (> 0); no default: from the scenario or the export options
  int horizon = 0;                 ///< F: target steps (>= 1); no default, like step
  int history = 0;                 ///< H: steps before t0 in vehicle polylines
  std::vector<std::string> inputNames;
  std::vector<std::string> metricNames;
  /// deflate level of the bulk arrays (vectors): 0 = none (fastest, ~2x larger), 1..9.
  /// Not stored: HDF5 records the filter per dataset, h5py reads either.
  int compression = 1;
  /// Set by readers of version-1 files: vehicle sizes are not stored there and were assumed.
  bool vehicleSizesAssumed = false;
  /// Set by readers of version-1 and -2 files: every vehicle is read as a car.
  bool roadUsersAssumed = false;
};

class DatasetReader;

class DatasetWriter {
 public:
  /// Creates the file at `path` (callers write to a temporary path and rename when
  /// complete; `name_in_messages`, e.g. the final path, is what errors name).
  /// Throws IoError naming the file, the array and the cause (e.g. a full disk).
  DatasetWriter(const std::filesystem::path& path, DatasetHeader header,
                const std::filesystem::path& name_in_messages = {});
  DatasetWriter(const DatasetWriter&) = delete;
  DatasetWriter& operator=(const DatasetWriter&) = delete;
  ~DatasetWriter();

  /// Stores a map's lane-boundary vectors once; polylines with a sharedStart then
  /// refer to them instead of repeating them per sample. Call before append().
  void setSharedVectors(const std::vector<Feature>& pool);
  /// Appends one scene (its target length must equal the horizon). Buffered.
  void append(const VectorizedScene& scene);
  /// Appends sample `sample` of `source` exactly as stored there (its float32 vectors
  /// and targets are copied, not recomputed from absolute coordinates), so joining
  /// files sample by sample gives the bytes of writing them in one go. `source` must
  /// have the same header and shared lane vectors; throws DatasetError otherwise.
  void appendCopy(const DatasetReader& source, std::size_t sample);
  std::size_t size() const;
  /// Flushes and writes the string tables; the file is complete afterwards.
  void close();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

class DatasetReader {
 public:
  /// Opens and checks a dataset. Throws DatasetError naming the file for a missing,
  /// corrupt, foreign or unknown-schema file.
  explicit DatasetReader(const std::filesystem::path& path);
  DatasetReader(const DatasetReader&) = delete;
  DatasetReader& operator=(const DatasetReader&) = delete;
  ~DatasetReader();

  const std::filesystem::path& path() const;
  const DatasetHeader& header() const;
  /// Version of vsd-sumo that wrote the file.
  const std::string& toolVersion() const;
  std::size_t size() const;
  const std::vector<std::string>& labels() const;
  const std::string& label(std::size_t sample) const;
  /// Reads one scene (with inputs, metrics and provenance).
  VectorizedScene scene(std::size_t sample) const;
  /// Indices of the samples with `label`, in file order.
  std::vector<std::size_t> samplesWithLabel(const std::string& label) const;

  /// What ties each sample to the run that made it, without reading any vector.
  struct SampleRecord {
    std::uint64_t sample = 0;    ///< sample index (window number for map exports)
    std::string sourceSha256;    ///< of the scenario or map file
    std::vector<double> inputs;  ///< concrete inputs (generated scenarios)
  };
  std::vector<SampleRecord> records() const;

 private:
  friend class DatasetWriter;  // appendCopy reads samples in stored form
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Result of a full consistency check of a dataset file.
struct DatasetValidation {
  std::filesystem::path path;
  std::size_t samples = 0;
  std::vector<std::string> problems;  ///< empty: valid
  bool ok() const { return problems.empty(); }
};

/// Checks every invariant of the schema: offsets and counts consistent, one Ego
/// polyline per sample whose last vector is its initial vector, object types and
/// polyline ids as documented, finite valid vectors and targets, timestamps within
/// [-history, horizon] steps, string tables in range. Unreadable files yield one problem.
/// A run folder (or a file its manifest lists) is first checked against its
/// manifest: present, unedited (its checksum), complete, every file's size and SHA-256
/// as listed, and its records consistent (runFolderRecordProblems).
DatasetValidation validateDataset(const std::filesystem::path& path);

/// Problems (one line each; empty: consistent) of the records of a run's output folder
/// (`run`, a shard, a merged sweep, `search`): what its manifest says against what its
/// files hold. Its concrete.csv lists exactly the manifest's seed (and, for a shard, the
/// shard's sample range); every sample of its dataset.h5 is a completed scenario of
/// concrete.csv with the same inputs, made from the manifest's scenario file (SHA-256),
/// and every completed scenario is in the dataset. A dataset.h5 joined from files of
/// another run (another seed, a round file of another search) or a manifest whose seed
/// was edited fails here. Folders without concrete.csv (exports) have no such records.
std::vector<std::string> runFolderRecordProblems(const std::filesystem::path& folder);

/// What `vsd-sumo dataset info` prints.
struct DatasetSummary {
  std::filesystem::path path;
  std::string schema;
  DatasetHeader header;
  std::size_t samples = 0;
  std::map<std::string, std::size_t> samplesPerLabel;
  std::vector<std::string> sources;
  double vectorsPerSample = 0.0;
  double polylinesPerSample = 0.0;
  std::uintmax_t bytes = 0;
  std::array<double, kFeatures> featureMin{};
  std::array<double, kFeatures> featureMax{};  ///< over valid vectors, absolute coordinates
  std::string toolVersion;
  std::string report() const;
};
DatasetSummary summarizeDataset(const std::filesystem::path& path);

/// Several dataset files seen as one list of samples, without copying.
class DatasetCollection {
 public:
  struct SampleRef {
    std::size_t file = 0;
    std::size_t index = 0;
  };
  /// Opens a file, the dataset.h5 inside a run's output folder, or every shard's
  /// dataset.h5 of a sharded sweep's folder (see datasetFiles).
  void add(const std::filesystem::path& path_or_run_folder);
  std::size_t files() const { return readers_.size(); }
  const DatasetReader& reader(std::size_t file) const { return *readers_.at(file); }
  /// Every sample of every file, file by file.
  std::vector<SampleRef> all() const;
  /// Every sample with `label`.
  std::vector<SampleRef> withLabel(const std::string& label) const;
  /// Labels and their sample counts over all files.
  std::map<std::string, std::size_t> labelCounts() const;
  VectorizedScene scene(const SampleRef& ref) const { return readers_.at(ref.file)->scene(ref.index); }

 private:
  std::vector<std::unique_ptr<DatasetReader>> readers_;
};

/// `path` if it is a file; `path/dataset.h5` if it is a run's output folder —
/// after checking that the folder is complete (its manifest lists dataset.h5 and
/// every listed file has its size). Throws DatasetError naming the folder.
std::filesystem::path resolveDatasetPath(const std::filesystem::path& path);

/// The dataset files `path` stands for: a file; a run folder's dataset.h5; or, for a
/// sweep folder with shards/ and no merged dataset.h5, every shard's dataset.h5 in
/// sample order — after checking that the shards form one complete sweep (throws
/// DatasetError naming a missing, unfinished or foreign shard).
std::vector<std::filesystem::path> datasetFiles(const std::filesystem::path& path);

}  // namespace vsd::vector
