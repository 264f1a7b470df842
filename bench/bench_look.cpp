// How much of a target's texture the liquid's vertex colours keep (issue 46 item 3: "vertex colours, or UVs into the
// target's own texture where that keeps more detail: say which, with a measurement"). A table, not a Google Benchmark.
//
//   bench_look RUN_DIR [--samples N]
//
// RUN_DIR is the folder of a run whose target 0 has "appearance": "target" (its report.json names the target and its
// transform; mesh/final.obj carries the vertex colours). The truth at any point p of the formed surface is the target's
// colour at the point of the target nearest to p (what the pipeline gives each vertex). Printed, in sRGB steps of 1/255:
//   at vertices      the written colour against the truth (the OBJ's 8-bit sRGB rounding only);
//   vertex colours   N points spread over the formed triangles (uniform in area): the colour interpolated from the
//                    triangle's corners against the truth at the point: what vertex colours lose between vertices;
//   UVs              the same points with UVs instead: each corner takes the UV of its nearest target point and the
//                    point the texture at the interpolated UV; counted apart are the triangles whose corners land in
//                    different UV charts of the target (across a seam: there interpolated UVs sweep the texture
//                    between the charts, the smear a UV mapping of a new surface cannot avoid);
//   UVs as written   when final.obj has UVs (fluidform chose them): the same points through the OBJ's own vt, seams
//                    handled as pipeline/liquid_look.h does (the UV map of one target triangle across a seam).
#include "io/target_look.h"
#include "sampling/mesh_field.h"
#include "scene/scene.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numeric>
#include <random>
#include <sstream>

namespace {
namespace fs = std::filesystem;
using namespace ff;

struct Formed {
  std::vector<Vec3f> positions;
  std::vector<Vec3f> srgb;  // 0–255
  std::vector<Eigen::Vector2f> uv;  // the OBJ's vt (one per vertex, as fluidform writes them), when it has them
  std::vector<std::array<Index, 3>> triangles;
};

Formed read_obj(const fs::path& file) {
  Formed m;
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line)) {
    float x, y, z, r, g, b;
    unsigned a, bb, c;
    if (std::sscanf(line.c_str(), "v %f %f %f %f %f %f", &x, &y, &z, &r, &g, &b) == 6) {
      m.positions.emplace_back(x, y, z), m.srgb.emplace_back(255 * r, 255 * g, 255 * b);
    } else if (std::sscanf(line.c_str(), "vt %f %f", &x, &y) == 2) {
      m.uv.emplace_back(x, y);
    } else if (std::sscanf(line.c_str(), "f %u/%*u/%*u %u/%*u/%*u %u/%*u/%*u", &a, &bb, &c) == 3 ||
               std::sscanf(line.c_str(), "f %u//%*u %u//%*u %u//%*u", &a, &bb, &c) == 3) {
      m.triangles.push_back({a - 1, bb - 1, c - 1});
    }
  }
  if (m.uv.size() != m.positions.size()) m.uv.clear();
  return m;
}

Vec3f to_srgb(const Vec3f& linear) {
  return Vec3f(io::linear_to_srgb(linear.x()), io::linear_to_srgb(linear.y()), io::linear_to_srgb(linear.z()));
}
Vec3f to_linear(const Vec3f& srgb) {
  const auto l = [](float s) { return io::srgb_to_linear(static_cast<std::uint8_t>(std::lround(std::clamp(s, 0.0f, 255.0f)))); };
  return Vec3f(l(srgb.x()), l(srgb.y()), l(srgb.z()));
}

struct Near {
  Index triangle;
  Vec3f bary;
};
Near nearest(const io::TargetLook& look, const sampling::MeshField& field, const Vec3f& p) {
  const auto c = field.closest(p);
  const auto& t = look.mesh.triangles[c.triangle];
  const Vec3f a = look.mesh.vertices[t[0]], b = look.mesh.vertices[t[1]], cc = look.mesh.vertices[t[2]];
  const Vec3f n = (b - a).cross(cc - a);
  const float area = std::max(n.squaredNorm(), 1e-30f);
  const float wa = n.dot((b - c.point).cross(cc - c.point)) / area, wb = n.dot((cc - c.point).cross(a - c.point)) / area;
  return {c.triangle, Vec3f(wa, wb, 1.0f - wa - wb)};
}

// UV charts: the look's triangles joined by shared vertices (its vertices are split along seams).
std::vector<Index> charts(const io::TargetLook& look) {
  std::vector<Index> parent(look.mesh.vertices.size());
  std::iota(parent.begin(), parent.end(), Index{0});
  const auto find = [&](Index v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  for (const auto& t : look.mesh.triangles) parent[find(t[1])] = find(t[0]), parent[find(t[2])] = find(t[0]);
  std::vector<Index> chart(look.mesh.triangles.size());
  for (std::size_t t = 0; t < chart.size(); ++t) chart[t] = find(look.mesh.triangles[t][0]);
  return chart;
}

struct Stat {
  double sum = 0;
  std::size_t n = 0, over = 0;
  void add(const Vec3f& a, const Vec3f& b) {
    const double d = (a - b).cwiseAbs().sum() / 3.0;
    sum += d, ++n, over += d > 16.0;
  }
  std::string row(const char* what) const {
    return fmt::format("| {:<34} | {:>8} | {:>10.2f} | {:>10.2f} % |", what, n, n ? sum / double(n) : 0.0,
                       n ? 100.0 * double(over) / double(n) : 0.0);
  }
};

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_look RUN_DIR [--samples N]\n");
    return 2;
  }
  const fs::path dir = argv[1];
  std::size_t samples = 200000;
  for (int i = 2; i + 1 < argc; ++i)
    if (std::string(argv[i]) == "--samples") samples = std::stoul(argv[i + 1]);
  std::ifstream rj(dir / "report.json");
  const auto report = nlohmann::json::parse(rj, nullptr, false);
  if (report.is_discarded() || !report.contains("scene")) return std::fprintf(stderr, "no report.json in %s\n", argv[1]), 1;
  auto scene = scene::parse_scene(report["scene"].dump(), "/", "report.json's scene");
  if (!scene || scene->targets.empty()) return std::fprintf(stderr, "report.json's scene has no target\n"), 1;
  auto look = io::load_target_look(scene->targets[0].mesh, scene->targets[0].transform);
  if (!look) return std::fprintf(stderr, "%s\n", look.error().message.c_str()), 1;
  auto field = sampling::MeshField::build(look->mesh);
  if (!field) return std::fprintf(stderr, "%s\n", field.error().message.c_str()), 1;
  const Formed m = read_obj(dir / "mesh" / "final.obj");
  if (m.srgb.empty()) return std::fprintf(stderr, "final.obj has no vertex colours\n"), 1;
  const std::vector<Index> chart = charts(*look);
  const bool uv = !look->uv.empty();

  Stat at_vertices, vertex_colours, uv_all, uv_one_chart, uv_written;
  std::vector<Near> corner(m.positions.size());
  for (std::size_t v = 0; v < m.positions.size(); ++v) {
    corner[v] = nearest(*look, *field, m.positions[v]);
    at_vertices.add(m.srgb[v], to_srgb(look->colour_at(corner[v].triangle, corner[v].bary)));
  }
  // Points uniform in area over the formed triangles.
  std::vector<double> cum(m.triangles.size());
  double total = 0;
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    const auto& f = m.triangles[t];
    total += 0.5 * double((m.positions[f[1]] - m.positions[f[0]]).cross(m.positions[f[2]] - m.positions[f[0]]).norm());
    cum[t] = total;
  }
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::size_t straddling = 0;
  for (std::size_t s = 0; s < samples; ++s) {
    const std::size_t t = std::min<std::size_t>(std::lower_bound(cum.begin(), cum.end(), u01(rng) * total) - cum.begin(), cum.size() - 1);
    double r1 = std::sqrt(u01(rng)), r2 = u01(rng);
    const Vec3f w(float(1 - r1), float(r1 * (1 - r2)), float(r1 * r2));
    const auto& f = m.triangles[t];
    const Vec3f p = w.x() * m.positions[f[0]] + w.y() * m.positions[f[1]] + w.z() * m.positions[f[2]];
    const Near q = nearest(*look, *field, p);
    const Vec3f truth = to_srgb(look->colour_at(q.triangle, q.bary));
    const Vec3f lin = w.x() * to_linear(m.srgb[f[0]]) + w.y() * to_linear(m.srgb[f[1]]) + w.z() * to_linear(m.srgb[f[2]]);
    vertex_colours.add(to_srgb(lin), truth);
    if (!uv) continue;
    // UVs: each corner's UV at its nearest target point, interpolated; the texture there (one material assumed).
    Eigen::Vector2f at = Eigen::Vector2f::Zero();
    bool one_chart = true;
    for (int c = 0; c < 3; ++c) {
      const Near& n = corner[f[c]];
      const auto& lt = look->mesh.triangles[n.triangle];
      at += w[c] * (n.bary.x() * look->uv[lt[0]] + n.bary.y() * look->uv[lt[1]] + n.bary.z() * look->uv[lt[2]]);
      one_chart &= chart[n.triangle] == chart[corner[f[0]].triangle];
    }
    // The texture at a UV, times the glTF factor, as TargetLook::colour_at reads it (one textured material assumed).
    const io::LookMaterial& mat = look->materials[look->material[q.triangle]];
    const auto texture_at = [&](const Eigen::Vector2f& at_uv) {
      if (mat.texture < 0) return to_srgb(mat.colour);
      const Vec3f c = io::sample_texture(look->textures[std::size_t(mat.texture)], at_uv);
      return to_srgb(mat.factor_with_texture ? Vec3f(c.cwiseProduct(mat.colour)) : c);
    };
    const Vec3f by_uv = texture_at(at);
    uv_all.add(by_uv, truth);
    if (!m.uv.empty()) uv_written.add(texture_at(w.x() * m.uv[f[0]] + w.y() * m.uv[f[1]] + w.z() * m.uv[f[2]]), truth);
    if (one_chart) uv_one_chart.add(by_uv, truth);
    straddling += !one_chart;
  }
  std::vector<Index> distinct = chart;
  std::sort(distinct.begin(), distinct.end());
  const auto n_charts = std::size_t(std::unique(distinct.begin(), distinct.end()) - distinct.begin());
  const std::string texture = look->textures.empty() ? "none" : fmt::format("{}x{}", look->textures[0].width, look->textures[0].height);
  std::printf("%s: %zu formed vertices, %zu triangles; target %s: %zu triangles, %zu UV charts, texture %s\n\n",
              dir.string().c_str(), m.positions.size(), m.triangles.size(), scene->targets[0].mesh.filename().string().c_str(),
              look->mesh.triangles.size(), n_charts, texture.c_str());
  std::printf("| %-34s | %8s | %10s | %12s |\n", "colour against the truth", "points", "mean /255", "over 16/255");
  std::printf("|%s|%s|%s|%s|\n", std::string(36, '-').c_str(), std::string(10, '-').c_str(), std::string(12, '-').c_str(),
              std::string(14, '-').c_str());
  std::printf("%s\n%s\n", at_vertices.row("at the vertices (as written)").c_str(), vertex_colours.row("vertex colours, inside triangles").c_str());
  if (uv) {
    std::printf("%s\n%s\n", uv_all.row("UVs, inside triangles").c_str(), uv_one_chart.row("UVs, triangles within one chart").c_str());
    if (!m.uv.empty()) std::printf("%s\n", uv_written.row("UVs as written (the OBJ's vt)").c_str());
    std::printf("\n%.2f %% of the sampled points lie in formed triangles across a UV seam of the target\n",
                100.0 * double(straddling) / double(std::max<std::size_t>(samples, 1)));
  }
  return 0;
}
