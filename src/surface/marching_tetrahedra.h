#pragma once
// Marching tetrahedra on the sparse field: the extraction half of Treece, Prager & Gee's regularised marching
// tetrahedra (RMT, METHOD.md §c.9). The regularisation half is cluster_reduce.h, run by reconstruct() over the
// node ids recorded here, exactly as for marching cubes (SurfaceParams::extraction, ::reduction).
//
// Subdivision. Each cube is split into the 6 tetrahedra of its Kuhn (Freudenthal) subdivision: the ones around the
// main diagonal from corner 0 to corner 7, one per order in which a path from 0 to 7 steps along x, y and z. The
// subdivision is the same in every cube, so the two cubes sharing a face cut it along the same diagonal (from the
// face's lowest corner to its highest), and two tetrahedra sharing a face see the same three corner values and
// draw the same segment on it. A tetrahedron has no ambiguous case (one corner against three: one triangle; two
// against two: a quad, split along its shorter diagonal, which lies inside the tetrahedron where no neighbour
// sees it), so the mesh is closed, 2-manifold and consistently wound by construction: no decider, no centre
// vertices.
//
// Welding. Every tetrahedron edge joins a node p to p + s, s ∈ {0, 1}³ \ {0}: 3 cube edges, 3 face diagonals and
// the main diagonal per node, 7 edges each node owns. Vertices are numbered as in marching_cubes.h: per block, a
// bitset of the crossed edges its own 8³ nodes start, with prefix counts per word; a cube whose edge starts on
// the block's +x/+y/+z apron finds the vertex in the neighbouring block (which is kept: the edge's two nodes,
// one on each side, are in its 9³ nodes too, with bit-identical values).
//
// Placement and cells. Vertices by linear interpolation along their edge, kept 1 % of the edge from either node
// (no two vertices coincide, so no zero-area triangle: three vertices on three edges of one tetrahedron are never
// collinear when none sits on a node). Each records its nearest node along its edge: Treece et al.'s cell, over
// which cluster_reduce() merges (about one vertex per node next to the surface).
#include "core/error.h"
#include "surface/marching_cubes.h"  // McMesh, kNoCluster: the two extractions hand the same thing on
#include "surface/sparse_field.h"

namespace ff::surface {

/// Welded, closed mesh wound counter-clockwise seen from outside (φ < iso), with each vertex's nearest node
/// (McMesh::cluster; never kNoCluster here, and centre_vertices = 0). Deterministic for any thread count.
/// Errors: Numerical when the blocks disagree about an edge (a bug; never expected), or more than 2^31 vertices.
Result<McMesh> marching_tetrahedra(const SparseField& field);

}  // namespace ff::surface
