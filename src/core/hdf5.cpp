#include "vsd/core/hdf5.hpp"

#include <fmt/format.h>
#include <libdeflate.h>

#include <algorithm>
#include <memory>
#include <numeric>

namespace vsd::h5 {

namespace {
hsize_t product(const std::vector<hsize_t>& values) {
  return std::accumulate(values.begin(), values.end(), hsize_t{1}, std::multiplies<>());
}

/// HDF5's shuffle filter: byte b of every element, then byte b + 1, ... (element order kept).
void shuffleBytes(const unsigned char* in, std::size_t bytes, std::size_t element_size, unsigned char* out) {
  const std::size_t elements = bytes / element_size;
  for (std::size_t b = 0; b < element_size; ++b) {
    unsigned char* row = out + b * elements;
    for (std::size_t e = 0; e < elements; ++e) row[e] = in[e * element_size + b];
  }
}

struct CompressorDeleter {
  void operator()(libdeflate_compressor* compressor) const { libdeflate_free_compressor(compressor); }
};

/// A thread's compressors (one per level: a file's arrays may use two levels, and a level-4
/// compressor takes 0.7 MB to set up) and its buffers for one chunk.
struct ChunkCompression {
  static constexpr int kLevels = 13;  // libdeflate: 0 .. 12
  std::unique_ptr<libdeflate_compressor, CompressorDeleter> compressors[kLevels];
  std::vector<unsigned char> shuffled;
  std::vector<unsigned char> stored;

  /// Gives back buffers a large chunk left behind (a run with many road users or instants).
  void releaseLargeBuffers() {
    constexpr std::size_t kKept = std::size_t{16} << 20;
    if (shuffled.capacity() > kKept) std::vector<unsigned char>().swap(shuffled);
    if (stored.capacity() > kKept) std::vector<unsigned char>().swap(stored);
  }
};

ChunkCompression& chunkCompression() {
  thread_local ChunkCompression compression;
  return compression;
}

/// A chunk as HDF5's shuffle + deflate filters store it: shuffled, then a zlib stream at
/// `level` (1 .. 9, HDF5's range). The buffer is the calling thread's, valid until its next call.
const std::vector<unsigned char>& deflateChunk(const unsigned char* chunk, std::size_t bytes,
                                               std::size_t element_size, int level) {
  ChunkCompression& compression = chunkCompression();
  auto& compressor = compression.compressors[std::clamp(level, 0, ChunkCompression::kLevels - 1)];
  if (!compressor) {
    compressor.reset(libdeflate_alloc_compressor(level));
    if (!compressor) throw std::bad_alloc();
  }
  compression.shuffled.resize(bytes);
  shuffleBytes(chunk, bytes, element_size, compression.shuffled.data());
  std::vector<unsigned char>& stored = compression.stored;
  stored.resize(libdeflate_zlib_compress_bound(compressor.get(), bytes));
  const std::size_t size =
      libdeflate_zlib_compress(compressor.get(), compression.shuffled.data(), bytes, stored.data(), stored.size());
  if (size == 0) throw H5::DataSetIException("deflateChunk", "libdeflate could not compress a chunk");
  stored.resize(size);
  return stored;
}
}  // namespace

template <typename T>
Appendable<T>::Appendable(H5::Group& parent, const std::string& name, std::vector<hsize_t> row_shape,
                          hsize_t chunk_rows, int deflate_level)
    : rowShape_(std::move(row_shape)), chunkRows_(std::max<hsize_t>(chunk_rows, 1)), deflateLevel_(deflate_level) {
  std::vector<hsize_t> dims = {0};
  std::vector<hsize_t> max_dims = {H5S_UNLIMITED};
  std::vector<hsize_t> chunk = {chunkRows_};
  for (hsize_t extent : rowShape_) {
    dims.push_back(extent);
    max_dims.push_back(extent);
    chunk.push_back(std::max<hsize_t>(extent, 1));
  }
  H5::DataSpace space(static_cast<int>(dims.size()), dims.data(), max_dims.data());
  H5::DSetCreatPropList properties;
  properties.setChunk(static_cast<int>(chunk.size()), chunk.data());
  if (deflate_level > 0) {
    properties.setShuffle();  // the order writeWholeChunk applies them in
    properties.setDeflate(deflate_level);
  }
  H5Pset_obj_track_times(properties.getId(), false);
  dataset_ = parent.createDataSet(name, nativeType<T>(), space, properties);
}

template <typename T>
hsize_t Appendable<T>::rowSize() const {
  return product(rowShape_);
}

template <typename T>
void Appendable<T>::extendTo(hsize_t rows) {
  std::vector<hsize_t> new_dims = {rows};
  new_dims.insert(new_dims.end(), rowShape_.begin(), rowShape_.end());
  dataset_.extend(new_dims.data());
}

template <typename T>
void Appendable<T>::writeThroughFilters(const T* data, hsize_t rows) {
  extendTo(rows_ + rows);
  H5::DataSpace file_space = dataset_.getSpace();
  std::vector<hsize_t> start(rowShape_.size() + 1, 0);
  start[0] = rows_;
  std::vector<hsize_t> count = {rows};
  count.insert(count.end(), rowShape_.begin(), rowShape_.end());
  file_space.selectHyperslab(H5S_SELECT_SET, count.data(), start.data());
  H5::DataSpace memory_space(static_cast<int>(count.size()), count.data());
  dataset_.write(data, nativeType<T>(), memory_space, file_space);
  rows_ += rows;
}

template <typename T>
void Appendable<T>::writeWholeChunk(const T* chunk, hsize_t first) {
  const auto bytes = static_cast<std::size_t>(chunkRows_ * rowSize()) * sizeof(T);
  const std::vector<unsigned char>& stored =
      deflateChunk(reinterpret_cast<const unsigned char*>(chunk), bytes, sizeof(T), deflateLevel_);
  std::vector<hsize_t> offset(rowShape_.size() + 1, 0);
  offset[0] = first;
  extendTo(first + chunkRows_);
  // Filter mask 0: every filter of the dataset was applied. A cached copy of the chunk
  // (its head, written through the filters) is dropped, not flushed over this one.
  const herr_t written = H5Dwrite_chunk(dataset_.getId(), H5P_DEFAULT, 0, offset.data(), stored.size(), stored.data());
  chunkCompression().releaseLargeBuffers();
  if (written < 0) throw H5::DataSetIException("H5Dwrite_chunk", "writing a chunk failed");
  rows_ = first + chunkRows_;
}

template <typename T>
void Appendable<T>::append(const T* data, hsize_t rows) {
  if (rows == 0) return;
  try {
    if (deflateLevel_ <= 0) {
      writeThroughFilters(data, rows);
      return;
    }
    const hsize_t row_size = rowSize();
    while (rows > 0) {
      const hsize_t head_rows = rows_ % chunkRows_;
      const hsize_t take = std::min(chunkRows_ - head_rows, rows);
      if (head_rows + take < chunkRows_) {  // the chunk stays incomplete: HDF5 compresses it when it is flushed
        chunkHead_.insert(chunkHead_.end(), data, data + take * row_size);
        writeThroughFilters(data, take);
      } else if (head_rows == 0) {
        writeWholeChunk(data, rows_);
      } else {  // completes a chunk whose head is in the file already
        chunkHead_.insert(chunkHead_.end(), data, data + take * row_size);
        writeWholeChunk(chunkHead_.data(), rows_ - head_rows);
        chunkHead_.clear();
      }
      data += take * row_size;
      rows -= take;
    }
  } catch (const H5::Exception& error) {
    // Which array failed, and why (the cause first: the next HDF5 call clears it).
    const std::string cause = errorCause(error);
    dropUnwrittenHead();
    throw H5::DataSetIException("append", fmt::format("writing '{}' failed: {}", dataset_.getObjName(), cause));
  } catch (...) {
    dropUnwrittenHead();
    throw;
  }
}

template <typename T>
void Appendable<T>::dropUnwrittenHead() {
  // rows_ counts only rows in the file: the head keeps exactly those of the current chunk.
  chunkHead_.resize(static_cast<std::size_t>((rows_ % chunkRows_) * rowSize()));
}

template <typename T>
void Appendable<T>::append(const std::vector<T>& data) {
  const hsize_t row_size = rowSize();
  append(data.data(), row_size == 0 ? 0 : data.size() / row_size);
}

template class Appendable<double>;
template class Appendable<float>;
template class Appendable<std::int64_t>;
template class Appendable<std::int32_t>;
template class Appendable<std::uint8_t>;
template class Appendable<std::int8_t>;

void writeAttribute(H5::H5Object& object, const std::string& name, const std::string& value) {
  // Variable-length UTF-8: h5py returns these as str (fixed-length ones come back as bytes).
  H5::StrType type(H5::PredType::C_S1, H5T_VARIABLE);
  type.setCset(H5T_CSET_UTF8);
  H5::Attribute attribute = object.createAttribute(name, type, H5::DataSpace(H5S_SCALAR));
  attribute.write(type, value);
}

void writeAttribute(H5::H5Object& object, const std::string& name, double value) {
  H5::Attribute attribute = object.createAttribute(name, H5::PredType::NATIVE_DOUBLE, H5::DataSpace(H5S_SCALAR));
  attribute.write(H5::PredType::NATIVE_DOUBLE, &value);
}

void writeAttribute(H5::H5Object& object, const std::string& name, std::int64_t value) {
  H5::Attribute attribute = object.createAttribute(name, H5::PredType::NATIVE_INT64, H5::DataSpace(H5S_SCALAR));
  attribute.write(H5::PredType::NATIVE_INT64, &value);
}

bool hasAttribute(const H5::H5Object& object, const std::string& name) { return object.attrExists(name); }

namespace {

/// An attribute that must hold one value of `type_class`; reading a longer one into
/// a single value would write past it.
H5::Attribute openSingleAttribute(const H5::H5Object& object, const std::string& name,
                                  std::initializer_list<H5T_class_t> classes, const char* expected) {
  H5::Attribute attribute = object.openAttribute(name);
  const H5T_class_t type_class = attribute.getTypeClass();
  const bool class_ok = std::find(classes.begin(), classes.end(), type_class) != classes.end();
  if (attribute.getSpace().getSimpleExtentNpoints() != 1 || !class_ok) {
    throw H5::AttributeIException("readAttribute", fmt::format("attribute '{}' is not a single {}", name, expected));
  }
  return attribute;
}

}  // namespace

std::string readStringAttribute(const H5::H5Object& object, const std::string& name) {
  H5::Attribute attribute = openSingleAttribute(object, name, {H5T_STRING}, "string");
  H5::StrType type = attribute.getStrType();
  std::string value;
  attribute.read(type, value);
  while (!value.empty() && value.back() == '\0') value.pop_back();
  return value;
}

double readDoubleAttribute(const H5::H5Object& object, const std::string& name) {
  double value = 0.0;
  openSingleAttribute(object, name, {H5T_FLOAT, H5T_INTEGER}, "number").read(H5::PredType::NATIVE_DOUBLE, &value);
  return value;
}

std::int64_t readIntAttribute(const H5::H5Object& object, const std::string& name) {
  // Integers only: HDF5 would truncate 25.7 to 25 and clip 1e30 silently.
  std::int64_t value = 0;
  openSingleAttribute(object, name, {H5T_INTEGER}, "whole number").read(H5::PredType::NATIVE_INT64, &value);
  return value;
}

void writeStrings(H5::Group& parent, const std::string& name, const std::vector<std::string>& values) {
  H5::StrType type(H5::PredType::C_S1, H5T_VARIABLE);
  type.setCset(H5T_CSET_UTF8);
  const hsize_t count = values.size();
  H5::DataSpace space(1, &count);
  H5::DSetCreatPropList properties;
  H5Pset_obj_track_times(properties.getId(), false);
  H5::DataSet dataset = parent.createDataSet(name, type, space, properties);
  std::vector<const char*> pointers;
  pointers.reserve(values.size());
  for (const auto& value : values) pointers.push_back(value.c_str());
  if (!pointers.empty()) dataset.write(pointers.data(), type);
}

std::vector<std::string> readStrings(const H5::Group& parent, const std::string& name) {
  H5::DataSet dataset = parent.openDataSet(name);
  const auto dims = shapeOf(dataset);
  const hsize_t count = dims.empty() ? 0 : dims[0];
  std::vector<std::string> values;
  if (count == 0) return values;
  H5::StrType type(H5::PredType::C_S1, H5T_VARIABLE);
  type.setCset(H5T_CSET_UTF8);
  std::vector<char*> pointers(count, nullptr);
  dataset.read(pointers.data(), type);
  for (char* pointer : pointers) values.emplace_back(pointer != nullptr ? pointer : "");
  H5::DataSpace space = dataset.getSpace();
  H5Dvlen_reclaim(type.getId(), space.getId(), H5P_DEFAULT, pointers.data());
  return values;
}

std::vector<hsize_t> shapeOf(const H5::DataSet& dataset) {
  H5::DataSpace space = dataset.getSpace();
  const int rank = space.getSimpleExtentNdims();
  std::vector<hsize_t> dims(static_cast<std::size_t>(rank));
  if (rank > 0) space.getSimpleExtentDims(dims.data());
  return dims;
}

void checkStoredSize(const H5::DataSet& dataset) {
  const auto dims = shapeOf(dataset);
  long double elements = 1.0L;
  for (const hsize_t dim : dims) elements *= static_cast<long double>(dim);
  const long double logical = elements * static_cast<long double>(dataset.getDataType().getSize());
  const auto stored = static_cast<long double>(dataset.getStorageSize());
  // Deflate compresses at most ~1032:1; a dataset claiming much more than that is an
  // extent without data (a damaged or forged file), and reading it would allocate it.
  if (logical > 1100.0L * stored + 1024.0L * 1024.0L) {
    throw H5::DataSetIException("checkStoredSize",
                                fmt::format("{}: its shape claims {:.0f} bytes but the file stores only {:.0f}",
                                            dataset.getObjName(), static_cast<double>(logical),
                                            static_cast<double>(stored)));
  }
}

template <typename T>
std::vector<T> readRows(const H5::DataSet& dataset, hsize_t first, hsize_t count) {
  const auto dims = shapeOf(dataset);
  std::vector<hsize_t> start(dims.size(), 0);
  std::vector<hsize_t> extent = dims;
  if (!dims.empty()) {
    // Checked before allocating: a damaged index must not become a huge allocation.
    if (first > dims[0] || count > dims[0] - first) {
      throw H5::DataSetIException("readRows", fmt::format("{}: rows {} .. {} requested, it has {}", dataset.getObjName(),
                                                          first, first + count, dims[0]));
    }
    start[0] = first;
    extent[0] = count;
  }
  std::vector<T> values(static_cast<std::size_t>(product(extent)));
  if (values.empty()) return values;
  H5::DataSpace file_space = dataset.getSpace();
  file_space.selectHyperslab(H5S_SELECT_SET, extent.data(), start.data());
  H5::DataSpace memory_space(static_cast<int>(extent.size()), extent.data());
  dataset.read(values.data(), nativeType<T>(), memory_space, file_space);
  return values;
}

template <typename T>
std::vector<T> readAll(const H5::DataSet& dataset) {
  const auto dims = shapeOf(dataset);
  return readRows<T>(dataset, 0, dims.empty() ? 1 : dims[0]);
}

#define VSD_INSTANTIATE_READ(T)                                                           \
  template std::vector<T> readRows<T>(const H5::DataSet&, hsize_t, hsize_t);             \
  template std::vector<T> readAll<T>(const H5::DataSet&);
VSD_INSTANTIATE_READ(double)
VSD_INSTANTIATE_READ(float)
VSD_INSTANTIATE_READ(std::int64_t)
VSD_INSTANTIATE_READ(std::int32_t)
VSD_INSTANTIATE_READ(std::uint8_t)
VSD_INSTANTIATE_READ(std::int8_t)
#undef VSD_INSTANTIATE_READ

void silenceErrorStack() { H5::Exception::dontPrint(); }

std::string errorCause(const H5::Exception& error) {
  std::string innermost;
  const auto visit = [](unsigned, const H5E_error2_t* entry, void* data) -> herr_t {
    if (entry->desc != nullptr) *static_cast<std::string*>(data) = entry->desc;
    return 0;
  };
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_DOWNWARD, visit, &innermost);
  // A failed system call reports "..., errno = 28, error message = 'No space left on
  // device', ...": the operating system's words are the cause a user can act on.
  const std::string marker = "error message = '";
  if (const auto at = innermost.find(marker); at != std::string::npos) {
    const auto begin = at + marker.size();
    const auto end = innermost.find('\'', begin);
    return innermost.substr(begin, end == std::string::npos ? std::string::npos : end - begin);
  }
  if (!innermost.empty()) return innermost;
  return error.getDetailMsg();
}

}  // namespace vsd::h5
