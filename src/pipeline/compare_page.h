#pragma once
// OUT/compare.html from `fluidform compare` (issue 46 item 2): the paper's Table 3 layout with every column of
// table.md, sortable by any column, failures marked as the paper marks them, a picture of each controller's formed
// shape beside the target's (as the paper's Fig. 5; io/picture.h, one view and one scale for all), and a link to each
// controller's report.html. Self-contained: the pictures are inline and the sorting is a few lines of plain script.
#include "core/error.h"
#include "io/picture.h"
#include "pipeline/compare.h"

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>

namespace ff::pipeline {

/// The pictures' colours: a target in orange, the liquid in the water blue of the 3D views.
inline constexpr std::array<std::uint8_t, 3> kTargetColour{208, 99, 43}, kLiquidColour{47, 143, 216};

/// The one view of every picture of a compare: the targets' box, widened by a quarter so that what spills shows.
io::PictureView compare_view(const io::TriangleMesh& targets);

/// Draws `mesh` with `view` into `png` (atomically), in the target's colour or the liquid's.
Status write_still(const std::filesystem::path& png, const io::TriangleMesh& mesh, const io::PictureView& view, bool target);

/// Writes OUT/compare.html from `table` and the pictures beside it: OUT/target.png and OUT/NAME/formed.png (a row
/// without one shows "no mesh"). Called after every controller, like table.md.
Status write_compare_page(const std::filesystem::path& out_dir, const CompareTable& table);

/// base64 of `bytes` (the pages' inline pictures and arrays).
std::string base64(const std::uint8_t* bytes, std::size_t n);

}  // namespace ff::pipeline
