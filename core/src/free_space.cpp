#include "handtrack/core/free_space.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace handtrack {

namespace {

constexpr float kFar = std::numeric_limits<float>::infinity();

// The exact squared Euclidean distance transform along one line (Felzenszwalb and Huttenlocher,
// "Distance Transforms of Sampled Functions", 2012): out[i] = min_j (i - j)^2 + f[j], the lower
// envelope of the parabolas rooted at each j with f[j] finite. `site` and `bound` are scratch of
// n and n + 1 entries.
void squared_distance_1d(const float* f, int n, float* out, int* site, float* bound) {
  int k = -1;
  for (int q = 0; q < n; ++q) {
    const float fq = f[q];
    if (fq == kFar) continue;
    float s = -kFar;
    while (k >= 0) {
      const int p = site[k];
      // Where the parabolas of p and q meet.
      s = ((fq + static_cast<float>(q) * q) - (f[p] + static_cast<float>(p) * p)) / (2.0F * static_cast<float>(q - p));
      if (s > bound[k]) break;
      --k;
    }
    ++k;
    site[k] = q;
    bound[k] = k == 0 ? -kFar : s;
    bound[k + 1] = kFar;
  }
  for (int q = 0, j = 0; q < n; ++q) {
    if (k < 0) {
      out[q] = kFar;
      continue;
    }
    while (bound[j + 1] < static_cast<float>(q)) ++j;
    const auto d = static_cast<float>(q - site[j]);
    out[q] = d * d + f[site[j]];
  }
}

}  // namespace

void FreeSpaceMap::clear() {
  distance_px_.clear();
  width_ = height_ = 0;
  cap_px_ = 0.0;
}

void FreeSpaceMap::reserve(int width, int height) {
  // The largest box (the whole image and its ring), and the row transform's scratch: at most one
  // entry per column of cells, and one more bound.
  const auto most_columns = static_cast<size_t>(std::max(width, 0) / kCellPx + 3);
  const auto most_cells = most_columns * static_cast<size_t>(std::max(height, 0) / kCellPx + 3);
  if (distance_px_.capacity() < most_cells) distance_px_.reserve(most_cells);
  if (scratch_.capacity() < most_cells) scratch_.reserve(most_cells);
  if (site_.capacity() < most_columns) site_.reserve(most_columns);
  if (bound_.capacity() < most_columns + 1) bound_.reserve(most_columns + 1);
}

void FreeSpaceMap::build(const CameraIntrinsics& camera, const std::vector<float>& depth_mm,
                         const std::vector<uint8_t>& hand_mask, const FreeSpaceConfig& config) {
  const int w = camera.width;
  const int h = camera.height;
  const auto pixels = static_cast<size_t>(w) * static_cast<size_t>(h);
  clear();
  if (!config.enabled || w <= 0 || h <= 0 || depth_mm.size() != pixels || hand_mask.size() != pixels) return;
  // The hand's box and depth range.
  int u_lo = w;
  int v_lo = h;
  int u_hi = -1;
  int v_hi = -1;
  float near_mm = kFar;
  float far_mm = 0.0F;
  for (int v = 0; v < h; ++v) {
    const uint8_t* mask = hand_mask.data() + static_cast<size_t>(v) * w;
    const float* depth = depth_mm.data() + static_cast<size_t>(v) * w;
    // Most rows hold no hand: find its first and last pixels (memchr-fast) before looking at depths.
    const auto* first = static_cast<const uint8_t*>(std::memchr(mask, 1, static_cast<size_t>(w)));
    if (first == nullptr) continue;
    const auto* last = static_cast<const uint8_t*>(memrchr(mask, 1, static_cast<size_t>(w)));
    const auto seen = [&](int u) { return mask[u] != 0 && depth[u] > 0.0F; };
    // The depth range of the row's hand pixels with a depth (branch-free: vectorised) ...
    float row_near = kFar;
    float row_far = 0.0F;
#pragma omp simd reduction(min : row_near) reduction(max : row_far)
    for (int u = static_cast<int>(first - mask); u <= static_cast<int>(last - mask); ++u) {
      row_near = std::min(row_near, seen(u) ? depth[u] : kFar);
      row_far = std::max(row_far, seen(u) ? depth[u] : 0.0F);
    }
    if (row_far == 0.0F) continue;  // none has a depth
    // ... and the first and last of them.
    int u_first = static_cast<int>(first - mask);
    while (!seen(u_first)) ++u_first;
    int u_last = static_cast<int>(last - mask);
    while (!seen(u_last)) --u_last;
    u_lo = std::min(u_lo, u_first);
    u_hi = std::max(u_hi, u_last);
    v_lo = std::min(v_lo, v);
    v_hi = std::max(v_hi, v);
    near_mm = std::min(near_mm, row_near);
    far_mm = std::max(far_mm, row_far);
  }
  if (u_hi < 0) return;
  // The cap in pixels where it is largest, at the hand's nearest depth; the box reaches that far
  // around the hand and a cell more (sample() ramps to the cap over the half cell beyond the
  // box's last cell centres), and a cell beyond the image (not free: the hand may go on there).
  // Cells are aligned with the image (at even pixels), so that with an even width and height no
  // cell holds pixels both on and off the image.
  cap_px_ = config.cap_mm * camera.focal() / near_mm;
  const int reach = static_cast<int>(std::ceil(cap_px_)) + 1 + kCellPx;
  const auto cell_start = [](int p) { return p >= 0 ? p - p % kCellPx : -((kCellPx - 1 - p) / kCellPx) * kCellPx; };
  u0_ = std::max(-kCellPx, cell_start(u_lo - reach));
  v0_ = std::max(-kCellPx, cell_start(v_lo - reach));
  width_ = (std::min(w + kCellPx - 1, u_hi + reach) - u0_) / kCellPx + 1;
  height_ = (std::min(h + kCellPx - 1, v_hi + reach) - v0_) / kCellPx + 1;
  const size_t cells = static_cast<size_t>(width_) * static_cast<size_t>(height_);
  reserve(w, h);
  distance_px_.resize(cells);
  scratch_.resize(cells);
  site_.resize(static_cast<size_t>(width_));
  bound_.resize(static_cast<size_t>(width_) + 1);
  // A cell is free (infinity) where all its pixels are free, not free (0) where any one is; pixels
  // beyond the image are not free.
  const float free_beyond_mm = far_mm + static_cast<float>(config.margin_mm);
  const auto not_free = [free_beyond_mm](float d) { return d > 0.0F && d <= free_beyond_mm; };
  // The cells whose pixels all lie in the image, [x_in, x_out) (the box starts at an even pixel,
  // -2 at the least), and the image's last column where it is the first of a cell (an odd width).
  const int x_in = std::max(0, -u0_ / kCellPx);
  const int x_out = std::clamp((w - u0_) / kCellPx, x_in, width_);
  const bool odd_column = x_out < width_ && u0_ + kCellPx * x_out == w - 1;
  std::fill(scratch_.begin(), scratch_.end(), kFar);
  for (int v = std::max(0, v0_); v < std::min(h, v0_ + height_ * kCellPx); ++v) {
    float* out = scratch_.data() + static_cast<size_t>((v - v0_) / kCellPx) * width_;
    const float* depth = depth_mm.data() + static_cast<size_t>(v) * w;
    static_assert(kCellPx == 2, "the loop below reads a cell's two pixels of the row");
    for (int x = x_in; x < x_out; ++x) {  // branch-free: vectorised
      const int u = u0_ + kCellPx * x;
      const bool any = not_free(depth[u]) | not_free(depth[u + 1]);
      out[x] = any ? 0.0F : out[x];
    }
    if (odd_column && not_free(depth[w - 1])) out[x_out] = 0.0F;
  }
  // The box's first or last column (row) of cells reaches beyond the image where it has a pixel
  // outside it.
  const bool left = u0_ < 0;
  const bool right = u0_ + width_ * kCellPx > w;
  const bool top = v0_ < 0;
  const bool bottom = v0_ + height_ * kCellPx > h;
  for (int y = 0; y < height_; ++y) {
    float* row = scratch_.data() + static_cast<size_t>(y) * width_;
    if ((top && y == 0) || (bottom && y == height_ - 1)) std::fill(row, row + width_, 0.0F);
    if (left) row[0] = 0.0F;
    if (right) row[width_ - 1] = 0.0F;
  }
  // Squared distances (in cells) along the columns, then along the rows of those (separable: the
  // exact EDT of the cells). Along a column the input is binary (0 or infinity): the distance to
  // the nearest cell that is not free is one sweep down and one up, a whole row at a time
  // (vectorised). A column distance at or beyond the cap stays beyond it in any row: such a cell
  // roots no parabola.
  const auto w_cells = static_cast<size_t>(width_);
  for (int y = 0; y < height_; ++y) {
    const float* in = scratch_.data() + y * w_cells;
    float* out = distance_px_.data() + y * w_cells;
    const float* above = y > 0 ? out - w_cells : nullptr;
    for (size_t x = 0; x < w_cells; ++x) out[x] = in[x] == 0.0F ? 0.0F : (above != nullptr ? above[x] + 1.0F : kFar);
  }
  for (int y = height_ - 2; y >= 0; --y) {
    float* out = distance_px_.data() + static_cast<size_t>(y) * w_cells;
    const float* below = out + w_cells;
    for (size_t x = 0; x < w_cells; ++x) out[x] = std::min(out[x], below[x] + 1.0F);
  }
  const auto cap_cells = static_cast<float>(cap_px_ / kCellPx);
  for (float& d : distance_px_) d = d < cap_cells ? d * d : kFar;
  for (int y = 0; y < height_; ++y) {
    float* row = distance_px_.data() + static_cast<ptrdiff_t>(y) * width_;
    std::copy(row, row + width_, scratch_.data());
    squared_distance_1d(scratch_.data(), width_, row, site_.data(), bound_.data());
  }
  // From cells to pixels: a cell that is not free has a pixel half a pixel nearer than its centre
  // (along the axes), so the distance from a free cell's centre is half a pixel less.
  const auto cap = static_cast<float>(cap_px_);
  constexpr float kNearerPx = 0.5F * (kCellPx - 1);
  for (float& d : distance_px_) d = d > 0.0F ? std::min(cap, std::sqrt(d) * static_cast<float>(kCellPx) - kNearerPx) : 0.0F;
}

double FreeSpaceMap::cell(int x, int y) const {
  if (x < 0 || y < 0 || x >= width_ || y >= height_) return cap_px_;
  return distance_px_[static_cast<size_t>(y) * width_ + x];
}

double FreeSpaceMap::at(int u, int v) const { return sample(u, v).distance_px; }

FreeSpaceMap::Sample FreeSpaceMap::sample(double u, double v) const {
  if (empty() || !std::isfinite(u) || !std::isfinite(v)) return {cap_px_, 0.0, 0.0};
  // In cells, the centre of cell (x, y) at (x, y): pixel u0 + kCellPx x + (kCellPx - 1) / 2.
  const double x = (u - u0_ - 0.5 * (kCellPx - 1)) / kCellPx;
  const double y = (v - v0_ - 0.5 * (kCellPx - 1)) / kCellPx;
  // Far outside the box: the cap (and no overflow in the conversion below).
  if (x < -2.0 || y < -2.0 || x > width_ + 1.0 || y > height_ + 1.0) return {cap_px_, 0.0, 0.0};
  const double fx = std::floor(x);
  const double fy = std::floor(y);
  const double a = x - fx;
  const double b = y - fy;
  const int i = static_cast<int>(fx);
  const int j = static_cast<int>(fy);
  const double d00 = cell(i, j);
  const double d10 = cell(i + 1, j);
  const double d01 = cell(i, j + 1);
  const double d11 = cell(i + 1, j + 1);
  Sample s;
  s.distance_px = (1 - a) * (1 - b) * d00 + a * (1 - b) * d10 + (1 - a) * b * d01 + a * b * d11;
  s.d_du = ((1 - b) * (d10 - d00) + b * (d11 - d01)) / kCellPx;
  s.d_dv = ((1 - a) * (d01 - d00) + a * (d11 - d10)) / kCellPx;
  return s;
}

}  // namespace handtrack
