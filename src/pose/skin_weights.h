#pragma once
// Skin weights of control samples at the bind pose (issue 19 item 2): every sample of a skinned target gets the
// four largest joint weights, renormalised, that move it with the skin.
//
// Two ways, measured against each other (tests/pose/skin_weights_test.cpp, bench/RESULTS.md "Animated
// characters"):
//  - ClosestPoint: the weights interpolated (barycentric) at the closest surface point. Exact on the surface; inside,
//    a sample takes the weights of whichever surface is nearest, so across a limb's medial axis (near a joint that
//    blends two bones on one side only) neighbouring samples can take different joints and tear apart.
//  - Diffusion: the closest-point weights held on the samples within one spacing of the surface, and the interior
//    samples' weights the harmonic extension of those over the samples' neighbour graph (Jacobi iterations of
//    the neighbour mean): they vary smoothly through the volume, so the interior bends with the limb.
#include "core/error.h"
#include "core/types.h"
#include "io/skin.h"
#include "io/triangle_mesh.h"
#include "sampling/mesh_field.h"

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace ff::pose {

enum class SkinWeighting { ClosestPoint, Diffusion };

struct SampleSkin {
  std::vector<std::array<std::uint16_t, io::kMaxInfluences>> joints;
  std::vector<std::array<float, io::kMaxInfluences>> weights;
};

/// The weights of `samples` (world, bind pose) from the skin of `mesh` (world, bind pose; `field` built from it,
/// triangle indices as in `mesh`). `spacing` is the samples' d_c. Errors: Param for sizes that disagree.
Result<SampleSkin> sample_skin_weights(const io::TriangleMesh& mesh, const sampling::MeshField& field, const io::Skin& skin,
                                       std::span<const Vec3f> samples, float spacing, SkinWeighting how);

/// The four largest of `dense` (one weight per joint), renormalised (ties: lower joint first); all zero when
/// `dense` is.
void top_influences(std::span<const float> dense, std::array<std::uint16_t, io::kMaxInfluences>& joints,
                    std::array<float, io::kMaxInfluences>& weights);

}  // namespace ff::pose
