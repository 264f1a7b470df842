// `fluidform report OUT`: OUT/report.html made again from a run's folder (every run writes it; this one is for a run
// made before the page existed, or after its meshes were made again with `fluidform mesh OUT -o OUT`).
#include "app/cli.h"
#include "pipeline/report_page.h"

#include <spdlog/spdlog.h>

#include <memory>

namespace ff::app {

Command add_report(CLI::App& app) {
  auto dir = std::make_shared<std::filesystem::path>();
  auto* report = app.add_subcommand("report", "write OUT/report.html again from a run's output folder");
  report->add_option("out", *dir, "a run's output folder (with report.json)")->required();
  return {report, [dir] {
            auto page = pipeline::write_report_page(*dir);
            if (!page) return fail(page.error());
            spdlog::info("{}", page->describe(*dir));
            return 0;
          }};
}

}  // namespace ff::app
