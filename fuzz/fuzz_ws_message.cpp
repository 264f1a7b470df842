// The live viewer's client messages (server/messages.h): any bytes as one WebSocket text message, as the server's
// on_text handler (server/serve.cpp) gives them to parse_command. An accepted command holds only values the
// simulation may be handed.
#include "fuzz_target.h"
#include "server/messages.h"

#include <cmath>

FF_FUZZ_TARGET(ws_message) {
  using namespace ff;
  using Kind = server::Command::Kind;
  auto c = server::parse_command(fuzz::as_text(data, size));
  if (!c) {
    fuzz::check_refusal(c.error());
    return 0;
  }
  FF_FUZZ_CHECK(size <= server::kMaxClientMessage);
  if (c->kind == Kind::Pose) {
    FF_FUZZ_CHECK(c->pose.translate.allFinite() && c->pose.rotate_deg.allFinite());
    FF_FUZZ_CHECK(c->pose.translate.cwiseAbs().maxCoeff() <= 1e6f && c->pose.rotate_deg.cwiseAbs().maxCoeff() <= 1e6f);
    FF_FUZZ_CHECK(c->pose.scale > 0.0f && c->pose.scale < 1e3f);
  }
  if (c->kind == Kind::Controller) FF_FUZZ_CHECK(c->name.size() <= 64);
  FF_FUZZ_CHECK(c->target <= 1'000'000 && c->mesh <= 1'000'000 && c->frame <= 1'000'000);
  return 0;
}
