#include "quadtree.hpp"

#include "handtrack/core/hand_layout.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace handtrack {

namespace {

// Cell sides are given at 320 px image width and scale with the width.
int scaled_px(int px_at_320, int width) { return std::max(1, px_at_320 * std::max(1, width / 320)); }

}  // namespace

void QuadtreeBuilder::build(const DepthInputConfig& config, const PixelBox& box, DepthInput& out) {
  config_ = &config;
  out_ = &out;
  out_->gaussians.clear();
  if (out_->hand_pixels == 0) return;
  const int w = out_->camera.width;
  const int root = scaled_px(config_->quadtree_root_px, w);
  // The smallest cell: the root halved while it is above the minimum leaf side (and even).
  int cell = root;
  while (cell > scaled_px(config_->quadtree_min_leaf_px, w) && cell % 2 == 0) cell /= 2;
  // Count, sum, min and max of the hand's depths per smallest cell over the roots that touch the
  // hand's bounding box, in one pass over the pixels; every quadtree node then aggregates cells
  // instead of rescanning its pixels.
  cells_.x0 = (box.u0 / root) * root;
  cells_.y0 = (box.v0 / root) * root;
  cells_.side = cell;
  cells_.columns = ((box.u1 / root + 1) * root - cells_.x0) / cell;
  const int rows = ((box.v1 / root + 1) * root - cells_.y0) / cell;
  // Room for a grid over the whole image once per resolution: no allocation in the steady state.
  const auto whole_image = static_cast<size_t>((w / root + 1) * root / cell) *
                           static_cast<size_t>((out_->camera.height / root + 1) * root / cell);
  cells_.stats.reserve(whole_image);
  cells_.stats.assign(static_cast<size_t>(cells_.columns) * static_cast<size_t>(rows), CellStats{});
  for (int v = box.v0; v <= box.v1; ++v) {
    for (int u = box.u0; u <= box.u1; ++u) {
      const auto i = static_cast<size_t>(v) * w + u;
      if (!out_->hand_mask[i]) continue;
      cells_.at((u - cells_.x0) / cell, (v - cells_.y0) / cell).add(out_->filtered_mm[i]);
    }
  }
  for (int y = cells_.y0; y <= box.v1; y += root) {
    for (int x = cells_.x0; x <= box.u1; x += root) quad(x, y, root, true);
  }
}

void QuadtreeBuilder::quad(int x, int y, int side, bool split_partial) {
  const int w = out_->camera.width;
  const int h = out_->camera.height;
  const int xe = std::min(x + side, w);
  const int ye = std::min(y + side, h);
  CellStats node;
  const int per_side = side / cells_.side;
  const int cx = (x - cells_.x0) / cells_.side;
  const int cy = (y - cells_.y0) / cells_.side;
  for (int j = cy; j < cy + per_side; ++j) {
    for (int i = cx; i < cx + per_side; ++i) node.merge(cells_.at(i, j));
  }
  const int count = node.count;
  if (count == 0) return;
  const int area = (xe - x) * (ye - y);
  const bool full_enough = count >= config_->min_leaf_fill * area;
  const bool flat = node.hi - node.lo < config_->quadtree_threshold_mm;
  const bool leaf = flat && full_enough;
  const bool partial = count < config_->split_partial_leaf_fill * area;
  if (side > cells_.side && (!leaf || (split_partial && partial))) {
    const int half = side / 2;
    quad(x, y, half, !leaf);
    quad(x + half, y, half, !leaf);
    quad(x, y + half, half, !leaf);
    quad(x + half, y + half, half, !leaf);
    return;
  }
  if (!full_enough) return;
  ImageGaussian g;
  g.u = x + 0.5 * side - 0.5;  // pixel centres are at integer coordinates
  g.v = y + 0.5 * side - 0.5;
  g.sigma_px = side / std::sqrt(2.0);  // Sec. 3.1: sigma = a / sqrt(2)
  g.depth_mm = node.sum / count;
  g.side_px = side;
  const auto& labels = out_->pixel_labels;
  if (!labels.empty()) {
    std::array<int, kNumPartLabels + 1> votes{};
    for (int v = y; v < ye; ++v) {
      for (int u = x; u < xe; ++u) {
        const auto i = static_cast<size_t>(v) * w + u;
        if (out_->hand_mask[i] && labels[i] <= kNumPartLabels) ++votes[labels[i]];
      }
    }
    g.label = static_cast<int>(std::max_element(votes.begin() + 1, votes.end()) - votes.begin());
    if (votes[static_cast<size_t>(g.label)] == 0) g.label = 0;
  }
  out_->gaussians.push_back(g);
}

}  // namespace handtrack
