#include "io/write_vdb.h"

#include <fmt/format.h>

#include <cmath>
#include <system_error>

#include <fcntl.h>
#include <unistd.h>

#ifdef FF_HAVE_OPENVDB
#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>
#endif

namespace ff::io {
namespace fs = std::filesystem;

bool vdb_available() {
#ifdef FF_HAVE_OPENVDB
  return true;
#else
  return false;
#endif
}

Status write_level_set_vdb(const fs::path& path, const TriangleMesh& mesh, const VdbOptions& o) {
  if (!(std::isfinite(o.voxel_size) && o.voxel_size > 0.0f))
    return param_error(fmt::format("vdb: voxel size {} must be > 0", o.voxel_size));
  if (!(std::isfinite(o.half_width) && o.half_width >= 1.0f))
    return param_error(fmt::format("vdb: half width {} voxels must be ≥ 1", o.half_width));
  if (mesh.triangles.empty()) return input_error(fmt::format("{}: an empty mesh has no level set", path.string()));
#ifndef FF_HAVE_OPENVDB
  return param_error("--vdb: this build has no OpenVDB (install libopenvdb-dev and rebuild)");
#else
  // Idempotent and thread-safe (the grid type registry).
  openvdb::initialize();
  try {
    const auto xform = openvdb::math::Transform::createLinearTransform(double(o.voxel_size));
    std::vector<openvdb::Vec3s> points;
    points.reserve(mesh.vertices.size());
    for (const auto& v : mesh.vertices) points.emplace_back(xform->worldToIndex(openvdb::Vec3d(v.x(), v.y(), v.z())));
    std::vector<openvdb::Vec3I> tris;
    tris.reserve(mesh.triangles.size());
    // OpenVDB's mesh-to-volume wants index-space points; its winding convention does not matter for a closed mesh
    // (the sign comes from an inside/outside flood fill).
    for (const auto& t : mesh.triangles) tris.emplace_back(t[0], t[1], t[2]);
    openvdb::tools::QuadAndTriangleDataAdapter<openvdb::Vec3s, openvdb::Vec3I> adapter(points, tris);
    openvdb::FloatGrid::Ptr grid =
        openvdb::tools::meshToVolume<openvdb::FloatGrid>(adapter, *xform, o.half_width, o.half_width);
    grid->setGridClass(openvdb::GRID_LEVEL_SET);
    grid->setName(o.grid_name);
    grid->insertMeta("creator", openvdb::StringMetadata("fluidform"));
    // Written under a temporary name and renamed, as every output (io/atomic_file.h: `path.tmp.<pid>`, which
    // remove_stale_temp_files clears after a kill).
    const fs::path tmp = path.string() + ".tmp." + std::to_string(::getpid());
    {
      openvdb::io::File file(tmp.string());
      file.write({grid});
      file.close();
    }
    // OpenVDB does not check its stream after writing (a full disk leaves a short file): read the grid back before
    // the file is published, and sync it, as write_file_atomic does.
    {
      openvdb::io::File check(tmp.string());
      check.open(false);
      if (!check.readGrid(o.grid_name)) throw std::runtime_error("the written file does not read back");
      check.close();
    }
    if (const int fd = ::open(tmp.c_str(), O_RDONLY); fd >= 0) {
      const int rc = ::fsync(fd);
      ::close(fd);
      if (rc != 0) throw std::runtime_error("fsync failed");
    }
    std::error_code ec;
    fs::rename(tmp, path, ec);
    if (ec) {
      fs::remove(tmp, ec);
      return io_error(fmt::format("{}: cannot write: {}", path.string(), ec.message()));
    }
  } catch (const std::exception& e) {
    std::error_code ec;
    fs::remove(path.string() + ".tmp." + std::to_string(::getpid()), ec);
    return io_error(fmt::format("{}: cannot write the VDB: {}", path.string(), e.what()));
  }
  return {};
#endif
}

}  // namespace ff::io
