#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <sstream>

#include "test_support.hpp"
#include "vsd/core/csv.hpp"
#include "vsd/core/error.hpp"

using namespace vsd;

TEST(Csv, RoundTripsQuotedCellsAndSpecialNumbers) {
  TemporaryDirectory dir;
  std::ostringstream text;
  CsvWriter writer(text);
  writer.writeRow({"name", "value", "note"});
  writer.writeRow({"a", formatNumber(0.1), "plain"});
  writer.writeRow({"b", formatNumber(std::numeric_limits<double>::quiet_NaN()), "has, comma and \"quotes\""});
  writer.writeRow({"c", formatNumber(std::numeric_limits<double>::infinity()), "multi\nline"});
  const auto path = test::writeFile(dir.path() / "t.csv", text.str());
  const auto table = CsvTable::read(path);
  ASSERT_EQ(table.rows(), 3u);
  EXPECT_EQ(table.cell(1, table.column("note")), "has, comma and \"quotes\"");
  EXPECT_EQ(table.cell(2, table.column("note")), "multi\nline");
  EXPECT_DOUBLE_EQ(table.number(0, 1), 0.1);
  EXPECT_TRUE(std::isnan(table.number(1, 1)));
  EXPECT_TRUE(std::isinf(table.number(2, 1)));
}

TEST(Csv, ShortestExactNumberFormatRoundTrips) {
  for (double value : {0.1, 1.0 / 3.0, -1e-300, 12345.678901234567}) {
    EXPECT_EQ(std::stod(formatNumber(value)), value);
  }
}

TEST(Csv, ErrorsNameFileColumnAndValue) {
  TemporaryDirectory dir;
  const auto path = test::writeFile(dir.path() / "bad.csv", "a,b\n1,x\n");
  const auto table = CsvTable::read(path);
  try {
    table.number(0, 1);
    FAIL() << "expected DatasetError";
  } catch (const DatasetError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("bad.csv"), std::string::npos);
    EXPECT_NE(message.find("'b'"), std::string::npos);
    EXPECT_NE(message.find("'x'"), std::string::npos);
  }
  EXPECT_THROW(table.column("missing"), DatasetError);
  const auto ragged = test::writeFile(dir.path() / "ragged.csv", "a,b\n1,2,3\n");
  EXPECT_THROW(CsvTable::read(ragged), DatasetError);
}
