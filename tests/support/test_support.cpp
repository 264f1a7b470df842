#include "support/test_support.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <mutex>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

namespace ff::test {
namespace fs = std::filesystem;

fs::path source_dir() {
  const char* s = std::getenv("FF_SOURCE_DIR");
  return s ? fs::path(s) : fs::path(FF_SOURCE_DIR_PATH);
}
fs::path data_dir() { return source_dir() / "tests" / "data"; }
fs::path binary() {
  const char* s = std::getenv("FF_BINARY");
  return s ? fs::path(s) : fs::path(FF_BINARY_PATH);
}

namespace {
// The folders temp_dir made in this process, removed when it exits with every test passed; a failed program keeps
// them to look at (so does FF_KEEP_TEST_DIRS=1). A forked child that exits (a death test, a test's own fork) leaves
// its parent's folders alone.
class TempDirs {
 public:
  void add(const fs::path& p) {
    const std::lock_guard<std::mutex> lock(mutex_);
    dirs_.push_back(p);
  }
  ~TempDirs() {
    if (::getpid() != owner_ || std::getenv("FF_KEEP_TEST_DIRS") || !::testing::UnitTest::GetInstance()->Passed())
      return;
    std::error_code ec;
    for (const fs::path& p : dirs_) fs::remove_all(p, ec);
  }

 private:
  std::mutex mutex_;
  std::vector<fs::path> dirs_;
  const pid_t owner_ = ::getpid();
};
}  // namespace

fs::path temp_dir(const std::string& tag) {
  static std::atomic<int> counter{0};
  static TempDirs made;
  const fs::path p = fs::temp_directory_path() /
                     ("fluidform-test-" + tag + "-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
  fs::remove_all(p);
  fs::create_directories(p);
  made.add(p);
  return p;
}

std::pair<int, std::string> shell(const std::string& cmd, bool echo) {
  std::string out;
  FILE* p = ::popen((cmd + " 2>&1").c_str(), "r");
  if (!p) return {-1, ""};
  char buf[4096];
  while (std::fgets(buf, sizeof buf, p)) {
    out += buf;
    if (echo) std::fputs(buf, stdout), std::fflush(stdout);
  }
  const int rc = ::pclose(p);
  return {WIFEXITED(rc) ? WEXITSTATUS(rc) : -1, out};
}

io::TriangleMesh sphere_mesh(float radius, int subdivisions) {
  io::TriangleMesh m;
  const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
  m.vertices = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  m.triangles = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                 {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  for (auto& v : m.vertices) v.normalize();
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<Index, Index>, Index> mid;
    auto midpoint = [&](Index a, Index b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      m.vertices.push_back((m.vertices[a] + m.vertices[b]).normalized());
      const auto id = static_cast<Index>(m.vertices.size() - 1);
      mid.emplace(key, id);
      return id;
    };
    std::vector<std::array<Index, 3>> next;
    for (const auto& tri : m.triangles) {
      const Index a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), c = midpoint(tri[2], tri[0]);
      next.push_back({tri[0], a, c});
      next.push_back({tri[1], b, a});
      next.push_back({tri[2], c, b});
      next.push_back({a, b, c});
    }
    m.triangles.swap(next);
  }
  for (auto& v : m.vertices) v *= radius;
  return m;
}

io::TriangleMesh box_mesh(const Vec3f& lo, const Vec3f& hi) {
  io::TriangleMesh m;
  for (int i = 0; i < 8; ++i)
    m.vertices.emplace_back((i & 1) ? hi.x() : lo.x(), (i & 2) ? hi.y() : lo.y(), (i & 4) ? hi.z() : lo.z());
  // Two triangles per face, CCW seen from outside.
  m.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                 {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return m;
}

void write_obj(const fs::path& path, const io::TriangleMesh& mesh) {
  std::ofstream f(path);
  f.precision(9);
  for (const auto& v : mesh.vertices) f << "v " << v.x() << ' ' << v.y() << ' ' << v.z() << '\n';
  for (const auto& t : mesh.triangles) f << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
}

}  // namespace ff::test
