#pragma once
// Free space around the hand (ours, not in the paper): where the camera sees through to something
// well behind the hand, or sees nothing, no part of the hand can be. E_sim (Sec. 4.1) rewards a
// model Gaussian that lands on data and is indifferent to one that lands on nothing, so a finger
// the camera cannot see (curled behind the back of the hand, a thumb tucked behind the index) is
// left wherever the optimiser drops it, often stretched out over the background. E_free
// (energy.hpp) charges that, with the distance this map gives.
//
// A pixel is free when its depth is missing (0) or farther than the segmented hand's farthest
// pixel by more than `margin_mm`; anything nearer (the hand, the forearm at the wrist, a body or
// an object in front, the other hand) is not: a model part behind it is hidden, not floating.
// Pixels outside the image are not free either (the hand may go on beyond the image's edge).
// The map holds, for a box around the hand, the Euclidean distance (px) to the nearest pixel that
// is not free, capped at `cap_mm` at the hand's nearest depth: beyond the cap, and outside the box,
// the distance is the cap and its gradient 0. It is held at half resolution, in cells of 2 x 2
// pixels, a cell not free where any of its pixels is not: within about a pixel of the exact
// distance (E_free forgives 5 mm, 3-4 px at arm's length), at a quarter of the cost (measured in
// docs/BENCHMARKS.md).

#include "handtrack/core/camera.hpp"

#include <cstdint>
#include <vector>

namespace handtrack {

struct FreeSpaceConfig {
  double margin_mm = 30.0;  // free = farther than the hand's farthest pixel by this much, or no depth
  double cap_mm = 60.0;     // distances are capped here (and the map's box reaches this far)
  bool enabled = true;      // false: build() leaves the map empty (no tracker energy reads it)
};

class FreeSpaceMap {
 public:
  // The distance at a point (px, pixel centres at integers), bilinear between pixel centres, and
  // its derivatives along u and v.
  struct Sample {
    double distance_px = 0.0;
    double d_du = 0.0;
    double d_dv = 0.0;
  };

  // Builds the map from the full-image depth (mm, 0 = none) and the hand's mask (1 = hand pixel);
  // empty without hand pixels, or when not config.enabled. Storage is reused: no allocation after
  // the first frame of a size.
  void build(const CameraIntrinsics& camera, const std::vector<float>& depth_mm, const std::vector<uint8_t>& hand_mask,
             const FreeSpaceConfig& config = {});
  void clear();
  // Room for the map of any hand in a width x height image: build() for such images, and copies of
  // their maps into this one, allocate nothing afterwards.
  void reserve(int width, int height);

  [[nodiscard]] bool empty() const { return distance_px_.empty(); }
  [[nodiscard]] double cap_px() const { return cap_px_; }
  [[nodiscard]] Sample sample(double u, double v) const;
  // The distance at pixel (u, v): sample(u, v), the cap outside the box.
  [[nodiscard]] double at(int u, int v) const;

  static constexpr int kCellPx = 2;  // a cell's side, in pixels

 private:
  // The distance at the centre of cell (x, y); the cap outside the box.
  [[nodiscard]] double cell(int x, int y) const;

  int u0_ = 0;  // the box: cells of pixels [u0 + 2x, u0 + 2x + 1] x [v0 + 2y, v0 + 2y + 1], x < width,
  int v0_ = 0;  // y < height, at even pixels; it may reach a cell beyond the image
  int width_ = 0;
  int height_ = 0;
  double cap_px_ = 0.0;
  std::vector<float> distance_px_;  // row-major over the cells
  std::vector<float> scratch_;      // build(): free (infinity) or not (0), then one row at a time
  std::vector<int> site_;           // build(): the row transform's parabola roots
  std::vector<float> bound_;        // and where each one's reign begins
};

}  // namespace handtrack
