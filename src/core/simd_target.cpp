#include "core/simd_target.h"

#include <hwy/highway.h>
#include <hwy/targets.h>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>

namespace ff::core {
namespace {

struct Named {
  std::string_view name;
  std::int64_t target;
};
constexpr Named kTargets[] = {{"avx512", HWY_AVX3}, {"avx2", HWY_AVX2}, {"sse4", HWY_SSE4}};

std::int64_t available() { return hwy::SupportedTargets() & HWY_TARGETS; }

}  // namespace

std::string simd_target() {
  const std::int64_t t = available();
  return hwy::TargetName(t & -t);  // the lowest bit is the best target (Highway's order)
}

std::vector<std::string> simd_targets() {
  std::vector<std::string> out;
  for (std::int64_t t : hwy::SupportedAndGeneratedTargets()) out.emplace_back(hwy::TargetName(t));
  return out;
}

Status select_simd_target(std::string_view name) {
  std::string lower(name);
  std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
  if (lower.empty() || lower == "auto") {
    hwy::SetSupportedTargetsForTest(0);
    hwy::GetChosenTarget().Update(hwy::SupportedTargets());
    return {};
  }
  for (const Named& n : kTargets) {
    if (n.name != lower) continue;
    hwy::SetSupportedTargetsForTest(0);  // what the CPU has, unpinned
    if (!(available() & n.target))
      return param_error(fmt::format("FF_SIMD={}: this CPU or build has no {} (it has: {})", name, n.name,
                                     fmt::join(simd_targets(), ", ")));
    hwy::SetSupportedTargetsForTest(n.target);
    hwy::GetChosenTarget().Update(hwy::SupportedTargets());
    return {};
  }
  return param_error(fmt::format("FF_SIMD={}: unknown instruction set (sse4, avx2, avx512 or auto)", name));
}

Status select_simd_target_from_env() {
  const char* v = std::getenv("FF_SIMD");
  if (!v) return {};
  return select_simd_target(v);
}

}  // namespace ff::core
