#pragma once
// The two-pass 3-4 chamfer distance transform (Borgefors 1986, "Distance transformations in
// digital images"): each cell takes the least of its own value and a neighbour's plus 3 (edge) or
// 4 (diagonal), forward then backward, so a cell ends with min over sources j of value(j) plus the
// chamfer length of a path from j (about 3 x the Euclidean distance in pixels, within 8 %). Private
// to core; shared by segmentation (the palm centre) and the body eraser (body_eraser.hpp).
#include <algorithm>
#include <vector>

namespace handtrack {

// In place over a w x h grid (row-major): only cells where `open(i)` holds are updated, so other
// cells are fixed sources (their value) or, given a large value, walls that nothing crosses. Cells
// beyond the grid read `outside`.
template <typename Open>
void chamfer_transform(std::vector<int>& d, int w, int h, int outside, Open open) {
  const auto at = [&](int u, int v) -> int& { return d[static_cast<size_t>(v) * w + u]; };
  // A cell's neighbour; only cells on the grid's edge look beyond it.
  const auto relax = [&](int u, int v, int du, int dv, int cost, bool edge) {
    const int uu = u + du;
    const int vv = v + dv;
    const int other = edge && (uu < 0 || vv < 0 || uu >= w || vv >= h) ? outside : at(uu, vv);
    at(u, v) = std::min(at(u, v), other + cost);
  };
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      if (!open(static_cast<size_t>(v) * w + u)) continue;
      const bool edge = u == 0 || v == 0 || u == w - 1 || v == h - 1;
      relax(u, v, -1, 0, 3, edge);
      relax(u, v, 0, -1, 3, edge);
      relax(u, v, -1, -1, 4, edge);
      relax(u, v, 1, -1, 4, edge);
    }
  }
  for (int v = h - 1; v >= 0; --v) {
    for (int u = w - 1; u >= 0; --u) {
      if (!open(static_cast<size_t>(v) * w + u)) continue;
      const bool edge = u == 0 || v == 0 || u == w - 1 || v == h - 1;
      relax(u, v, 1, 0, 3, edge);
      relax(u, v, 0, 1, 3, edge);
      relax(u, v, 1, 1, 4, edge);
      relax(u, v, -1, 1, 4, edge);
    }
  }
}

}  // namespace handtrack
