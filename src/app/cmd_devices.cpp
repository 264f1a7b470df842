// `fluidform devices`: the Vulkan devices of this machine (index, name, type, driver, API, memory), the choice the
// GPU backend (issue 45) makes from. No Vulkan loader or driver is a one-line error, exit code 1.
#include "app/cli.h"
#include "pipeline/front_doors.h"

#include <fmt/format.h>

namespace ff::app {

Command add_devices(CLI::App& app) {
  auto* sub = app.add_subcommand("devices", "list the Vulkan devices (GPUs, and lavapipe on the CPU)");
  return {sub, [] {
            auto found = pipeline::gpu_devices();
            if (!found) return fail(found.error());
            if (found->empty()) return fail(io_error("Vulkan: no Vulkan device on this machine"));
            fmt::print("{:>5}  {:<40} {:<10} {:>9}  {:<8} {}\n", "index", "name", "type", "memory", "api", "driver");
            for (const pipeline::GpuDevice& d : *found)
              fmt::print("{:>5}  {:<40} {:<10} {:>6.1f} GB  {:<8} {}{}\n", d.index, d.name, d.type,
                         static_cast<double>(d.memory_bytes) / 1e9, d.api, d.driver, d.compute ? "" : " (no compute queue)");
            return 0;
          }};
}

}  // namespace ff::app
