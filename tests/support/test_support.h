#pragma once
// Shared helpers for the test suite: paths to the source tree and built binary, temporary folders,
// and procedural meshes (libigl test_common idea: families of shapes, not golden files).
#include "io/triangle_mesh.h"

#include <filesystem>
#include <string>
#include <utility>

namespace ff::test {

/// Built with AddressSanitizer or ThreadSanitizer (gcc says so with __SANITIZE_*__, clang only through __has_feature).
/// A few numeric tests measure fewer poses or sizes there: the same code runs, at 20-40× its release cost.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
inline constexpr bool kSanitized = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif
#else
inline constexpr bool kSanitized = false;
#endif

/// The repository root (FF_SOURCE_DIR, set by CTest).
std::filesystem::path source_dir();
/// tests/data inside the repository.
std::filesystem::path data_dir();
/// The fluidform binary (FF_BINARY, set by CTest).
std::filesystem::path binary();
/// A fresh empty folder under the system temp dir, unique per call; removed when the test program exits with every
/// test passed (kept after a failure, or with FF_KEEP_TEST_DIRS=1).
std::filesystem::path temp_dir(const std::string& tag);

/// Runs a shell command; its exit code (−1 when it did not exit normally) and its output, stdout and stderr.
/// `echo`: also print the output as it comes (the progress of a long test shows with ctest -V).
std::pair<int, std::string> shell(const std::string& cmd, bool echo = false);

/// Closed unit-radius sphere (icosphere, `subdivisions` ≥ 0), outward CCW triangles.
io::TriangleMesh sphere_mesh(float radius, int subdivisions);
/// Closed axis-aligned box [lo, hi], outward CCW triangles.
io::TriangleMesh box_mesh(const Vec3f& lo, const Vec3f& hi);

/// Writes `mesh` as a Wavefront OBJ (for feeding tests through the real importer).
void write_obj(const std::filesystem::path& path, const io::TriangleMesh& mesh);

}  // namespace ff::test
