#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "breccia/common/csv.hpp"
#include "breccia/common/error.hpp"

using namespace breccia;

namespace {
std::filesystem::path write(const std::string& name, const std::string& text) {
  const auto p = std::filesystem::path(::testing::TempDir()) / name;
  std::ofstream(p) << text;
  return p;
}
}  // namespace

TEST(Csv, SplitsQuotedFieldsAndKeepsTheRestInTheLastField) {
  EXPECT_EQ(split_csv_line(" a , \"b,c\" ,\"say \"\"hi\"\"\"\r"), (std::vector<std::string>{"a", "b,c", "say \"hi\""}));
  // max_fields: the last field takes the rest of the line, commas included (free text).
  EXPECT_EQ(split_csv_line("1,2,peak stress, relative", 3), (std::vector<std::string>{"1", "2", "peak stress, relative"}));
  EXPECT_EQ(split_csv_line("", 0), (std::vector<std::string>{""}));
  EXPECT_EQ(split_csv_line("x,y,z", 1), (std::vector<std::string>{"x,y,z"}));
}

TEST(Csv, PlainFieldCannotSplitItsRow) {
  const std::string f = csv_plain_field("a, \"b\"\nc");
  EXPECT_EQ(f, "a;  b  c");
  EXPECT_EQ(split_csv_line("1," + f).size(), 2u);
}

TEST(Csv, ReadsColumnsUnderTheHeader) {
  const auto p = write("columns.csv", "step,time_s,E\r\n0,0.0,1e-3\n\n1, 2.5e-6 ,2\n");
  const CsvColumns t = read_csv_columns(p, {});
  EXPECT_EQ(t.names, (std::vector<std::string>{"step", "time_s", "E"}));
  ASSERT_EQ(t.columns.size(), 3u);
  EXPECT_EQ(t.columns[1], (std::vector<double>{0.0, 2.5e-6}));
  EXPECT_EQ(t.line, (std::vector<int>{2, 4}));  // the blank line 3 skipped
}

TEST(Csv, OptionalHeaderAndComments) {
  const auto p = write("table.csv", "# a load table\n0,1\n1e-6,2\n");
  const CsvColumns t = read_csv_columns(p, {.header_optional = true, .comments = true});
  EXPECT_TRUE(t.names.empty());
  EXPECT_EQ(t.columns[1], (std::vector<double>{1.0, 2.0}));
}

TEST(Csv, BadCellNamesFileLineAndColumn) {
  const auto p = write("bad.csv", "t,v\n0,1\n1,x\n");
  try {
    read_csv_columns(p, {});
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), p.string());
    EXPECT_EQ(e.field(), "line 3, column v");
  }
  EXPECT_THROW(read_csv_columns(write("short.csv", "t,v\n0\n"), {}), InputError);
  EXPECT_THROW(read_csv_columns(write("empty.csv", ""), {}), InputError);
  EXPECT_THROW(read_csv_columns(std::filesystem::path(::testing::TempDir()) / "missing.csv", {}), InputError);
}
