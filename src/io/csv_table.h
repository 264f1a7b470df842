#pragma once
// A CSV file with a header line, as text (the run's metrics.csv, read back by `compare` and by the viewer's
// playback). Plain comma splitting: our files have no quoted fields.
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace ff::io {

struct CsvTable {
  std::vector<std::string> head;               ///< the header's column names
  std::vector<std::vector<std::string>> rows;  ///< each later line's fields (a line may have fewer than head)
  /// The index of column `name`, or head.size() when the header has none.
  std::size_t column(std::string_view name) const;
};

/// `line` cut at every `sep` (no trailing empty field).
std::vector<std::string> split_fields(const std::string& line, char sep = ',');

/// Reads `path`. A missing or empty file gives an empty table.
CsvTable read_csv(const std::filesystem::path& path);

}  // namespace ff::io
