// SPDX-License-Identifier: Apache-2.0
// The envpis command's subcommands register themselves here: one file per subcommand
// (table.cpp, render.cpp, compare.cpp, ...), each with a static RegisterCommand object.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>
#include <string>
#include <vector>

namespace envpis::app {

struct Command {
  std::string name;
  std::string help;
  /// Adds the subcommand's options to `sub` and sets its callback. The callback may throw
  /// envpis::Error (or any std::exception): main prints "envpis <name>: error: <what>" and exits 1.
  std::function<void(CLI::App& sub)> setup;
};

inline std::vector<Command>& command_registry() {
  static std::vector<Command> commands;
  return commands;
}

struct RegisterCommand {
  explicit RegisterCommand(Command c) { command_registry().push_back(std::move(c)); }
};

}  // namespace envpis::app
