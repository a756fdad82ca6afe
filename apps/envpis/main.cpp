// SPDX-License-Identifier: Apache-2.0
// envpis: the command-line front end (table, render, compare, ...).
#include <algorithm>
#include <cstdio>
#include <exception>

#include "build_commit.h"
#include "command.h"
#include "envpis/envpis.h"

int main(int argc, char** argv) {
  CLI::App app{"envpis: fast product importance sampling of environment maps"};
  // "envpis 0.2.0 (commit 1d3bd5d)": the library's version and the commit the command was built from.
  app.set_version_flag("--version",
                       std::string("envpis ") + envpis::version() + " (commit " + envpis::app::kBuildCommit + ")");
  app.require_subcommand(1);
  auto& commands = envpis::app::command_registry();
  std::sort(commands.begin(), commands.end(), [](const auto& a, const auto& b) { return a.name < b.name; });
  std::string current;
  for (auto& c : commands) {
    CLI::App* sub = app.add_subcommand(c.name, c.help);
    c.setup(*sub);
    sub->preparse_callback([&current, name = c.name](std::size_t) { current = name; });
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "envpis %s: error: %s\n", current.c_str(), e.what());
    return 1;
  }
  return 0;
}
