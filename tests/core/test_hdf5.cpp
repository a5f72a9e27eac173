// Appendable datasets: what is appended is what any HDF5 reader reads back, whichever way
// the rows arrive (whole chunks compressed by vsd-sumo, chunk tails through HDF5's filters).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <type_traits>
#include <unistd.h>
#include <vector>

#include "vsd/core/hdf5.hpp"

namespace fs = std::filesystem;
using namespace vsd;

namespace {

/// Distinct, not too compressible values: a wrong order or a lost row shows.
template <typename T>
std::vector<T> rowValues(std::size_t rows, std::size_t row_size, std::size_t first_row) {
  std::vector<T> values;
  for (std::size_t r = first_row; r < first_row + rows; ++r) {
    for (std::size_t i = 0; i < row_size; ++i) {
      const double value = std::sin(0.37 * static_cast<double>(r * row_size + i)) * 100.0;
      if constexpr (std::is_integral_v<T>) {
        values.push_back(static_cast<T>(std::lround(value * 1.2)));  // within -120 .. 120: any integer type
      } else {
        values.push_back(static_cast<T>(value + static_cast<double>(r)));
      }
    }
  }
  return values;
}

/// Appends `pieces` rows at a time to a new dataset, closes the file and reads it back.
template <typename T>
std::vector<T> writeAndReadBack(const fs::path& path, const std::vector<hsize_t>& row_shape, hsize_t chunk_rows,
                                int deflate_level, const std::vector<std::size_t>& pieces, std::vector<T>& expected) {
  std::size_t row_size = 1;
  for (const hsize_t extent : row_shape) row_size *= extent;
  {
    H5::H5File file(path.string(), H5F_ACC_TRUNC);
    H5::Group root = file.openGroup("/");
    h5::Appendable<T> column(root, "column", row_shape, chunk_rows, deflate_level);
    std::size_t rows = 0;
    for (const std::size_t piece : pieces) {
      const auto values = rowValues<T>(piece, row_size, rows);
      column.append(values.data(), piece);
      expected.insert(expected.end(), values.begin(), values.end());
      rows += piece;
      EXPECT_EQ(column.rows(), rows);
    }
  }
  H5::H5File file(path.string(), H5F_ACC_RDONLY);
  const H5::DataSet dataset = file.openDataSet("column");
  std::size_t total_rows = 0;
  for (const std::size_t piece : pieces) total_rows += piece;
  EXPECT_EQ(h5::shapeOf(dataset).front(), total_rows);
  return h5::readAll<T>(dataset);
}

class Hdf5Appendable : public ::testing::Test {
 protected:
  void SetUp() override {
    directory_ = fs::temp_directory_path() / ("vsd_test_hdf5_" + std::to_string(::getpid()));
    fs::create_directories(directory_);
  }
  void TearDown() override { fs::remove_all(directory_); }
  fs::path directory_;
};

// Pieces that start chunks, complete a chunk whose head is written already, span several
// chunks and end in the middle of one (chunks of 8 rows: 51 rows, the last 3 an incomplete
// chunk that HDF5's own filter compresses when the file closes).
const std::vector<std::size_t> kPieces = {3, 5, 8, 2, 20, 1, 9, 3};

TEST_F(Hdf5Appendable, RowsReadBackWhateverSizesTheyAreAppendedIn) {
  for (const int level : {0, 1, 6}) {
    std::vector<double> expected;
    const auto read = writeAndReadBack<double>(directory_ / "doubles.h5", {3, 2}, 8, level, kPieces, expected);
    EXPECT_EQ(read, expected) << "deflate level " << level;
  }
  std::vector<std::int8_t> bytes_expected;
  EXPECT_EQ(writeAndReadBack<std::int8_t>(directory_ / "bytes.h5", {5}, 8, 1, kPieces, bytes_expected),
            bytes_expected);
  std::vector<std::int64_t> integers_expected;
  EXPECT_EQ(writeAndReadBack<std::int64_t>(directory_ / "integers.h5", {}, 8, 1, kPieces, integers_expected),
            integers_expected);
}

// A chunk larger than HDF5's chunk cache (1 MiB): its head goes to the file at once, and
// the whole chunk written later replaces it.
TEST_F(Hdf5Appendable, ChunksLargerThanHdf5sCacheReadBack) {
  std::vector<double> expected;
  const auto read = writeAndReadBack<double>(directory_ / "large.h5", {20000}, 8, 1, kPieces, expected);
  EXPECT_EQ(read, expected);
}

// The dataset declares shuffle + deflate, the filters every chunk is stored with: h5py or
// any other reader decodes it without plugins.
TEST_F(Hdf5Appendable, CompressedDatasetsDeclareShuffleAndDeflate) {
  std::vector<double> expected;
  writeAndReadBack<double>(directory_ / "filters.h5", {4}, 8, 1, kPieces, expected);
  H5::H5File file((directory_ / "filters.h5").string(), H5F_ACC_RDONLY);
  const H5::DSetCreatPropList properties = file.openDataSet("column").getCreatePlist();
  ASSERT_EQ(properties.getNfilters(), 2);
  const auto filterOf = [&properties](int index) {
    unsigned int flags = 0;
    unsigned int client_data[8] = {};
    std::size_t values = 8;
    unsigned int filter_info = 0;
    char name[64] = {};
    return properties.getFilter(index, flags, values, client_data, sizeof(name), name, filter_info);
  };
  EXPECT_EQ(filterOf(0), H5Z_FILTER_SHUFFLE);
  EXPECT_EQ(filterOf(1), H5Z_FILTER_DEFLATE);
  // Compressed, not stored raw: less than the 7 chunks of 8 rows it spans.
  EXPECT_LT(file.openDataSet("column").getStorageSize(), 7u * 8u * 4u * sizeof(double));
}

}  // namespace
