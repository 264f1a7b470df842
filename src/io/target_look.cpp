#include "io/target_look.h"

#include "io/isolate.h"

#include <assimp/Importer.hpp>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/format.h>
#include <stb_image.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <cstring>

namespace ff::io {
namespace {
namespace fs = std::filesystem;

// Triangles only, node transforms baked into one vertex space; vertices joined only where every attribute agrees
// (UV seams stay open). Normals, bones, animations, lights and cameras are not needed.
constexpr unsigned kPostProcess = aiProcess_Triangulate | aiProcess_RemoveComponent | aiProcess_JoinIdenticalVertices |
                                  aiProcess_PreTransformVertices | aiProcess_SortByPType;
constexpr int kRemovedComponents = aiComponent_NORMALS | aiComponent_TANGENTS_AND_BITANGENTS | aiComponent_BONEWEIGHTS |
                                   aiComponent_ANIMATIONS | aiComponent_LIGHTS | aiComponent_CAMERAS;

Error file_error(const fs::path& path, std::string_view reason) {
  return input_error(fmt::format("{}: {}", path.string(), reason));
}

float clamp01(float v) { return std::isfinite(v) ? std::clamp(v, 0.0f, 1.0f) : 0.0f; }
float srgb_to_linear_float(float s) { return s <= 0.04045f ? s / 12.92f : std::pow((s + 0.055f) / 1.055f, 2.4f); }

// ---- in the child: Assimp's scene → TargetLook ----

// The texture file a material names: as written, beside the model, or (a path from another machine) its file name
// beside the model; files written on Windows also with '\\' as separators and the name's case ignored.
fs::path find_texture_file(const fs::path& model, std::string name) {
  std::replace(name.begin(), name.end(), '\\', '/');
  const fs::path given(name);
  const fs::path dir = model.parent_path();
  std::string relative = name;
  while (!relative.empty() && relative[0] == '/') relative.erase(0, 1);
  std::error_code ec;
  const auto lower = [](std::string t) {
    for (char& c : t) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return t;
  };
  std::vector<fs::path> candidates;
  if (given.is_absolute()) candidates.push_back(given);  // a relative name is the model's folder's, never ours
  candidates.insert(candidates.end(), {dir / fs::path(relative), dir / given.filename()});
  for (const fs::path& p : candidates) {
    if (p.filename().empty()) continue;
    if (fs::is_regular_file(p, ec)) return p;
    if (!fs::is_directory(p.parent_path(), ec)) continue;
    fs::directory_iterator it(p.parent_path(), ec), end;
    for (; !ec && it != end; it.increment(ec))
      if (lower(it->path().filename().string()) == lower(p.filename().string()) && fs::is_regular_file(it->path(), ec))
        return it->path();
  }
  return {};
}

Result<Texture> decode_image(const std::uint8_t* bytes, std::size_t size) {
  if (size > std::size_t(std::numeric_limits<int>::max())) return input_error("larger than 2 GB");
  int w = 0, h = 0, n = 0;
  const int len = static_cast<int>(size);
  if (stbi_info_from_memory(bytes, len, &w, &h, &n) == 0) return input_error(fmt::format("not an image stb_image reads ({})", stbi_failure_reason()));
  if (w <= 0 || h <= 0 || w > kMaxTextureSide || h > kMaxTextureSide)
    return input_error(fmt::format("{}×{} pixels, more than {} on a side", w, h, kMaxTextureSide));
  std::uint8_t* px = stbi_load_from_memory(bytes, len, &w, &h, &n, 3);
  if (px == nullptr) return input_error(fmt::format("cannot be decoded ({})", stbi_failure_reason()));
  Texture t;
  t.width = w, t.height = h;
  t.rgb.assign(px, px + std::size_t(w) * std::size_t(h) * 3);
  stbi_image_free(px);
  return t;
}

// An embedded texture: compressed (a PNG/JPEG file in memory, mHeight 0) or raw BGRA texels.
Result<Texture> embedded_texture(const aiTexture& tex) {
  if (tex.pcData == nullptr) return input_error("embedded texture without data");
  if (tex.mHeight == 0) return decode_image(reinterpret_cast<const std::uint8_t*>(tex.pcData), tex.mWidth);
  if (tex.mWidth == 0) return input_error("embedded texture of no width");
  if (tex.mWidth > unsigned(kMaxTextureSide) || tex.mHeight > unsigned(kMaxTextureSide))
    return input_error(fmt::format("{}×{} pixels, more than {} on a side", tex.mWidth, tex.mHeight, kMaxTextureSide));
  Texture t;
  t.width = int(tex.mWidth), t.height = int(tex.mHeight);
  t.rgb.resize(std::size_t(t.width) * std::size_t(t.height) * 3);
  for (std::size_t i = 0; i < std::size_t(t.width) * std::size_t(t.height); ++i) {
    t.rgb[3 * i] = tex.pcData[i].r, t.rgb[3 * i + 1] = tex.pcData[i].g, t.rgb[3 * i + 2] = tex.pcData[i].b;
  }
  return t;
}

Result<Texture> read_texture(const fs::path& model, const aiScene& scene, const std::string& name) {
  if (const aiTexture* tex = scene.GetEmbeddedTexture(name.c_str())) return embedded_texture(*tex);
  if (!name.empty() && name[0] == '*') return input_error("names an embedded texture the file does not have");
  const fs::path file = find_texture_file(model, name);
  if (file.empty()) return input_error("no such file beside the model");
  std::error_code ec;
  if (fs::file_size(file, ec) > (std::uintmax_t{1} << 30) || ec) return input_error("is larger than 1 GiB or cannot be sized");
  std::ifstream in(file, std::ios::binary);
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (!in.good() && !in.eof()) return input_error("cannot be read");
  if (bytes.empty()) return input_error("is empty");
  return decode_image(bytes.data(), bytes.size());
}

// Material m's colour and texture; a texture that cannot be used is a warning and the material keeps its colour.
// Materials naming the same texture share one decoded copy (`decoded`: name → index in look.textures).
LookMaterial read_material(const fs::path& model, const aiScene& scene, const aiMaterial& mat, TargetLook& look,
                           std::map<std::string, int>& decoded) {
  LookMaterial out;
  aiColor4D c;
  if (mat.Get(AI_MATKEY_BASE_COLOR, c) == AI_SUCCESS) {
    out.colour = Vec3f(clamp01(c.r), clamp01(c.g), clamp01(c.b));
    out.factor_with_texture = true;
  } else if (mat.Get(AI_MATKEY_COLOR_DIFFUSE, c) == AI_SUCCESS) {
    out.colour = Vec3f(clamp01(c.r), clamp01(c.g), clamp01(c.b));
  }
  aiString name;
  bool has = false;
  for (const aiTextureType type : {aiTextureType_BASE_COLOR, aiTextureType_DIFFUSE})
    if (mat.GetTextureCount(type) > 0 && mat.GetTexture(type, 0, &name) == AI_SUCCESS) {
      has = true;
      break;
    }
  if (!has) return out;
  if (const auto it = decoded.find(name.C_Str()); it != decoded.end()) {
    out.texture = it->second;
    return out;
  }
  Result<Texture> tex = input_error("cannot be read");
  try {
    tex = read_texture(model, scene, name.C_Str());
  } catch (const std::exception& e) {
    tex = input_error(e.what());
  }
  if (!tex) {
    look.warnings.push_back(fmt::format("{}: texture '{}' {}: its material colour is used", model.filename().string(),
                                        name.C_Str(), tex.error().message));
    decoded[name.C_Str()] = -1;
    return out;
  }
  out.texture = static_cast<int>(look.textures.size());
  decoded[name.C_Str()] = out.texture;
  look.textures.push_back(std::move(*tex));
  return out;
}

// Every triangle of every mesh, with its vertices' UVs and colours and its material.
Status gather_meshes(const fs::path& path, const aiScene& scene, TargetLook& look) {
  // glTF's COLOR_0 is linear; every other format's vertex colours (PLY, OBJ, Collada, FBX …) are display values, sRGB.
  std::string ext = path.extension().string();
  for (char& ch : ext) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  const bool linear = ext == ".gltf" || ext == ".glb";
  bool any_uv = false, any_colour = false;
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
    const aiMesh* mesh = scene.mMeshes[m];
    if (mesh != nullptr && mesh->mVertices != nullptr) any_uv |= mesh->HasTextureCoords(0), any_colour |= mesh->HasVertexColors(0);
  }
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
    const aiMesh* mesh = scene.mMeshes[m];
    if (mesh == nullptr || mesh->mVertices == nullptr || mesh->mFaces == nullptr) continue;
    const std::size_t base = look.mesh.vertices.size();
    if (base + mesh->mNumVertices > kMaxMeshVertices) return file_error(path, "has too many vertices for its look");
    const auto material = static_cast<std::uint16_t>(std::min<std::size_t>(mesh->mMaterialIndex, look.materials.size() - 1));
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices != 3) continue;
      std::array<Index, 3> t{};
      for (unsigned c = 0; c < 3; ++c) {
        if (face.mIndices[c] >= mesh->mNumVertices) return file_error(path, "a face uses a vertex out of range");
        t[c] = static_cast<Index>(base + face.mIndices[c]);
      }
      look.mesh.triangles.push_back(t);
      look.material.push_back(material);
    }
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
      look.mesh.vertices.emplace_back(mesh->mVertices[v].x, mesh->mVertices[v].y, mesh->mVertices[v].z);
      if (any_uv) {
        const bool has = mesh->HasTextureCoords(0);
        look.uv.emplace_back(has ? mesh->mTextureCoords[0][v].x : 0.0f, has ? mesh->mTextureCoords[0][v].y : 0.0f);
      }
      if (any_colour) {
        const bool has = mesh->HasVertexColors(0);
        const aiColor4D c = has ? mesh->mColors[0][v] : aiColor4D(1, 1, 1, 1);
        const auto lin = [&](float x) { return linear ? clamp01(x) : srgb_to_linear_float(clamp01(x)); };
        look.colours.emplace_back(lin(c.r), lin(c.g), lin(c.b));
      }
    }
  }
  if (look.mesh.triangles.empty()) return file_error(path, "contains no triangles");
  return {};
}

Result<TargetLook> import_look(const fs::path& path) {
  Assimp::Importer importer;
  importer.SetPropertyInteger(AI_CONFIG_PP_RVC_FLAGS, kRemovedComponents);
  importer.SetPropertyBool(AI_CONFIG_IMPORT_NO_SKELETON_MESHES, true);
  const aiScene* scene = importer.ReadFile(path.string(), kPostProcess | aiProcess_ValidateDataStructure);
  if (scene == nullptr) return file_error(path, one_line(importer.GetErrorString()));
  if (scene->mNumMeshes == 0 || scene->mMeshes == nullptr) return file_error(path, "contains no meshes");
  TargetLook look;
  std::map<std::string, int> decoded;
  for (unsigned m = 0; m < scene->mNumMaterials && m < 65535; ++m)  // a null material keeps its index (a default)
    look.materials.push_back(scene->mMaterials[m] != nullptr
                                 ? read_material(path, *scene, *scene->mMaterials[m], look, decoded) : LookMaterial{});
  if (look.materials.empty()) look.materials.emplace_back();
  FF_CHECK(gather_meshes(path, *scene, look));
  return look;
}

// ---- the answer between the child and us ----

struct PlainMaterial {
  float r, g, b;
  std::int32_t texture;
  std::uint8_t factor_with_texture;
};

std::string encode(const Result<TargetLook>& r) {
  AnswerWriter out;
  if (!r) {
    out.put(std::uint8_t{0});
    out.put(static_cast<std::uint8_t>(r.error().kind));
    out.put_string(r.error().message);
    return out.take();
  }
  const TargetLook& l = r.value();
  out.put(std::uint8_t{1});
  std::vector<std::array<float, 3>> xyz, rgb;
  for (const Vec3f& v : l.mesh.vertices) xyz.push_back({v.x(), v.y(), v.z()});
  for (const Vec3f& c : l.colours) rgb.push_back({c.x(), c.y(), c.z()});
  std::vector<std::array<float, 2>> uv;
  for (const Vec2f& t : l.uv) uv.push_back({t.x(), t.y()});
  std::vector<PlainMaterial> mats;
  for (const LookMaterial& m : l.materials) {
    PlainMaterial pm;
    std::memset(&pm, 0, sizeof pm);  // no uninitialised padding in the answer
    pm.r = m.colour.x(), pm.g = m.colour.y(), pm.b = m.colour.z(), pm.texture = m.texture;
    pm.factor_with_texture = std::uint8_t(m.factor_with_texture);
    mats.push_back(pm);
  }
  out.put_vector(xyz), out.put_vector(l.mesh.triangles), out.put_vector(uv), out.put_vector(rgb);
  out.put_vector(l.material), out.put_vector(mats);
  out.put(std::uint64_t{l.textures.size()});
  for (const Texture& t : l.textures) out.put(std::int32_t{t.width}), out.put(std::int32_t{t.height}), out.put_vector(t.rgb);
  out.put(std::uint64_t{l.warnings.size()});
  for (const std::string& w : l.warnings) out.put_string(w);
  return out.take();
}

// Every count and index checked: a child whose heap a bad file corrupted may still have answered.
bool decode_look(AnswerReader& in, TargetLook& l) {
  std::vector<std::array<float, 3>> xyz, rgb;
  std::vector<std::array<float, 2>> uv;
  std::vector<PlainMaterial> mats;
  if (!in.get_vector(xyz) || !in.get_vector(l.mesh.triangles) || !in.get_vector(uv) || !in.get_vector(rgb) ||
      !in.get_vector(l.material) || !in.get_vector(mats))
    return false;
  std::uint64_t n = 0;
  if (!in.get_count(n, 16)) return false;
  l.textures.resize(n);
  for (Texture& t : l.textures) {
    std::int32_t w = 0, h = 0;
    if (!in.get(w) || !in.get(h) || !in.get_vector(t.rgb) || w <= 0 || h <= 0 || w > kMaxTextureSide ||
        h > kMaxTextureSide || t.rgb.size() != std::size_t(w) * std::size_t(h) * 3)
      return false;
    t.width = w, t.height = h;
  }
  if (!in.get_count(n, 8)) return false;
  l.warnings.resize(n);
  for (std::string& w : l.warnings) {
    if (!in.get_string(w)) return false;
    w = one_line(w);
  }
  if (!in.at_end() || mats.empty() || l.material.size() != l.mesh.triangles.size()) return false;
  if ((!uv.empty() && uv.size() != xyz.size()) || (!rgb.empty() && rgb.size() != xyz.size())) return false;
  for (const auto& p : xyz) l.mesh.vertices.emplace_back(p[0], p[1], p[2]);
  for (const auto& c : rgb) l.colours.emplace_back(clamp01(c[0]), clamp01(c[1]), clamp01(c[2]));
  for (const auto& t : uv) l.uv.emplace_back(std::isfinite(t[0]) ? t[0] : 0.0f, std::isfinite(t[1]) ? t[1] : 0.0f);
  for (const auto& m : mats) {
    if (m.texture < -1 || m.texture >= std::int32_t(l.textures.size())) return false;
    l.materials.push_back({Vec3f(clamp01(m.r), clamp01(m.g), clamp01(m.b)), m.texture, m.factor_with_texture != 0});
  }
  for (const auto m : l.material)
    if (m >= l.materials.size()) return false;
  for (const auto& t : l.mesh.triangles)
    for (const Index i : t)
      if (i >= l.mesh.vertices.size()) return false;
  return true;
}

}  // namespace

Vec3f sample_texture(const Texture& t, Vec2f uv) {
  const float u = uv.x() - std::floor(uv.x()), v = uv.y() - std::floor(uv.y());
  const float x = u * float(t.width) - 0.5f, y = (1.0f - v) * float(t.height) - 0.5f;  // UV origin bottom-left
  const float fx = std::floor(x), fy = std::floor(y);
  const float ax = x - fx, ay = y - fy;
  const auto wrap = [](long i, int n) { return static_cast<std::size_t>(((i % n) + n) % n); };
  Vec3f out = Vec3f::Zero();
  for (int dy = 0; dy < 2; ++dy)
    for (int dx = 0; dx < 2; ++dx) {
      const std::size_t px = wrap(long(fx) + dx, t.width), py = wrap(long(fy) + dy, t.height);
      const std::uint8_t* c = &t.rgb[(py * std::size_t(t.width) + px) * 3];
      const float w = (dx ? ax : 1.0f - ax) * (dy ? ay : 1.0f - ay);
      out += w * Vec3f(srgb_to_linear(c[0]), srgb_to_linear(c[1]), srgb_to_linear(c[2]));
    }
  return out;
}


float srgb_to_linear(std::uint8_t c) {
  static const std::array<float, 256> table = [] {
    std::array<float, 256> t{};
    for (int i = 0; i < 256; ++i) {
      const double s = i / 255.0;
      t[i] = float(s <= 0.04045 ? s / 12.92 : std::pow((s + 0.055) / 1.055, 2.4));
    }
    return t;
  }();
  return table[c];
}

std::uint8_t linear_to_srgb(float c) {
  const double l = std::isfinite(c) ? std::clamp(double(c), 0.0, 1.0) : 0.0;
  const double s = l <= 0.0031308 ? 12.92 * l : 1.055 * std::pow(l, 1.0 / 2.4) - 0.055;
  return static_cast<std::uint8_t>(std::lround(std::clamp(s, 0.0, 1.0) * 255.0));
}

Vec3f TargetLook::colour_at(Index t, const Vec3f& bary) const {
  const LookMaterial& m = materials[material[t]];
  const auto& tri = mesh.triangles[t];
  Vec3f c = m.colour;
  if (m.texture >= 0 && !uv.empty()) {
    const Vec2f at = bary.x() * uv[tri[0]] + bary.y() * uv[tri[1]] + bary.z() * uv[tri[2]];
    c = sample_texture(textures[std::size_t(m.texture)], at);
    if (m.factor_with_texture) c = c.cwiseProduct(m.colour);
  } else if (!colours.empty()) {
    c = m.factor_with_texture ? m.colour : Vec3f::Ones();  // glTF: factor × COLOR_0; others: the colours alone
  }
  if (!colours.empty()) c = c.cwiseProduct(bary.x() * colours[tri[0]] + bary.y() * colours[tri[1]] + bary.z() * colours[tri[2]]);
  return c;
}

Result<TargetLook> load_target_look(const fs::path& path, const MeshTransform& transform, double import_timeout_s) {
  FF_CHECK(transform.validate());
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return file_error(path, "no such file");
  auto answer = run_isolated(
      [&] {
        try {
          return encode(import_look(path));
        } catch (const std::bad_alloc&) {
          return encode(file_error(path, "out of memory while reading its look"));
        } catch (const std::exception& e) {
          return encode(file_error(path, one_line(e.what())));
        } catch (...) {
          return encode(file_error(path, "unknown error while reading its look"));
        }
      },
      "Assimp's import of the look", IsolateOptions{import_timeout_s});
  if (!answer) return answer.error().kind == Error::Kind::Input ? file_error(path, answer.error().message) : answer.error();
  AnswerReader in(*answer);
  std::uint8_t ok = 0;
  if (!in.get(ok)) return file_error(path, "the import process sent a garbled answer");
  if (ok == 0) {
    std::string message;
    return in.get_input_error(message) ? input_error(std::move(message))
                                       : file_error(path, "the import process sent a garbled answer");
  }
  TargetLook look;
  if (ok != 1 || !decode_look(in, look)) return file_error(path, "the import process sent a garbled answer");
  transform_mesh(look.mesh, transform);
  for (std::size_t v = 0; v < look.mesh.vertices.size(); ++v)
    if (!look.mesh.vertices[v].allFinite()) return file_error(path, fmt::format("vertex {} of its look is not finite", v));
  return look;
}

}  // namespace ff::io
