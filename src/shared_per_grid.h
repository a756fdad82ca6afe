// SPDX-License-Identifier: Apache-2.0
#pragma once
// Internal: values that depend on a table's grid alone (T top cells per side, S sub-cells per cell
// side), made once per grid and shared by every holder while one keeps it (the cells' cones, the portal
// view's sub-cell arrays); made afresh (the same values) after the last holder let go.
#include <map>
#include <memory>
#include <mutex>
#include <utility>

namespace envpis::detail {

/// The value of type V for grid (T, S): make() when no holder keeps one. Thread-safe.
template <class V, class Make>
std::shared_ptr<const V> shared_per_grid(int T, int S, Make make) {
  static std::mutex mutex;  // one registry per V
  static std::map<std::pair<int, int>, std::weak_ptr<const V>> made;
  {
    const std::lock_guard<std::mutex> lock(mutex);
    if (auto held = made[{T, S}].lock()) return held;
  }
  // Made without the lock: a task that waits for a lock inside a parallel region can be the one the
  // lock's holder needs (TBB lets a waiting thread take other tasks). Two callers may both make it; the
  // values are the same, and the first one stored is shared from then on.
  std::shared_ptr<const V> value = make();
  const std::lock_guard<std::mutex> lock(mutex);
  if (auto held = made[{T, S}].lock()) return held;
  made[{T, S}] = value;
  return value;
}

}  // namespace envpis::detail
