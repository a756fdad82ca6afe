// SPDX-License-Identifier: Apache-2.0
// The commit the envpis command was built from (build/apps/envpis/build_commit.cpp, regenerated at every
// build by cmake/envpisGitCommit.cmake): "1d3bd5d", "1d3bd5d+dirty" or "unknown". Kept out of the
// library's headers so a new commit recompiles one file, not the library.
#pragma once

namespace envpis::app {
extern const char* const kBuildCommit;
}
