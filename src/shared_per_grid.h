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

template <class V>
struct GridRegistry {
  std::mutex mutex;
  std::map<std::pair<int, int>, std::weak_ptr<const V>> made;
};
/// One registry per V (a function template's statics would be one per V and Make, i.e. per call site).
template <class V>
GridRegistry<V>& grid_registry() {
  static GridRegistry<V> registry;
  return registry;
}

/// The value of type V for grid (T, S): make() when no holder keeps one. Thread-safe.
template <class V, class Make>
std::shared_ptr<const V> shared_per_grid(int T, int S, Make make) {
  GridRegistry<V>& r = grid_registry<V>();
  {
    const std::lock_guard<std::mutex> lock(r.mutex);
    if (auto held = r.made[{T, S}].lock()) return held;
  }
  // Made without the lock: a task that waits for a lock inside a parallel region can be the one the
  // lock's holder needs (TBB lets a waiting thread take other tasks). Two callers may both make it; the
  // values are the same, and the first one stored is shared from then on.
  std::shared_ptr<const V> value = make();
  const std::lock_guard<std::mutex> lock(r.mutex);
  if (auto held = r.made[{T, S}].lock()) return held;
  r.made[{T, S}] = value;
  return value;
}

}  // namespace envpis::detail
