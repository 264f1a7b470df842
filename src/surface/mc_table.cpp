#include "surface/mc_table.h"

#include <cassert>

namespace ff::surface {
namespace {

using P3 = std::array<float, 3>;

P3 corner_pos(int c) { return {float(c & 1), float((c >> 1) & 1), float((c >> 2) & 1)}; }

P3 edge_mid(int e) {
  const CubeEdge ce = McTable::edge(e);
  P3 p = corner_pos(ce.c0);
  p[ce.axis] = 0.5f;
  return p;
}

// The edge joining two corners that differ in one bit.
int edge_between(int ca, int cb) {
  const int d = ca ^ cb;
  const int a = d == 1 ? 0 : d == 2 ? 1 : 2;
  const int c0 = ca & ~d;
  const int p = a == 0 ? 1 : 0, q = a == 2 ? 1 : 2;
  return 4 * a + ((c0 >> p) & 1) + 2 * ((c0 >> q) & 1);
}

// The two faces an edge lies on.
std::array<int, 2> edge_faces(int e) {
  const CubeEdge ce = McTable::edge(e);
  const int a = ce.axis;
  const int p = a == 0 ? 1 : 0, q = a == 2 ? 1 : 2;
  return {2 * p + ((ce.c0 >> p) & 1), 2 * q + ((ce.c0 >> q) & 1)};
}

bool share_face(int e1, int e2) {
  const auto f1 = edge_faces(e1), f2 = edge_faces(e2);
  return f1[0] == f2[0] || f1[0] == f2[1] || f1[1] == f2[0] || f1[1] == f2[1];
}

// Corners of face f in cyclic order around it: (u, v) = (0,0), (1,0), (1,1), (0,1), u < v its in-plane axes.
std::array<int, 4> face_cycle(int f) {
  const int a = f / 2, s = f & 1;
  const int u = a == 0 ? 1 : 0, v = a == 2 ? 1 : 2;
  const int c = s << a;
  return {c, c | (1 << u), c | (1 << u) | (1 << v), c | (1 << v)};
}

bool is_ambiguous(int m, int f) {
  const auto cyc = face_cycle(f);
  int crossings = 0;
  for (int k = 0; k < 4; ++k) crossings += ((m >> cyc[k]) & 1) != ((m >> cyc[(k + 1) % 4]) & 1);
  return crossings == 4;
}

// True when corner `c` lies left of p1 → p2 seen from outside face f (looking against its outward normal).
bool left_of(int f, const P3& p1, const P3& p2, int c) {
  const P3 cp = corner_pos(c);
  const float ax = p2[0] - p1[0], ay = p2[1] - p1[1], az = p2[2] - p1[2];
  const float bx = cp[0] - p1[0], by = cp[1] - p1[1], bz = cp[2] - p1[2];
  const P3 cr = {ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx};
  const float n = (f & 1) ? 1.0f : -1.0f;
  return cr[f / 2] * n > 0.0f;
}

// Builds the triangulation of inside mask m with the given face-centre choices (bit f: centre of face f inside).
CubeTriangulation build(int m, int face_centres) {
  std::array<int, 12> next;
  next.fill(-1);
  auto inside = [&](int c) { return ((m >> c) & 1) != 0; };
  // Directs segment e1–e2 so that the inside part of the face lies on its left, seen from outside the cube:
  // the loops then run the same way round every inside region, and their triangles share one orientation.
  auto add_segment = [&](int f, int e1, int e2, int ref_corner, bool ref_on_left) {
    const bool left = left_of(f, edge_mid(e1), edge_mid(e2), ref_corner);
    if (left == ref_on_left) {
      assert(next[e1] < 0);
      next[e1] = e2;
    } else {
      assert(next[e2] < 0);
      next[e2] = e1;
    }
  };
  for (int f = 0; f < 6; ++f) {
    const auto cyc = face_cycle(f);
    std::array<int, 4> cross_edge{};
    int crossings = 0;
    for (int k = 0; k < 4; ++k)
      if (inside(cyc[k]) != inside(cyc[(k + 1) % 4])) cross_edge[crossings++] = edge_between(cyc[k], cyc[(k + 1) % 4]);
    if (crossings == 2) {
      int ref = cyc[0];
      for (int k = 0; k < 4; ++k)
        if (inside(cyc[k])) ref = cyc[k];
      add_segment(f, cross_edge[0], cross_edge[1], ref, true);
    } else if (crossings == 4) {
      // Centre inside: the inside diagonal is joined and the segments cut off the outside corners, else the
      // inside ones.
      const bool centre_in = ((face_centres >> f) & 1) != 0;
      for (int k = 0; k < 4; ++k) {
        const int c = cyc[k];
        if (inside(c) == centre_in) continue;
        const int e1 = edge_between(cyc[(k + 3) % 4], c), e2 = edge_between(c, cyc[(k + 1) % 4]);
        add_segment(f, e1, e2, c, inside(c));
      }
    }
  }
  CubeTriangulation out;
  std::array<bool, 12> seen{};
  for (int start = 0; start < 12; ++start) {
    if (next[start] < 0 || seen[start]) continue;
    std::array<int, 12> loop{};
    int n = 0;
    for (int e = start; !seen[e]; e = next[e]) {
      seen[e] = true;
      loop[n++] = e;
      assert(next[e] >= 0);
    }
    // Fan vertex: none of its chords may join two vertices of one cube face (see the header).
    int fan = -1;
    for (int s = 0; s < n && fan < 0; ++s) {
      bool ok = true;
      for (int k = 0; k < n && ok; ++k) {
        if (k == s || k == (s + 1) % n || k == (s + n - 1) % n) continue;
        ok = !share_face(loop[s], loop[k]);
      }
      if (ok) fan = s;
    }
    // The loop runs counter-clockwise round the inside region seen from outside the cube, i.e. seen from the
    // inside of the fluid; the outward winding is the reverse.
    auto emit = [&](int a, int b, int c) {
      out.triangles[out.triangle_count++] = {std::uint8_t(a), std::uint8_t(c), std::uint8_t(b)};
    };
    if (fan >= 0) {
      for (int i = 1; i + 1 < n; ++i) emit(loop[fan], loop[(fan + i) % n], loop[(fan + i + 1) % n]);
    } else {
      const int centre = 12 + out.centre_count;
      std::uint16_t mask = 0;
      for (int i = 0; i < n; ++i) {
        mask = std::uint16_t(mask | (1u << loop[i]));
        emit(centre, loop[i], loop[(i + 1) % n]);
      }
      out.centre_edges[out.centre_count++] = mask;
    }
  }
  return out;
}

}  // namespace

McTable::McTable() {
  std::uint32_t base = 0;
  for (int m = 0; m < 256; ++m) {
    base_[m] = base;
    int n = 0;
    for (int f = 0; f < 6; ++f)
      if (is_ambiguous(m, f)) ambiguous_faces_[m][n++] = std::uint8_t(f);
    ambiguous_count_[m] = std::uint8_t(n);
    base += 1u << n;
  }
  cases_.resize(base);
  for (int m = 0; m < 256; ++m) {
    const int n = ambiguous_count_[m];
    for (int bits = 0; bits < (1 << n); ++bits) {
      int face_centres = 0;
      for (int j = 0; j < n; ++j)
        if ((bits >> j) & 1) face_centres |= 1 << ambiguous_faces_[m][j];
      cases_[base_[m] + bits] = build(m, face_centres);
    }
  }
}

const McTable& McTable::get() {
  static const McTable table;
  return table;
}

}  // namespace ff::surface
