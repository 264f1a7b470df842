#include "server/static_files.h"

#include <algorithm>

namespace ff::server {
namespace fs = std::filesystem;

namespace {
int hex(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

// True when `p` (canonical) is `root` (canonical) or below it.
bool under(const fs::path& p, const fs::path& root) {
  auto [r, q] = std::mismatch(root.begin(), root.end(), p.begin(), p.end());
  return r == root.end();
}
}  // namespace

std::optional<std::string> percent_decode(std::string_view s) {
  std::string out;
  out.reserve(s.size());
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i] != '%') {
      out += s[i];
      continue;
    }
    if (i + 2 >= s.size()) return std::nullopt;
    const int a = hex(s[i + 1]), b = hex(s[i + 2]);
    if (a < 0 || b < 0) return std::nullopt;
    out += static_cast<char>(a * 16 + b);
    i += 2;
  }
  return out;
}

std::string_view mime_type(const fs::path& file) {
  const std::string ext = file.extension().string();
  if (ext == ".html") return "text/html; charset=utf-8";
  if (ext == ".js" || ext == ".mjs") return "text/javascript; charset=utf-8";
  if (ext == ".css") return "text/css; charset=utf-8";
  if (ext == ".json") return "application/json";
  if (ext == ".glb") return "model/gltf-binary";
  if (ext == ".gltf") return "model/gltf+json";
  if (ext == ".png") return "image/png";
  if (ext == ".svg") return "image/svg+xml";
  if (ext == ".wasm") return "application/wasm";
  if (ext == ".txt" || ext == ".md") return "text/plain; charset=utf-8";
  return "application/octet-stream";
}

StaticFiles::StaticFiles(std::vector<Mount> mounts) : mounts_(std::move(mounts)) {
  std::stable_sort(mounts_.begin(), mounts_.end(),
                   [](const Mount& a, const Mount& b) { return a.prefix.size() > b.prefix.size(); });
  for (auto& m : mounts_) {
    std::error_code ec;
    const fs::path c = fs::canonical(m.dir, ec);
    if (!ec) m.dir = c;
  }
}

StaticResult StaticFiles::resolve(std::string_view target) const {
  StaticResult r;
  target = target.substr(0, target.find_first_of("?#"));
  const auto path = percent_decode(target);
  if (!path || path->empty() || path->front() != '/') return r.status = 400, r;
  if (path->find('\0') != std::string::npos || path->find('\\') != std::string::npos) return r.status = 403, r;
  // Segment by segment: ".." anywhere is refused outright (no normalising it away), "." and empty ones are dropped.
  std::vector<std::string_view> segs;
  const std::string_view p = *path;
  for (std::size_t i = 1; i <= p.size();) {
    const std::size_t j = std::min(p.find('/', i), p.size());
    const std::string_view s = p.substr(i, j - i);
    if (s == "..") return r.status = 403, r;
    if (!s.empty() && s != ".") segs.push_back(s);
    i = j + 1;
  }
  const bool folder = p.back() == '/';
  std::string clean = "/";
  for (std::size_t k = 0; k < segs.size(); ++k) clean += std::string(segs[k]) + (k + 1 < segs.size() || folder ? "/" : "");
  for (const auto& m : mounts_) {
    // "/vendor/three" (no slash) also names the mount's folder.
    const bool exact = clean + "/" == m.prefix;
    if (clean.rfind(m.prefix, 0) != 0 && !exact) continue;
    // The segments after the prefix's own, under the mount's folder.
    const auto skip = static_cast<std::size_t>(std::count(m.prefix.begin(), m.prefix.end(), '/')) - 1;
    fs::path file = m.dir;
    for (std::size_t k = skip; k < segs.size(); ++k) file /= segs[k];
    std::error_code ec;
    if (fs::is_directory(file, ec)) file /= "index.html";
    const fs::path real = fs::canonical(file, ec);
    if (ec || !fs::is_regular_file(real, ec)) return r.status = 404, r;
    if (!under(real, m.dir)) return r.status = 403, r;  // a symlink out of the mount
    r.status = 200;
    r.file = real;
    r.mime = mime_type(real);
    return r;
  }
  return r;
}

}  // namespace ff::server
