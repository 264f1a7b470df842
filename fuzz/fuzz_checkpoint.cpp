// Checkpoints (sim/checkpoint.h), and what `run --resume` does with one (pipeline/run.cpp resume_from_checkpoint):
// decode, then read the per-frame metric rows back from its JSON "extra" block.
//
// Every input is tried twice: as it is (which the FNV-1a checksum at its end almost always refuses), and with its last
// 8 bytes replaced by the checksum of the rest, so that mutations reach the parser behind the checksum. A real
// checkpoint in the corpus is the same both ways.
#include "fuzz_target.h"
#include "metrics/report.h"
#include "sim/checkpoint.h"

#include <nlohmann/json.hpp>

#include <cstring>
#include <vector>

namespace {
void decode(std::span<const std::uint8_t> bytes) {
  using namespace ff;
  auto c = sim::decode_checkpoint(bytes);
  if (!c) {
    fuzz::check_refusal(c.error());
    return;
  }
  FF_FUZZ_CHECK(c->particles.consistent());
  // As resume_from_checkpoint: an unreadable extra block is no error (the rows start over), a readable one is read.
  const nlohmann::json extra = nlohmann::json::parse(c->extra, nullptr, false);
  if (!extra.is_discarded() && extra.contains("rows")) (void)metrics::rows_from_json(extra["rows"]);
  if (!extra.is_discarded() && extra.contains("target_rows")) (void)metrics::target_rows_from_json(extra["target_rows"]);
}
}  // namespace

FF_FUZZ_TARGET(checkpoint) {
  decode({data, size});
  if (size >= 8) {
    std::vector<std::uint8_t> fixed(data, data + size);
    const std::uint64_t sum = ff::sim::fnv1a(std::span<const std::uint8_t>(fixed).first(size - 8));
    std::memcpy(fixed.data() + size - 8, &sum, 8);
    decode(fixed);
  }
  return 0;
}
