#include "handtrack/core/image_mixture.hpp"

#include "handtrack/core/depth_input.hpp"
#include "handtrack/core/hand_layout.hpp"

#include <algorithm>
#include <numeric>

namespace handtrack {

void ImageMixture::Columns::resize(std::size_t n) {
  u.resize(n);
  v.resize(n);
  sigma2.resize(n);
  depth_mm.resize(n);
}

void ImageMixture::Columns::set(std::size_t i, const ImageGaussian& g) {
  u[i] = g.u;
  v[i] = g.v;
  sigma2[i] = g.sigma_px * g.sigma_px;
  depth_mm[i] = g.depth_mm;
}

namespace {

// The first element of the sorted [first, first + n) for which `before(element)` is false, like
// std::partition_point, without branches: each step halves the range with a conditional move,
// so the ~10 steps over a frame's few hundred leaves cost no mispredictions.
template <class Before>
const double* partition_point(const double* first, std::size_t n, Before before) {
  if (n == 0) return first;
  while (n > 1) {
    const std::size_t half = n / 2;
    first = before(first[half]) ? first + half : first;
    n -= half;
  }
  return first + (before(*first) ? 1 : 0);
}

}  // namespace

ImageMixtureSlice ImageMixture::Columns::slice(std::size_t begin, std::size_t end, double lo_mm,
                                               double hi_mm) const {
  const double* lo = partition_point(depth_mm.data() + begin, end - begin, [&](double d) { return d < lo_mm; });
  const double* hi = partition_point(lo, static_cast<std::size_t>(depth_mm.data() + end - lo),
                                     [&](double d) { return d <= hi_mm; });
  return span(static_cast<std::size_t>(lo - depth_mm.data()), static_cast<std::size_t>(hi - depth_mm.data()));
}

ImageMixtureSlice ImageMixture::Columns::span(std::size_t first, std::size_t last) const {
  return {u.data() + first, v.data() + first, sigma2.data() + first, depth_mm.data() + first, last - first, first};
}

void ImageMixture::DepthIndex::build(const std::vector<double>& sorted_depth_mm) {
  const std::size_t n = sorted_depth_mm.size();
  first.resize(n + 1);
  if (n == 0) {
    first[0] = 0;
    return;
  }
  origin_mm = sorted_depth_mm.front();
  const double range_mm = sorted_depth_mm.back() - origin_mm;
  inv_width = range_mm > 0.0 ? static_cast<double>(n) / range_mm : 1.0;
  std::size_t k = 0;
  for (std::size_t b = 0; b <= n; ++b) {
    while (k < n && bucket(sorted_depth_mm[k]) < b) ++k;
    first[b] = k;
  }
}

std::size_t ImageMixture::DepthIndex::bucket(double depth_mm) const {
  const double x = (depth_mm - origin_mm) * inv_width;
  const auto last = static_cast<double>(first.size() - 2);
  // Clamped in double before the conversion (any x, an infinity too, converts within range).
  return x > 0.0 ? static_cast<std::size_t>(std::min(x, last)) : 0;
}

void ImageMixture::Columns::reserve(std::size_t n) {
  u.reserve(n);
  v.reserve(n);
  sigma2.reserve(n);
  depth_mm.reserve(n);
}

void ImageMixture::reserve(std::size_t n) {
  by_depth_.reserve(n);
  depth_index_.first.reserve(n + 1);
  by_label_.reserve(n);
  order_.reserve(n);
  covered_.reserve(n);
  open_.reserve(n);
  pairs_.values.reserve(2 * kMaxPairedModelGaussians * n);
  label_begin_.reserve(kNumPartLabels + 2);  // assign(): labels 0..kNumPartLabels
}

void ImageMixture::assign(const std::vector<ImageGaussian>& gaussians) {
  const std::size_t n = gaussians.size();
  by_depth_.resize(n);
  by_label_.resize(n);
  order_.resize(n);
  covered_.resize(n);
  open_.resize(n);
  std::iota(order_.begin(), order_.end(), std::size_t{0});
  const auto depth = [&](std::size_t i) { return gaussians[i].depth_mm; };
  std::sort(order_.begin(), order_.end(), [&](std::size_t a, std::size_t b) { return depth(a) < depth(b); });
  for (std::size_t k = 0; k < n; ++k) by_depth_.set(k, gaussians[order_[k]]);
  depth_index_.build(by_depth_.depth_mm);

  // By label, then depth (std::sort: no allocation, unlike std::stable_sort).
  std::sort(order_.begin(), order_.end(), [&](std::size_t a, std::size_t b) {
    const int la = gaussians[a].label;
    const int lb = gaussians[b].label;
    return la < lb || (la == lb && depth(a) < depth(b));
  });
  int max_label = 0;
  if (n > 0) max_label = std::max(max_label, gaussians[order_[n - 1]].label);
  label_begin_.assign(static_cast<std::size_t>(max_label) + 2, 0);
  for (std::size_t k = 0; k < n; ++k) {
    const ImageGaussian& g = gaussians[order_[k]];
    by_label_.set(k, g);
    ++label_begin_[static_cast<std::size_t>(g.label) + 1];
  }
  std::partial_sum(label_begin_.begin(), label_begin_.end(), label_begin_.begin());
}

double* ImageMixture::pair_scratch(std::size_t values) const {
  if (pairs_.values.size() < values) pairs_.values.resize(values);
  return pairs_.values.data();
}

ImageMixtureSlice ImageMixture::depth_slice(double lo_mm, double hi_mm) const {
  if (size() == 0) return by_depth_.span(0, 0);
  // Each bound searched within its own bucket (DepthIndex): the same Gaussians as a search of all.
  const double* depth = by_depth_.depth_mm.data();
  const std::vector<std::size_t>& first = depth_index_.first;
  const std::size_t b_lo = depth_index_.bucket(lo_mm);
  const std::size_t b_hi = depth_index_.bucket(hi_mm);
  const double* lo = partition_point(depth + first[b_lo], first[b_lo + 1] - first[b_lo],
                                     [&](double d) { return d < lo_mm; });
  const double* hi = partition_point(depth + first[b_hi], first[b_hi + 1] - first[b_hi],
                                     [&](double d) { return d <= hi_mm; });
  return by_depth_.span(static_cast<std::size_t>(lo - depth), static_cast<std::size_t>(std::max(lo, hi) - depth));
}

ImageMixtureSlice ImageMixture::label_slice(int label, double lo_mm, double hi_mm) const {
  if (label < 0 || static_cast<std::size_t>(label) + 1 >= label_begin_.size()) return {};
  const auto l = static_cast<std::size_t>(label);
  return by_label_.slice(label_begin_[l], label_begin_[l + 1], lo_mm, hi_mm);
}

}  // namespace handtrack
