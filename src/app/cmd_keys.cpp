// `fluidform keys`: every scene-file key with its type, default, range and meaning, from the parameter structs' one
// field list each (core/fields.h). The table of keys in docs/scene-keys.md is this output (a test keeps the two equal).
#include "app/cli.h"
#include "scene/scene.h"

#include <fmt/format.h>

namespace ff::app {

Command add_keys(CLI::App& app) {
  auto* keys = app.add_subcommand("keys", "print every scene-file key: type, default, range, meaning (Markdown)");
  return {keys, [] {
            fmt::print(stdout, "{}", scene::scene_keys_markdown());
            return 0;
          }};
}

}  // namespace ff::app
