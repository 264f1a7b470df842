#pragma once
// Procedural test meshes for the sampling stage (libigl test_common idea: families of shapes, each with a known
// inside): all closed ones are watertight, welded (shared vertices) and wound CCW seen from outside.
#include "core/error.h"
#include "io/triangle_mesh.h"

namespace ff::test {

/// Latitude-longitude sphere centred at the origin: `segments` around, segments / 2 bands, single-vertex poles.
io::TriangleMesh uv_sphere(float radius, int segments);
/// Box centred at the origin, each face split into n × n quads.
io::TriangleMesh box(const Vec3f& half_extents, int n = 1);
/// Torus around the y axis: tube centre radius `major`, tube radius `minor`, n segments around y, m around the tube.
io::TriangleMesh torus(float major, float minor, int n, int m);
/// A thin-walled vase: a curved outer profile revolved about y, hollowed from the top with a wall (and floor)
/// of `wall` m, closed at the lip. Height `height`, widest radius `radius`.
io::TriangleMesh vase(float height = 1.0f, float radius = 0.35f, float wall = 0.05f, int segments = 48,
                      int profile_points = 24);
/// Two uv spheres of radius `radius` centred at (±offset/2, 0, 0), intersecting when offset < 2·radius; two
/// components in one mesh, not stitched.
io::TriangleMesh two_overlapping_spheres(float radius = 0.5f, float offset = 0.5f, int segments = 32);
/// uv_sphere(radius, segments) without the k triangles nearest to (radius, 0, 0): a small hole.
io::TriangleMesh sphere_with_hole(int k, float radius = 1.0f, int segments = 32);
/// The upper half of uv_sphere (y ≥ 0), open at the equator.
io::TriangleMesh hemisphere(float radius, int segments);
/// A flat n × n grid of quads in the xz plane (y = 0) over [−size/2, size/2]², normals +y.
io::TriangleMesh plane_sheet(int n, float size = 1.0f);

/// A standing figure about 1 m tall: a box body, a sphere head, two thin legs and two thin arms held out
/// sideways (arms end at x = ±0.52 m, y = 0.7 m). Parts overlap; the winding number makes them one solid.
io::TriangleMesh star_figure();
/// A lattice of thin square tubes (0.07 m) through a 0.8 m cube: 3 × 3 vertical and 3 × 3 horizontal
/// (carbon-tube-like), base at y = 0. Tubes overlap at their crossings.
io::TriangleMesh tube_lattice();

/// The hard-target families (issue 44): parts a few particles thick, as CAD models have them.
/// An open-top box (a bin, a tray): outer half extents `half`, centred at the origin, a floor and four walls `wall`
/// thick, five overlapping slabs as CAD exports them (the winding number makes them one solid). Its thinnest walls
/// are `wall`. (A box with a closed cavity would not do: MeshField turns an inward-wound shell outward, as it does
/// for the flipped parts of real files, and fills the cavity.)
io::TriangleMesh open_box(const Vec3f& half, float wall);
/// A pipe along y from 0 to `height`: outer radius `radius`, walls `wall` thick, open at both ends (flat annular
/// rims), `segments` around.
io::TriangleMesh pipe(float radius, float wall, float height, int segments = 64);
/// A spur-gear-like disc centred at the origin, `thickness` along y: `teeth` trapezoid teeth from radius `root` to
/// `tip` (a quarter of the pitch wide at the root, an eighth at the tip), the profile fanned from the axis.
io::TriangleMesh gear(int teeth, float root, float tip, float thickness);
/// Several closed parts overlapping in one mesh, as CAD exports an assembly: a box (base at y = 0), a ball half sunk
/// into it, a torus lying through its top and a gear standing across it. About 0.9 m wide.
io::TriangleMesh overlapping_parts();

/// Every triangle wound the other way.
io::TriangleMesh flip(io::TriangleMesh mesh);
/// Both meshes in one (b's indices shifted; no welding).
io::TriangleMesh merge(const io::TriangleMesh& a, const io::TriangleMesh& b);
/// Every vertex moved by t.
io::TriangleMesh translate(io::TriangleMesh mesh, const Vec3f& t);

/// The Stanford bunny from the npm package `bunny` (positions/cells arrays): read from $FF_BUNNY_JSON when set,
/// else <source>/node_modules/bunny/index.js. An Input error says how to install it when it is missing.
Result<io::TriangleMesh> stanford_bunny();

}  // namespace ff::test
