#pragma once
// The PBF constraint solve of one sub-step on a Vulkan device (issue 45; METHOD.md §c.2, sim/pbf_solver.cpp is the
// CPU reference): a uniform grid built by counting sort, then Jacobi iterations of λ and Δx, the state staying in
// device memory between passes. The constants are the CPU solver's (sim::PbfLambdaConsts, sim::PbfDeltaConsts),
// so both paths are fed from one place.
//
// The grid. Cells are cubes of edge `cell` ≥ h over a box; positions outside it fall into its border cells. The
// grid is built once per solve() on x* as it is then (the CPU cluster path builds its lists once per sub-step too),
// each particle keeps that cell, and the passes search the 27 cells around it, testing the distance at the current
// x*: a cell edge a little above h keeps pairs that come into range during the iterations.
//
// Determinism: counts and the prefix sum are integers, each cell's run is sorted by particle index after the
// scatter, and λ and Δx are gathers (each invocation writes only its own particle) summing neighbours in that
// fixed order. Two solves of the same input on one device give the same bits.
#include "core/error.h"
#include "core/types.h"
#include "gpu/context.h"
#include "gpu/kernel.h"
#include "sim/pbf_kernels.h"
#include "sim/pbf_solver.h"

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace ff::gpu {

/// A uniform grid of `dims` cells of edge `cell` from corner `lo`.
struct GridSpec {
  Vec3f lo = Vec3f::Zero();
  float cell = 0;
  std::array<int, 3> dims{1, 1, 1};

  /// The grid of cells of edge `cell` covering the box [lo, hi]; an Error if it has more than `max_cells`.
  static Result<GridSpec> covering(const Vec3f& lo, const Vec3f& hi, float cell, std::size_t max_cells = 1u << 26);
  /// The grid a sub-step uses for support h over [lo, hi]: cells of kSkin · h. It is built on x once a sub-step and
  /// the sweeps move x*, so a pair that comes within h during the sub-step must still lie in the 27 cells around.
  static constexpr float kSkin = 1.1f;
  static Result<GridSpec> for_support(const Vec3f& lo, const Vec3f& hi, float h) { return covering(lo, hi, kSkin * h); }
  std::size_t cells() const {
    return static_cast<std::size_t>(dims[0]) * static_cast<std::size_t>(dims[1]) * static_cast<std::size_t>(dims[2]);
  }
};

/// Device time of the passes of one solve() (timestamp queries), milliseconds; λ, Δx and the copy summed over the
/// iterations. All zero where the device has no timestamps.
struct PassTimes {
  double grid = 0, force = 0, lambda = 0, delta = 0, copy = 0, update = 0;
  double total() const { return grid + force + lambda + delta + copy + update; }
};

/// What one output frame on the device did (sim::FrameStats' counterpart).
struct DeviceFrame {
  int substeps = 0;
  float dt = 0;
  bool capped = false;     ///< CFL wanted more than max_substeps
  double max_speed = 0;    ///< m/s at the start of the frame, from which the sub-steps were planned
  double end_speed = 0;    ///< m/s at the end of the frame
  long sweeps = 0;         ///< density-constraint sweeps run over the frame's sub-steps
  double density_error_mean = 0, density_error_max = 0;  ///< of the last sweep: mean and largest max(ρ/ρ0 − 1, 0)
};

/// A shape controller's passes on the device, recorded into a sub-step at the solver's hook points (sim/controller.h).
class DeviceController {
 public:
  virtual ~DeviceController() = default;
  /// Before sub-steps `from`, `from` + 1, … of a frame of `substeps` sub-steps of `dt` from `time` are recorded: what
  /// they need from the host (the poses of moving targets), uploaded at once so that they are one submission. Returns
  /// the sub-step before which that submission must end (`substeps`, or where the controller's samples change: a
  /// morph's swap); the next call then starts there.
  virtual Result<int> prepare_frame(double time, float dt, int from, int substeps) = 0;
  /// After the grid on x (begin_step) of sub-step `substep` of the frame.
  virtual void record_begin(VkCommandBuffer cb, float dt, int substep) const = 0;
  /// After the forces, before the prediction: the accelerations buffer may be changed (add_accelerations).
  virtual void record_accelerations(VkCommandBuffer cb, float dt) const = 0;
  /// Before sweep `iteration` of the density constraint, on x* (correct_positions).
  virtual void record_correction(VkCommandBuffer cb, int iteration, float dt) const = 0;
};

class PbfDevice {
 public:
  struct Constants;  ///< the passes' push-constant block (defined in pbf_device.cpp)

  /// Buffers and kernels for `n` particles (n ≥ 1) on `grid`; `ctx` must outlive the PbfDevice.
  static Result<std::unique_ptr<PbfDevice>> create(Context& ctx, std::size_t n, const GridSpec& grid);

  std::size_t size() const { return n_; }
  /// x* to the device (n positions).
  Status set_predicted(std::span<const Vec3f> x);
  Status get_predicted(std::vector<Vec3f>& x) const;
  Status get_density(std::vector<float>& rho) const;
  Status get_lambda(std::vector<float>& lambda) const;
  /// The particles' state between sub-steps: positions x and velocities v (n each).
  Status set_state(std::span<const Vec3f> x, std::span<const Vec3f> v);
  /// The particles' ids (sim::ParticleSet::id): their random rotations in the surface tension (default 0, 1, …).
  Status set_ids(std::span<const Index> id);
  Status get_state(std::vector<Vec3f>& x, std::vector<Vec3f>& v) const;
  /// The sweeps of a sub-step: at least `iterations`, then more while the mean compression is above `target`, up
  /// to `max_iterations` (sim::PbfSolver::substep's rule); the controller corrects in the first `iterations` only.
  struct Sweeps {
    int iterations = 4, max_iterations = 4;
    float target = 0.0f;
  };
  /// One sub-step of the state (sim::PbfSolver::substep with the controller of set_controller(), surface tension and
  /// vorticity when fk asks for them): the grid on x, ρ(x), the forces and x*, the sweeps, v = (x* − x − shift)/Δt and
  /// x = x*. One submission; waits for it. The controller sees it as a frame of one sub-step at time 0 (a morph swaps
  /// its samples there only if its swap time is ≤ 0): this entry point is for tests and benchmarks of the passes.
  Status substep(const sim::PbfLambdaConsts& lk, const sim::PbfDeltaConsts& dk, const sim::PbfForceConsts& fk,
                 const Sweeps& sweeps, PassTimes* times = nullptr);
  /// One output frame of `frame_dt` seconds in equal sub-steps planned as the CPU plans them (sim::plan_substeps on
  /// the largest speed, reduced on the device), each a substep() with `solver`'s constants and a fixed
  /// params().iterations sweeps. A non-finite position or velocity, before or after the frame, is an Error naming
  /// the lowest such particle index.
  Result<DeviceFrame> advance(const sim::PbfSolver& solver, double time, double frame_dt);
  /// The largest |v| of the state, m/s, and the lowest index with a non-finite x or v (none: size()).
  struct Check {
    double max_speed = 0;
    std::size_t first_bad = 0;
  };
  Result<Check> check();
  /// The surface tension alone on the state's x (for tests): each particle's class (sim::SurfaceClass), Monte-Carlo
  /// normal and curvature, and the acceleration it adds (from zero).
  struct SurfaceResult {
    std::vector<std::uint8_t> cls;
    std::vector<Vec3f> normal, accel;
    std::vector<float> curv;
  };
  Result<SurfaceResult> surface_tension_only(const sim::PbfLambdaConsts& lk, const sim::PbfForceConsts& fk);
  /// The grid of the last solve: start (cells + 1 offsets into items) and items (particle indices by cell, then
  /// by index).
  Status get_grid(std::vector<std::uint32_t>& start, std::vector<std::uint32_t>& items) const;

  /// The grid on x*, then `iterations` Jacobi sweeps: λ (and density) at x*, next = clamp(x* + Δx), x* ← next.
  /// iterations = 0 builds the grid only. One submission; waits for it.
  /// With `times`, the passes are timed on the device (timestamp queries) into it.
  Status solve(const sim::PbfLambdaConsts& lk, const sim::PbfDeltaConsts& dk, int iterations, PassTimes* times = nullptr);
  /// One λ pass at x* on the grid of the last solve (density and λ only, x* unchanged).
  Status lambda_only(const sim::PbfLambdaConsts& lk);

  /// Points (vec4 each, `count` of them) sorted into this device's grid as the fluid is (or into `other`): each
  /// point's cell, the cells' runs (start: cells + 1) and the points by cell, then index. sort_into_grid() sorts them
  /// once (samples that do not move); record_point_grid() records the sort into a command buffer again (samples
  /// that move, each sub-step).
  struct PointGrid {
    DeviceBuffer cell, count, start, items;
    Kernel count_k, scan_k, scatter_k, order_k;
    std::size_t points = 0;
    GridSpec spec;
  };
  Result<PointGrid> sort_into_grid(const DeviceBuffer& points, std::size_t count, const GridSpec* other = nullptr) const;
  void record_point_grid(VkCommandBuffer cb, const PointGrid& g) const;
  /// The controller whose passes every later sub-step records (null: none); it must outlive its use here.
  void set_controller(DeviceController* controller) { controller_ = controller; }
  // What a DeviceController binds: the state, the accelerations, and the grid on x of the current sub-step.
  const DeviceBuffer& x_buffer() const { return x_; }
  const DeviceBuffer& predicted_buffer() const { return pos_; }
  const DeviceBuffer& velocity_buffer() const { return vel_; }
  const DeviceBuffer& acceleration_buffer() const { return accel_; }
  /// The part of x* − x that is not to become velocity (sim::ParticleSet::shift): 0 at each sub-step's start.
  const DeviceBuffer& shift_buffer() const { return shift_; }
  const DeviceBuffer& cell_buffer() const { return cell_; }
  const DeviceBuffer& start_buffer() const { return start_; }
  const DeviceBuffer& items_buffer() const { return items_; }
  const GridSpec& grid() const { return grid_; }
  Context& context() const { return *ctx_; }

  /// Device memory held, in bytes.
  std::size_t bytes() const;
  /// Whether the device's queue has timestamps (solve() then fills PassTimes).
  bool has_timestamps() const { return timestamps_ != VK_NULL_HANDLE; }
  ~PbfDevice();

 private:
  PbfDevice() = default;
  void record_grid(VkCommandBuffer cb, const void* constants) const;
  // One sub-step: c the sweeps' constants, cf the force pass's, cs the prediction's and update's.
  template <class Stamp>
  void record_substep(VkCommandBuffer cb, const Constants& c, const Constants& cf, const Constants& cs,
                      const sim::PbfForceConsts& fk, const Sweeps& sweeps, int substep, Stamp&& stamp) const;
  void record_surface_tension(VkCommandBuffer cb, const sim::PbfForceConsts& fk, const sim::PbfLambdaConsts& lk) const;
  sim::PbfLambdaConsts lk_;  // of the sub-step being recorded (h and m for the surface tension)
  // The sweeps of a sub-step, each followed by x* ← next and the density error; `stamp` after each pass (timestamps
  // when timed). With dt > 0 the controller's correction comes before each of the first sweeps.iterations.
  template <class Stamp>
  void record_sweeps(VkCommandBuffer cb, const void* constants, const Sweeps& sweeps, Stamp&& stamp, float dt) const;
  Status read_times(int iterations, bool with_force, PassTimes& times) const;
  void reset_sweeps(VkCommandBuffer cb, bool frame) const;
  Status prepare_substeps(const sim::PbfLambdaConsts& lk, const sim::PbfDeltaConsts& dk, const sim::PbfForceConsts& fk,
                          const Sweeps& sweeps, Constants& c, Constants& cf, Constants& cs);

  Context* ctx_ = nullptr;
  std::size_t n_ = 0;
  GridSpec grid_;
  DeviceBuffer pos_, next_, cell_, count_, start_, items_, density_, lambda_, x_, vel_, check_, accel_, shift_;
  DeviceBuffer partial_, state_;  // the density error's per-workgroup sums; the sweeps' state (density_decide.comp)
  // Surface tension: the particles' ids (their random rotations), the point set, each particle's class, n̂, κ.
  DeviceBuffer id_, points_, st_class_, st_normal_, st_curv_;
  int points_n_ = 0;         // points in points_ now
  std::vector<Index> ids_;   // the ids of set_ids(), for error messages (empty: the index is the id)
  std::size_t points_cap_ = 0;
  Kernel st_estimate_k_, st_smooth_k_;
  Status prepare_points(int n);
  Status make_surface_kernels();
  // Vorticity confinement (vort_omega.comp, vort_apply.comp), made on the first sub-step that asks for it: ω per
  // particle, and the passes. They run after the update, on x copied out to next_ before it.
  DeviceBuffer omega_;
  Kernel vort_omega_k_, vort_apply_k_;
  Status make_vorticity_kernels();
  void record_vorticity(VkCommandBuffer cb, const Constants& c, const sim::PbfForceConsts& fk) const;
  Kernel count_k_, scan_k_, scatter_k_, order_k_, lambda_k_, delta_k_, force_k_, predict_k_, update_k_, check_k_;
  Kernel copy_k_, error_k_, decide_k_;
  DeviceController* controller_ = nullptr;
  VkQueryPool timestamps_ = VK_NULL_HANDLE;  // 4 + 3·kMaxTimedIterations queries
  static constexpr VkDeviceSize kStateBytes = 24;  // done, sweeps, mean, max bits, total, last max
  static constexpr int kMaxTimedIterations = 64;
};

}  // namespace ff::gpu
