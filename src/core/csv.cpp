#include "vsd/core/csv.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstdlib>
#include <limits>

#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"

namespace vsd {

std::string columnWithUnit(const std::string& name, const std::string& unit) {
  if (unit.empty() || unit == "1") return name;
  std::string suffix;
  for (const char c : unit) {
    if (c == '/' || c == ' ' || c == '*') suffix += '_';
    else if (c != '^') suffix += c;
  }
  return name + "_" + suffix;
}

std::string formatNumber(double value) {
  if (std::isnan(value)) return "";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  return fmt::format("{}", value);
}

void CsvWriter::writeRow(const std::vector<std::string>& cells) {
  for (std::size_t i = 0; i < cells.size(); ++i) {
    if (i > 0) stream_ << ',';
    const std::string& cell = cells[i];
    if (cell.find_first_of(",\"\n\r") == std::string::npos) {
      stream_ << cell;
      continue;
    }
    stream_ << '"';
    for (char c : cell) {
      if (c == '"') stream_ << '"';
      stream_ << c;
    }
    stream_ << '"';
  }
  stream_ << '\n';
}

namespace {
std::vector<std::vector<std::string>> parseCsv(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  std::vector<std::string> row;
  std::string cell;
  bool quoted = false;
  bool row_has_content = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (quoted) {
      if (c == '"') {
        if (i + 1 < text.size() && text[i + 1] == '"') {
          cell += '"';
          ++i;
        } else {
          quoted = false;
        }
      } else {
        cell += c;
      }
      continue;
    }
    if (c == '"') {
      quoted = true;
      row_has_content = true;
    } else if (c == ',') {
      row.push_back(std::move(cell));
      cell.clear();
      row_has_content = true;
    } else if (c == '\n' || c == '\r') {
      if (c == '\r' && i + 1 < text.size() && text[i + 1] == '\n') ++i;
      if (row_has_content || !cell.empty()) {
        row.push_back(std::move(cell));
        rows.push_back(std::move(row));
      }
      row.clear();
      cell.clear();
      row_has_content = false;
    } else {
      cell += c;
      row_has_content = true;
    }
  }
  if (row_has_content || !cell.empty()) {
    row.push_back(std::move(cell));
    rows.push_back(std::move(row));
  }
  return rows;
}
}  // namespace

CsvTable CsvTable::read(const std::filesystem::path& path) {
  std::string text;
  try {
    text = readTextFile(path);
  } catch (const IoError& error) {
    throw DatasetError(error.what());
  }
  auto rows = parseCsv(text);
  if (rows.empty()) throw DatasetError(path.string() + ": empty CSV file (expected a header row)");
  CsvTable table;
  table.path_ = path;
  table.header_ = std::move(rows.front());
  for (std::size_t r = 1; r < rows.size(); ++r) {
    if (rows[r].size() != table.header_.size()) {
      throw DatasetError(fmt::format("{}: line {} has {} cells, the header has {}", path.string(), r + 1, rows[r].size(),
                                     table.header_.size()));
    }
    table.rows_.push_back(std::move(rows[r]));
  }
  return table;
}

std::optional<std::size_t> CsvTable::findColumn(const std::string& name) const {
  for (std::size_t i = 0; i < header_.size(); ++i) {
    if (header_[i] == name) return i;
  }
  return std::nullopt;
}

std::size_t CsvTable::column(const std::string& name) const {
  if (auto index = findColumn(name)) return *index;
  throw DatasetError(fmt::format("{}: no column '{}' (columns: {})", path_.string(), name, fmt::join(header_, ", ")));
}

double CsvTable::number(std::size_t row, std::size_t column) const {
  const std::string& text = rows_[row][column];
  if (text.empty()) return std::numeric_limits<double>::quiet_NaN();
  if (text == "inf") return std::numeric_limits<double>::infinity();
  if (text == "-inf") return -std::numeric_limits<double>::infinity();
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0') {
    throw DatasetError(fmt::format("{}: line {}, column '{}': got '{}', expected a number", path_.string(), row + 2,
                                   header_[column], text));
  }
  return value;
}

}  // namespace vsd
