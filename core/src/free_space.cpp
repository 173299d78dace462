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
    // Most rows hold no hand: find its first pixel (memchr-fast) before looking at depths.
    const auto* first = static_cast<const uint8_t*>(std::memchr(mask, 1, static_cast<size_t>(w)));
    if (first == nullptr) continue;
    for (int u = static_cast<int>(first - mask); u < w; ++u) {
      if (mask[u] == 0 || !(depth[u] > 0.0F)) continue;
      u_lo = std::min(u_lo, u);
      u_hi = std::max(u_hi, u);
      v_lo = std::min(v_lo, v);
      v_hi = std::max(v_hi, v);
      near_mm = std::min(near_mm, depth[u]);
      far_mm = std::max(far_mm, depth[u]);
    }
  }
  if (u_hi < 0) return;
  // The cap in pixels where it is largest, at the hand's nearest depth; the box reaches that far
  // around the hand, and one pixel beyond the image (not free: the hand may go on there).
  cap_px_ = config.cap_mm * camera.focal() / near_mm;
  const int reach = static_cast<int>(std::ceil(cap_px_)) + 1;
  u0_ = std::max(-1, u_lo - reach);
  v0_ = std::max(-1, v_lo - reach);
  width_ = std::min(w, u_hi + reach + 1) - u0_ + 1;
  height_ = std::min(h, v_hi + reach + 1) - v0_ + 1;
  const size_t box = static_cast<size_t>(width_) * static_cast<size_t>(height_);
  const size_t room = static_cast<size_t>(w + 2) * static_cast<size_t>(h + 2);
  if (distance_px_.capacity() < room) distance_px_.reserve(room);
  if (scratch_.capacity() < room) scratch_.reserve(room);
  // The row transform's scratch: at most one entry per box column (w + 2), and one more bound.
  if (site_.capacity() < static_cast<size_t>(w + 2)) {
    site_.reserve(static_cast<size_t>(w + 2));
    bound_.reserve(static_cast<size_t>(w + 3));
  }
  distance_px_.resize(box);
  scratch_.resize(box);
  site_.resize(static_cast<size_t>(width_));
  bound_.resize(static_cast<size_t>(width_) + 1);
  const float free_beyond_mm = far_mm + static_cast<float>(config.margin_mm);
  // The box's columns inside the image; the ring beyond it is not free.
  const int x_in_begin = -u0_ > 0 ? -u0_ : 0;
  const int x_in_end = std::min(width_, w - u0_);
  for (int y = 0; y < height_; ++y) {
    float* out = scratch_.data() + static_cast<size_t>(y) * width_;
    std::fill(out, out + width_, 0.0F);
    const int v = v0_ + y;
    if (v < 0 || v >= h) continue;
    const float* depth = depth_mm.data() + static_cast<size_t>(v) * w;
    for (int x = x_in_begin; x < x_in_end; ++x) {
      const float d = depth[u0_ + x];
      out[x] = (d <= 0.0F || d > free_beyond_mm) ? kFar : 0.0F;
    }
  }
  // Squared distances along the columns, then along the rows of those (separable: the exact EDT).
  // Along a column the input is binary (0 or infinity): the distance to the nearest pixel that is
  // not free is one sweep down and one up, a whole row at a time (vectorised).
  const auto w_box = static_cast<size_t>(width_);
  for (int y = 0; y < height_; ++y) {
    const float* in = scratch_.data() + y * w_box;
    float* out = distance_px_.data() + y * w_box;
    const float* above = y > 0 ? out - w_box : nullptr;
    for (size_t x = 0; x < w_box; ++x) out[x] = in[x] == 0.0F ? 0.0F : (above != nullptr ? above[x] + 1.0F : kFar);
  }
  for (int y = height_ - 2; y >= 0; --y) {
    float* out = distance_px_.data() + static_cast<size_t>(y) * w_box;
    const float* below = out + w_box;
    for (size_t x = 0; x < w_box; ++x) out[x] = std::min(out[x], below[x] + 1.0F);
  }
  for (float& d : distance_px_) d *= d;
  for (int y = 0; y < height_; ++y) {
    float* row = distance_px_.data() + static_cast<ptrdiff_t>(y) * width_;
    std::copy(row, row + width_, scratch_.data());
    squared_distance_1d(scratch_.data(), width_, row, site_.data(), bound_.data());
  }
  const auto cap = static_cast<float>(cap_px_);
  for (float& d : distance_px_) d = std::min(cap, std::sqrt(d));
}

double FreeSpaceMap::at(int u, int v) const {
  const int x = u - u0_;
  const int y = v - v0_;
  if (x < 0 || y < 0 || x >= width_ || y >= height_) return cap_px_;
  return distance_px_[static_cast<size_t>(y) * width_ + x];
}

FreeSpaceMap::Sample FreeSpaceMap::sample(double u, double v) const {
  if (empty() || !std::isfinite(u) || !std::isfinite(v)) return {cap_px_, 0.0, 0.0};
  // Far outside the box: the cap (and no overflow in the conversion below).
  const double lo_u = u0_ - 2.0;
  const double lo_v = v0_ - 2.0;
  if (u < lo_u || v < lo_v || u > u0_ + width_ + 1.0 || v > v0_ + height_ + 1.0) return {cap_px_, 0.0, 0.0};
  const double fu = std::floor(u);
  const double fv = std::floor(v);
  const double a = u - fu;
  const double b = v - fv;
  const int i = static_cast<int>(fu);
  const int j = static_cast<int>(fv);
  const double d00 = at(i, j);
  const double d10 = at(i + 1, j);
  const double d01 = at(i, j + 1);
  const double d11 = at(i + 1, j + 1);
  Sample s;
  s.distance_px = (1 - a) * (1 - b) * d00 + a * (1 - b) * d10 + (1 - a) * b * d01 + a * b * d11;
  s.d_du = (1 - b) * (d10 - d00) + b * (d11 - d01);
  s.d_dv = (1 - a) * (d01 - d00) + a * (d11 - d10);
  return s;
}

}  // namespace handtrack
