// The CSV table behind compare's and the viewer's reading of metrics.csv (io/csv_table.h).
#include "io/atomic_file.h"
#include "io/csv_table.h"
#include "support/test_support.h"

#include <gtest/gtest.h>

#include <filesystem>

namespace ff::io {
namespace {

TEST(CsvTable, SplitsAtEverySeparatorAndKeepsInnerEmptyFields) {
  EXPECT_EQ(split_fields("a,b,c"), (std::vector<std::string>{"a", "b", "c"}));
  EXPECT_EQ(split_fields("a,,c"), (std::vector<std::string>{"a", "", "c"}));
  EXPECT_EQ(split_fields("a,b,"), (std::vector<std::string>{"a", "b"}));  // no trailing empty field
  EXPECT_EQ(split_fields(""), std::vector<std::string>{});
  EXPECT_EQ(split_fields("x;y", ';'), (std::vector<std::string>{"x", "y"}));
  EXPECT_EQ(split_fields("x;y"), (std::vector<std::string>{"x;y"}));
}

TEST(CsvTable, ReadsTheHeaderAndEveryRowAndFindsColumnsByName) {
  const auto dir = test::temp_dir("csv_table");
  const auto path = dir / "metrics.csv";
  ASSERT_TRUE(write_file_atomic(path, std::string("frame,time_s,error_rate_pct\n0,0,100\n1,0.0333,97.5\n2,0.0667\n")).ok());
  const CsvTable t = read_csv(path);
  ASSERT_EQ(t.head, (std::vector<std::string>{"frame", "time_s", "error_rate_pct"}));
  ASSERT_EQ(t.rows.size(), 3u);
  EXPECT_EQ(t.rows[1], (std::vector<std::string>{"1", "0.0333", "97.5"}));
  EXPECT_EQ(t.rows[2].size(), 2u);  // a short line keeps the fields it has
  EXPECT_EQ(t.column("frame"), 0u);
  EXPECT_EQ(t.column("error_rate_pct"), 2u);
  EXPECT_EQ(t.column("no_such_column"), t.head.size());
}

TEST(CsvTable, AMissingOrEmptyFileIsAnEmptyTable) {
  const auto dir = test::temp_dir("csv_table_empty");
  const CsvTable missing = read_csv(dir / "none.csv");
  EXPECT_TRUE(missing.head.empty());
  EXPECT_TRUE(missing.rows.empty());
  ASSERT_TRUE(write_file_atomic(dir / "empty.csv", std::string()).ok());
  const CsvTable empty = read_csv(dir / "empty.csv");
  EXPECT_TRUE(empty.head.empty());
  EXPECT_TRUE(empty.rows.empty());
  EXPECT_EQ(empty.column("frame"), 0u);  // == head.size(): not found
}

}  // namespace
}  // namespace ff::io
