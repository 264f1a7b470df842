#pragma once
// OUT/report.html (issue 46): one self-contained page per run that opens from disk with no network: the summary,
// plots over the run's frames (metrics.csv) and the formed mesh with its target(s) in a three.js view, with the meshed
// forming (animation.glb) on a timeline when it is small enough to carry. The page's script and styles are built from
// web/report/ and embedded in the binary (src/pipeline/CMakeLists.txt); only the run's data is written here.
#include "core/error.h"

#include <cstddef>
#include <filesystem>
#include <string>

namespace ff::pipeline {

/// The most triangles of each mesh the page carries (the final mesh and each target are decimated to it): ~1.4 MB of
/// base64 each, so that the default scene's page stays well under 5 MB.
inline constexpr std::size_t kPageTriangles = 60'000;
/// The largest animation.glb the page carries (base64 makes it a third larger); a larger one stays beside it, and the
/// page plays its lighter copy, kPageAnimationFile (fewer frames, decimated: pipeline/mesh_export.h), instead.
inline constexpr std::size_t kPageAnimationBytes = 2u << 20;
inline constexpr const char* kPageAnimationFile = "animation_page.glb";

struct ReportPage {
  std::size_t bytes = 0;         ///< size of the page written
  bool view = false;             ///< the final mesh is in it (not a --no-mesh run)
  bool animation = false;        ///< animation.glb is in it
  std::size_t targets = 0;       ///< target meshes in it
  /// One line for the log: what the page holds, its size, where it is.
  std::string describe(const std::filesystem::path& out_dir) const;
};

/// Which of the folder's meshes are the run's own: a run says what it made this time (a --no-mesh run into a used
/// folder leaves an earlier run's final.obj there, which its page must not show); `fluidform report` takes the folder
/// as it is.
struct PageSources {
  bool final_mesh = true;  ///< mesh/final.obj
  bool animation = true;   ///< animation.glb
};

/// Writes `out_dir`/report.html (atomically) from what a run left there: report.json (required: else an Input error
/// naming the folder), metrics.csv, mesh/final.obj, animation.glb, and the target meshes report.json's scene names
/// (a missing one is left out of the view, with a line on the page). `fluidform report OUT` and every run call it.
Result<ReportPage> write_report_page(const std::filesystem::path& out_dir, const PageSources& sources = {});

}  // namespace ff::pipeline
