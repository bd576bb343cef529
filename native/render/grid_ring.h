// The cells of one ring of a 2D grid: those at Chebyshev distance r from
// cell (cx, cy), clipped to [0, nx) x [0, ny). Ring searches (the UV grid's
// nearest triangle, a baked frame image's nearest covered texel) visit a
// ring's own cells only, so a search out to ring R costs O(R^2) cells.
#pragma once

#include <algorithm>
#include <cstdlib>

namespace knit::render {

// Calls fn(x, y) for the cells of ring r, row by row from y = cy - r, left
// to right within a row; stops as soon as fn returns true, and returns
// whether it did.
template <class Fn>
bool for_each_ring_cell(int cx, int cy, int r, int nx, int ny, Fn&& fn) {
  for (int y = std::max(cy - r, 0); y <= std::min(cy + r, ny - 1); ++y) {
    const bool edge_row = std::abs(y - cy) == r;  // a whole row of the ring; else its two ends
    for (int x = std::max(cx - r, 0); x <= std::min(cx + r, nx - 1); x = edge_row || x == cx + r ? x + 1 : cx + r) {
      if (!edge_row && std::abs(x - cx) != r) continue;
      if (fn(x, y)) return true;
    }
  }
  return false;
}

}  // namespace knit::render
