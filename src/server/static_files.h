#pragma once
// Static files of the viewer: URL paths mapped onto a few folders ("mounts"), nothing outside them. A request
// path is percent-decoded once; any ".." segment, NUL or backslash is refused (403) before the file system is
// asked, and the resolved file must still lie under its mount after symlinks are followed (403 otherwise).
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace ff::server {

struct Mount {
  std::string prefix;          ///< URL prefix, starting and ending with '/': "/" or "/vendor/three/"
  std::filesystem::path dir;   ///< the folder it serves
};

struct StaticResult {
  int status = 404;                 ///< 200, 400, 403 or 404
  std::filesystem::path file;       ///< when 200
  std::string_view mime;            ///< when 200
};

class StaticFiles {
 public:
  explicit StaticFiles(std::vector<Mount> mounts);
  /// `target`: the request target, e.g. "/src/main.js?v=1". A folder serves its index.html.
  StaticResult resolve(std::string_view target) const;

 private:
  std::vector<Mount> mounts_;  // longest prefix first
};

/// "%2e%2E" → "..": one pass; nullopt for a malformed escape.
std::optional<std::string> percent_decode(std::string_view s);
/// Content type by extension (text types in UTF-8); application/octet-stream otherwise.
std::string_view mime_type(const std::filesystem::path& file);

}  // namespace ff::server
