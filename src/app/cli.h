#pragma once
// What the commands of the CLI share (one file per command: cmd_*.cpp). A command adds its sub-command and its
// options to the app and returns what runs it once the command line is parsed.
// Exit codes: 0 ok, 2 bad input or usage, 1 runtime failure. Errors are one line on stderr.
#include "core/error.h"

#include <CLI/CLI.hpp>

#include <filesystem>
#include <functional>
#include <string>

namespace ff::app {

struct Command {
  CLI::App* sub = nullptr;
  std::function<int()> run;  ///< the exit code
};

/// Prints "fluidform: error: MESSAGE" (one line) and returns the exit code for the error's kind.
int fail(const Error& e);
/// --controller NAME: checked against the controller table when parsed.
CLI::Option* add_controller_option(CLI::App* sub, std::string& name, const std::string& what);

Command add_run(CLI::App& app);
Command add_sample(CLI::App& app);
Command add_mesh(CLI::App& app);
Command add_compare(CLI::App& app);
Command add_serve(CLI::App& app);
Command add_keys(CLI::App& app);
Command add_devices(CLI::App& app);
Command add_report(CLI::App& app);
/// No sub-command: the bundled default scene into ./fluidform-out.
int run_default_scene();

}  // namespace ff::app
