// SPDX-License-Identifier: Apache-2.0
// Internal: the table build's parallel loops, over TBB when the library is built with it
// (ENVPIS_WITH_TBB, the default) and serial otherwise, so the core has no required threading library.
// fn(begin, end) processes the half-open range [begin, end); ranges never overlap.
#pragma once

#include <algorithm>
#include <cstddef>

#ifdef ENVPIS_WITH_TBB
#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#endif

namespace envpis::detail {

template <class Fn>
void parallel_for(int begin, int end, const Fn& fn) {
  if (begin >= end) return;
#ifdef ENVPIS_WITH_TBB
  tbb::parallel_for(tbb::blocked_range<int>(begin, end),
                    [&](const tbb::blocked_range<int>& r) { fn(r.begin(), r.end()); });
#else
  fn(begin, end);
#endif
}

/// How many threads parallel_for can use here (the arena's, capped by a tbb::global_control): loops
/// that split their work into as many disjoint parts as there are threads ask for it.
inline int parallel_threads() {
#ifdef ENVPIS_WITH_TBB
  const auto allowed = tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism);
  return std::max(1, static_cast<int>(std::min<std::size_t>(allowed, tbb::this_task_arena::max_concurrency())));
#else
  return 1;
#endif
}

/// Sets p[0, n) to `value` in parallel: a fresh array's pages are then first touched (faulted in and
/// zeroed by the kernel) by every thread instead of one.
template <class T>
void parallel_fill(T* p, std::size_t n, T value) {
  constexpr std::size_t kBlock = std::size_t(1) << 16;  // elements per task: 256 KB of floats
  const int blocks = static_cast<int>((n + kBlock - 1) / kBlock);
  parallel_for(0, blocks, [&](int begin, int end) {
    std::fill(p + std::size_t(begin) * kBlock, p + std::min(n, std::size_t(end) * kBlock), value);
  });
}

}  // namespace envpis::detail
