#pragma once
// OpenVDB export (`--vdb`): a reconstructed mesh as a narrow-band level set, the grid Blender's volume objects,
// Houdini and every VDB tool read. Only write_vdb.cpp includes OpenVDB.
#include "core/error.h"
#include "io/triangle_mesh.h"

#include <filesystem>
#include <string>

namespace ff::io {

struct VdbOptions {
  float voxel_size = 0.0f;     ///< m; > 0 (the meshing grid's cell, d/2, is what `mesh`/`run` use)
  float half_width = 3.0f;     ///< narrow band on each side of the surface, in voxels; ≥ 1
  std::string grid_name = "surface";
};

/// True when this build can write VDB files (OpenVDB was found at configure time).
bool vdb_available();

/// Writes `mesh` (closed, outward) to `path` as one FloatGrid of class level set (signed distance, negative
/// inside, ±half_width·voxel_size beyond the band), atomically (a temp file renamed over `path`). Errors: Param
/// for bad options or a build without OpenVDB, Input for an empty mesh, Io when the file cannot be written.
Status write_level_set_vdb(const std::filesystem::path& path, const TriangleMesh& mesh, const VdbOptions& options);

}  // namespace ff::io
