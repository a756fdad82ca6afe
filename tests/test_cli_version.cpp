// SPDX-License-Identifier: Apache-2.0
// `envpis --version`: one line "envpis VERSION (commit HASH)" and exit 0, the version being the library's
// (the CMake project version, envpis/version.h) and the commit the one the command was built from.
#include <gtest/gtest.h>

#include <cstdio>
#include <regex>
#include <string>

#include "cli_util.h"
#include "envpis/version.h"

namespace {

using envpis::test::CmdResult;
using envpis::test::run_envpis;

// `git rev-parse HEAD` of the source tree, empty when that is not a git checkout or git is missing.
std::string source_head() {
  const std::string cmd = "git -C " + envpis::test::shell_quote(ENVPIS_SOURCE_DIR) + " rev-parse HEAD 2>/dev/null";
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return {};
  char buf[128] = {};
  const std::size_t n = fread(buf, 1, sizeof buf - 1, p);
  const int status = pclose(p);
  std::string head(buf, n);
  while (!head.empty() && (head.back() == '\n' || head.back() == '\r')) head.pop_back();
  return status == 0 ? head : std::string();
}

TEST(CliVersion, PrintsVersionAndCommit) {
  const CmdResult r = run_envpis("--version");
  EXPECT_EQ(r.code, 0) << r.output;
  std::smatch m;
  const std::regex line(R"(envpis ([0-9]+\.[0-9]+\.[0-9]+) \(commit ([0-9a-f]{4,40}(\+dirty)?|unknown)\)\n)");
  ASSERT_TRUE(std::regex_match(r.output, m, line)) << "got: " << r.output;
  EXPECT_EQ(m[1].str(), envpis::kVersion);
  EXPECT_EQ(m[1].str(), ENVPIS_VERSION_STRING);
  EXPECT_EQ(std::string(envpis::version()), envpis::kVersion);  // the library and its headers agree

  // Built from a git checkout, the hash is the checkout's HEAD: "unknown" there means the build lost it.
  const std::string head = source_head();
  if (head.empty()) GTEST_SKIP() << ENVPIS_SOURCE_DIR << " is not a git checkout (or git is missing)";
  const std::string commit = m[2].str().substr(0, m[2].str().find('+'));
  EXPECT_EQ(head.compare(0, commit.size(), commit), 0)
      << "envpis reports commit " << m[2] << ", the source tree is at " << head << " (rebuild after committing)";
}

TEST(CliVersion, HelpListsIt) {
  const CmdResult r = run_envpis("--help");
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("--version"), std::string::npos) << r.output;
}

}  // namespace
