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

/// Removes the temporary files (`*.tmp.<pid>`) that writers killed mid-write (kill -9, power loss) left in
/// `dir` and its sub-folders; files of a writer that is still running are kept. Returns how many were removed.
std::size_t remove_stale_temp_files(const std::filesystem::path& dir);

/// Creates `dir` (and parents) if needed and checks that it is a writable directory.
Status ensure_writable_dir(const std::filesystem::path& dir);

}  // namespace ff::io
