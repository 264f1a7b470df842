#pragma once
// Atomic file output: write `path.tmp.<pid>`, flush and fsync, then rename over `path`. A reader (or a
// crash) never sees a half-written file, and a failed write leaves any previous file untouched.
#include "core/error.h"

#include <cstdint>
#include <filesystem>
#include <span>
#include <string_view>

namespace ff::io {

/// Writes `bytes` to `path` atomically. Errors name the path and the reason.
Status write_file_atomic(const std::filesystem::path& path, std::span<const std::uint8_t> bytes);
Status write_file_atomic(const std::filesystem::path& path, std::string_view text);

/// A file written in pieces and then published atomically: bytes go to `path.tmp.<pid>`; commit() syncs it and
/// renames it over `path`. Without a commit (an error, an exception) the temp file is removed, so `path` is
/// either its old self or complete. For outputs too large to assemble in memory (a point cache).
class AtomicFileWriter {
 public:
  AtomicFileWriter() = default;
  AtomicFileWriter(const AtomicFileWriter&) = delete;
  AtomicFileWriter& operator=(const AtomicFileWriter&) = delete;
  ~AtomicFileWriter();

  Status open(const std::filesystem::path& path);
  Status write(std::span<const std::uint8_t> bytes);
  /// Overwrites bytes already written at `offset` (e.g. a header whose counts are known at the end).
  Status write_at(std::uint64_t offset, std::span<const std::uint8_t> bytes);
  Status commit();

 private:
  Status fail(int err);
  std::filesystem::path path_, tmp_;
  int fd_ = -1;
};

/// Removes the temporary files (`*.tmp.<pid>`) that writers killed mid-write (kill -9, power loss) left in
/// `dir` and its sub-folders; files of a writer that is still running are kept. Returns how many were removed.
std::size_t remove_stale_temp_files(const std::filesystem::path& dir);

/// Creates `dir` (and parents) if needed and checks that it is a writable directory.
Status ensure_writable_dir(const std::filesystem::path& dir);

}  // namespace ff::io
