// SPDX-License-Identifier: Apache-2.0
// Internal: the table build's large fresh arrays (the fine level's values and sums, the map's channel
// averages, the splat's sums: tens of MB each) on transparent huge pages where Linux offers them.
//
// Why: first touching a fresh array costs one page fault per 4 KB page, and on a virtual machine a
// fault is expensive: zero-filling 67 MB cost about 200 ms of CPU on the 2-vCPU VM of BENCHMARKS.md
// with 4 KB pages and about 10 ms with 2 MB pages, and faults were about a quarter of the build's CPU.
// The advice is a hint only: the kernel may ignore it (THP "never"), and elsewhere it is a no-op.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#ifdef __linux__
#include <sys/mman.h>
#endif

namespace envpis::detail {

/// Advises huge pages for the whole 4 KB pages inside [p, p + bytes), if it is at least kMin long
/// (smaller arrays gain little and may share their pages with other allocations).
inline void advise_huge_pages(void* p, std::size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  constexpr std::size_t kMin = std::size_t(4) << 20, kPage = 4096;
  if (bytes < kMin) return;
  const std::uintptr_t a = reinterpret_cast<std::uintptr_t>(p), b = a + bytes;
  const std::uintptr_t lo = (a + kPage - 1) / kPage * kPage, hi = b / kPage * kPage;
  if (hi > lo) madvise(reinterpret_cast<void*>(lo), hi - lo, MADV_HUGEPAGE);
#else
  (void)p, (void)bytes;
#endif
}

/// v = n copies of value in fresh memory advised as above (reserved and advised before the fill
/// touches it).
template <class T>
void assign_fresh(std::vector<T>& v, std::size_t n, const T& value) {
  std::vector<T>().swap(v);
  v.reserve(n);
  advise_huge_pages(v.data(), n * sizeof(T));
  v.assign(n, value);
}

}  // namespace envpis::detail
