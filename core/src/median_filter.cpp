#include "median_filter.hpp"

#include "target_clones.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace handtrack {

namespace {

// The three passes of the 3x3 median, each a loop of min and max (exact at any vector width),
// compiled for AVX-512, AVX2 and the baseline (target_clones.hpp).

// Non-finite samples as 0 (no depth).
HANDTRACK_TARGET_CLONES void clean_depth(const float* __restrict in, size_t n, float* __restrict out) {
  for (size_t i = 0; i < n; ++i) out[i] = std::abs(in[i]) <= std::numeric_limits<float>::max() ? in[i] : 0.0F;
}

// Sorts the column triples (a[u], b[u], c[u]) of three rows into lo[u] <= mid[u] <= hi[u].
HANDTRACK_TARGET_CLONES void sort_columns(const float* __restrict a, const float* __restrict b,
                                          const float* __restrict c, int n, float* __restrict lo,
                                          float* __restrict mid, float* __restrict hi) {
  for (int u = 0; u < n; ++u) {
    const float ab_lo = std::min(a[u], b[u]);
    const float ab_hi = std::max(a[u], b[u]);
    lo[u] = std::min(ab_lo, c[u]);
    hi[u] = std::max(ab_hi, c[u]);
    mid[u] = std::max(ab_lo, std::min(ab_hi, c[u]));
  }
}

// One output row from the sorted triples of its window's columns, padded by one on each side.
HANDTRACK_TARGET_CLONES void median_row(const float* __restrict lo, const float* __restrict mid,
                                        const float* __restrict hi, int n, float* __restrict out) {
  for (int u = 0; u < n; ++u) {
    const float max_lo = std::max(std::max(lo[u], lo[u + 1]), lo[u + 2]);
    const float min_hi = std::min(std::min(hi[u], hi[u + 1]), hi[u + 2]);
    const float med_mid = std::max(std::min(mid[u], mid[u + 1]), std::min(std::max(mid[u], mid[u + 1]), mid[u + 2]));
    out[u] = std::max(std::min(max_lo, med_mid), std::min(std::max(max_lo, med_mid), min_hi));
  }
}

}  // namespace

const std::vector<float>& MedianFilter::apply(const DepthImage& depth, int radius) {
  out_.resize(depth.depth_mm.size());
  if (radius == 1) {
    median_3x3(depth);
  } else {
    median_any(depth, radius);
  }
  return out_;
}

// The 3x3 median as the median of three column-sorted triples (Paeth, "Median finding on a 3x3
// grid", Graphics Gems 1990): with every column of the window sorted into (lo, mid, hi),
//   median = med3(max(lo_1, lo_2, lo_3), med3(mid_1, mid_2, mid_3), min(hi_1, hi_2, hi_3)).
// Branch-free min/max over rows, which the compiler vectorises. Borders repeat the edge pixel.
void MedianFilter::median_3x3(const DepthImage& depth) {
  const int w = depth.width();
  const int h = depth.height();
  clean_.resize(depth.depth_mm.size());
  clean_depth(depth.depth_mm.data(), clean_.size(), clean_.data());
  const auto row = [&](int v) { return clean_.data() + static_cast<size_t>(std::clamp(v, 0, h - 1)) * w; };
  // Column triples of the current window rows, padded by one column on each side.
  lo_.resize(static_cast<size_t>(w) + 2);
  mid_.resize(static_cast<size_t>(w) + 2);
  hi_.resize(static_cast<size_t>(w) + 2);
  float* __restrict lo = lo_.data();
  float* __restrict mid = mid_.data();
  float* __restrict hi = hi_.data();
  for (int v = 0; v < h; ++v) {
    const float* __restrict a = row(v - 1);
    const float* __restrict b = row(v);
    const float* __restrict c = row(v + 1);
    sort_columns(a, b, c, w, lo + 1, mid + 1, hi + 1);
    lo[0] = lo[1];
    mid[0] = mid[1];
    hi[0] = hi[1];
    lo[w + 1] = lo[w];
    mid[w + 1] = mid[w];
    hi[w + 1] = hi[w];
    median_row(lo, mid, hi, w, out_.data() + static_cast<size_t>(v) * w);
  }
}

// Any other radius: sort each (2r+1)^2 window (r = 0 copies).
void MedianFilter::median_any(const DepthImage& depth, int r) {
  const int w = depth.width();
  const int h = depth.height();
  
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      window_.clear();
      for (int dv = -r; dv <= r; ++dv) {
        for (int du = -r; du <= r; ++du) {
          const float d = depth.at(std::clamp(u + du, 0, w - 1), std::clamp(v + dv, 0, h - 1));
          window_.push_back(std::isfinite(d) ? d : 0.0F);
        }
      }
      const auto mid = window_.begin() + static_cast<std::ptrdiff_t>(window_.size() / 2);
      std::nth_element(window_.begin(), mid, window_.end());
      out_[static_cast<size_t>(v) * w + u] = *mid;
    }
  }
}

}  // namespace handtrack
