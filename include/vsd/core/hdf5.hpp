#pragma once
// Small helpers over HDF5's C++ API for the project's files (traces, datasets):
// datasets that grow along their first dimension (streamed writing with flat
// memory), attributes, string lists. Datasets are written without object
// timestamps so that the same content gives the same bytes.
//
// Compression uses only deflate (+ shuffle), which h5py reads without plugins. Whole
// chunks are shuffled and compressed here (libdeflate, which costs fewer instructions than
// the zlib behind HDF5's own filter: results/alks/instruction_profile_cut_in*.txt) and stored
// with H5Dwrite_chunk: the same HDF5 file with the same filters, any reader decodes it.

#include <H5Cpp.h>

#include <cstdint>
#include <initializer_list>
#include <string>
#include <vector>

namespace vsd::h5 {

template <typename T>
const H5::PredType& nativeType();
template <>
inline const H5::PredType& nativeType<double>() { return H5::PredType::NATIVE_DOUBLE; }
template <>
inline const H5::PredType& nativeType<float>() { return H5::PredType::NATIVE_FLOAT; }
template <>
inline const H5::PredType& nativeType<std::int64_t>() { return H5::PredType::NATIVE_INT64; }
template <>
inline const H5::PredType& nativeType<std::int32_t>() { return H5::PredType::NATIVE_INT32; }
template <>
inline const H5::PredType& nativeType<std::uint8_t>() { return H5::PredType::NATIVE_UINT8; }
template <>
inline const H5::PredType& nativeType<std::int8_t>() { return H5::PredType::NATIVE_INT8; }

/// A dataset of shape [rows, row_shape...] that grows by appending rows.
template <typename T>
class Appendable {
 public:
  Appendable() = default;
  /// `chunk_rows` rows per chunk; `deflate_level` 0 = uncompressed, 1..9 = gzip (+ shuffle).
  Appendable(H5::Group& parent, const std::string& name, std::vector<hsize_t> row_shape, hsize_t chunk_rows,
             int deflate_level);

  /// Appends `rows` rows laid out contiguously (row-major) at `data`. Every appended row is
  /// in the file when it returns (a chunk's incomplete tail through HDF5's filters).
  void append(const T* data, hsize_t rows);
  void append(const std::vector<T>& data);
  hsize_t rows() const { return rows_; }
  hsize_t rowSize() const;

  /// Buffers values (row-major); flush() appends the buffered rows. Writers push per
  /// sample and flush every few hundred samples, so memory stays flat.
  void push(T value) { buffer_.push_back(value); }
  void push(std::initializer_list<T> values) { buffer_.insert(buffer_.end(), values); }
  template <typename Iterator>
  void push(Iterator first, Iterator last) {
    buffer_.insert(buffer_.end(), first, last);
  }
  void flush() {
    append(buffer_);
    buffer_.clear();
  }

 private:
  void extendTo(hsize_t rows);
  /// Writes rows [rows_, rows_ + rows) through HDF5's filter pipeline.
  void writeThroughFilters(const T* data, hsize_t rows);
  /// Writes the chunk that starts at row `first` (chunkRows_ full rows), compressed here.
  void writeWholeChunk(const T* chunk, hsize_t first);
  /// After a failed write: the chunk head holds again only rows that are in the file.
  void dropUnwrittenHead();

  H5::DataSet dataset_;
  std::vector<hsize_t> rowShape_;
  hsize_t rows_ = 0;
  hsize_t chunkRows_ = 1;
  int deflateLevel_ = 0;
  std::vector<T> buffer_;
  std::vector<T> chunkHead_;  ///< rows of the current, incomplete chunk already written
};

/// Flushes every given buffered column.
template <typename... Columns>
void flushAll(Columns&... columns) {
  (columns.flush(), ...);
}

void writeAttribute(H5::H5Object& object, const std::string& name, const std::string& value);
void writeAttribute(H5::H5Object& object, const std::string& name, double value);
void writeAttribute(H5::H5Object& object, const std::string& name, std::int64_t value);
bool hasAttribute(const H5::H5Object& object, const std::string& name);
std::string readStringAttribute(const H5::H5Object& object, const std::string& name);
double readDoubleAttribute(const H5::H5Object& object, const std::string& name);
std::int64_t readIntAttribute(const H5::H5Object& object, const std::string& name);

/// A 1-D dataset of variable-length UTF-8 strings.
void writeStrings(H5::Group& parent, const std::string& name, const std::vector<std::string>& values);
std::vector<std::string> readStrings(const H5::Group& parent, const std::string& name);

/// Dimensions of a dataset.
std::vector<hsize_t> shapeOf(const H5::DataSet& dataset);
/// Throws H5::DataSetIException (naming the dataset) if its shape claims far more data
/// than the file stores (more than deflate could compress into it): reading it would
/// allocate memory for data that is not there. Costs a walk over its chunks.
void checkStoredSize(const H5::DataSet& dataset);
/// Reads rows [first, first + count) of a dataset of T (all trailing dimensions);
/// throws H5::DataSetIException for rows outside the dataset (before allocating).
template <typename T>
std::vector<T> readRows(const H5::DataSet& dataset, hsize_t first, hsize_t count);
/// Reads a whole dataset of T.
template <typename T>
std::vector<T> readAll(const H5::DataSet& dataset);

/// Turns HDF5's exceptions into silence: HDF5 prints its error stack to stderr by
/// default, which we report ourselves as one line.
void silenceErrorStack();

/// The innermost cause of an HDF5 failure, read from HDF5's error stack (call it in
/// the catch block, before any other HDF5 call): the operating system's message for
/// a failed read or write (e.g. "No space left on device"), else HDF5's own words.
std::string errorCause(const H5::Exception& error);

}  // namespace vsd::h5
