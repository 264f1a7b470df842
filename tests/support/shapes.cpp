#include "support/shapes.h"

#include "support/test_support.h"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

namespace ff::test {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

struct ProfilePoint {
  float r, y;  // distance from the y axis, height
};

// Revolves a profile in the (r, y) half-plane about the y axis. Points with r = 0 become single pole
// vertices; a `loop` profile also joins its last point to its first. Traversed counter-clockwise in (r, y)
// (solid on the left), the triangles come out wound CCW seen from outside.
io::TriangleMesh revolve(const std::vector<ProfilePoint>& profile, int segments, bool loop) {
  io::TriangleMesh m;
  std::vector<Index> first(profile.size());
  for (std::size_t i = 0; i < profile.size(); ++i) {
    first[i] = static_cast<Index>(m.vertices.size());
    const auto [r, y] = profile[i];
    if (r == 0.0f) {
      m.vertices.emplace_back(0.0f, y, 0.0f);
      continue;
    }
    for (int j = 0; j < segments; ++j) {
      const float theta = 2.0f * kPi * float(j) / float(segments);
      m.vertices.emplace_back(r * std::cos(theta), y, r * std::sin(theta));
    }
  }
  auto id = [&](std::size_t i, int j) { return profile[i].r == 0.0f ? first[i] : first[i] + Index(j % segments); };
  auto emit = [&](Index a, Index b, Index c) {
    if (a != b && b != c && a != c) m.triangles.push_back({a, b, c});
  };
  const std::size_t edges = loop ? profile.size() : profile.size() - 1;
  for (std::size_t i = 0; i < edges; ++i) {
    const std::size_t n = (i + 1) % profile.size();
    for (int j = 0; j < segments; ++j) {
      const Index a = id(i, j), b = id(i, j + 1), c = id(n, j + 1), d = id(n, j);
      emit(a, d, c);
      emit(a, c, b);
    }
  }
  return m;
}

// Merges vertices at identical positions (faces generated separately share their edges' exact floats).
io::TriangleMesh weld(const io::TriangleMesh& in) {
  io::TriangleMesh out;
  std::map<std::array<float, 3>, Index> ids;
  std::vector<Index> remap(in.vertices.size());
  for (std::size_t v = 0; v < in.vertices.size(); ++v) {
    const std::array<float, 3> key{in.vertices[v].x(), in.vertices[v].y(), in.vertices[v].z()};
    auto [it, added] = ids.emplace(key, static_cast<Index>(out.vertices.size()));
    if (added) out.vertices.push_back(in.vertices[v]);
    remap[v] = it->second;
  }
  for (const auto& t : in.triangles) out.triangles.push_back({remap[t[0]], remap[t[1]], remap[t[2]]});
  return out;
}

// The bracketed array that follows `key` in `text`, as a flat list of numbers.
Result<std::vector<double>> numbers_after(const std::string& text, std::string_view key, const std::string& where) {
  const std::size_t at = text.find(key);
  const std::size_t open = at == std::string::npos ? at : text.find('[', at);
  if (open == std::string::npos) return input_error(fmt::format("{}: no '{}' array", where, key));
  std::vector<double> out;
  int depth = 0;
  for (std::size_t i = open; i < text.size();) {
    const char ch = text[i];
    if (ch == '[') ++depth;
    if (ch == ']' && --depth == 0) return out;
    if (ch == '-' || (ch >= '0' && ch <= '9')) {
      double v = 0.0;
      const auto [end, ec] = std::from_chars(text.data() + i, text.data() + text.size(), v);
      if (ec != std::errc()) return input_error(fmt::format("{}: bad number in '{}'", where, key));
      out.push_back(v);
      i = static_cast<std::size_t>(end - text.data());
      continue;
    }
    ++i;
  }
  return input_error(fmt::format("{}: unterminated '{}' array", where, key));
}

}  // namespace

io::TriangleMesh uv_sphere(float radius, int segments) {
  const int bands = std::max(2, segments / 2);
  std::vector<ProfilePoint> p;
  for (int i = 0; i <= bands; ++i) {
    const float phi = kPi * float(i) / float(bands);
    p.push_back({(i == 0 || i == bands) ? 0.0f : radius * std::sin(phi), -radius * std::cos(phi)});
  }
  return revolve(p, segments, false);
}

io::TriangleMesh hemisphere(float radius, int segments) {
  const int bands = std::max(2, segments / 4);
  std::vector<ProfilePoint> p;
  for (int i = 0; i <= bands; ++i) {
    const float phi = 0.5f * kPi * float(i) / float(bands);  // from the equator up to the pole
    p.push_back({i == bands ? 0.0f : radius * std::cos(phi), radius * std::sin(phi)});
  }
  return revolve(p, segments, false);
}

io::TriangleMesh torus(float major, float minor, int n, int m) {
  std::vector<ProfilePoint> p;
  for (int i = 0; i < m; ++i) {
    const float phi = 2.0f * kPi * float(i) / float(m);
    p.push_back({major + minor * std::cos(phi), minor * std::sin(phi)});
  }
  return revolve(p, n, true);
}

io::TriangleMesh vase(float height, float radius, float wall, int segments, int profile_points) {
  // Belly low, narrow neck, flaring lip; the inner wall is the outer one moved in by `wall`.
  auto outer = [&](float t) { return radius * (0.6f + 0.4f * std::sin(kPi * (0.1f + 1.1f * t))); };
  const int k = std::max(4, profile_points);
  std::vector<ProfilePoint> p{{0.0f, 0.0f}};
  for (int i = 0; i < k; ++i) {
    const float t = float(i) / float(k - 1);
    p.push_back({outer(t), t * height});
  }
  const float floor_t = wall / height;
  for (int i = 0; i < k; ++i) {
    const float t = 1.0f - (1.0f - floor_t) * float(i) / float(k - 1);
    p.push_back({outer(t) - wall, t * height});
  }
  p.push_back({0.0f, wall});
  return revolve(p, segments, false);
}

io::TriangleMesh box(const Vec3f& half_extents, int n) {
  io::TriangleMesh m;
  for (int a = 0; a < 3; ++a)
    for (const float s : {-1.0f, 1.0f}) {
      const int u = (a + 1) % 3, v = (a + 2) % 3;  // e_u × e_v = e_a
      const auto base = static_cast<Index>(m.vertices.size());
      for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
          Vec3f x;
          x[a] = s * half_extents[a];
          x[u] = -half_extents[u] + 2.0f * half_extents[u] * float(i) / float(n);
          x[v] = -half_extents[v] + 2.0f * half_extents[v] * float(j) / float(n);
          m.vertices.push_back(x);
        }
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          const Index p00 = base + Index(j * (n + 1) + i), p10 = p00 + 1, p01 = p00 + Index(n + 1), p11 = p01 + 1;
          if (s > 0) {
            m.triangles.push_back({p00, p10, p11});
            m.triangles.push_back({p00, p11, p01});
          } else {
            m.triangles.push_back({p00, p11, p10});
            m.triangles.push_back({p00, p01, p11});
          }
        }
    }
  return weld(m);
}

io::TriangleMesh two_overlapping_spheres(float radius, float offset, int segments) {
  const io::TriangleMesh s = uv_sphere(radius, segments);
  return merge(translate(s, Vec3f(-0.5f * offset, 0, 0)), translate(s, Vec3f(0.5f * offset, 0, 0)));
}

io::TriangleMesh sphere_with_hole(int k, float radius, int segments) {
  io::TriangleMesh m = uv_sphere(radius, segments);
  const Vec3f at(radius, 0, 0);
  auto dist = [&](const std::array<Index, 3>& t) {
    return ((m.vertices[t[0]] + m.vertices[t[1]] + m.vertices[t[2]]) / 3.0f - at).squaredNorm();
  };
  std::stable_sort(m.triangles.begin(), m.triangles.end(),
                   [&](const auto& x, const auto& y) { return dist(x) < dist(y); });
  m.triangles.erase(m.triangles.begin(), m.triangles.begin() + std::min<std::ptrdiff_t>(k, std::ssize(m.triangles)));
  return m;
}

io::TriangleMesh plane_sheet(int n, float size) {
  io::TriangleMesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      m.vertices.emplace_back(size * (float(i) / float(n) - 0.5f), 0.0f, size * (float(j) / float(n) - 0.5f));
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const Index a = Index(j * (n + 1) + i), b = a + 1, c = a + Index(n + 1), d = c + 1;  // a: (i, j); c: (i, j+1)
      m.triangles.push_back({a, c, b});                                                    // (0,0,1) × (1,0,0) = +y
      m.triangles.push_back({b, c, d});
    }
  return m;
}

io::TriangleMesh star_figure() {
  io::TriangleMesh m = translate(box(Vec3f(0.12f, 0.25f, 0.08f)), Vec3f(0, 0.55f, 0));
  m = merge(m, translate(uv_sphere(0.1f, 24), Vec3f(0, 0.9f, 0)));
  m = merge(m, translate(box(Vec3f(0.04f, 0.2f, 0.04f)), Vec3f(-0.07f, 0.2f, 0)));
  m = merge(m, translate(box(Vec3f(0.04f, 0.2f, 0.04f)), Vec3f(0.07f, 0.2f, 0)));
  m = merge(m, translate(box(Vec3f(0.22f, 0.035f, 0.035f)), Vec3f(-0.3f, 0.7f, 0)));
  m = merge(m, translate(box(Vec3f(0.22f, 0.035f, 0.035f)), Vec3f(0.3f, 0.7f, 0)));
  return m;
}

io::TriangleMesh tube_lattice() {
  io::TriangleMesh m;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      const float u = -0.3f + 0.3f * float(a), v = -0.3f + 0.3f * float(b);
      m = merge(m, translate(box(Vec3f(0.035f, 0.4f, 0.035f)), Vec3f(u, 0.4f, v)));
      m = merge(m, translate(box(Vec3f(0.4f, 0.035f, 0.035f)), Vec3f(0, 0.1f + 0.3f * float(a), v)));
    }
  return m;
}

io::TriangleMesh open_box(const Vec3f& half, float wall) {
  const float w = 0.5f * wall;
  io::TriangleMesh m = translate(box(Vec3f(half.x(), w, half.z()), 8), Vec3f(0.0f, -half.y() + w, 0.0f));  // floor
  for (const float sx : {-1.0f, 1.0f}) {
    m = merge(m, translate(box(Vec3f(w, half.y(), half.z()), 8), Vec3f(sx * (half.x() - w), 0.0f, 0.0f)));
    m = merge(m, translate(box(Vec3f(half.x(), half.y(), w), 8), Vec3f(0.0f, 0.0f, sx * (half.z() - w))));
  }
  return m;
}

io::TriangleMesh pipe(float radius, float wall, float height, int segments) {
  // Four rings: outer bottom/top, inner bottom/top. Along the angle a (x = cos a, z = sin a) the tangent t, with the
  // radial r and up u: u × t = r, t × r = u, which fixes each face's winding.
  io::TriangleMesh m;
  const float inner = radius - wall;
  for (const float rho : {radius, inner})
    for (const float y : {0.0f, height})
      for (int s = 0; s < segments; ++s) {
        const double a = 2.0 * std::numbers::pi * s / segments;
        m.vertices.push_back(Vec3f(rho * float(std::cos(a)), y, rho * float(std::sin(a))));
      }
  const auto at = [&](int ring, int s) { return static_cast<Index>(ring * segments + (s % segments)); };
  constexpr int ob = 0, ot = 1, ib = 2, it = 3;
  for (int s = 0; s < segments; ++s) {
    m.triangles.push_back({at(ob, s), at(ot, s), at(ot, s + 1)});  // outer wall, facing r
    m.triangles.push_back({at(ob, s), at(ot, s + 1), at(ob, s + 1)});
    m.triangles.push_back({at(ib, s), at(it, s + 1), at(it, s)});  // inner wall, facing −r
    m.triangles.push_back({at(ib, s), at(ib, s + 1), at(it, s + 1)});
    m.triangles.push_back({at(it, s), at(it, s + 1), at(ot, s)});  // top rim, facing u
    m.triangles.push_back({at(it, s + 1), at(ot, s + 1), at(ot, s)});
    m.triangles.push_back({at(ib, s), at(ob, s), at(ib, s + 1)});  // bottom rim, facing −u
    m.triangles.push_back({at(ib, s + 1), at(ob, s), at(ob, s + 1)});
  }
  return m;
}

io::TriangleMesh gear(int teeth, float root, float tip, float thickness) {
  // The profile: per tooth a root gap, the tooth's flank up, its tip, the flank down (8 points a tooth), in order of
  // angle; a tooth spans a quarter of the pitch at its root and an eighth at its tip.
  std::vector<std::pair<double, float>> profile;
  const double pitch = 2.0 * std::numbers::pi / teeth;
  for (int k = 0; k < teeth; ++k) {
    const double a0 = pitch * k;
    for (const auto& [f, r] : {std::pair{0.0, root}, std::pair{0.125, root}, std::pair{0.25, root}, std::pair{0.3125, tip},
                               std::pair{0.4375, tip}, std::pair{0.5, root}, std::pair{0.75, root}, std::pair{0.875, root}})
      profile.emplace_back(a0 + f * pitch, r);
  }
  io::TriangleMesh m;
  const auto n = static_cast<Index>(profile.size());
  for (const float y : {-0.5f * thickness, 0.5f * thickness})
    for (const auto& [a, r] : profile) m.vertices.push_back(Vec3f(r * float(std::cos(a)), y, r * float(std::sin(a))));
  const Index cb = 2 * n, ct = 2 * n + 1;
  m.vertices.push_back(Vec3f(0.0f, -0.5f * thickness, 0.0f));
  m.vertices.push_back(Vec3f(0.0f, 0.5f * thickness, 0.0f));
  for (Index i = 0; i < n; ++i) {
    const Index j = (i + 1) % n;
    m.triangles.push_back({ct, n + j, n + i});  // top, facing u (t × r = u)
    m.triangles.push_back({cb, i, j});          // bottom, facing −u
    m.triangles.push_back({i, n + i, n + j});   // side: u × (edge along increasing angle) faces out
    m.triangles.push_back({i, n + j, j});
  }
  return m;
}

io::TriangleMesh overlapping_parts() {
  io::TriangleMesh m = translate(box(Vec3f(0.4f, 0.15f, 0.3f), 4), Vec3f(0.0f, 0.15f, 0.0f));
  m = merge(m, translate(uv_sphere(0.2f, 32), Vec3f(0.22f, 0.3f, 0.0f)));
  m = merge(m, translate(torus(0.2f, 0.06f, 48, 16), Vec3f(-0.2f, 0.3f, 0.0f)));
  // The gear stands upright (its axis along z) across the box's back edge.
  io::TriangleMesh g = gear(12, 0.16f, 0.21f, 0.06f);
  for (auto& v : g.vertices) v = Vec3f(v.x(), v.z(), -v.y()) + Vec3f(0.0f, 0.3f, -0.3f);
  return merge(m, g);
}

io::TriangleMesh flip(io::TriangleMesh mesh) {
  for (auto& t : mesh.triangles) std::swap(t[1], t[2]);
  return mesh;
}

io::TriangleMesh merge(const io::TriangleMesh& a, const io::TriangleMesh& b) {
  io::TriangleMesh m = a;
  const auto shift = static_cast<Index>(a.vertices.size());
  m.vertices.insert(m.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (const auto& t : b.triangles) m.triangles.push_back({t[0] + shift, t[1] + shift, t[2] + shift});
  return m;
}

io::TriangleMesh translate(io::TriangleMesh mesh, const Vec3f& t) {
  for (auto& v : mesh.vertices) v += t;
  return mesh;
}

Result<io::TriangleMesh> stanford_bunny() {
  const char* env = std::getenv("FF_BUNNY_JSON");
  const std::filesystem::path path = env ? std::filesystem::path(env) : source_dir() / "node_modules/bunny/index.js";
  std::ifstream f(path);
  if (!f)
    return input_error(
        fmt::format("{} is missing: run `npm install --no-save --no-package-lock bunny` in the "
                    "repository root, or set FF_BUNNY_JSON to a {{positions, cells}} JSON file",
                    path.string()));
  std::stringstream ss;
  ss << f.rdbuf();
  const std::string text = ss.str();
  FF_TRY(const std::vector<double> pos, numbers_after(text, "positions", path.string()));
  FF_TRY(const std::vector<double> cells, numbers_after(text, "cells", path.string()));
  if (pos.empty() || pos.size() % 3 || cells.empty() || cells.size() % 3)
    return input_error(fmt::format("{}: positions/cells are not lists of triples", path.string()));
  io::TriangleMesh m;
  for (std::size_t i = 0; i < pos.size(); i += 3)
    m.vertices.emplace_back(static_cast<float>(pos[i]), static_cast<float>(pos[i + 1]), static_cast<float>(pos[i + 2]));
  for (std::size_t i = 0; i < cells.size(); i += 3)
    m.triangles.push_back(
        {static_cast<Index>(cells[i]), static_cast<Index>(cells[i + 1]), static_cast<Index>(cells[i + 2])});
  return m;
}

}  // namespace ff::test
