#pragma once
// A run's particle-frame sequence on disk: OUT/particles/frame_NNNNN.ply (NNNNN: the frame number, 5 digits or
// more). The one place that names the files: `run` writes them through frame_path(), `mesh` and the server's
// playback find them through particle_frames().
#include "core/error.h"

#include <filesystem>
#include <vector>

namespace ff::io {

/// OUT/particles/frame_NNNNN.ply.
std::filesystem::path frame_path(const std::filesystem::path& out, int frame);
/// frame_NNNNN.ply → NNNNN; −1 for any other name.
long frame_number(const std::filesystem::path& file);
/// The particle frames of `input`: one PLY file, a folder of frame_NNNNN.ply files, or a run's output folder
/// (its particles/ folder), in frame order. Input error when there are none.
Result<std::vector<std::filesystem::path>> particle_frames(const std::filesystem::path& input);

}  // namespace ff::io
