// SPDX-License-Identifier: Apache-2.0
// Running the built `envpis` command from tests: exit status and combined output, several commands at
// once (short runs are dominated by the command's start-up and the map's tables), and
// the check that a bad command line fails with one line "envpis CMD: error: ...".
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

namespace envpis::test {

inline const std::string& envpis_binary() {
  static const std::string path = ENVPIS_BINARY_DIR "/apps/envpis/envpis";
  return path;
}

struct CmdResult {
  int code = -1;        ///< exit status; -1 when killed by a signal (a crash) or not run
  std::string output;   ///< stdout and stderr
};

/// Single-quotes `s` for /bin/sh.
inline std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

/// Runs `envpis ARGS` for every entry, `parallel` at a time, each under `timeout` (a hang is a failure,
/// reported as code 124), and returns the results in order.
inline std::vector<CmdResult> run_envpis_all(const std::vector<std::string>& args, std::size_t parallel = 4,
                                             int timeout_seconds = 120) {
  std::vector<CmdResult> results(args.size());
  for (std::size_t begin = 0; begin < args.size(); begin += parallel) {
    const std::size_t end = std::min(args.size(), begin + parallel);
    std::vector<FILE*> pipes;
    for (std::size_t i = begin; i < end; ++i)
      pipes.push_back(popen(("timeout " + std::to_string(timeout_seconds) + " " + shell_quote(envpis_binary()) + " " +
                             args[i] + " 2>&1")
                                .c_str(),
                            "r"));
    for (std::size_t i = begin; i < end; ++i) {
      FILE* p = pipes[i - begin];
      if (!p) continue;
      char buf[4096];
      std::size_t n;
      while ((n = fread(buf, 1, sizeof buf, p)) > 0) results[i].output.append(buf, n);
      const int status = pclose(p);
      results[i].code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    }
  }
  return results;
}

inline CmdResult run_envpis(const std::string& args) { return run_envpis_all({args})[0]; }

/// The line starting with `prefix` ("envpis render: error: "), with its newline; empty when absent.
inline std::string line_starting(const std::string& output, const std::string& prefix) {
  std::size_t at = output.find(prefix);
  if (at == std::string::npos) return {};
  const std::size_t nl = output.find('\n', at);
  return output.substr(at, nl == std::string::npos ? std::string::npos : nl - at + 1);
}

/// Exit 1 and exactly one output line: "envpis CMD: error: ..." containing `expect`.
inline void expect_one_line_error(const std::string& cmd, const std::string& args, const CmdResult& r,
                                  const std::string& expect) {
  EXPECT_EQ(r.code, 1) << args << "\n" << r.output;
  const std::string line = line_starting(r.output, "envpis " + cmd + ": error: ");
  EXPECT_NE(line.find(expect), std::string::npos) << args << "\nexpected: " << expect << "\ngot: " << r.output;
  EXPECT_EQ(r.output, line) << args << ": more than the one error line";
}

/// Runs every (command line, expected text) at once, `parallel` at a time; each must be a one-line
/// error of its command (the first word of its command line).
inline void expect_one_line_errors(const std::vector<std::pair<std::string, std::string>>& cases,
                                   std::size_t parallel = 4) {
  std::vector<std::string> args;
  for (const auto& c : cases) args.push_back(c.first);
  const std::vector<CmdResult> r = run_envpis_all(args, parallel);
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const std::string cmd = cases[i].first.substr(0, cases[i].first.find(' '));
    expect_one_line_error(cmd, args[i], r[i], cases[i].second);
  }
}

}  // namespace envpis::test
