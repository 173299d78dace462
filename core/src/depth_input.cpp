#include "handtrack/core/depth_input.hpp"

#include "handtrack/core/hand_model.hpp"

#include "fast_exp.hpp"
#include "target_clones.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace handtrack {
namespace {

using Eigen::Vector3d;

// Radius around the palm centre that holds the whole hand, in hand lengths: an extended middle
// fingertip is ~0.75 hand lengths from the palm centre; the margin allows for motion between frames
// and a palm centre that is off.
constexpr double kHandRadiusInLengths = 1.0;
// Distance from the palm centre found by the distance transform down to the wrist cut, in hand
// lengths (an open palm's centre is about a quarter hand length above the wrist).
constexpr double kWristBelowPalmCentre = 0.25;
// A hand is at most this many default hand lengths long (subjects vary by about 10 %).
constexpr double kHandLengthMargin = 1.1;
// The forearm is cut this far below the wrist joint (mm): the wrist's own surface stays in.
constexpr double kWristCutMarginMm = 10.0;
// A blob whose outline runs along the far plane of the working volume for more than this share
// is a larger surface (a shoulder, a desk) reaching into the volume, not a hand in front of one.
// Measured: synthetic hands with their forearms 0-0.10, the shoulder of the .oni recording
// 0.18-0.24; a real hand straddling the far plane (SR305 231615/100: 0.25) is missed until it
// comes nearer, which is what a working volume means.
constexpr double kMaxFarPlaneCut = 0.15;
// Quadtree leaves with room reserved up front (DepthInputBuilder's constructor).
constexpr size_t kReservedLeaves = 2048;
// Pixels this close to the image border mark the end of a blob where the arm leaves the image.
constexpr int kBorderPx = 3;

// Two-pass 3-4 chamfer distance transform in place: nonzero cells get their distance (in thirds of
// a pixel) to the nearest zero cell.
void chamfer_distance(std::vector<int>& d, int w, int h) {
  const auto at = [&](int u, int v) -> int& { return d[static_cast<size_t>(v) * w + u]; };
  const auto relax = [&](int u, int v, int du, int dv, int cost) {
    const int uu = u + du;
    const int vv = v + dv;
    const int other = (uu < 0 || vv < 0 || uu >= w || vv >= h) ? 0 : at(uu, vv);
    at(u, v) = std::min(at(u, v), other + cost);
  };
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      if (at(u, v) == 0) continue;
      relax(u, v, -1, 0, 3);
      relax(u, v, 0, -1, 3);
      relax(u, v, -1, -1, 4);
      relax(u, v, 1, -1, 4);
    }
  }
  for (int v = h - 1; v >= 0; --v) {
    for (int u = w - 1; u >= 0; --u) {
      if (at(u, v) == 0) continue;
      relax(u, v, 1, 0, 3);
      relax(u, v, 0, 1, 3);
      relax(u, v, 1, 1, 4);
      relax(u, v, -1, 1, 4);
    }
  }
}

// Pairs of image Gaussians with |mu_p - mu_q|^2 / 2S > kPairCutoff add less than e^-kPairCutoff of
// their peak to E(C_I,C_I) and count 0.
constexpr double kPairCutoff = 25.0;

// sum_k s2 s2_k / S_k exp(-((u_k - u)^2 + (v_k - v)^2) / 2 S_k), S_k = s2 + s2_k, over the pairs in
// reach: one run of E(C_I,C_I). The hand's leaves lie close together (a third of all pairs are in
// reach, in no predictable order), so the run is branch-free and vectorised like E_sim's pair sums
// (energy.cpp): 2 doubles per SSE2 register, 4 with FMA in the x86-64-v3 clone.
HANDTRACK_TARGET_CLONES double pair_run(const double* us, const double* vs,
                                                                            const double* s2s, size_t n, double u,
                                                                            double v, double s2) {
  double sum = 0.0;
#pragma omp simd reduction(+ : sum)
  for (size_t k = 0; k < n; ++k) {
    const double du = us[k] - u;
    const double dv = vs[k] - v;
    const double s = s2 + s2s[k];
    const double x = (du * du + dv * dv) / (2.0 * s);
    const double term = s2 * s2s[k] / s * detail::exp_nonpositive(-x);
    sum += x <= kPairCutoff ? term : 0.0;
  }
  return sum;
}

// Pixels checked at once when scanning for depth in the working volume (0 outside it).
constexpr int kScanChunk = 16;

// True when none of the kScanChunk depths from `d` is in the working volume: one vectorised max.
bool nothing_in(const float* d) {
  float m = 0.0F;
  for (int k = 0; k < kScanChunk; ++k) m = std::max(m, d[k]);
  return m <= 0.0F;
}

int scaled_px(int px_at_320, int width) { return std::max(1, px_at_320 * std::max(1, width / 320)); }

}  // namespace

DepthInputBuilder::DepthInputBuilder(DepthInputConfig config) : config_(config) {
  // Steady state without allocation (the daemon's pipeline): a hand at arm's length makes 200-500
  // quadtree leaves; storage grows only for more than kReservedLeaves (a hand very near the camera).
  out_.gaussians.reserve(kReservedLeaves);
  out_.mixture.reserve(kReservedLeaves);
}

const DepthInput& DepthInputBuilder::build(const DepthImage& depth, const std::optional<HandHint>& hint,
                                           const PixelLabeller* labeller) {
  out_.camera = depth.camera;
  median_filter(depth);
  segment(hint);
  out_.pixel_labels.clear();
  if (labeller != nullptr && out_.hand_pixels > 0) labeller->label(out_, out_.pixel_labels);
  build_quadtree();
  out_.self_similarity = image_self_similarity(out_.gaussians);
  out_.mixture.assign(out_.gaussians);
  return out_;
}

void DepthInputBuilder::median_filter(const DepthImage& depth) {
  const int r = config_.median_radius_px;
  out_.filtered_mm.resize(depth.depth_mm.size());
  unclamped_mm_.resize(depth.depth_mm.size());
  if (r == 1) {
    median_3x3(depth);
  } else {
    median_any(depth);
  }
  const auto near = static_cast<float>(config_.near_mm);
  const auto far = static_cast<float>(config_.far_mm);
  for (size_t i = 0; i < unclamped_mm_.size(); ++i) {
    const float m = unclamped_mm_[i];
    out_.filtered_mm[i] = (m >= near && m <= far) ? m : 0.0F;
  }
}

// The 3x3 median as the median of three column-sorted triples (Paeth, "Median finding on a 3x3
// grid", Graphics Gems 1990): with every column of the window sorted into (lo, mid, hi),
//   median = med3(max(lo_1, lo_2, lo_3), med3(mid_1, mid_2, mid_3), min(hi_1, hi_2, hi_3)).
// Branch-free min/max over rows, which the compiler vectorises. Borders repeat the edge pixel.
void DepthInputBuilder::median_3x3(const DepthImage& depth) {
  const int w = depth.width();
  const int h = depth.height();
  // Non-finite samples count as 0 (no depth).
  clean_.resize(depth.depth_mm.size());
  for (size_t i = 0; i < clean_.size(); ++i) {
    const float d = depth.depth_mm[i];
    clean_[i] = std::abs(d) <= std::numeric_limits<float>::max() ? d : 0.0F;
  }
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
    float* __restrict out = unclamped_mm_.data() + static_cast<size_t>(v) * w;
    for (int u = 0; u < w; ++u) {
      const float max_lo = std::max(std::max(lo[u], lo[u + 1]), lo[u + 2]);
      const float min_hi = std::min(std::min(hi[u], hi[u + 1]), hi[u + 2]);
      const float med_mid = std::max(std::min(mid[u], mid[u + 1]), std::min(std::max(mid[u], mid[u + 1]), mid[u + 2]));
      out[u] = std::max(std::min(max_lo, med_mid), std::min(std::max(max_lo, med_mid), min_hi));
    }
  }
}

void DepthInputBuilder::sort_columns(const float* __restrict a, const float* __restrict b, const float* __restrict c,
                                     int n, float* __restrict lo, float* __restrict mid, float* __restrict hi) {
  for (int u = 0; u < n; ++u) {
    const float ab_lo = std::min(a[u], b[u]);
    const float ab_hi = std::max(a[u], b[u]);
    lo[u] = std::min(ab_lo, c[u]);
    hi[u] = std::max(ab_hi, c[u]);
    mid[u] = std::max(ab_lo, std::min(ab_hi, c[u]));
  }
}

// Any other radius: sort each (2r+1)^2 window (r = 0 copies).
void DepthInputBuilder::median_any(const DepthImage& depth) {
  const int w = depth.width();
  const int h = depth.height();
  const int r = config_.median_radius_px;
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
      unclamped_mm_[static_cast<size_t>(v) * w + u] = *mid;
    }
  }
}

void DepthInputBuilder::segment(const std::optional<HandHint>& hint) {
  const auto& cam = out_.camera;
  const int w = cam.width;
  const int h = cam.height;
  const auto n = static_cast<size_t>(w) * h;
  const auto& d = out_.filtered_mm;
  out_.hand_mask.assign(n, 0);
  out_.hand_pixels = 0;
  const auto point = [&](size_t i) {
    return cam.unproject(static_cast<double>(i % w), static_cast<double>(i / w), d[i]);
  };
  const double hand_radius = kHandRadiusInLengths * config_.hand_length_mm;

  Vector3d centre;
  Vector3d axis;
  Vector3d wrist;
  bool found = false;
  if (hint) {
    centre = hint->palm_centre_mm;
    axis = hint->finger_axis;
    wrist = hint->wrist_mm;
    found = true;
  }
  // Keeps the pixels near `centre` and above the forearm cut; sets hand_box_ (their bounding box)
  // and hand_sum_ (the sum of their 3D points). The cut is the wrist plane, but never lower than
  // one (generous) hand length below the farthest point along the axis: a wrist that drifted down
  // the forearm must not let the forearm in, or the model follows it further down. Returns how many
  // pixels it kept. Two passes over the image, no per-pixel lists: nothing grows with the hand.
  const auto select = [&]() {
    std::fill(out_.hand_mask.begin(), out_.hand_mask.end(), 0);
    // Unprojection by ray: p = (r_u d, r_v d, d) with r_u = (u - c_x) / f_x, r_v = (v - c_y) / f_y.
    ray_u_.resize(static_cast<size_t>(w));
    for (int u = 0; u < w; ++u) ray_u_[static_cast<size_t>(u)] = (u - cam.cx) / cam.fx;
    const auto ray_v = [&](int v) { return (v - cam.cy) / cam.fy; };
    const auto ray_point = [&](int u, double r_v, float depth) {
      return Vector3d(ray_u_[static_cast<size_t>(u)] * depth, r_v * depth, depth);
    };
    PixelBox near{w, h, -1, -1};
    double tip = -std::numeric_limits<double>::infinity();
    for (int v = 0; v < h; ++v) {
      const float* row = d.data() + static_cast<size_t>(v) * w;
      const double r_v = ray_v(v);
      for (int u = 0; u < w; ++u) {
        if (u % kScanChunk == 0 && u + kScanChunk <= w && nothing_in(row + u)) {
          u += kScanChunk - 1;  // most of the image is outside the working volume
          continue;
        }
        if (row[u] <= 0.0F) continue;
        const Vector3d p = ray_point(u, r_v, row[u]);
        if ((p - centre).squaredNorm() > hand_radius * hand_radius) continue;
        out_.hand_mask[static_cast<size_t>(v) * w + u] = 1;
        near.add(u, v);
        tip = std::max(tip, p.dot(axis));
      }
    }
    const double cut = std::max(wrist.dot(axis) - kWristCutMarginMm, tip - kHandLengthMargin * config_.hand_length_mm);
    hand_box_ = PixelBox{w, h, -1, -1};
    hand_sum_ = Vector3d::Zero();
    int kept = 0;
    for (int v = near.v0; v <= near.v1; ++v) {
      const double r_v = ray_v(v);
      for (int u = near.u0; u <= near.u1; ++u) {
        const auto i = static_cast<size_t>(v) * w + u;
        if (!out_.hand_mask[i]) continue;
        const Vector3d p = ray_point(u, r_v, d[i]);
        if (p.dot(axis) < cut) {
          out_.hand_mask[i] = 0;
          continue;
        }
        hand_box_.add(u, v);
        hand_sum_ += p;
        ++kept;
      }
    }
    return kept;
  };
  const auto area_mm2 = [&](int pixels, double depth_mm) { return pixels * depth_mm * depth_mm / (cam.fx * cam.fy); };

  int count = found ? select() : 0;
  if (found && area_mm2(count, centre.z()) < config_.min_hand_area_mm2) found = false;

  if (!found) {
    // No usable hint: the nearest sizeable surface in the working volume is the hand (and maybe
    // its forearm). Label 4-connected surfaces whose neighbouring depths differ < continuity_mm.
    component_.assign(n, -1);
    struct Blob {
      int pixels = 0;
      double depth_sum = 0.0;
    };
    std::vector<Blob> blobs;
    for (size_t seed = 0; seed < n; ++seed) {
      if (d[seed] <= 0.0F || component_[seed] >= 0) continue;
      const int id = static_cast<int>(blobs.size());
      Blob blob;
      stack_.clear();
      stack_.push_back(static_cast<int>(seed));
      component_[seed] = id;
      while (!stack_.empty()) {
        const auto i = static_cast<size_t>(stack_.back());
        stack_.pop_back();
        ++blob.pixels;
        blob.depth_sum += d[i];
        const int u = static_cast<int>(i % w);
        const int v = static_cast<int>(i / w);
        const auto visit = [&](int uu, int vv) {
          if (uu < 0 || vv < 0 || uu >= w || vv >= h) return;
          const auto j = static_cast<size_t>(vv) * w + uu;
          if (component_[j] >= 0 || d[j] <= 0.0F || std::abs(d[j] - d[i]) >= config_.continuity_mm) return;
          component_[j] = id;
          stack_.push_back(static_cast<int>(j));
        };
        visit(u - 1, v);
        visit(u + 1, v);
        visit(u, v - 1);
        visit(u, v + 1);
      }
      blobs.push_back(blob);
    }
    int best = -1;
    double best_depth = std::numeric_limits<double>::infinity();
    for (size_t b = 0; b < blobs.size(); ++b) {
      const double mean = blobs[b].depth_sum / blobs[b].pixels;
      if (area_mm2(blobs[b].pixels, mean) < config_.min_hand_area_mm2) continue;
      if (mean < best_depth) {
        best_depth = mean;
        best = static_cast<int>(b);
      }
    }
    if (best < 0) {
      std::fill(out_.hand_mask.begin(), out_.hand_mask.end(), 0);
      out_.gaussians.clear();
      return;
    }
    // Principal axis of the blob; the hand is the end that does not leave the image (the arm
    // does), or, when neither or both do, the end nearer the camera.
    Vector3d mean = Vector3d::Zero();
    int pixels = 0;
    for (size_t i = 0; i < n; ++i) {
      if (component_[i] != best) continue;
      mean += point(i);
      ++pixels;
    }
    mean /= pixels;
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (size_t i = 0; i < n; ++i) {
      if (component_[i] != best) continue;
      const Vector3d q = point(i) - mean;
      cov += q * q.transpose();
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    axis = eig.eigenvectors().col(2);
    double lo = std::numeric_limits<double>::infinity();
    double hi = -lo;
    for (size_t i = 0; i < n; ++i) {
      if (component_[i] != best) continue;
      const double s = (point(i) - mean).dot(axis);
      lo = std::min(lo, s);
      hi = std::max(hi, s);
    }
    constexpr double kEndMm = 40.0;
    struct End {
      int border = 0;
      int pixels = 0;
      double depth = 0.0;
    } top, bottom;
    for (size_t i = 0; i < n; ++i) {
      if (component_[i] != best) continue;
      const double s = (point(i) - mean).dot(axis);
      End* end = s > hi - kEndMm ? &top : s < lo + kEndMm ? &bottom : nullptr;
      if (end == nullptr) continue;
      const int u = static_cast<int>(i % w);
      const int v = static_cast<int>(i / w);
      end->border += (u < kBorderPx || v < kBorderPx || u >= w - kBorderPx || v >= h - kBorderPx) ? 1 : 0;
      end->depth += d[i];
      ++end->pixels;
    }
    const bool top_is_hand = top.border != bottom.border ? top.border < bottom.border
                                                         : top.depth / std::max(1, top.pixels) <=
                                                               bottom.depth / std::max(1, bottom.pixels);
    if (!top_is_hand) {
      axis = -axis;
      std::swap(lo, hi);
      lo = -lo;
      hi = -hi;
    }
    // The palm centre is the hand pixel farthest from the hand's outline (the centre of the largest
    // inscribed disc): the palm is the widest part of a hand, open or closed, and wider than the
    // forearm. Search within one hand length of the tip.
    const double length = config_.hand_length_mm;
    std::vector<int>& dist = stack_;
    dist.assign(n, 0);
    for (size_t i = 0; i < n; ++i) {
      if (component_[i] == best && (point(i) - mean).dot(axis) >= hi - length) dist[i] = 1 << 20;
    }
    chamfer_distance(dist, w, h);
    const auto centre_px = static_cast<size_t>(std::max_element(dist.begin(), dist.end()) - dist.begin());
    centre = point(centre_px);
    // The wrist sits about half a palm below the palm centre.
    wrist = centre - axis * (kWristBelowPalmCentre * length);
    count = select();
    if (far_plane_cut_fraction(best) > kMaxFarPlaneCut) count = 0;
  }
  out_.hand_pixels = count;
  out_.finger_axis = axis;
  out_.palm_centre_mm = centre;
  out_.hand_centroid_mm = count > 0 ? Vector3d(hand_sum_ / count) : centre;
  if (area_mm2(count, out_.hand_centroid_mm.z()) < config_.min_hand_area_mm2) {
    std::fill(out_.hand_mask.begin(), out_.hand_mask.end(), 0);
    out_.hand_pixels = 0;
  }
}

double DepthInputBuilder::far_plane_cut_fraction(int blob) const {
  const int w = out_.camera.width;
  const int h = out_.camera.height;
  const auto far = static_cast<float>(config_.far_mm);
  const auto reach = static_cast<float>(config_.far_mm + config_.continuity_mm);
  int boundary = 0;
  int continued = 0;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      if (component_[static_cast<size_t>(v) * w + u] != blob) continue;
      bool edge = false;
      bool beyond = false;
      for (const auto& [du, dv] : {std::pair{-1, 0}, std::pair{1, 0}, std::pair{0, -1}, std::pair{0, 1}}) {
        const int uu = u + du;
        const int vv = v + dv;
        if (uu < 0 || vv < 0 || uu >= w || vv >= h) continue;
        const auto j = static_cast<size_t>(vv) * w + uu;
        if (component_[j] == blob) continue;
        edge = true;
        beyond = beyond || (unclamped_mm_[j] > far && unclamped_mm_[j] <= reach);
      }
      boundary += edge ? 1 : 0;
      continued += beyond ? 1 : 0;
    }
  }
  return boundary > 0 ? static_cast<double>(continued) / boundary : 0.0;
}

void DepthInputBuilder::build_quadtree() {
  out_.gaussians.clear();
  if (out_.hand_pixels == 0) return;
  const int w = out_.camera.width;
  const int root = scaled_px(config_.quadtree_root_px, w);
  // The smallest cell: the root halved while it is above the minimum leaf side (and even).
  int cell = root;
  while (cell > scaled_px(config_.quadtree_min_leaf_px, w) && cell % 2 == 0) cell /= 2;
  // Count, sum, min and max of the hand's depths per smallest cell over the roots that touch the
  // hand's bounding box, in one pass over the pixels; every quadtree node then aggregates cells
  // instead of rescanning its pixels.
  const PixelBox& box = hand_box_;
  cells_.x0 = (box.u0 / root) * root;
  cells_.y0 = (box.v0 / root) * root;
  cells_.side = cell;
  cells_.columns = ((box.u1 / root + 1) * root - cells_.x0) / cell;
  const int rows = ((box.v1 / root + 1) * root - cells_.y0) / cell;
  // Room for a grid over the whole image once per resolution: no allocation in the steady state.
  const auto whole_image = static_cast<size_t>((w / root + 1) * root / cell) *
                           static_cast<size_t>((out_.camera.height / root + 1) * root / cell);
  cells_.stats.reserve(whole_image);
  cells_.stats.assign(static_cast<size_t>(cells_.columns) * static_cast<size_t>(rows), CellStats{});
  for (int v = box.v0; v <= box.v1; ++v) {
    for (int u = box.u0; u <= box.u1; ++u) {
      const auto i = static_cast<size_t>(v) * w + u;
      if (!out_.hand_mask[i]) continue;
      cells_.at((u - cells_.x0) / cell, (v - cells_.y0) / cell).add(out_.filtered_mm[i]);
    }
  }
  for (int y = cells_.y0; y <= box.v1; y += root) {
    for (int x = cells_.x0; x <= box.u1; x += root) quad(x, y, root);
  }
}

void DepthInputBuilder::quad(int x, int y, int side) {
  const int w = out_.camera.width;
  const int h = out_.camera.height;
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
  const bool full_enough = count >= config_.min_leaf_fill * area;
  const bool flat = node.hi - node.lo < config_.quadtree_threshold_mm;
  if (side > cells_.side && !(flat && full_enough)) {
    const int half = side / 2;
    quad(x, y, half);
    quad(x + half, y, half);
    quad(x, y + half, half);
    quad(x + half, y + half, half);
    return;
  }
  if (!full_enough) return;
  ImageGaussian g;
  g.u = x + 0.5 * side - 0.5;  // pixel centres are at integer coordinates
  g.v = y + 0.5 * side - 0.5;
  g.sigma_px = side / std::sqrt(2.0);  // Sec. 3.1: sigma = a / sqrt(2)
  g.depth_mm = node.sum / count;
  g.side_px = side;
  const auto& labels = out_.pixel_labels;
  if (!labels.empty()) {
    std::array<int, kNumPartLabels + 1> votes{};
    for (int v = y; v < ye; ++v) {
      for (int u = x; u < xe; ++u) {
        const auto i = static_cast<size_t>(v) * w + u;
        if (out_.hand_mask[i] && labels[i] <= kNumPartLabels) ++votes[labels[i]];
      }
    }
    g.label = static_cast<int>(std::max_element(votes.begin() + 1, votes.end()) - votes.begin());
    if (votes[static_cast<size_t>(g.label)] == 0) g.label = 0;
  }
  out_.gaussians.push_back(g);
}

void FixedLabels::label(const DepthInput& input, std::vector<uint8_t>& labels) const {
  labels.assign(input.hand_mask.size(), 0);
  if (labels_ == nullptr || labels_->size() != labels.size()) return;
  for (size_t i = 0; i < labels.size(); ++i) labels[i] = input.hand_mask[i] ? (*labels_)[i] : uint8_t{0};
}

double image_self_similarity(const std::vector<ImageGaussian>& gaussians) {
  // E(C_I,C_I) = sum_p sum_q D_pq, D_pq = 2 pi s_p^2 s_q^2 / S exp(-|mu_p - mu_q|^2 / 2S),
  // S = s_p^2 + s_q^2 (eq. 3, unit weights): D_pp = pi s_p^2 and D_pq = D_qp, so each unordered pair
  // is summed once and counted twice. Sorted by u, the partners q > p of p that can be in reach lie
  // in one run |u_q - u_p| <= sqrt(2 S_max kPairCutoff).
  thread_local std::vector<double> us, vs, s2s;  // reused: no allocation once grown
  thread_local std::vector<size_t> order;
  for (auto* column : {&us, &vs, &s2s}) column->reserve(kReservedLeaves);
  order.reserve(kReservedLeaves);
  order.resize(gaussians.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return gaussians[a].u < gaussians[b].u; });
  us.clear();
  vs.clear();
  s2s.clear();
  double s2_max = 0.0;
  for (const size_t i : order) {
    us.push_back(gaussians[i].u);
    vs.push_back(gaussians[i].v);
    s2s.push_back(gaussians[i].sigma_px * gaussians[i].sigma_px);
    s2_max = std::max(s2_max, s2s.back());
  }
  double diagonal = 0.0;
  double pairs = 0.0;
  for (size_t p = 0; p < us.size(); ++p) {
    diagonal += std::numbers::pi * s2s[p];
    const double reach = std::sqrt(2.0 * kPairCutoff * (s2s[p] + s2_max));
    const auto first = us.begin() + static_cast<std::ptrdiff_t>(p) + 1;
    const auto n = static_cast<size_t>(std::upper_bound(first, us.end(), us[p] + reach) - first);
    pairs += pair_run(us.data() + p + 1, vs.data() + p + 1, s2s.data() + p + 1, n, us[p], vs[p], s2s[p]);
  }
  return diagonal + 2.0 * 2.0 * std::numbers::pi * pairs;
}

}  // namespace handtrack
