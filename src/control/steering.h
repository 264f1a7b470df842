#pragma once
// Live steering (`fluidform serve`): a controller whose targets can be moved while it runs. The live viewer
// drags a target; the server calls set_target_pose between two frames and the samples move there from the next
// sub-step on (paper §5.2, Table 2 "AR editing motion"). Controllers that have targets implement it (adaptive and the
// baselines through BaselineCore); `none` does not, and steerable() then gives nullptr.
#include "pose/target_motion.h"
#include "sim/controller.h"

#include <cstddef>

namespace ff::control {

class Steerable {
 public:
  virtual ~Steerable() = default;
  /// Target `target` holds `pose` (about its own pivot; the pose's pivot is ignored) from the next sub-step on,
  /// replacing its keyframes. An index past the last target is ignored.
  virtual void set_target_pose(std::size_t target, const pose::Pose& pose) = 0;
};

/// The controller's steering interface, or nullptr when it has none.
inline Steerable* steerable(sim::Controller& c) { return dynamic_cast<Steerable*>(&c); }

}  // namespace ff::control
