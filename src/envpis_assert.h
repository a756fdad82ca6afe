// SPDX-License-Identifier: Apache-2.0
// Internal: ENVPIS_ASSERT(condition) checks an invariant of the library's own code in debug builds
// (NDEBUG not defined) and compiles to nothing in release builds, so it may sit on hot paths.
// A failure names the file, line and condition, then aborts: it is a bug in envpis, never a user
// error (user errors throw envpis::Error).
#pragma once

#ifdef NDEBUG
#define ENVPIS_ASSERT(condition) ((void)0)
#else
#include <cstdio>
#include <cstdlib>
#define ENVPIS_ASSERT(condition)                                                                   \
  ((condition) ? (void)0                                                                           \
               : (std::fprintf(stderr, "envpis: internal check failed at %s:%d: %s\n", __FILE__, \
                               __LINE__, #condition),                                              \
                  std::abort()))
#endif
