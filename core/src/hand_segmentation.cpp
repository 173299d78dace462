#include "hand_segmentation.hpp"

#include "chamfer.hpp"

#include "handtrack/core/hand_model.hpp"

#include <Eigen/Eigenvalues>

#include <cmath>

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
// Pixels this close to the image border mark the end of a blob where the arm leaves the image.
constexpr int kBorderPx = 3;
// A surface whose ends tie (neither or both leave the image) may be a hand without its arm; it is
// read as one where it is longer than a fist (an adult fist from the wrist to the knuckles is
// 100-110 mm, 0.6 hand lengths) and no longer than this many hand lengths. Along its principal
// axis a hand alone measures its own length plus about 20 mm (the heel of the palm, the tip's
// skin): 1.10 lengths for a hand 7 % longer than the model's; a hand with its forearm going away
// behind fingers that point at the camera measured 1.14-1.6 (docs/TRACKER.md, "A hand without
// its arm").
constexpr double kFistInLengths = 0.6;
constexpr double kHandAloneInLengths = 1.25;
// There the fingers are the end farther from the palm only where the two ends' distances from it
// differ by at least this (mm); otherwise the end nearer the camera is the hand, as for an arm.
constexpr double kEndsAlikeMm = 20.0;

// Whether a 4-neighbour of pixel (u, v) has a measured depth nearer than the working volume: the
// surface leaves the volume toward the camera there.
bool beside_near_plane(const DepthInputConfig& config, const std::vector<float>& unclamped_mm, int w, int h, int u,
                       int v) {
  const auto near = static_cast<float>(config.near_mm);
  for (const auto& [du, dv] : {std::pair{-1, 0}, std::pair{1, 0}, std::pair{0, -1}, std::pair{0, 1}}) {
    const int uu = u + du;
    const int vv = v + dv;
    if (uu < 0 || vv < 0 || uu >= w || vv >= h) continue;
    const float z = unclamped_mm[static_cast<size_t>(vv) * w + uu];
    if (z > 0.0F && z < near) return true;
  }
  return false;
}

// Pixels checked at once when scanning for depth in the working volume (0 outside it).
constexpr int kScanChunk = 16;

// True when none of the kScanChunk depths from `d` is in the working volume: one vectorised max.
bool nothing_in(const float* d) {
  float m = 0.0F;
  for (int k = 0; k < kScanChunk; ++k) m = std::max(m, d[k]);
  return m <= 0.0F;
}

}  // namespace

void HandSegmenter::segment(const DepthInputConfig& config, const std::vector<float>& unclamped_mm,
                            const std::optional<HandHint>& hint, DepthInput& out, const std::vector<uint8_t>* foreign) {
  const auto& cam = out.camera;
  const int w = cam.width;
  const int h = cam.height;
  const auto n = static_cast<size_t>(w) * h;
  // The surfaces this hand may be segmented from: the filtered depth, without the foreign pixels
  // (out.filtered_mm keeps them: they still hide what is behind them).
  own_mm_.resize(n);  // on the first frame, not on the first with foreign pixels (no allocation later)
  // And the start path's buffers (label_surfaces below), so that the first check that segments
  // afresh, many frames on, does not allocate either.
  component_.resize(n);
  blobs_.reserve(n);
  stack_.reserve(n);
  body_.reserve(w, h);
  // The frame shared out among hands: this slot's pixels are those not foreign.
  const bool shared_out = foreign != nullptr && foreign->size() == n;
  if (shared_out) {
    for (size_t i = 0; i < n; ++i) own_mm_[i] = (*foreign)[i] != 0 ? 0.0F : out.filtered_mm[i];
  }
  // What is segmented: the filtered depth, or own_mm_ where it differs (foreign pixels, a body).
  const std::vector<float>* segmented = shared_out ? &own_mm_ : &out.filtered_mm;
  out.hand_mask.assign(n, 0);
  out.hand_pixels = 0;
  const auto point = [&](size_t i) {
    return cam.unproject(static_cast<double>(i % w), static_cast<double>(i / w), (*segmented)[i]);
  };
  const double hand_radius = kHandRadiusInLengths * config.hand_length_mm;

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
    std::fill(out.hand_mask.begin(), out.hand_mask.end(), 0);
    ray_u_.resize(static_cast<size_t>(w));
    for (int u = 0; u < w; ++u) ray_u_[static_cast<size_t>(u)] = (u - cam.cx) / cam.fx;
    PixelBox near{w, h, -1, -1};
    double tip = -std::numeric_limits<double>::infinity();
    for (int v = 0; v < h; ++v) {
      const float* row = segmented->data() + static_cast<size_t>(v) * w;
      const double r_v = ray_v_of(cam, v);
      for (int u = 0; u < w; ++u) {
        if (u % kScanChunk == 0 && u + kScanChunk <= w && nothing_in(row + u)) {
          u += kScanChunk - 1;  // most of the image is outside the working volume
          continue;
        }
        if (row[u] <= 0.0F) continue;
        const Vector3d p = ray_point(u, r_v, row[u]);
        if ((p - centre).squaredNorm() > hand_radius * hand_radius) continue;
        out.hand_mask[static_cast<size_t>(v) * w + u] = 1;
        near.add(u, v);
        tip = std::max(tip, p.dot(axis));
      }
    }
    const double cut = std::max(wrist.dot(axis) - kWristCutMarginMm, tip - kHandLengthMargin * config.hand_length_mm);
    hand_box_ = PixelBox{w, h, -1, -1};
    hand_sum_ = Vector3d::Zero();
    int kept = 0;
    for (int v = near.v0; v <= near.v1; ++v) {
      const double r_v = ray_v_of(cam, v);
      for (int u = near.u0; u <= near.u1; ++u) {
        const auto i = static_cast<size_t>(v) * w + u;
        if (!out.hand_mask[i]) continue;
        const Vector3d p = ray_point(u, r_v, (*segmented)[i]);
        if (p.dot(axis) < cut) {
          out.hand_mask[i] = 0;
          continue;
        }
        hand_box_.add(u, v);
        hand_sum_ += p;
        ++kept;
      }
    }
    return keep_near_palm(config, cam, *segmented, centre, out.hand_mask, kept);
  };
  const auto area_mm2 = [&](int pixels, double depth_mm) { return surface_area_mm2(cam, pixels, depth_mm); };

  int count = found ? select() : 0;
  if (found && area_mm2(count, centre.z()) < config.min_hand_area_mm2) found = false;

  if (!found) {
    // No usable hint: the nearest sizeable surface in the working volume is the hand (and maybe
    // its forearm). Label 4-connected surfaces whose neighbouring depths differ < continuity_mm.
    label_surfaces(config, *segmented, w, h, component_, stack_, blobs_);
    // A body in the volume: its parts wider than a hand are not the hand (body_eraser.hpp).
    if (body_.find(config, cam, *segmented, component_, blobs_)) {
      if (segmented != &own_mm_) std::copy(out.filtered_mm.begin(), out.filtered_mm.end(), own_mm_.begin());
      segmented = &own_mm_;
      body_.erase(own_mm_);
      label_surfaces(config, own_mm_, w, h, component_, stack_, blobs_);
    }
    // Where the frame was shared out among hands, the hand is the largest of the slot's own
    // sizeable surfaces instead: touching hands are split pixel by pixel, which can leave a slot a
    // sliver of the other hand nearer the camera than its own.
    int best = -1;
    double best_depth = std::numeric_limits<double>::infinity();
    double best_area = 0.0;
    for (size_t b = 0; b < blobs_.size(); ++b) {
      const double mean = blobs_[b].mean_depth();
      const double area = area_mm2(blobs_[b].pixels, mean);
      if (area < config.min_hand_area_mm2) continue;
      if (shared_out ? area > best_area : mean < best_depth) {
        best_depth = mean;
        best_area = area;
        best = static_cast<int>(b);
      }
    }
    if (best < 0) {
      std::fill(out.hand_mask.begin(), out.hand_mask.end(), 0);
      out.gaussians.clear();
      return;
    }
    // Principal axis of the blob; the hand is the end that does not leave the image or the working
    // volume through its near plane (the arm does: a head-mounted camera sees the forearm come from
    // below the near plane), or, when neither or both do, the end nearer the camera.
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
      end->border += (u < kBorderPx || v < kBorderPx || u >= w - kBorderPx || v >= h - kBorderPx ||
                      beside_near_plane(config, unclamped_mm, w, h, u, v))
                         ? 1
                         : 0;
      end->depth += (*segmented)[i];
      ++end->pixels;
    }
    const double length = config.hand_length_mm;
    std::vector<int>& dist = stack_;
    // Each pixel of the blob among those `in` gets its chamfer distance to their outline (about 3 x
    // pixels); returns the pixel where `weight(i) * dist[i]` is largest.
    const auto widest = [&](const auto& in, const auto& weight) {
      dist.assign(n, 0);
      for (size_t i = 0; i < n; ++i) {
        if (component_[i] == best && in(i)) dist[i] = 1 << 20;
      }
      chamfer_transform(dist, w, h, 0, [&](size_t i) { return dist[i] != 0; });
      size_t at = 0;
      double most = 0.0;
      for (size_t i = 0; i < n; ++i) {
        const double d = weight(i) * dist[i];
        if (d > most) {
          most = d;
          at = i;
        }
      }
      return at;
    };
    bool top_is_hand = top.border < bottom.border;
    if (top.border == bottom.border) {
      // Neither end leaves the image or the volume (or both do). A hand without its arm (a
      // renderer's hand model cut at the wrist) has its fingers at the end farther from its widest
      // part, the palm: an open hand's middle fingertip about 0.75 hand lengths from the palm
      // centre, the wrist 0.25. Widths in mm here (pixels x depth): in pixels the end nearer the
      // camera looks widest. Otherwise (a forearm going back through the far plane, or seen along
      // its length behind fingers that point at the camera; a fist), the hand is the end nearer the
      // camera. So too in a frame shared out among hands, where a surface may be a hand whose
      // forearm the other hand hides: with the rule there, the two-hand scenes' left hands lost
      // 0.2 mm and two more frames (seeds 1-3).
      top_is_hand = top.depth / std::max(1, top.pixels) <= bottom.depth / std::max(1, bottom.pixels);
      if (!shared_out && hi - lo > kFistInLengths * length && hi - lo <= kHandAloneInLengths * length) {
        const auto all = [](size_t) { return true; };
        const double s = (point(widest(all, [&](size_t i) { return (*segmented)[i]; })) - mean).dot(axis);
        const double to_top = hi - s;
        const double to_bottom = s - lo;
        if (std::abs(to_top - to_bottom) >= kEndsAlikeMm) top_is_hand = to_top > to_bottom;
      }
    }
    if (!top_is_hand) {
      axis = -axis;
      std::swap(lo, hi);
      lo = -lo;
      hi = -hi;
    }
    // The palm centre is the hand pixel farthest from the hand's outline (the centre of the largest
    // inscribed disc), within one hand length of the tip: the palm is the widest part of a hand, open
    // or closed, and wider than the forearm. (In pixels: weighting by depth, to compare widths in mm,
    // put the centre on the forearm behind a fist; docs/TRACKER.md "Segmentation".)
    centre = point(widest([&](size_t i) { return (point(i) - mean).dot(axis) >= hi - length; },
                          [](size_t) { return 1.0; }));
    // The wrist sits about half a palm below the palm centre.
    wrist = centre - axis * (kWristBelowPalmCentre * length);
    count = select();
    if (reaches_in_through_far_plane(config, far_plane_cut(config, unclamped_mm, component_, best, w, h))) count = 0;
  }
  out.hand_pixels = count;
  out.finger_axis = axis;
  out.palm_centre_mm = centre;
  out.hand_centroid_mm = count > 0 ? Vector3d(hand_sum_ / count) : centre;
  if (area_mm2(count, out.hand_centroid_mm.z()) < config.min_hand_area_mm2) {
    std::fill(out.hand_mask.begin(), out.hand_mask.end(), 0);
    out.hand_pixels = 0;
  }
}

int HandSegmenter::keep_near_palm(const DepthInputConfig& config, const CameraIntrinsics& cam,
                                  const std::vector<float>& depth, const Eigen::Vector3d& centre,
                                  std::vector<uint8_t>& mask, int kept) {
  // The mask's connected parts (neighbours closer than continuity_mm) that come within
  // kNearPalmInLengths hand lengths of the palm centre are the hand: a sizeable part beyond, however
  // near the hand's sphere it reaches, is something else (a head or a torso behind the hand,
  // another object), which the sphere alone let in (docs/TRACKER.md, "A body in the working
  // volume"). The parts reached from the pixels near the palm are marked 2.
  if (kept == 0) return 0;
  const int w = cam.width;
  const PixelBox box = hand_box_;
  const double near2 = std::pow(kNearPalmInLengths * config.hand_length_mm, 2);
  const auto point = [&](int u, int v, float d) { return ray_point(u, ray_v_of(cam, v), d); };
  stack_.reserve(mask.size());  // every pixel at most once: no allocation once a frame was seen
  part_.reserve(mask.size());
  // Floods from the pixels on stack_ through their 4-neighbours in the box that are still 1 and
  // continuous in depth, marking them `mark`; `visit` sees each pixel flooded.
  const auto flood = [&](uint8_t mark, const auto& visit) {
    flood4(
        box, w, stack_,
        [&](size_t j, size_t i) {
          if (mask[j] != 1 || std::abs(depth[j] - depth[i]) >= config.continuity_mm) return false;
          mask[j] = mark;
          return true;
        },
        visit);
  };
  stack_.clear();
  for (int v = box.v0; v <= box.v1; ++v) {
    for (int u = box.u0; u <= box.u1; ++u) {
      const auto i = static_cast<size_t>(v) * w + u;
      if (mask[i] != 1 || (point(u, v, depth[i]) - centre).squaredNorm() > near2) continue;
      mask[i] = 2;
      stack_.push_back(static_cast<int>(i));
    }
  }
  flood(2, [](size_t) {});
  // The parts not reached: each one leaves when it is sizeable (min_hand_area_mm2: a head, a
  // torso), while specks of noise and flying pixels stay as they were (marked 3 once looked at).
  int dropped = 0;
  for (int v = box.v0; v <= box.v1; ++v) {
    for (int u = box.u0; u <= box.u1; ++u) {
      const auto seed = static_cast<size_t>(v) * w + u;
      if (mask[seed] != 1) continue;
      part_.clear();
      stack_.assign(1, static_cast<int>(seed));
      mask[seed] = 3;
      double area = 0.0;
      flood(3, [&](size_t i) {
        part_.push_back(static_cast<int>(i));
        area += surface_area_mm2(cam, 1, depth[i]);
      });
      if (area < config.min_hand_area_mm2) continue;
      for (const int i : part_) {
        mask[static_cast<size_t>(i)] = 0;
        hand_sum_ -= point(static_cast<int>(i % w), static_cast<int>(i / w), depth[static_cast<size_t>(i)]);
      }
      dropped += static_cast<int>(part_.size());
    }
  }
  // Back to 1; the box shrinks to what stays (unchanged when nothing left).
  PixelBox stays{w, cam.height, -1, -1};
  for (int v = box.v0; v <= box.v1; ++v) {
    for (int u = box.u0; u <= box.u1; ++u) {
      const auto i = static_cast<size_t>(v) * w + u;
      if (mask[i] == 0) continue;
      mask[i] = 1;
      stays.add(u, v);
    }
  }
  if (dropped > 0) hand_box_ = stays;
  return kept - dropped;
}

}  // namespace handtrack
