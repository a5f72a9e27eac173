// Mutation of dataset files (attributes, arrays, truncation) and of model files
// (the JSON description, the parameter tensors), each handed to a command that
// reads it.
#include <H5Cpp.h>
#include <caffe2/serialize/inline_container.h>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>

#include "fuzz_cases.hpp"

namespace fs = std::filesystem;

namespace vsd::fuzz {

namespace {

// --- commands that read a dataset or a model ---------------------------------------------

/// A command reading `dataset` and `model` (one of them under test); outputs go to `folder`.
Case consumerCase(const std::string& consumer, const fs::path& dataset, const fs::path& model, const fs::path& folder,
                  const fs::path& training_data) {
  Case c;
  const std::string d = dataset.string();
  const std::string m = model.string();
  if (consumer == "validate") {
    c.args = {"dataset", "validate", d};
    c.exitOneIsAVerdict = true;
  } else if (consumer == "info") {
    c.args = {"dataset", "info", d};
  } else if (consumer == "show") {
    c.outputs = {folder / "s.svg"};
    c.args = {"dataset", "show", d, "--sample", "1", "--svg", c.outputs[0].string()};
  } else if (consumer == "evaluate") {
    c.outputs = {folder / "e.csv"};
    c.args = {"evaluate", "--model", m, "--data", d, "--csv", c.outputs[0].string(), "--threads", "1"};
  } else if (consumer == "predict") {
    c.outputs = {folder / "p.h5"};
    c.args = {"predict", "--model", m, "--data", d, "--out", c.outputs[0].string(), "--threads", "1"};
  } else if (consumer == "compare") {
    c.outputs = {folder / "report"};
    c.args = {"compare", "--model", m, "--data", d, "--out", c.outputs[0].string(), "--threads", "1"};
  } else if (consumer == "compare-scenario") {
    c.outputs = {folder / "report"};
    c.args = {"compare", (fs::path(VSD_SOURCE_DIR) / "scenarios" / "acc.yaml").string(), "--model", m, "--samples", "4",
              "--out", c.outputs[0].string(), "--threads", "1"};
  } else if (consumer == "train") {
    c.outputs = {folder / "m.pt"};
    c.args = {"train", "--data", d, "--out", c.outputs[0].string(), "--steps", "3", "--batch", "8", "--hidden", "8",
              "--global-width", "8", "--decoder-hidden", "16", "--threads", "1"};
  } else if (consumer == "resume") {
    // The mutated file is a training checkpoint: resume from it.
    c.outputs = {folder / "model.pt"};
    fs::copy_file(model, folder / "model.pt.last", fs::copy_options::overwrite_existing);
    c.args = {"train", "--data", training_data.string(), "--out", c.outputs[0].string(), "--steps", "8", "--batch",
              "8", "--hidden", "8", "--global-width", "8", "--decoder-hidden", "16", "--threads", "1", "--resume"};
  }
  return c;
}

// --- dataset mutation -------------------------------------------------------------------------

void deleteAttribute(H5::Group& root, const std::string& name) {
  if (root.attrExists(name)) root.removeAttr(name);
}

void mutateAttribute(H5::Group& root, Random& random, std::string& description) {
  static const std::vector<std::string> names = {"schema", "feature_version", "features", "kind",
                                                 "step",   "horizon",         "history",  "tool_version"};
  const std::string& name = random.pick(names);
  const int operation = static_cast<int>(random.index(5));
  deleteAttribute(root, name);
  if (operation == 0) {
    description = "attribute " + name + " removed";
    return;
  }
  if (operation == 1) {  // a hostile integer
    const std::int64_t value = random.pick(std::vector<std::int64_t>{-1, 0, 2, 1001, 1LL << 31, 1LL << 62,
                                                                     std::numeric_limits<std::int64_t>::min()});
    root.createAttribute(name, H5::PredType::NATIVE_INT64, H5::DataSpace(H5S_SCALAR))
        .write(H5::PredType::NATIVE_INT64, &value);
    description = fmt::format("attribute {} = {} (int)", name, value);
  } else if (operation == 2) {  // a hostile float
    const double value = random.pick(std::vector<double>{-0.2, 0.0, 1e-9, 0.1, 25.5, 1e300,
                                                         std::numeric_limits<double>::quiet_NaN(),
                                                         std::numeric_limits<double>::infinity()});
    root.createAttribute(name, H5::PredType::NATIVE_DOUBLE, H5::DataSpace(H5S_SCALAR))
        .write(H5::PredType::NATIVE_DOUBLE, &value);
    description = fmt::format("attribute {} = {} (float)", name, value);
  } else if (operation == 3) {  // a string where a number belongs, or a foreign one
    H5::StrType type(H5::PredType::C_S1, H5T_VARIABLE);
    const std::string value = random.pick(std::vector<std::string>{"", "25", "vsd-dataset/9", "map", "weird"});
    root.createAttribute(name, type, H5::DataSpace(H5S_SCALAR)).write(type, value);
    description = fmt::format("attribute {} = '{}' (string)", name, value);
  } else {  // several values where one belongs
    const hsize_t count = 4;
    const std::int64_t values[4] = {25, 25, 25, 25};
    root.createAttribute(name, H5::PredType::NATIVE_INT64, H5::DataSpace(1, &count))
        .write(H5::PredType::NATIVE_INT64, values);
    description = fmt::format("attribute {} = [4 values]", name);
  }
}

std::vector<std::string> datasetNames(const H5::Group& root) {
  std::vector<std::string> names;
  for (hsize_t i = 0; i < root.getNumObjs(); ++i) names.push_back(root.getObjnameByIdx(i));
  return names;
}

/// Overwrites row `row`'s first value with a hostile one of the dataset's kind.
void overwriteValue(H5::DataSet& dataset, Random& random, std::string& description) {
  H5::DataSpace space = dataset.getSpace();
  const int rank = space.getSimpleExtentNdims();
  std::vector<hsize_t> dims(static_cast<std::size_t>(rank));
  space.getSimpleExtentDims(dims.data());
  if (rank == 0 || dims[0] == 0) return;
  std::vector<hsize_t> start(dims.size(), 0);
  std::vector<hsize_t> count(dims.size(), 1);
  start[0] = random.index(dims[0]);
  if (rank > 1) start[1] = random.index(dims[1]);
  space.selectHyperslab(H5S_SELECT_SET, count.data(), start.data());
  H5::DataSpace one(1, std::vector<hsize_t>{1}.data());
  if (dataset.getTypeClass() == H5T_FLOAT) {
    const double value = random.pick(std::vector<double>{std::numeric_limits<double>::quiet_NaN(),
                                                         std::numeric_limits<double>::infinity(), -1e38, 1e300, -1.0});
    dataset.write(&value, H5::PredType::NATIVE_DOUBLE, one, space);
    description += fmt::format(" row {} = {}", start[0], value);
  } else if (dataset.getTypeClass() == H5T_INTEGER) {
    const std::int64_t value = random.pick(std::vector<std::int64_t>{-1, -7, 1 << 20, 2147483647, 1LL << 40,
                                                                     std::numeric_limits<std::int64_t>::max()});
    // HDF5 clips a value the stored type cannot hold: the extremes of int8/int32 arrays.
    dataset.write(&value, H5::PredType::NATIVE_INT64, one, space);
    description += fmt::format(" row {} = {}", start[0], value);
  }
}

void mutateArray(H5::Group& root, Random& random, std::string& description) {
  const auto names = datasetNames(root);
  const std::string name = random.pick(names);
  description = "array " + name;
  const int operation = static_cast<int>(random.index(5));
  if (operation == 0) {
    root.unlink(name);
    description += " removed";
    return;
  }
  H5::DataSet dataset = root.openDataSet(name);
  if (operation <= 2) {
    overwriteValue(dataset, random, description);
    return;
  }
  H5::DataSpace space = dataset.getSpace();
  const int rank = space.getSimpleExtentNdims();
  std::vector<hsize_t> dims(static_cast<std::size_t>(rank));
  space.getSimpleExtentDims(dims.data());
  if (operation == 3 && rank > 0 && dataset.getCreatePlist().getLayout() == H5D_CHUNKED) {
    // More rows than were written: small (fill values) or absurd (an extent without data).
    auto grown = dims;
    grown[0] = random.chance(0.5) ? dims[0] + 3 : (dims[0] + 1) * 1'000'000'000ULL;
    dataset.extend(grown.data());
    description += fmt::format(" grown to {} rows", grown[0]);
    return;
  }
  // Replaced by an array of the same name but another shape.
  const H5::DataType type = dataset.getDataType();
  dataset.close();
  root.unlink(name);
  std::vector<hsize_t> shape = dims;
  if (shape.empty()) shape = {1};
  if (random.chance(0.5)) shape[0] = shape[0] > 0 ? shape[0] - 1 : 1;
  else shape.push_back(3);
  root.createDataSet(name, type, H5::DataSpace(static_cast<int>(shape.size()), shape.data()));
  description += fmt::format(" replaced by shape [{}]", fmt::join(shape, ", "));
}

void truncateFile(const fs::path& path, Random& random, std::string& description) {
  const auto size = fs::file_size(path);
  const auto keep = static_cast<std::uintmax_t>(random.index(static_cast<std::size_t>(size)));
  fs::resize_file(path, keep);
  description = fmt::format("truncated to {} of {} bytes", keep, size);
}

std::string mutateDataset(const fs::path& path, Random& random) {
  std::string description;
  const int kind = static_cast<int>(random.index(10));
  if (kind == 0) {
    truncateFile(path, random, description);
    return description;
  }
  H5::Exception::dontPrint();
  H5::H5File file(path.string(), H5F_ACC_RDWR);
  H5::Group root = file.openGroup("/");
  if (kind <= 3) mutateAttribute(root, random, description);
  else mutateArray(root, random, description);
  return description;
}

// --- model mutation ---------------------------------------------------------------------------

/// The records of a torch archive, and where the JSON description sits in data.pkl.
struct Archive {
  std::vector<std::pair<std::string, std::string>> records;  ///< name -> bytes
  std::uint64_t version = 0;
};

Archive readArchive(const fs::path& path) {
  caffe2::serialize::PyTorchStreamReader reader(path.string());
  Archive archive;
  archive.version = reader.version();
  for (const auto& name : reader.getAllRecords()) {
    if (name == "version" || name == ".data/version") continue;  // written by writeEndOfFile
    auto [data, size] = reader.getRecord(name);
    archive.records.emplace_back(name, std::string(static_cast<const char*>(data.get()), size));
  }
  return archive;
}

void writeArchive(const Archive& archive, const fs::path& path) {
  caffe2::serialize::PyTorchStreamWriter writer(path.string());
  writer.setMinVersion(archive.version);
  for (const auto& [name, bytes] : archive.records) writer.writeRecord(name, bytes.data(), bytes.size());
  writer.writeEndOfFile();
}

/// Replaces the pickled JSON description (a BINUNICODE string: 'X', 4-byte length, bytes).
bool editDescription(std::string& pickle, const std::function<std::string(const std::string&)>& edit) {
  const auto at = pickle.find("{\"architecture\"");
  if (at == std::string::npos || at < 5 || pickle[at - 5] != 'X') return false;
  std::uint32_t length = 0;
  std::memcpy(&length, &pickle[at - 4], 4);
  const std::string replacement = edit(pickle.substr(at, length));
  const auto new_length = static_cast<std::uint32_t>(replacement.size());
  std::memcpy(&pickle[at - 4], &new_length, 4);
  pickle.replace(at, length, replacement);
  return true;
}

std::string mutateDescription(const std::string& text, Random& random, std::string& description) {
  nlohmann::json json = nlohmann::json::parse(text);
  static const std::vector<std::string> config_keys = {"hidden", "subgraph_layers", "global_width", "heads",
                                                       "decoder_hidden", "horizon", "step", "coordinate_scale"};
  static const std::vector<std::string> top_keys = {"format", "feature_version", "dataset_schema", "mix",
                                                    "seed",   "epoch",           "validation_ade", "labels"};
  const bool config = random.chance(0.7);
  const std::string key = config ? random.pick(config_keys) : random.pick(top_keys);
  nlohmann::json& target = config ? json["config"][key] : json[key];
  const nlohmann::json original = target;
  const int operation = static_cast<int>(random.index(6));
  if (operation == 0) {
    (config ? json["config"] : json).erase(key);
    description = "description: " + key + " removed";
    return json.dump();
  }
  const std::vector<nlohmann::json> values = {
      -1, 0, 1, 7, 2147483647, 1e300, 64.5, "64", nullptr, true, nlohmann::json::array({1, 2}),
      std::numeric_limits<double>::quiet_NaN()};
  if (operation <= 2 && original.is_number()) {
    // A plausible but wrong value: the tensors no longer match the description.
    target = original.is_number_integer() ? nlohmann::json(original.get<std::int64_t>() * 2 + 1)
                                          : nlohmann::json(original.get<double>() * 3.0);
  } else {
    target = random.pick(values);
  }
  description = fmt::format("description: {} = {}", key, target.dump());
  if (random.chance(0.1)) {
    description += " (JSON cut short)";
    const std::string dumped = json.dump();
    return dumped.substr(0, dumped.size() / 2);
  }
  return json.dump();
}

std::string mutateModel(const fs::path& path, Random& random) {
  Archive archive = readArchive(path);
  std::string description;
  const int kind = static_cast<int>(random.index(4));
  if (kind <= 1) {
    for (auto& [name, bytes] : archive.records) {
      if (name != "data.pkl") continue;
      editDescription(bytes, [&](const std::string& text) { return mutateDescription(text, random, description); });
    }
  } else {
    // The tensors: one dropped, cut short, or exchanged with another of another size.
    std::vector<std::size_t> tensors;
    for (std::size_t i = 0; i < archive.records.size(); ++i) {
      if (archive.records[i].first.rfind("data/", 0) == 0) tensors.push_back(i);
    }
    const std::size_t t = random.pick(tensors);
    if (kind == 2 && random.chance(0.5)) {
      description = "tensor record " + archive.records[t].first + " removed";
      archive.records.erase(archive.records.begin() + static_cast<std::ptrdiff_t>(t));
    } else if (kind == 2) {
      auto& bytes = archive.records[t].second;
      description = fmt::format("tensor record {} cut from {} to {} bytes", archive.records[t].first, bytes.size(),
                                bytes.size() / 2);
      bytes.resize(bytes.size() / 2);
    } else {
      const std::size_t other = random.pick(tensors);
      description = fmt::format("tensor records {} and {} exchanged", archive.records[t].first,
                                archive.records[other].first);
      std::swap(archive.records[t].second, archive.records[other].second);
    }
  }
  writeArchive(archive, path);
  return description;
}

}  // namespace

std::vector<Case> datasetCases(const Fixtures& fixtures, Random& random, std::size_t count) {
  const std::vector<std::string> consumers = {"validate", "info", "show", "evaluate", "predict", "compare", "train"};
  std::vector<Case> cases;
  for (std::size_t i = 0; i < count; ++i) {
    const fs::path folder = caseFolder(fixtures, "dataset", i);
    const bool map = random.chance(0.3);
    const fs::path source = map ? fixtures.mapDataset : fixtures.run / "dataset.h5";
    const fs::path file = folder / "data.h5";
    fs::copy_file(source, file, fs::copy_options::overwrite_existing);
    std::string description;
    try {
      description = mutateDataset(file, random);
    } catch (const H5::Exception& error) {
      description = "mutation failed half-way: " + error.getDetailMsg();
    }
    const std::string& consumer = random.pick(consumers);
    Case c = consumerCase(consumer, file, fixtures.model, folder, fixtures.run);
    c.name = fmt::format("dataset/{} {}: {}", map ? "map" : "run", consumer, description);
    cases.push_back(std::move(c));
  }
  return cases;
}

std::vector<Case> modelCases(const Fixtures& fixtures, Random& random, std::size_t count) {
  const std::vector<std::string> consumers = {"evaluate", "predict", "compare", "compare-scenario", "resume"};
  std::vector<Case> cases;
  for (std::size_t i = 0; i < count; ++i) {
    const fs::path folder = caseFolder(fixtures, "model", i);
    const std::string& consumer = random.pick(consumers);
    const fs::path file = folder / "mutated.pt";
    fs::copy_file(consumer == "resume" ? fixtures.checkpoint : fixtures.model, file,
                  fs::copy_options::overwrite_existing);
    const std::string description = mutateModel(file, random);
    Case c = consumerCase(consumer, fixtures.run / "dataset.h5", file, folder, fixtures.run);
    c.name = fmt::format("model/{}: {}", consumer, description);
    cases.push_back(std::move(c));
  }
  return cases;
}

}  // namespace vsd::fuzz
