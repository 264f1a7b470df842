#include "io/load_mesh.h"

#include "core/params.h"

#include <assimp/DefaultLogger.hpp>
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/format.h>

#include <Eigen/Geometry>

#include <cctype>
#include <cmath>
#include <fstream>
#include <iterator>
#include <numbers>

namespace ff::io {
namespace fs = std::filesystem;

bool MeshTransform::is_identity() const {
  return scale == Vec3f::Ones() && rotate_deg == Vec3f::Zero() && translate == Vec3f::Zero();
}

Vec3f MeshTransform::apply(const Vec3f& p) const {
  constexpr double kDeg = std::numbers::pi / 180.0;
  const Eigen::Matrix3d r = (Eigen::AngleAxisd(rotate_deg.z() * kDeg, Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(rotate_deg.y() * kDeg, Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(rotate_deg.x() * kDeg, Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  return (r * p.cast<double>().cwiseProduct(scale.cast<double>()) + translate.cast<double>()).cast<float>();
}

Status MeshTransform::validate() const {
  for (int a = 0; a < 3; ++a)
    if (!(std::isfinite(scale[a]) && scale[a] > 0.0f))
      return param_error(fmt::format("transform.scale.{} = {} must be finite and > 0", "xyz"[a], scale[a]));
  FF_CHECK(core::check_vec("transform", "rotate", rotate_deg, -1e9, 1e9));
  FF_CHECK(core::check_vec("transform", "translate", translate, -1e30, 1e30));
  return {};
}

void transform_mesh(TriangleMesh& mesh, const MeshTransform& t) {
  if (t.is_identity()) return;
  for (auto& v : mesh.vertices) v = t.apply(v);
}

double signed_volume(const TriangleMesh& mesh) {
  double v = 0.0;
  for (const auto& t : mesh.triangles) {
    const Vec3d a = mesh.vertices[t[0]].cast<double>(), b = mesh.vertices[t[1]].cast<double>(),
                c = mesh.vertices[t[2]].cast<double>();
    v += a.dot(b.cross(c));
  }
  return v / 6.0;
}

namespace {

std::string one_line(std::string s) {
  for (char& c : s)
    if (c == '\n' || c == '\r') c = ' ';
  while (!s.empty() && s.back() == ' ') s.pop_back();
  return s;
}

// Assimp's text parsers read a "nan" token as some finite number (or lose sync), so a NaN-bearing text
// file would import as a silently wrong mesh. A standalone nan token in a text file is therefore refused
// up front. Binary files are checked on the imported floats instead.
bool text_has_nan_token(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::string buf((std::istreambuf_iterator<char>(in)), {});
  if (buf.find('\0') != std::string::npos) return false;  // binary: NaNs survive import as real NaNs
  auto sep = [](char c) { return std::isspace(static_cast<unsigned char>(c)) || c == ',' || c == '<' || c == '>' || c == '"' || c == '/'; };
  for (std::size_t i = 0; i + 3 <= buf.size(); ++i) {
    const bool start = i == 0 || sep(buf[i - 1]) || buf[i - 1] == '-' || buf[i - 1] == '+';
    if (!start) continue;
    if (std::tolower(buf[i]) == 'n' && std::tolower(buf[i + 1]) == 'a' && std::tolower(buf[i + 2]) == 'n' &&
        (i + 3 == buf.size() || sep(buf[i + 3]) || buf[i + 3] == '(')) {
      // Skip comment lines ('#' first on the line) so that prose does not trip the check.
      const std::size_t bol = buf.rfind('\n', i);
      const std::size_t first = buf.find_first_not_of(" \t", bol == std::string::npos ? 0 : bol + 1);
      if (first != std::string::npos && buf[first] == '#') continue;
      return true;
    }
  }
  return false;
}

// Assimp's OFF reader reserves the face count of the header before reading: a corrupt count costs minutes
// and gigabytes. Each face needs at least 6 bytes of text ("3 a b c"), so an impossible count is refused.
std::string off_header_problem(const fs::path& path, std::uintmax_t size) {
  std::string ext = path.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext != ".off") return {};
  std::ifstream in(path);
  std::string magic;
  double nv = 0, nf = 0;
  if (!(in >> magic) || magic.find("OFF") == std::string::npos) return {};
  if (!(in >> nv >> nf)) return {};
  if (nv < 0 || nf < 0 || nv * 6.0 > double(size) || nf * 6.0 > double(size))
    return fmt::format("the OFF header declares {} vertices and {} faces, impossible in a file of {} bytes", nv, nf, size);
  return {};
}

}  // namespace

Result<TriangleMesh> load_mesh(const fs::path& path, const LoadOptions& options, MeshLoadStats* stats_out) {
  FF_CHECK(options.transform.validate());
  const std::string name = path.string();
  std::error_code ec;
  if (!fs::exists(path, ec)) return input_error(fmt::format("{}: no such file", name));
  if (fs::is_directory(path, ec)) return input_error(fmt::format("{}: is a folder, not a mesh file", name));
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec || size == 0) return input_error(fmt::format("{}: the file is empty", name));
  if (const std::string why = off_header_problem(path, size); !why.empty())
    return input_error(fmt::format("{}: {}", name, why));
  if (size < (std::uintmax_t{512} << 20) && text_has_nan_token(path))
    return input_error(fmt::format("{}: contains a NaN coordinate", name));

  Assimp::Importer importer;
  // Points and lines are dropped by Assimp (SortByPType + RemoveComponent) only after we count them.
  const unsigned flags = aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_PreTransformVertices |
                         aiProcess_SortByPType | aiProcess_ValidateDataStructure;
  const aiScene* scene = importer.ReadFile(path.c_str(), flags);
  if (!scene) {
    std::string why = one_line(importer.GetErrorString());
    if (why.empty()) why = "unreadable or unsupported mesh file";
    return input_error(fmt::format("{}: {}", name, why));
  }
  if ((scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) || scene->mNumMeshes == 0)
    return input_error(fmt::format("{}: contains no mesh", name));

  MeshLoadStats stats;
  stats.source_meshes = scene->mNumMeshes;
  TriangleMesh mesh;
  std::size_t total_vertices = 0;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) total_vertices += scene->mMeshes[m]->mNumVertices;
  if (total_vertices == 0) return input_error(fmt::format("{}: contains no vertices", name));
  if (total_vertices > options.max_vertices)
    return input_error(fmt::format("{}: {} vertices is more than the limit of {}", name, total_vertices, options.max_vertices));
  mesh.vertices.reserve(total_vertices);
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* am = scene->mMeshes[m];
    const auto base = static_cast<Index>(mesh.vertices.size());
    for (unsigned v = 0; v < am->mNumVertices; ++v) {
      const aiVector3D& p = am->mVertices[v];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
        return input_error(fmt::format("{}: vertex {} has a non-finite coordinate (NaN/Inf)", name, mesh.vertices.size()));
      mesh.vertices.emplace_back(p.x, p.y, p.z);
    }
    for (unsigned f = 0; f < am->mNumFaces; ++f) {
      const aiFace& face = am->mFaces[f];
      if (face.mNumIndices != 3) {
        ++stats.dropped_non_triangles;
        continue;
      }
      mesh.triangles.push_back({base + face.mIndices[0], base + face.mIndices[1], base + face.mIndices[2]});
    }
  }
  if (mesh.triangles.empty())
    return input_error(fmt::format("{}: contains no triangles (only points/lines)", name));

  // Drop degenerate triangles: a repeated vertex, or an area negligible against the mesh size.
  const Aabb box = mesh.bounds();
  const double diag2 = double(box.size().squaredNorm());
  std::vector<std::array<Index, 3>> kept;
  kept.reserve(mesh.triangles.size());
  for (const auto& t : mesh.triangles) {
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
      ++stats.dropped_degenerate;
      continue;
    }
    const Vec3d a = mesh.vertices[t[0]].cast<double>(), b = mesh.vertices[t[1]].cast<double>(),
                c = mesh.vertices[t[2]].cast<double>();
    if ((b - a).cross(c - a).norm() <= 1e-12 * diag2) {
      ++stats.dropped_degenerate;
      continue;
    }
    kept.push_back(t);
  }
  if (kept.empty()) return input_error(fmt::format("{}: every triangle is degenerate (zero area)", name));
  mesh.triangles.swap(kept);

  // Remove vertices no triangle uses any more (points, dropped faces), keeping their order.
  std::vector<Index> remap(mesh.vertices.size(), kInvalidIndex);
  for (const auto& t : mesh.triangles)
    for (Index i : t) remap[i] = 0;
  Index next = 0;
  for (std::size_t i = 0; i < remap.size(); ++i)
    if (remap[i] == 0) {
      remap[i] = next;
      mesh.vertices[next++] = mesh.vertices[i];
    }
  mesh.vertices.resize(next);
  for (auto& t : mesh.triangles)
    for (Index& i : t) i = remap[i];

  transform_mesh(mesh, options.transform);
  if (stats_out) *stats_out = stats;
  return mesh;
}

}  // namespace ff::io
