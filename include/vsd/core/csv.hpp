#pragma once
// CSV (RFC 4180 quoting) for results tables. Numbers are written in their
// shortest exact form; NaN (not applicable / not computed) as an empty cell,
// infinities as "inf" / "-inf".

#include <filesystem>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace vsd {

/// Shortest exact text of a number; "" for NaN, "inf"/"-inf" for infinities.
std::string formatNumber(double value);

/// A column name with its unit as a suffix, the convention of the results tables
/// (comparison.csv, baseline's table, the experiment's ade.csv): ("ade", "m") -> "ade_m",
/// ("a_min_predicted", "m/s^2") -> "a_min_predicted_m_s2"; unitless ("" or "1"): the name.
std::string columnWithUnit(const std::string& name, const std::string& unit);

class CsvWriter {
 public:
  explicit CsvWriter(std::ostream& stream) : stream_(stream) {}
  void writeRow(const std::vector<std::string>& cells);

 private:
  std::ostream& stream_;
};

/// A whole CSV file in memory, with typed access and messages naming file, row and column.
class CsvTable {
 public:
  /// Reads `path`; throws DatasetError if it cannot be read or rows have the wrong number of cells.
  static CsvTable read(const std::filesystem::path& path);

  const std::vector<std::string>& header() const { return header_; }
  std::size_t rows() const { return rows_.size(); }
  std::optional<std::size_t> findColumn(const std::string& name) const;
  /// Throws DatasetError naming the file and listing the columns if `name` is absent.
  std::size_t column(const std::string& name) const;
  const std::string& cell(std::size_t row, std::size_t column) const { return rows_[row][column]; }
  /// Parses a cell as a number: "" -> NaN, "inf" -> inf; throws DatasetError otherwise.
  double number(std::size_t row, std::size_t column) const;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
  std::vector<std::string> header_;
  std::vector<std::vector<std::string>> rows_;
};

}  // namespace vsd
