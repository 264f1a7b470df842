#include "io/csv_table.h"

#include <algorithm>
#include <fstream>
#include <sstream>

namespace ff::io {

std::size_t CsvTable::column(std::string_view name) const {
  return static_cast<std::size_t>(std::find(head.begin(), head.end(), name) - head.begin());
}

std::vector<std::string> split_fields(const std::string& line, char sep) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  for (std::string f; std::getline(ss, f, sep);) out.push_back(f);
  return out;
}

CsvTable read_csv(const std::filesystem::path& path) {
  CsvTable t;
  std::ifstream in(path);
  std::string line;
  if (!in || !std::getline(in, line)) return t;
  t.head = split_fields(line);
  while (std::getline(in, line)) t.rows.push_back(split_fields(line));
  return t;
}

}  // namespace ff::io
