#include "app/cli.h"

#include "pipeline/front_doors.h"

#include <fmt/format.h>

namespace ff::app {

int fail(const Error& e) {
  std::string msg = e.message;
  for (char& c : msg)
    if (c == '\n' || c == '\r') c = ' ';
  fmt::print(stderr, "fluidform: error: {}\n", msg);
  return e.is_input() ? 2 : 1;
}

CLI::Option* add_controller_option(CLI::App* sub, std::string& name, const std::string& what) {
  return sub->add_option("--controller", name, fmt::format("shape controller: {}{}", pipeline::controller_names(), what))
      ->check(CLI::Validator(
          [](std::string& v) {
            return pipeline::is_controller(v) ? std::string()
                                              : fmt::format("{} is not one of: {}", v, pipeline::controller_names());
          },
          "CONTROLLER"));
}

}  // namespace ff::app
