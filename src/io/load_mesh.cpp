// Mesh import through Assimp (docs/ARCHITECTURE.md), from a file or (load_mesh_from_memory) from bytes in memory. The
// import runs in two phases on one Importer:
//   1. ReadFile (ReadFileFromMemory) without post-processing, then our checks on the raw scene: some vertices, all
//      finite, some faces. Non-finite positions must be refused before post-processing, because SpatialSort (used by
//      JoinIdenticalVertices) std::sorts positions and NaN keys make that undefined behaviour.
//   2. ApplyPostProcessing: validate, triangulate, keep positions only, weld identical positions, bake node
//      transforms (merging the meshes), split by primitive type.
// Then the triangle meshes are merged (indices offset). Those two phases and the merge run in a child process
// (options.isolate, io/isolate.h), which sends the merged mesh back: Assimp 5.2.5 corrupts its heap on some malformed
// files (its OBJ line and face arrays, among others), and no check of ours can foresee every such bug. Back in this
// process options.transform is applied, degenerate triangles are dropped and unreferenced vertices removed. No unit
// or global scaling: units stay as in the file.
// Before Assimp sees a file (check_before_assimp), OFF and PLY headers are checked against the file size
// (check_declared_counts: Assimp 5.2.5 allocates whatever they declare), a PLY header must have its end_header
// (without one Assimp 5.2.5 never returns), and an OFF file's lines must not overrun Assimp's OFF reader
// (check_off_lines).
#include "io/load_mesh.h"

#include "core/rotation.h"

#include "core/printable.h"
#include "io/isolate.h"

#include <assimp/Importer.hpp>
#include <assimp/config.h>
#include <assimp/mesh.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/format.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <exception>
#include <fstream>
#include <new>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

namespace ff::io {
namespace {
namespace fs = std::filesystem;

/// A triangle is degenerate when |(b−a)×(c−a)| ≤ kDegenerateFactor × (bbox diagonal)².
constexpr double kDegenerateFactor = 1e-12;
/// How much of a file check_before_assimp reads to find the OFF/PLY header.
constexpr std::uintmax_t kHeaderBytes = 64 * 1024;
constexpr std::size_t kNone = static_cast<std::size_t>(-1);

/// Phase 2 post-processing. RemoveComponent drops normals, UVs, colours and materials so that
/// JoinIdenticalVertices welds positions across UV/normal seams (a closed model stays closed) and
/// PreTransformVertices merges every mesh into as few as possible. No aiProcess_GlobalScale: units as in the file.
constexpr unsigned kPostProcess = aiProcess_ValidateDataStructure | aiProcess_Triangulate |
                                  aiProcess_RemoveComponent | aiProcess_JoinIdenticalVertices |
                                  aiProcess_PreTransformVertices | aiProcess_SortByPType;
constexpr int kRemovedComponents = aiComponent_NORMALS | aiComponent_TANGENTS_AND_BITANGENTS | aiComponent_COLORS |
                                   aiComponent_TEXCOORDS | aiComponent_BONEWEIGHTS | aiComponent_ANIMATIONS |
                                   aiComponent_TEXTURES | aiComponent_LIGHTS | aiComponent_CAMERAS |
                                   aiComponent_MATERIALS;

/// The path as shown in messages: a control character in a file name must not break the one-line rule.
std::string shown(const fs::path& path) {
  std::string s = path.string();
  for (char& c : s)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = '?';
  return s;
}

Error file_error(const fs::path& path, std::string_view reason) {
  return input_error(fmt::format("{}: {}", shown(path), reason));
}

/// The reason Assimp gave, as one line, or `fallback` when it gave none.
std::string assimp_reason(const Assimp::Importer& importer, std::string_view fallback) {
  std::string reason = one_line(importer.GetErrorString());
  return reason.empty() ? std::string(fallback) : reason;
}

bool finite(const aiVector3D& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

/// Index of the first vertex with a NaN/Inf coordinate, or kNone.
std::size_t first_non_finite(const std::vector<Vec3f>& vertices) {
  for (std::size_t i = 0; i < vertices.size(); ++i)
    if (!vertices[i].allFinite()) return i;
  return kNone;
}

// ---- header sanity (before Assimp) ----

/// The decimal count `t` (digits only), saturating at UINT64_MAX; nullopt when `t` is not a count.
std::optional<std::uint64_t> parse_count(std::string_view t) {
  if (t.empty()) return std::nullopt;
  std::uint64_t n = 0;
  for (const char c : t) {
    if (c < '0' || c > '9') return std::nullopt;
    const auto d = static_cast<std::uint64_t>(c - '0');
    n = n > (UINT64_MAX - d) / 10 ? UINT64_MAX : n * 10 + d;
  }
  return n;
}

/// Next whitespace-separated token of `s` from `i`, skipping `#` comments (OFF syntax).
std::string_view next_token(std::string_view s, std::size_t& i) {
  for (;;) {
    while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i]))) ++i;
    if (i >= s.size() || s[i] != '#') break;
    while (i < s.size() && s[i] != '\n') ++i;
  }
  const std::size_t b = i;
  while (i < s.size() && !std::isspace(static_cast<unsigned char>(s[i])) && s[i] != '#') ++i;
  return s.substr(b, i - b);
}

/// [ST][C][N][4][n]OFF, the header keyword Assimp's OFF reader accepts.
bool is_off_keyword(std::string_view t) {
  if (t.size() < 3 || t.substr(t.size() - 3) != "OFF") return false;
  std::string_view p = t.substr(0, t.size() - 3);
  for (const std::string_view prefix : {"ST", "C", "N", "4", "n"})
    if (p.substr(0, prefix.size()) == prefix) p.remove_prefix(prefix.size());
  return p.empty();
}

/// True when Assimp will read the file as OFF: by its extension, or by the keyword it starts with.
bool read_as_off(const fs::path& path, std::string_view head) {
  std::string ext = path.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  std::size_t i = 0;
  if (head.starts_with("\xEF\xBB\xBF")) head.remove_prefix(3);
  return ext == ".off" || is_off_keyword(next_token(head, i));
}

/// A cursor over an OFF file that moves the way Assimp's OFF reader and its parsing helpers do.
struct OffCursor {
  std::string_view text;
  std::size_t end = 0;  // Assimp's copy of the file ends with a NUL, and its parsing stops at the first NUL in it
  std::size_t p = 0;
  std::size_t line_number = 0;
  bool too_long = false;

  explicit OffCursor(std::string_view t) : text(t), end(t.size() + 1) {}
  char at(std::size_t k) const { return k < text.size() ? text[k] : '\0'; }
  static bool line_end(char c) { return c == '\r' || c == '\n' || c == '\0' || c == '\f'; }
  void skip_spaces_and_line_end() {
    while (at(p) == ' ' || at(p) == '\t' || at(p) == '\r' || at(p) == '\n') ++p;
  }
  void skip_line() {
    while (at(p) != '\r' && at(p) != '\n' && at(p) != '\0') ++p;
    while (at(p) == '\r' || at(p) == '\n') ++p;
  }
  void token() {  // OFFLoader's NextToken
    skip_spaces_and_line_end();
    while (p < end && (at(p) == '#' || at(p) == '\n' || at(p) == '\r')) skip_line(), skip_spaces_and_line_end();
  }
  std::uint32_t number(std::size_t& k) const {  // strtoul10, wrapping like Assimp's unsigned int
    std::uint32_t v = 0;
    while (at(k) >= '0' && at(k) <= '9') v = v * 10u + static_cast<std::uint32_t>(at(k++) - '0');
    return v;
  }
  bool next_line(std::string_view& line) {  // GetNextLine into char[4096]
    if (at(p) == '\0') return false;
    const std::size_t b = p;
    while (!line_end(at(p)) && p - b < 4096) ++p;
    too_long = too_long || p - b == 4096;
    line = text.substr(b, p - b);
    while (line_end(at(p)) && at(p) != '\0') ++p;
    ++line_number;
    return true;
  }
};

/// The vertex and face counts of an OFF header as Assimp reads them (wrapped to 32 bits), the cursor left after
/// them; nullopt where Assimp refuses the header itself.
std::optional<std::pair<std::uint32_t, std::uint32_t>> read_off_counts(OffCursor& c) {
  std::size_t& p = c.p;
  const std::size_t end = c.end;
  c.token();
  bool dimension = false;
  if (p + 2 < end && c.at(p) == 'S' && c.at(p + 1) == 'T') p += 2;
  if (p + 1 < end && c.at(p) == 'C') ++p;
  if (p + 1 < end && c.at(p) == 'N') ++p;
  if (p + 1 < end && c.at(p) == '4') ++p;
  if (p + 1 < end && c.at(p) == 'n') dimension = true, ++p;
  if (p + 3 < end && c.at(p) == 'O' && c.at(p + 1) == 'F' && c.at(p + 2) == 'F') {
    p += 3;
    c.token();
  } else {
    c.token();
    if (p + 1 >= end || c.at(p) < '0' || c.at(p) > '9') return std::nullopt;  // Assimp: "Header is invalid"
  }
  if (dimension) {
    if (c.number(p) > 3) return std::nullopt;  // Assimp: "higher than 3 unsupported"
    c.token();
  }
  c.token();
  const std::uint32_t vertices = c.number(p);
  c.token();
  const std::uint32_t faces = c.number(p);
  c.token();
  c.number(p);  // edges
  c.token();
  return std::pair{vertices, faces};
}

/// Assimp 5.2.5's OFF reader, as far as it counts faces (code/AssetLib/OFF/OFFLoader.cpp, on the helpers of
/// ParsingUtils.h): it drops a face line whose vertex count is 0 or over 9 by decrementing the mesh's face count, once
/// per such line and without counting the line, so more of them than the header's faces wrap the count round and
/// Assimp reads far past its face array (SIGSEGV). It also copies each line into a 4096-byte buffer and writes one
/// byte past it for a longer line. This walks `text` (the whole file) the way that reader does and refuses both.
Status check_off_lines(const fs::path& path, std::string_view text) {
  if (text.starts_with("\xEF\xBB\xBF")) text.remove_prefix(3);  // Assimp drops a UTF-8 byte order mark
  if (text.starts_with("\xFF\xFE") || text.starts_with("\xFE\xFF") || text.starts_with(std::string_view("\0\0\xFE\xFF", 4)))
    return file_error(path, "OFF in UTF-16 or UTF-32 is not supported");
  OffCursor cur(text);
  const auto counts = read_off_counts(cur);
  if (!counts) return {};
  const auto [vertices, faces] = *counts;
  if (vertices == 0 || faces == 0) return {};  // Assimp refuses these itself
  // The counts as Assimp reads them (after a byte order mark, wrapped to 32 bits), which is what it allocates for
  // before reading a line: each vertex and each face takes at least one byte of the file.
  if (vertices > text.size())
    return file_error(path, fmt::format("header declares {} vertices, more than a {}-byte file can hold", vertices,
                                        text.size()));
  if (faces > text.size())
    return file_error(path, fmt::format("header declares {} faces, more than a {}-byte file can hold", faces,
                                        text.size()));

  std::string_view line;
  for (std::uint32_t v = 0; v < vertices && cur.next_line(line);) ++v;
  std::uint64_t dropped = 0;
  for (std::uint32_t f = 0; f < faces && cur.next_line(line);) {
    std::size_t k = static_cast<std::size_t>(line.data() - text.data());  // SkipSpaces, then strtoul10
    while (cur.at(k) == ' ' || cur.at(k) == '\t') ++k;
    const std::uint32_t n = cur.number(k);
    if (n >= 1 && n <= 9) {
      ++f;
    } else if (++dropped > faces) {
      return file_error(path, fmt::format("{} face lines without a vertex count of 1 to 9, more than the header's {} "
                                          "faces", dropped, faces));
    }
  }
  if (cur.too_long) return file_error(path, "has a line of 4096 characters or more (more than the OFF reader takes)");
  return {};
}

/// Assimp 5.2.5's OFF and PLY readers allocate (and zero) whatever their header declares before reading any
/// data: invalid/OutOfMemory.off declares 353535235358 vertices and makes Assimp touch 16 GB for 30 s; a PLY
/// header with "element vertex 300000000" grows without bound as well. Every element takes at least one byte
/// of the file, so a declared count above the file size is refused here, before Assimp sees the file.
/// `h`: the first kHeaderBytes of the file (or all of it).
Status check_declared_counts(const fs::path& path, std::string_view h, std::uintmax_t file_size) {
  auto too_many = [&](std::uint64_t n, std::string_view what) {  // parse_count saturates at 2^64 - 1
    const std::string count = n == UINT64_MAX ? std::string("over 2^64") : fmt::format("{}", n);
    return file_error(path,
                      fmt::format("header declares {} {}, more than a {}-byte file can hold", count, what, file_size));
  };

  // PLY: Assimp takes any first line that starts with "ply" or "PLY" (in any case) for its magic.
  const auto lower = [](char c) { return static_cast<char>(std::tolower(static_cast<unsigned char>(c))); };
  if (h.size() >= 3 && lower(h[0]) == 'p' && lower(h[1]) == 'l' && lower(h[2]) == 'y') {
    // Lines "element <name> <count>" until end_header.
    std::size_t line_start = 0;
    while (line_start < h.size()) {
      std::size_t line_end = h.find('\n', line_start);
      if (line_end == std::string_view::npos) line_end = h.size();
      const std::string_view line = h.substr(line_start, line_end - line_start);
      line_start = line_end + 1;
      if (line.starts_with("end_header")) break;
      if (!line.starts_with("element") || line.size() < 8 || !std::isspace(static_cast<unsigned char>(line[7]))) continue;
      std::size_t i = 7;
      const std::string_view name = next_token(line, i);
      if (const auto n = parse_count(next_token(line, i)); n && *n > file_size)
        return too_many(*n, fmt::format("'{}' elements", printable(name)));
    }
    // Assimp 5.2.5 reads a header without its end_header line for ever: "end_header" must start a line and be
    // followed by what its TokenMatch takes for a token's end (IsSpaceOrNewLine: space, tab, \r, \n, \f or NUL;
    // not a vertical tab, after which it hangs).
    const auto token_end = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\0'; };
    bool end_header = false;
    for (std::size_t k = h.find("end_header"); k != std::string_view::npos && !end_header; k = h.find("end_header", k + 1)) {
      const std::size_t after = k + 10;
      end_header = k > 0 && (h[k - 1] == '\n' || h[k - 1] == '\r') && (after == h.size() || token_end(h[after]));
    }
    if (!end_header)
      return file_error(path, fmt::format("PLY header has no end_header line{}",
                                          file_size > h.size() ? fmt::format(" in its first {} bytes", h.size()) : ""));
    return {};
  }

  // OFF: optional keyword (and dimension for nOFF), then "<vertices> <faces> <edges>".
  if (!read_as_off(path, h)) return {};
  if (h.starts_with("\xEF\xBB\xBF")) h.remove_prefix(3);  // Assimp drops a UTF-8 byte order mark
  std::size_t i = 0;
  std::string_view t = next_token(h, i);
  const bool keyword = is_off_keyword(t);
  if (keyword) {
    if (t.find('n') != std::string_view::npos) next_token(h, i);  // nOFF: the dimension comes first
    t = next_token(h, i);
  }
  if (const auto n = parse_count(t); n && *n > file_size) return too_many(*n, "vertices");
  if (const auto n = parse_count(next_token(h, i)); n && *n > file_size) return too_many(*n, "faces");
  return {};
}

/// What is checked before Assimp sees a file: the counts its header declares (`head`: its first kHeaderBytes), and
/// the lines of an OFF file (`whole()`: all of its bytes, asked for only then).
template <class Whole>
Status check_before_assimp(const fs::path& path, std::string_view head, std::uintmax_t file_size, Whole&& whole) {
  FF_CHECK(check_declared_counts(path, head, file_size));
  if (!read_as_off(path, head)) return {};
  return check_off_lines(path, whole());
}

Status check_before_assimp(const fs::path& path, std::uintmax_t file_size) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return {};  // Assimp reports the open failure
  std::string head(static_cast<std::size_t>(std::min(file_size, kHeaderBytes)), '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(in.gcount()));
  std::string all;
  return check_before_assimp(path, head, file_size, [&] {
    all.resize(static_cast<std::size_t>(file_size));
    in.clear();
    in.seekg(0);
    in.read(all.data(), static_cast<std::streamsize>(all.size()));
    all.resize(static_cast<std::size_t>(in.gcount()));
    return std::string_view(all);
  });
}

// ---- scene → TriangleMesh ----

/// Phase 1 checks on the raw, not yet validated scene (only counts and positions are read): there are
/// vertices, every coordinate is finite, and there are faces. A file of bare vertices (a point cloud) gets its
/// own message here; Assimp's validation would only say "Mesh contains no faces".
Status check_raw_scene(const fs::path& path, const aiScene& scene, MeshLoadStats& stats) {
  std::size_t k = 0, faces = 0;  // k: running vertex number over the file's meshes
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
    const aiMesh* mesh = scene.mMeshes[m];
    if (mesh == nullptr || mesh->mVertices == nullptr) continue;  // validation reports it in phase 2
    for (unsigned v = 0; v < mesh->mNumVertices; ++v, ++k)
      if (!finite(mesh->mVertices[v]))
        return file_error(path, fmt::format("vertex {} has a non-finite coordinate (NaN/Inf)", k));
    faces += mesh->mNumFaces;
  }
  if (k == 0) return file_error(path, "contains no vertices");
  if (faces == 0) {
    stats.dropped_non_triangles = k;  // every vertex is a point primitive
    return file_error(path, "contains no triangles (only points/lines)");
  }
  return {};
}

/// Merges the triangle meshes of the post-processed scene (indices offset) and counts the point and line
/// primitives, whose meshes (SortByPType split them off) are skipped with their vertices.
Result<TriangleMesh> merged_triangles(const fs::path& path, const aiScene& scene, std::size_t max_vertices,
                                      MeshLoadStats& stats) {
  // Count first so that an oversized mesh is refused before anything is allocated.
  std::size_t n_vertices = 0, n_triangles = 0, n_other = 0;
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
    const aiMesh* mesh = scene.mMeshes[m];
    if (mesh == nullptr || mesh->mVertices == nullptr || mesh->mFaces == nullptr) continue;
    std::size_t tris = 0;
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) ++(mesh->mFaces[f].mNumIndices == 3 ? tris : n_other);
    if (tris == 0) continue;
    n_triangles += tris;
    n_vertices += mesh->mNumVertices;
  }
  stats.dropped_non_triangles = n_other;
  if (n_triangles == 0)
    return file_error(path, n_other > 0 ? "contains no triangles (only points/lines)" : "contains no vertices");
  if (n_vertices > max_vertices)
    return file_error(path, fmt::format("has {} vertices, more than the limit of {}", n_vertices, max_vertices));

  TriangleMesh out;
  out.vertices.reserve(n_vertices);
  out.triangles.reserve(n_triangles);
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
    const aiMesh* mesh = scene.mMeshes[m];
    if (mesh == nullptr || mesh->mVertices == nullptr || mesh->mFaces == nullptr) continue;
    const auto base = static_cast<Index>(out.vertices.size());  // ≤ max_vertices ≤ 2^32 − 2
    bool any = false;
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices != 3) continue;
      std::array<Index, 3> t{};
      for (unsigned c = 0; c < 3; ++c) {
        const unsigned i = face.mIndices[c];
        if (i >= mesh->mNumVertices)  // validation already refuses this; never index out of range regardless
          return file_error(path, fmt::format("face {} uses vertex {} of a mesh with {}", f, i, mesh->mNumVertices));
        t[c] = base + i;
      }
      out.triangles.push_back(t);
      any = true;
    }
    if (!any) continue;
    for (unsigned v = 0; v < mesh->mNumVertices; ++v)
      out.vertices.emplace_back(mesh->mVertices[v].x, mesh->mVertices[v].y, mesh->mVertices[v].z);
  }
  return out;
}

/// Drops degenerate triangles (repeated index, or |cross| ≤ 1e-12 × diagonal² of the box of the referenced
/// vertices), then removes unreferenced vertices keeping their relative order. Returns the number dropped.
std::size_t drop_degenerate(TriangleMesh& mesh) {
  Eigen::AlignedBox3d box;
  for (const auto& t : mesh.triangles)
    for (const Index i : t) box.extend(mesh.vertices[i].cast<double>());
  const double limit = box.isEmpty() ? 0.0 : kDegenerateFactor * box.diagonal().squaredNorm();

  std::size_t kept = 0;
  for (const auto& t : mesh.triangles) {
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
    const Vec3d a = mesh.vertices[t[0]].cast<double>();
    const Vec3d b = mesh.vertices[t[1]].cast<double>();
    const Vec3d c = mesh.vertices[t[2]].cast<double>();
    if (!((b - a).cross(c - a).norm() > limit)) continue;
    mesh.triangles[kept++] = t;
  }
  const std::size_t dropped = mesh.triangles.size() - kept;
  mesh.triangles.resize(kept);

  drop_unused_vertices(mesh);  // in their relative order
  return dropped;
}

Status check_options(const fs::path& path, const LoadOptions& options) {
  if (auto s = options.transform.validate(); !s.ok())
    return param_error(fmt::format("{}: {}", shown(path), s.error().message));
  if (!(options.max_vertices >= 1 && options.max_vertices <= kMaxMeshVertices))
    return param_error(fmt::format("{}: max_vertices = {} is outside [1, {}]", shown(path), options.max_vertices,
                                   kMaxMeshVertices));
  if (!(options.import_timeout_s > 0.0 && options.import_timeout_s <= 86400.0))
    return param_error(fmt::format("{}: import_timeout_s = {} is outside (0, 86400]", shown(path),
                                   options.import_timeout_s));
  return {};
}

}  // namespace

bool is_mesh_extension(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext.size() < 2 || ext == ".json") return false;
  // Assimp's list is of its importers' extensions; asking needs no file and no scene.
  const Assimp::Importer importer;
  return importer.IsExtensionSupported(ext.c_str());
}

namespace {

void configure(Assimp::Importer& importer) {
  // No logger is created, so Assimp logs into its default NullLogger: nothing reaches stdout or stderr.
  importer.SetPropertyInteger(AI_CONFIG_PP_RVC_FLAGS, kRemovedComponents);
  // A skeleton-only file (BVH, MD5 anim …) must not turn into a mesh of bone sticks.
  importer.SetPropertyBool(AI_CONFIG_IMPORT_NO_SKELETON_MESHES, true);
}

/// Assimp's part (`scene`: what ReadFile or ReadFileFromMemory returned): the raw scene's checks, post-processing,
/// and the merge into one triangle mesh (node transforms baked, not yet checked for overflow).
Result<TriangleMesh> import_triangles(const fs::path& path, Assimp::Importer& importer, const aiScene* scene,
                                      std::size_t max_vertices, MeshLoadStats& stats) {
  if (scene == nullptr) return file_error(path, assimp_reason(importer, "cannot be read (no reason given)"));
  stats.source_meshes = scene->mNumMeshes;
  if (scene->mNumMeshes == 0 || scene->mMeshes == nullptr) return file_error(path, "contains no meshes");
  FF_CHECK(check_raw_scene(path, *scene, stats));

  scene = importer.ApplyPostProcessing(kPostProcess);
  if (scene == nullptr) return file_error(path, assimp_reason(importer, "post-processing failed (no reason given)"));
  return merged_triangles(path, *scene, max_vertices, stats);
}

// ---- the import in a child process (io/isolate.h): its answer as bytes ----
//
// The statistics (source meshes, dropped non-triangles), then one byte, 1 for a mesh, 0 for an error. An error: its
// kind (one byte) and message. A mesh: its vertices (x, y, z floats) and its triangles (three uint32 indices).

std::string encode(const Result<TriangleMesh>& r, const MeshLoadStats& stats) {
  AnswerWriter out;
  out.put(std::uint64_t{stats.source_meshes});
  out.put(std::uint64_t{stats.dropped_non_triangles});  // counted on the way to an error too
  if (!r) {
    out.put(std::uint8_t{0});
    out.put(static_cast<std::uint8_t>(r.error().kind));
    out.put_string(r.error().message);
    return out.take();
  }
  const TriangleMesh& m = r.value();
  out.put(std::uint8_t{1});
  std::vector<std::array<float, 3>> xyz(m.vertices.size());
  for (std::size_t v = 0; v < xyz.size(); ++v) xyz[v] = {m.vertices[v].x(), m.vertices[v].y(), m.vertices[v].z()};
  out.put_vector(xyz);
  out.put_vector(m.triangles);
  return out.take();
}

/// The child's answer back into a mesh; every count is checked against the bytes that came, and every index
/// against the vertices, since a child whose heap Assimp corrupted may still have answered.
Result<TriangleMesh> decode(const fs::path& path, std::string_view bytes, std::size_t max_vertices,
                            MeshLoadStats& stats) {
  const Error garbled = file_error(path, "the import process sent a garbled answer");
  AnswerReader in(bytes);
  std::uint64_t meshes = 0, other = 0;
  std::uint8_t ok = 0;
  if (!in.get(meshes) || !in.get(other) || !in.get(ok)) return garbled;
  stats.source_meshes = meshes;
  stats.dropped_non_triangles = other;
  if (ok == 0) {
    // The child's errors are all about the file (file_error): any other kind is a garbled answer, not an exit 1.
    std::string message;
    return in.get_input_error(message) ? input_error(std::move(message)) : garbled;
  }
  std::vector<std::array<float, 3>> xyz;
  TriangleMesh m;
  if (ok != 1 || !in.get_vector(xyz) || !in.get_vector(m.triangles) || !in.at_end() || xyz.size() > max_vertices)
    return garbled;
  m.vertices.resize(xyz.size());
  for (std::size_t v = 0; v < xyz.size(); ++v) m.vertices[v] = Vec3f(xyz[v][0], xyz[v][1], xyz[v][2]);
  for (const auto& t : m.triangles)
    for (const Index i : t)
      if (i >= m.vertices.size()) return garbled;
  return m;
}

/// Assimp's part, in this process or (options.isolate) in a child. `read(importer)` runs ReadFile or
/// ReadFileFromMemory.
template <class Read>
Result<TriangleMesh> assimp_triangles(const fs::path& path, const LoadOptions& options, MeshLoadStats& stats,
                                      Read&& read) {
  const auto here = [&](MeshLoadStats& s) -> Result<TriangleMesh> {
    Assimp::Importer importer;
    configure(importer);
    return import_triangles(path, importer, read(importer), options.max_vertices, s);
  };
  if (!options.isolate) return here(stats);
  auto answer = run_isolated(
      [&] {
        MeshLoadStats s;
        try {
          return encode(here(s), s);
        } catch (const std::bad_alloc&) {
          return encode(file_error(path, "out of memory while reading"), s);
        } catch (const std::exception& e) {
          return encode(file_error(path, one_line(e.what())), s);
        } catch (...) {
          return encode(file_error(path, "unknown error while reading"), s);
        }
      },
      "Assimp's import", IsolateOptions{options.import_timeout_s});
  if (!answer) return answer.error().kind == Error::Kind::Input ? file_error(path, answer.error().message) : answer.error();
  return decode(path, *answer, options.max_vertices, stats);
}

/// Our part, after Assimp's: node transforms that overflowed, `options.transform`, degenerate triangles.
Result<TriangleMesh> finish_import(const fs::path& path, TriangleMesh mesh, const LoadOptions& options,
                                   MeshLoadStats& stats) {
  if (const auto k = first_non_finite(mesh.vertices); k != kNone)  // a huge node transform can overflow
    return file_error(path, fmt::format("vertex {} has a non-finite coordinate (NaN/Inf) after node transforms", k));
  if (!options.transform.is_identity()) {
    transform_mesh(mesh, options.transform);
    if (const auto k = first_non_finite(mesh.vertices); k != kNone)
      return file_error(path, fmt::format("vertex {} has a non-finite coordinate (NaN/Inf) after the transform", k));
  }

  // Degeneracy is judged on the final geometry (after the transform), which is what later stages see.
  const std::size_t n_triangles = mesh.triangles.size();
  stats.dropped_degenerate = drop_degenerate(mesh);
  if (mesh.triangles.empty())
    return file_error(path, fmt::format("all {} triangles are degenerate (repeated vertex or zero area)", n_triangles));
  return mesh;
}

Result<TriangleMesh> load_mesh_impl(const fs::path& path, const LoadOptions& options, MeshLoadStats& stats) {
  FF_CHECK(check_options(path, options));
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (st.type() == fs::file_type::not_found) return file_error(path, "no such file");
  if (ec) return file_error(path, one_line(ec.message()));
  if (st.type() == fs::file_type::directory) return file_error(path, "is a directory, not a mesh file");
  if (st.type() != fs::file_type::regular) return file_error(path, "is not a regular file");
  const std::uintmax_t size = fs::file_size(path, ec);
  if (!ec && size == 0) return file_error(path, "file is empty");
  if (!ec) FF_CHECK(check_before_assimp(path, size));

  FF_TRY(TriangleMesh mesh, assimp_triangles(path, options, stats, [&](Assimp::Importer& importer) {
           return importer.ReadFile(path.string(), 0);
         }));
  return finish_import(path, std::move(mesh), options, stats);
}

Status check_mesh_bytes_impl(std::span<const std::uint8_t> bytes, const fs::path& name) {
  if (bytes.empty()) return file_error(name, "file is empty");
  const std::string_view all(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  return check_before_assimp(name, all.substr(0, static_cast<std::size_t>(kHeaderBytes)), bytes.size(),
                             [&] { return all; });
}

Result<TriangleMesh> load_mesh_memory_impl(std::span<const std::uint8_t> bytes, const fs::path& name,
                                           const LoadOptions& options, MeshLoadStats& stats) {
  FF_CHECK(check_options(name, options));
  FF_CHECK(check_mesh_bytes_impl(bytes, name));

  std::string hint = name.extension().string();  // Assimp picks the importer by it: "obj", "ply" ...
  if (!hint.empty()) hint.erase(0, 1);
  FF_TRY(TriangleMesh mesh, assimp_triangles(name, options, stats, [&](Assimp::Importer& importer) {
           return importer.ReadFileFromMemory(bytes.data(), bytes.size(), 0, hint.c_str());
         }));
  return finish_import(name, std::move(mesh), options, stats);
}

/// `import()`, keeping the no-throw promise: Assimp catches its own import errors; this catches allocation failures
/// in the merge and anything an importer lets through.
template <class F>
Result<TriangleMesh> guarded(const fs::path& path, MeshLoadStats* stats, F&& import) {
  MeshLoadStats local;
  MeshLoadStats& s = stats != nullptr ? *stats : local;
  s = {};
  try {
    return import(s);
  } catch (const std::bad_alloc&) {
    return file_error(path, "out of memory while reading");
  } catch (const std::exception& e) {
    return file_error(path, one_line(e.what()));
  } catch (...) {
    return file_error(path, "unknown error while reading");
  }
}

}  // namespace

bool MeshTransform::is_identity() const {
  return scale == Vec3f::Ones() && rotate_deg == Vec3f::Zero() && translate == Vec3f::Zero();
}

Vec3f MeshTransform::apply(const Vec3f& p) const {
  return (core::rotation_from_degrees<double>(rotate_deg.cast<double>()) * p.cast<double>().cwiseProduct(scale.cast<double>()) + translate.cast<double>())
      .cast<float>();
}

Status MeshTransform::validate() const {
  static constexpr std::array<char, 3> kAxis{'x', 'y', 'z'};
  for (int a = 0; a < 3; ++a)
    if (!(std::isfinite(scale[a]) && scale[a] != 0.0f))
      return param_error(fmt::format("transform.scale.{} = {} must be finite and non-zero", kAxis[a], scale[a]));
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(rotate_deg[a]))
      return param_error(fmt::format("transform.rotate.{} = {} must be finite (degrees)", kAxis[a], rotate_deg[a]));
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(translate[a]))
      return param_error(fmt::format("transform.translate.{} = {} must be finite (metres)", kAxis[a], translate[a]));
  return {};
}

Result<TriangleMesh> load_mesh(const fs::path& path, const LoadOptions& options, MeshLoadStats* stats) {
  return guarded(path, stats, [&](MeshLoadStats& s) { return load_mesh_impl(path, options, s); });
}

Result<TriangleMesh> load_mesh_from_memory(std::span<const std::uint8_t> bytes, const fs::path& name,
                                           const LoadOptions& options, MeshLoadStats* stats) {
  return guarded(name, stats, [&](MeshLoadStats& s) { return load_mesh_memory_impl(bytes, name, options, s); });
}

Status check_mesh_bytes(std::span<const std::uint8_t> bytes, const fs::path& name) {
  try {
    return check_mesh_bytes_impl(bytes, name);
  } catch (const std::bad_alloc&) {
    return file_error(name, "out of memory while reading");
  }
}

Result<TriangleMesh> mesh_from_import_answer(std::span<const std::uint8_t> answer, const fs::path& name,
                                             const LoadOptions& options, MeshLoadStats* stats) {
  return guarded(name, stats, [&](MeshLoadStats& s) -> Result<TriangleMesh> {
    FF_CHECK(check_options(name, options));
    const std::string_view bytes(reinterpret_cast<const char*>(answer.data()), answer.size());
    FF_TRY(TriangleMesh mesh, decode(name, bytes, options.max_vertices, s));
    return finish_import(name, std::move(mesh), options, s);
  });
}

std::string import_answer(const Result<TriangleMesh>& result, const MeshLoadStats& stats) {
  return encode(result, stats);
}

void transform_mesh(TriangleMesh& mesh, const MeshTransform& t) {
  const Eigen::Matrix3d rs = core::rotation_from_degrees<double>(t.rotate_deg.cast<double>()) * t.scale.cast<double>().asDiagonal();
  const Vec3d shift = t.translate.cast<double>();
  for (auto& v : mesh.vertices) v = (rs * v.cast<double>() + shift).cast<float>();
  // A mirror (an odd number of negative scales, det < 0) turns every triangle inside out: reversing the winding
  // keeps the normals pointing out, so the mesh's signed volume, and everything downstream, stays as unmirrored.
  if (t.mirrors())
    for (auto& tri : mesh.triangles) std::swap(tri[1], tri[2]);
}

double signed_volume(const TriangleMesh& mesh) {
  double six_v = 0.0;
  for (const auto& t : mesh.triangles) {
    const Vec3d a = mesh.vertices[t[0]].cast<double>();
    const Vec3d b = mesh.vertices[t[1]].cast<double>();
    const Vec3d c = mesh.vertices[t[2]].cast<double>();
    six_v += a.dot(b.cross(c));
  }
  return six_v / 6.0;
}

}  // namespace ff::io
