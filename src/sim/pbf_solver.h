#pragma once
// Position Based Fluids solver (Macklin & Müller 2013) with the seed paper's external forces
// (METHOD.md §c.2, §a.4 eq. 12, §a.6 step order).
//
// Symbols (METHOD.md §0):
//   r  particle radius, d = 2r spacing, h = H_p support (default 4r = 2d)
//   m  particle mass = ρ_phys d³;  ρ0 = m · Σ_j W(x_i − x_j) over a resting cubic lattice (calibrated, so a
//      resting lattice starts exactly at rest; ≈ 1.010 ρ_phys for h = 2d)
//   S_0 = Σ_k |∇_k C_i|² of that lattice neighbourhood; ε = epsilon · S_0 (scale-free relaxation)
//
// One sub-step Δt:
//   1. neighbour search on x (particles are re-sorted by grid cell for locality; ids keep identity)
//   2. ρ(x) (and the surface classification); a_ext = g + XSPH(η/Δt) + surface tension (Zorilla) + drag (Gissler)
//      [+ controller.add_accelerations]
//   3. v* = v + Δt a_ext; x* = x + Δt v*; walls
//   4. N_it × { controller.correct_positions; λ_i; Δx_i with s_corr; x* += Δx; walls }, N_it ≥ iterations,
//      continuing up to max_iterations while the mean compression exceeds max_density_error
//   5. v = (x* − x)/Δt; optional vorticity confinement; x = x*
// The neighbour lists of step 1 serve the whole sub-step (as in SPlisHSPlasH); the CFL limit keeps the
// distance travelled per sub-step below 0.4 d, so pairs entering the support during the sub-step are rare.
//
// Every loop is a gather over CSR neighbour lists with a static schedule and every reduction is a
// fixed-order sum, so a run is bit-identical for any thread count.
#include "core/clusters.h"
#include "core/error.h"
#include "core/kernels.h"
#include "core/neighbor_grid.h"
#include "sim/controller.h"
#include "sim/drag.h"
#include "sim/particle_set.h"
#include "sim/pbf_kernels.h"
#include "sim/solver_params.h"
#include "sim/surface_tension.h"

namespace ff::sim {

/// Seconds spent per phase, accumulated over the sub-steps of a frame.
struct StageTimes {
  double neighbors = 0, forces = 0, solve = 0, control = 0, update = 0;
  long iterations = 0;  ///< density-constraint sweeps done
  double total() const { return neighbors + forces + solve + control + update; }
};

/// What one output frame's sub-steps did.
struct FrameStats {
  int substeps = 0;
  double dt = 0.0;                   ///< s, sub-step used
  double density_error_mean = 0.0;   ///< mean of max(ρ/ρ0 − 1, 0) at the end of the frame
  double density_error_max = 0.0;
  double max_speed = 0.0;            ///< m/s at the end of the frame
  bool substeps_capped = false;      ///< CFL wanted more than max_substeps
  StageTimes times;
};

/// The sub-steps of one output frame (CFL on the fastest particle, allowing for gravity's speed-up over the frame,
/// and at most the capillary sub-step), as PbfSolver::advance and the GPU path (gpu/pbf_device.h) both take them.
struct SubstepPlan {
  int steps = 1;
  float dt = 0;
  bool capped = false;  ///< CFL wanted more than max_substeps
};
SubstepPlan plan_substeps(const SolverParams& params, double max_speed, double frame_dt);

class PbfSolver {
 public:
  PbfSolver(const SolverParams& params, const Domain& domain);

  /// Advances the particles by one output frame of `frame_dt` seconds starting at `time`, in
  /// CFL-limited equal sub-steps. Errors: a non-finite position or velocity (names the particle id).
  Result<FrameStats> advance(ParticleSet& particles, double time, double frame_dt, Controller& controller);

  /// One sub-step of Δt seconds (exposed for benchmarks and tests).
  void substep(ParticleSet& particles, double time, float dt, Controller& controller, StageTimes& times);

  /// Densities at the current positions, kg/m³, into particles.density (neighbour search included).
  void compute_densities(ParticleSet& particles);

  /// Calibrated rest density ρ0 (kg/m³) and particle mass (kg).
  float rest_density() const { return rho0_; }
  float particle_mass() const { return mass_; }
  float s0() const { return s0_; }
  const SolverParams& params() const { return params_; }
  const Domain& domain() const { return domain_; }
  /// Bytes of solver scratch (neighbour lists, grid, buffers): for the memory budget.
  std::size_t scratch_bytes() const;
  const core::NeighborList& neighbors() const { return neighbors_; }
  /// The Jacobi passes on cluster pairs (Highway kernels, sim/pbf_kernels.h) instead of the neighbour lists. Off by
  /// default: at H_p = 2d a cluster pair's lanes are ~13 % useful and the passes run slower on the machines we
  /// measured (bench_pair_kernels, bench/RESULTS.md); kept for that benchmark and its test.
  void set_cluster_kernels(bool on) { cluster_kernels_ = on; }
  /// The constants of the λ and Δx passes: the cluster kernels' and the GPU passes' (gpu/pbf_device.h) one source.
  PbfLambdaConsts lambda_consts() const;
  PbfDeltaConsts delta_consts() const;
  PbfForceConsts force_consts(float dt) const;

 private:
  void search(ParticleSet& p);
  /// ρ at x; with `candidates`, also the surface-tension classification (one flag per particle).
  void densities(std::span<const Vec3f> x, std::vector<float>& rho, std::uint8_t* candidates = nullptr) const;
  void external_accelerations(ParticleSet& p, float dt, double time);
  void xsph_accelerations(ParticleSet& p, float dt, const DragModel* drag) const;
  void solve_iteration(ParticleSet& p);
  void solve_iteration_lists(ParticleSet& p);
  // solve_iteration_lists, pass 1: density at x* and λ_i of every particle (four neighbours at a time).
  void lambda_pass_lists(ParticleSet& p) const;
  // solve_iteration_lists, pass 2: the Jacobi position corrections (with s_corr) into x*.
  void position_pass_lists(ParticleSet& p);
  void clamp_to_walls(std::vector<Vec3f>& x) const;
  void vorticity_confinement(ParticleSet& p, float dt);

  SolverParams params_;
  Domain domain_;
  core::Poly6 poly6_;
  core::Spiky spiky_;
  float mass_ = 0, rho0_ = 0, s0_ = 0, epsilon_ = 0, w_dq_ = 1;
  Vec3f wall_lo_, wall_hi_;
  core::NeighborGrid grid_;
  core::NeighborList neighbors_;
  ReorderScratch reorder_scratch_;
  // Cluster pairs of the fluid within H_p (core/clusters.h), built per sub-step; λ in the clusters' layout.
  bool cluster_kernels_ = false;
  core::ClusterSet clusters_;
  core::ClusterPairs pairs_;
  core::ClusterPairScratch pair_scratch_;
  core::Buffer<float> lambda_c_;
  static constexpr std::int64_t kClusterBlock = 16;  // clusters per scheduled block (~128 particles)
  std::vector<Vec3f> next_;        // x* after the current iteration (Jacobi double buffer)
  std::vector<Vec3f> omega_;       // vorticity (only when enabled)
  SurfaceTension surface_tension_; // per-particle normals and curvatures (only when σ > 0)
  std::vector<std::uint8_t> surface_candidates_;  // classifier output of the density pass (only when σ > 0)
};

}  // namespace ff::sim
