#pragma once
// The quadtree over the segmented hand (paper Sec. 3.1): cells are split until the depth range of
// their hand pixels is below epsilon_c; every leaf full enough of hand pixels becomes a unit-weight
// 2D Gaussian with sigma = a / sqrt(2) and the mean depth of its pixels, labelled by the majority
// part label of its pixels (Sec. 4.3). Ours: a leaf that the hand's outline crosses (less full than
// split_partial_leaf_fill) is split once more, so that its Gaussian, at the cell's centre, does not
// sit up to a quarter of the cell off the finger it half covers. Once only: split down to the
// smallest cell, a real sensor's ragged outline becomes hundreds of 2 px leaves. Private to core
// (DepthInputBuilder).
#include "hand_segmentation.hpp"

#include "handtrack/core/depth_input.hpp"

#include <limits>
#include <vector>

namespace handtrack {

class QuadtreeBuilder {
 public:
  // Appends the leaves of the hand inside `box` to out.gaussians (cleared first). Reads
  // out.camera, out.filtered_mm, out.hand_mask, out.hand_pixels and out.pixel_labels.
  void build(const DepthInputConfig& config, const PixelBox& box, DepthInput& out);

 private:
  // The cell of `side` px at (x, y); `split_partial`: whether a partial leaf may still be split
  // (false in the quarters of one that was).
  void quad(int x, int y, int side, bool split_partial);

  // The hand's depths per smallest quadtree cell.
  struct CellStats {
    int count = 0;
    float lo = std::numeric_limits<float>::infinity();
    float hi = 0.0F;
    double sum = 0.0;
    void add(float d) {
      ++count;
      sum += d;
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
    void merge(const CellStats& o) {
      count += o.count;
      sum += o.sum;
      lo = std::min(lo, o.lo);
      hi = std::max(hi, o.hi);
    }
  };
  struct CellGrid {
    int x0 = 0, y0 = 0;  // image pixel of cell (0, 0)
    int side = 1;        // cell side, px
    int columns = 0;
    std::vector<CellStats> stats;
    CellStats& at(int i, int j) { return stats[static_cast<size_t>(j) * static_cast<size_t>(columns) + static_cast<size_t>(i)]; }
  } cells_;
  const DepthInputConfig* config_ = nullptr;  // of the build() in progress
  DepthInput* out_ = nullptr;
};

}  // namespace handtrack
