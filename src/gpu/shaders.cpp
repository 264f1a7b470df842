#include "gpu/shaders.h"

namespace ff::gpu::shaders {

// Each NAME.inc is glslc's `-mfmt=num` output: the module's words as a comma-separated list.
std::span<const std::uint32_t> grid_count() {
  static constexpr std::uint32_t kWords[] = {
#include "grid_count.inc"
  };
  return kWords;
}
std::span<const std::uint32_t> grid_scan() {
  static constexpr std::uint32_t kWords[] = {
#include "grid_scan.inc"
  };
  return kWords;
}
std::span<const std::uint32_t> grid_scatter() {
  static constexpr std::uint32_t kWords[] = {
#include "grid_scatter.inc"
  };
  return kWords;
}
std::span<const std::uint32_t> grid_order() {
  static constexpr std::uint32_t kWords[] = {
#include "grid_order.inc"
  };
  return kWords;
}
std::span<const std::uint32_t> pbf_lambda() {
  static constexpr std::uint32_t kWords[] = {
#include "pbf_lambda.inc"
  };
  return kWords;
}
std::span<const std::uint32_t> pbf_delta() {
  static constexpr std::uint32_t kWords[] = {
#include "pbf_delta.inc"
  };
  return kWords;
}

std::span<const std::uint32_t> pbf_force() {
  static constexpr std::uint32_t kWords[] = {
#include "pbf_force.inc"
  };
  return kWords;
}
std::span<const std::uint32_t> pbf_update() {
  static constexpr std::uint32_t kWords[] = {
#include "pbf_update.inc"
  };
  return kWords;
}

std::span<const std::uint32_t> frame_check() {
  static constexpr std::uint32_t kWords[] = {
#include "frame_check.inc"
  };
  return kWords;
}
std::span<const std::uint32_t> pbf_predict() {
  static constexpr std::uint32_t kWords[] = {
#include "pbf_predict.inc"
  };
  return kWords;
}
std::span<const std::uint32_t> ctl_fill() {
  static constexpr std::uint32_t kWords[] = {
#include "ctl_fill.inc"
  };
  return kWords;
}
std::span<const std::uint32_t> ctl_bonds() {
  static constexpr std::uint32_t kWords[] = {
#include "ctl_bonds.inc"
  };
  return kWords;
}
std::span<const std::uint32_t> ctl_accel() {
  static constexpr std::uint32_t kWords[] = {
#include "ctl_accel.inc"
  };
  return kWords;
}
std::span<const std::uint32_t> ctl_spring() {
  static constexpr std::uint32_t kWords[] = {
#include "ctl_spring.inc"
  };
  return kWords;
}
std::span<const std::uint32_t> ctl_lambda() {
  static constexpr std::uint32_t kWords[] = {
#include "ctl_lambda.inc"
  };
  return kWords;
}
std::span<const std::uint32_t> ctl_correct() {
  static constexpr std::uint32_t kWords[] = {
#include "ctl_correct.inc"
  };
  return kWords;
}
std::span<const std::uint32_t> ctl_seed_init() {
  static constexpr std::uint32_t kWords[] = {
#include "ctl_seed_init.inc"
  };
  return kWords;
}
std::span<const std::uint32_t> ctl_seed_flood() {
  static constexpr std::uint32_t kWords[] = {
#include "ctl_seed_flood.inc"
  };
  return kWords;
}
std::span<const std::uint32_t> ctl_gather() {
  static constexpr std::uint32_t kWords[] = {
#include "ctl_gather.inc"
  };
  return kWords;
}
std::span<const std::uint32_t> vort_omega() {
  static constexpr std::uint32_t kWords[] = {
#include "vort_omega.inc"
  };
  return kWords;
}
std::span<const std::uint32_t> vort_apply() {
  static constexpr std::uint32_t kWords[] = {
#include "vort_apply.inc"
  };
  return kWords;
}
std::span<const std::uint32_t> pbf_copy() {
  static constexpr std::uint32_t kWords[] = {
#include "pbf_copy.inc"
  };
  return kWords;
}
std::span<const std::uint32_t> density_error() {
  static constexpr std::uint32_t kWords[] = {
#include "density_error.inc"
  };
  return kWords;
}
std::span<const std::uint32_t> density_decide() {
  static constexpr std::uint32_t kWords[] = {
#include "density_decide.inc"
  };
  return kWords;
}
std::span<const std::uint32_t> st_estimate() {
  static constexpr std::uint32_t kWords[] = {
#include "st_estimate.inc"
  };
  return kWords;
}
std::span<const std::uint32_t> st_smooth() {
  static constexpr std::uint32_t kWords[] = {
#include "st_smooth.inc"
  };
  return kWords;
}

}  // namespace ff::gpu::shaders
