// SPDX-License-Identifier: Apache-2.0
// Internal: the table build's one parallel loop, over TBB when the library is built with it
// (ENVPIS_WITH_TBB, the default) and serial otherwise, so the core has no required threading library.
// fn(begin, end) processes the half-open range [begin, end); ranges never overlap.
#pragma once

#ifdef ENVPIS_WITH_TBB
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
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

}  // namespace envpis::detail
