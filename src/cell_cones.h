// SPDX-License-Identifier: Apache-2.0
#pragma once
// Internal: the bounding cones of a table's cells, which depend on the grid alone (T top cells per side,
// S sub-cells per cell side), never on the map: computed once per grid and shared by every table built
// on it while one is alive (a product's plain and compensated tables, compare's strategies, the tests).
#include <memory>
#include <vector>

#include "envpis/importance_table.h"

namespace envpis::detail {

struct CellCones {
  std::vector<Cone> top;  // T^2, row-major
  std::vector<Cone> sub;  // T^2 S^2, cell-major (empty when S = 1)
};

/// The cones of the T x T grid and its S x S sub-cells; thread-safe. The same object for every caller
/// while one holder keeps it; computed afresh (the same values) after the last holder let go.
std::shared_ptr<const CellCones> cell_cones(int T, int S);

}  // namespace envpis::detail
