#include "pose/cage_guard.h"

#include "core/parallel.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <unordered_map>

namespace ff::pose {

namespace {

// The unit outward normal of posed triangle t (zero for one the pose collapses).
Vec3f face_normal(const MeshAnchors& a, const std::vector<Vec3f>& posed, Index t) {
  const auto& tri = a.mesh.triangles[t];
  const Vec3f n = (posed[tri[1]] - posed[tri[0]]).cross(posed[tri[2]] - posed[tri[0]]);
  const float len = n.norm();
  return len > 0.0f ? Vec3f((float(a.orientation[t]) / len) * n) : Vec3f::Zero();
}

// The angle-weighted pseudo-normal of `feature` of posed triangle t (closest_feature's numbering): the sign of
// (p − q)·n tells inside from outside for the closest point q of a closed mesh, on a face, an edge or a corner
// alike.
Vec3f pseudo_normal(const MeshAnchors& a, const std::vector<Vec3f>& posed, Index t, int feature) {
  const Vec3f n = face_normal(a, posed, t);
  if (feature == 0) return n;
  if (feature <= 3) {
    const Index other = a.across[t][static_cast<std::size_t>(feature - 1)];
    return other != kInvalidIndex ? n + face_normal(a, posed, other) : n;
  }
  const Index v = a.mesh.triangles[t][static_cast<std::size_t>(feature - 4)];
  Vec3f sum = Vec3f::Zero();
  for (std::uint32_t k = a.corner_begin[v]; k < a.corner_begin[v + 1]; ++k) {
    const Index s = a.corner_triangle[k];
    const auto& tri = a.mesh.triangles[s];
    const int at = tri[0] == v ? 0 : tri[1] == v ? 1 : 2;
    const Vec3f u = posed[tri[(at + 1) % 3]] - posed[v], w = posed[tri[(at + 2) % 3]] - posed[v];
    sum += std::atan2(u.cross(w).norm(), u.dot(w)) * face_normal(a, posed, s);
  }
  return sum;
}

}  // namespace

Vec3f closest_feature(const Vec3f& p, const Vec3f& a, const Vec3f& b, const Vec3f& c, int& feature) {
  const Vec3f ab = b - a, ac = c - a, ap = p - a;
  if (const float n2 = ab.cross(ac).squaredNorm(); !(n2 > 1e-12f * ab.squaredNorm() * ac.squaredNorm())) {
    // Degenerate (a needle, or corners that coincide): the closest point of its three edges as segments.
    const Vec3f* corner[3] = {&a, &b, &c};
    float best = std::numeric_limits<float>::infinity();
    Vec3f q = a;
    feature = 4;
    for (int e = 0; e < 3; ++e) {
      const Vec3f& s = *corner[e];
      const Vec3f d = *corner[(e + 1) % 3] - s;
      const float len2 = d.squaredNorm();
      const float t = len2 > 0.0f ? std::clamp((p - s).dot(d) / len2, 0.0f, 1.0f) : 0.0f;
      const Vec3f x = s + t * d;
      if (const float d2 = (p - x).squaredNorm(); d2 < best)
        best = d2, q = x, feature = t <= 0.0f ? 4 + e : t >= 1.0f ? 4 + (e + 1) % 3 : 1 + e;
    }
    return q;
  }
  const float d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0f && d2 <= 0.0f) return feature = 4, a;
  const Vec3f bp = p - b;
  const float d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0f && d4 <= d3) return feature = 5, b;
  const float vc = d1 * d4 - d3 * d2;
  // Each edge's denominator is 0 only where its two corners coincide (a triangle repeating a vertex): then its corner.
  if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) return feature = 1, d1 - d3 > 0.0f ? Vec3f(a + (d1 / (d1 - d3)) * ab) : a;
  const Vec3f cp = p - c;
  const float d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0f && d5 <= d6) return feature = 6, c;
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) return feature = 3, d2 - d6 > 0.0f ? Vec3f(a + (d2 / (d2 - d6)) * ac) : a;
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0.0f && d4 - d3 >= 0.0f && d5 - d6 >= 0.0f) {
    const float den = (d4 - d3) + (d5 - d6);
    return feature = 2, den > 0.0f ? Vec3f(b + ((d4 - d3) / den) * (c - b)) : b;
  }
  const float sum = va + vb + vc;
  if (!(sum > 0.0f)) return feature = 4, a;  // degenerate (a needle or a point) that no region above took: its corner
  return feature = 0, a + (vb / sum) * ab + (vc / sum) * ac;
}

float posed_winding_number(const MeshAnchors& a, const std::vector<Vec3f>& posed, const Vec3f& p) {
  // Van Oosterom & Strackee, per outward triangle:
  //   tan(Ω/2) = a·(b×c) / (|a||b||c| + (a·b)|c| + (a·c)|b| + (b·c)|a|).
  // In float: only which side of ½ it is on matters, and a fold's samples are not on the surface.
  float sum = 0.0f;
  for (std::size_t t = 0; t < a.mesh.triangles.size(); ++t) {
    const auto& tri = a.mesh.triangles[t];
    const Vec3f u = posed[tri[0]] - p, v = posed[tri[1]] - p, w = posed[tri[2]] - p;
    const float lu = u.norm(), lv = v.norm(), lw = w.norm();
    const float num = u.dot(v.cross(w)), den = lu * lv * lw + u.dot(v) * lw + u.dot(w) * lv + v.dot(w) * lu;
    if (a.orientation[t] != 0) sum += float(a.orientation[t]) * std::atan2(num, den);
  }
  return sum / (2.0f * 3.14159265f);
}

namespace {

// The guard's easing alone (see keep_inside).
Vec3f ease_in(const MeshAnchors& a, std::size_t i, const Vec3f& x, const std::vector<Vec3f>& posed) {
  const std::uint32_t begin = a.guard_begin[i], end = a.guard_begin[i + 1];
  if (begin == end) return x;
  float best = std::numeric_limits<float>::infinity();
  Vec3f q = x;
  Index near = kInvalidIndex;
  int feature = 0;
  for (std::uint32_t k = begin; k < end; ++k) {
    const Index t = a.guard_triangle[k];
    const auto& tri = a.mesh.triangles[t];
    int f = 0;
    const Vec3f p = closest_feature(x, posed[tri[0]], posed[tri[1]], posed[tri[2]], f);
    if (const float d2 = (x - p).squaredNorm(); d2 < best) best = d2, q = p, near = t, feature = f;
  }
  if (near == kInvalidIndex) return x;
  const Vec3f n = pseudo_normal(a, posed, near, feature);
  if (!(n.squaredNorm() > 0.0f)) return x;  // collapsed where it is closest: nothing tells in from out
  const Vec3f r = x - q;
  const float dist = std::sqrt(best);
  const float d = r.dot(n) > 0.0f ? -dist : dist;  // depth: positive inside
  const float m = a.guard_depth[i];
  if (d >= m) return x;
  const float phi = m * m / (2.0f * m - d);
  if (dist > 0.0f) return q + (phi / d) * r;  // |d| = dist > 0: along the line through q, on the inner side
  return q - (phi / n.norm()) * n;
}

}  // namespace

Vec3f keep_inside(const MeshAnchors& a, std::size_t i, const Vec3f& x, const std::vector<Vec3f>& posed, bool folds) {
  const Vec3f y = ease_in(a, i, x, posed);
  if (!folds || a.fold_partner.empty() || a.fold_partner[i] == kInvalidIndex) return y;
  // Only where the pose folds one of its triangles against a neighbour is the (costly, exact) winding number taken.
  bool fold = false;
  for (std::uint32_t k = a.guard_begin[i]; k < a.guard_begin[i + 1] && !fold; ++k) {
    const Index t = a.guard_triangle[k];
    const Vec3f n = face_normal(a, posed, t);
    for (const Index o : a.across[t])
      fold = fold || (o != kInvalidIndex && n.dot(face_normal(a, posed, o)) < kFoldCosine);
  }
  if (!fold || posed_winding_number(a, posed, y) > 0.5f) return y;
  // In a fold's pocket: towards its partner, deep in the same part and inside at every pose the clip was tried at,
  // by kFoldSteps halvings of the way between them, keeping the inner end (inside). A partner outside at this pose
  // (one the clip's tried poses did not show) leaves the sample where it was eased to.
  Vec3f out = y, in = a.place(a.fold_partner[i], posed);
  if (!(posed_winding_number(a, posed, in) > 0.5f)) return y;
  for (int k = 0; k < kFoldSteps; ++k) {
    const Vec3f mid = 0.5f * (out + in);
    (posed_winding_number(a, posed, mid) > 0.5f ? in : out) = mid;
  }
  return in;
}

namespace {

// The field keeps each triangle outward (flipping a file's inconsistent patches). One it dropped (zero area at bind)
// gets 0: no normal, and no share of the winding number, should a pose open it up.
void orient_triangles(MeshAnchors& a, const sampling::MeshField& bind) {
  a.orientation.assign(a.mesh.triangles.size(), 0);
  for (Index k = 0; k < bind.triangle_count(); ++k) {
    const Index t = bind.source_triangle(k);
    const auto& f = bind.triangles()[k];
    const auto& tri = a.mesh.triangles[t];
    const Vec3f& v0 = a.mesh.vertices[tri[0]];
    const Vec3f raw = (a.mesh.vertices[tri[1]] - v0).cross(a.mesh.vertices[tri[2]] - v0);
    a.orientation[t] = raw.dot((f.b - f.a).cross(f.c - f.a)) < 0.0f ? std::int8_t{-1} : std::int8_t{1};
  }
}

// Edge neighbours (an edge shared by exactly two triangles) and each vertex's triangles.
void build_adjacency(MeshAnchors& a) {
  const std::size_t nv = a.mesh.vertices.size(), nt = a.mesh.triangles.size();
  std::unordered_map<std::uint64_t, std::vector<std::pair<Index, int>>> edges;
  for (Index t = 0; t < nt; ++t)
    for (int e = 0; e < 3; ++e) {
      const Index u = a.mesh.triangles[t][e], v = a.mesh.triangles[t][(e + 1) % 3];
      edges[(std::uint64_t(std::min(u, v)) << 32) | std::max(u, v)].emplace_back(t, e);
    }
  a.across.assign(nt, {kInvalidIndex, kInvalidIndex, kInvalidIndex});
  for (const auto& [key, sides] : edges)
    if (sides.size() == 2) {
      a.across[sides[0].first][static_cast<std::size_t>(sides[0].second)] = sides[1].first;
      a.across[sides[1].first][static_cast<std::size_t>(sides[1].second)] = sides[0].first;
    }
  a.corner_begin.assign(nv + 1, 0);
  for (const auto& tri : a.mesh.triangles)
    for (const Index v : tri) ++a.corner_begin[v + 1];
  for (std::size_t v = 0; v < nv; ++v) a.corner_begin[v + 1] += a.corner_begin[v];
  a.corner_triangle.assign(a.corner_begin[nv], kInvalidIndex);
  {
    std::vector<std::uint32_t> fill(a.corner_begin.begin(), a.corner_begin.end() - 1);
    for (Index t = 0; t < nt; ++t)
      for (const Index v : a.mesh.triangles[t]) a.corner_triangle[fill[v]++] = t;
  }
}

// Each sample's closest triangle at every pose (the bind pose first) into near[i]; guard[i] = 1 where the sample
// comes within `band` of the surface (or out of the mesh) at one pose or more.
Status find_near_triangles(const MeshAnchors& a, const sampling::MeshField& bind,
                           std::span<const std::vector<Vec3f>> poses, float band, std::vector<std::vector<Index>>& near,
                           std::vector<std::uint8_t>& guard) {
  const auto ns = static_cast<std::int64_t>(near.size());
  for (std::size_t k = 0; k <= poses.size(); ++k) {  // the bind pose, then the poses
    const std::vector<Vec3f>& p = k == 0 ? a.mesh.vertices : poses[k - 1];
    FF_TRY(sampling::MeshField field, bind.moved(p));
    core::parallel_for(ns, [&](std::int64_t ii) {
      const auto i = static_cast<std::size_t>(ii);
      const Vec3f x = a.place(i, p);
      const auto c = field.closest(x);
      if (c.triangle == kInvalidIndex) return;
      if (near[i].empty() || near[i].back() != c.triangle) near[i].push_back(c.triangle);
      if (!guard[i] && (c.distance < band || !field.inside(x))) guard[i] = 1;
    });
  }
  return {};
}

// The guards: each guarded sample's depth at bind (within [kMinGuardDepth, kGuardBand] spacings) and its triangles,
// those near it at any pose and their edge neighbours.
void build_guards(MeshAnchors& a, const sampling::MeshField& bind, std::vector<std::vector<Index>>& near,
                  float spacing, float band, CageGuardStats& stats) {
  const std::size_t ns = near.size();
  std::vector<float> depth(ns, 0.0f);
  core::parallel_for(static_cast<std::int64_t>(ns), [&](std::int64_t ii) {
    const auto i = static_cast<std::size_t>(ii);
    if (!near[i].empty())
      depth[i] = std::clamp(-bind.signed_distance(a.place(i, a.mesh.vertices)), kMinGuardDepth * spacing, band);
  });
  a.guard_begin.assign(ns + 1, 0);
  a.guard_depth = std::move(depth);
  for (std::size_t i = 0; i < ns; ++i) {
    auto& ts = near[i];
    if (!ts.empty()) {
      const std::size_t own = ts.size();
      for (std::size_t k = 0; k < own; ++k)
        for (const Index o : a.across[ts[k]])
          if (o != kInvalidIndex) ts.push_back(o);
      std::sort(ts.begin(), ts.end());
      ts.erase(std::unique(ts.begin(), ts.end()), ts.end());
      ++stats.guarded, stats.triangles += ts.size();
    }
    a.guard_triangle.insert(a.guard_triangle.end(), ts.begin(), ts.end());
    a.guard_begin[i + 1] = static_cast<std::uint32_t>(a.guard_triangle.size());
  }
}

// Samples in a fold's pocket: where the pose folds the mesh over itself, the pocket between the folds is outside by
// the winding number though inside by its nearest triangle, and easing along that triangle cannot leave it. A
// sample that ends outside at one of the poses is given a partner: the nearest sample at least kFoldPartnerDepth
// spacings deep at bind that is inside at every pose; posed and outside, it is moved towards its partner.
Status find_fold_partners(MeshAnchors& a, const sampling::MeshField& bind, std::span<const std::vector<Vec3f>> poses,
                          const std::vector<std::uint8_t>& guard, float spacing, CageGuardStats& stats) {
  const std::size_t ns = guard.size();
  std::vector<Vec3f> at_bind(ns);  // guarded: placed as posing will place them
  std::vector<std::uint8_t> out(ns, 0), deep(ns, 0);
  core::parallel_for(static_cast<std::int64_t>(ns), [&](std::int64_t ii) {
    const auto i = static_cast<std::size_t>(ii);
    at_bind[i] = a.place(i, a.mesh.vertices);
    deep[i] = -bind.signed_distance(at_bind[i]) >= kFoldPartnerDepth * spacing;
  });
  for (const auto& p : poses) {
    FF_TRY(sampling::MeshField field, bind.moved(p));
    core::parallel_for(static_cast<std::int64_t>(ns), [&](std::int64_t ii) {
      const auto i = static_cast<std::size_t>(ii);
      if (!(guard[i] || deep[i])) return;
      if (field.inside(a.place(i, p))) return;
      if (guard[i]) out[i] = 1;
      deep[i] = 0;  // a partner is inside at every pose
    });
  }
  std::vector<Index> partner(ns, kInvalidIndex);
  core::parallel_for(static_cast<std::int64_t>(ns), [&](std::int64_t ii) {
    const auto i = static_cast<std::size_t>(ii);
    if (!out[i]) return;
    float best = std::numeric_limits<float>::infinity();
    for (std::size_t j = 0; j < ns; ++j)
      if (deep[j] && !out[j])
        if (const float d2 = (at_bind[j] - at_bind[i]).squaredNorm(); d2 < best)
          best = d2, partner[i] = static_cast<Index>(j);
  });
  stats.folded = static_cast<std::size_t>(
      std::count_if(partner.begin(), partner.end(), [](Index j) { return j != kInvalidIndex; }));
  if (stats.folded > 0) a.fold_partner = std::move(partner);
  return {};
}

}  // namespace

Result<CageGuardStats> guard_cage(MeshAnchors& a, const sampling::MeshField& bind,
                                  std::span<const std::vector<Vec3f>> poses, float spacing) {
  if (!a.caged()) return param_error("only a cage's samples can be guarded");
  const std::size_t nv = a.mesh.vertices.size(), ns = a.cage.size() / nv;
  for (const auto& p : poses)
    if (p.size() != nv) return param_error("a pose for a cage's guard does not match its vertices");
  if (!(spacing > 0.0f) || !std::isfinite(spacing)) return param_error("a cage's guard needs a positive spacing");
  // From here until the guard is built, place() is the cage alone.
  a.guard_begin.clear(), a.guard_triangle.clear(), a.guard_depth.clear(), a.fold_partner.clear();

  orient_triangles(a, bind);
  build_adjacency(a);

  // Each sample's closest triangle at every pose; a sample is guarded if it comes within the band of the surface (or
  // out of the mesh) at one pose or more. Its guard keeps the triangles closest to it at all of them, not only where
  // it came near: where two limbs come close, a sample deep in one can pass near the other's surface, and judged by
  // that surface alone at another pose it would seem far outside and be pulled over to it.
  const float band = kGuardBand * spacing;
  std::vector<std::vector<Index>> near(ns);
  std::vector<std::uint8_t> guard(ns, 0);
  FF_CHECK(find_near_triangles(a, bind, poses, band, near, guard));
  for (std::size_t i = 0; i < ns; ++i)
    if (!guard[i]) std::vector<Index>().swap(near[i]);
  CageGuardStats stats;
  build_guards(a, bind, near, spacing, band, stats);
  FF_CHECK(find_fold_partners(a, bind, poses, guard, spacing, stats));
  return stats;
}

}  // namespace ff::pose
