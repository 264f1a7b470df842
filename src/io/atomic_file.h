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

/// Creates `dir` (and parents) if needed and checks that it is a writable directory.
Status ensure_writable_dir(const std::filesystem::path& dir);

}  // namespace ff::io
