#include "io/particle_frames.h"

#include <fmt/format.h>

#include <algorithm>
#include <string>
#include <string_view>
#include <utility>

namespace ff::io {
namespace fs = std::filesystem;

fs::path frame_path(const fs::path& out, int frame) { return out / "particles" / fmt::format("frame_{:05d}.ply", frame); }

// By hand rather than <regex>: GCC 12's <regex> trips -Wmaybe-uninitialized at -O1 (the ASan preset).
long frame_number(const fs::path& file) {
  const std::string name = file.filename().string();
  constexpr std::string_view head = "frame_", tail = ".ply";
  if (name.size() <= head.size() + tail.size() || name.rfind(head, 0) != 0 ||
      name.compare(name.size() - tail.size(), tail.size(), tail) != 0)
    return -1;
  const std::string digits = name.substr(head.size(), name.size() - head.size() - tail.size());
  if (digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos) return -1;
  return std::stol(digits);
}

Result<std::vector<fs::path>> particle_frames(const fs::path& input) {
  std::error_code ec;
  if (!fs::exists(input, ec)) return input_error(fmt::format("{}: no such file or folder", input.string()));
  if (!fs::is_directory(input, ec)) return std::vector<fs::path>{input};
  fs::path dir = input;
  if (fs::is_directory(input / "particles", ec)) dir = input / "particles";
  std::vector<std::pair<long, fs::path>> found;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (const long k = frame_number(e.path()); k >= 0 && e.is_regular_file(ec)) found.emplace_back(k, e.path());
  if (ec) return io_error(fmt::format("{}: {}", dir.string(), ec.message()));
  if (found.empty()) return input_error(fmt::format("{}: no particle frames (frame_NNNNN.ply) in it", dir.string()));
  std::sort(found.begin(), found.end());
  std::vector<fs::path> out;
  for (auto& [k, p] : found) out.push_back(std::move(p));
  return out;
}

}  // namespace ff::io
