#include "hand_splitter.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace handtrack {

namespace {

using Eigen::Vector3d;

// A tracked hand claims a surface when at least kMinClaimSamples of its sampled pixels lie within
// kClaimMm of the hand's last skeleton: the bones run through the fingers' and the palm's middle,
// about one finger or half a palm thickness (8-15 mm) below the surface, and the hand moves up to
// ~20 mm between frames at 60 fps in the fast halves of the synthetic motions.
constexpr double kClaimMm = 40.0;
constexpr int kMinClaimSamples = 4;
// Pixels are sampled every kSampleStridePx (at 320 px width; scaled with the width) to find the
// claims; the pixels of shared surfaces are each assigned.
constexpr int kSampleStridePx = 3;
// A new surface whose centroid is this near where one was found to be no hand is not tried again
// (HandsTracker keeps those places for TrackerConfig::new_hand_retry_frames).
constexpr double kRejectedRadiusMm = 60.0;

Vector3d unproject(const CameraIntrinsics& cam, int u, int v, float z) {
  return cam.unproject(static_cast<double>(u), static_cast<double>(v), z);
}

}  // namespace

Skeleton::Skeleton(const Joints& joints) {
  // Joint order (SPEC.md): wrist, then per finger (thumb..little) MCP/CMC, PIP, DIP, TIP.
  int b = 0;
  for (int f = 0; f < kNumFingers; ++f) {
    int parent = 0;
    for (int k = 0; k < 4; ++k) {
      const int child = 1 + 4 * f + k;
      const auto i = static_cast<size_t>(b);
      const Vector3d& from = joints[static_cast<size_t>(parent)];
      const Vector3d along = joints[static_cast<size_t>(child)] - from;
      from_x_[i] = from.x();
      from_y_[i] = from.y();
      from_z_[i] = from.z();
      along_x_[i] = along.x();
      along_y_[i] = along.y();
      along_z_[i] = along.z();
      const double l2 = along.squaredNorm();
      inverse_length2_[i] = l2 > 0.0 ? 1.0 / l2 : 0.0;
      parent = child;
      ++b;
    }
  }
  for (const auto& j : joints) centre_ += j;
  centre_ /= static_cast<double>(joints.size());
  for (const auto& j : joints) radius_ = std::max(radius_, (j - centre_).norm());
}

// Nearest point of bone a + t (b - a), t in [0, 1]: t = (p - a).(b - a) / |b - a|^2, clamped.
[[gnu::always_inline]] inline double Skeleton::bone_distance2(size_t b, double px, double py, double pz) const {
  const double ax = px - from_x_[b];
  const double ay = py - from_y_[b];
  const double az = pz - from_z_[b];
  const double t = std::clamp((ax * along_x_[b] + ay * along_y_[b] + az * along_z_[b]) * inverse_length2_[b], 0.0, 1.0);
  const double rx = ax - t * along_x_[b];
  const double ry = ay - t * along_y_[b];
  const double rz = az - t * along_z_[b];
  return rx * rx + ry * ry + rz * rz;
}

double Skeleton::distance2(const Vector3d& p) const {
  double best = std::numeric_limits<double>::infinity();
  const double px = p.x();
  const double py = p.y();
  const double pz = p.z();
#pragma omp simd reduction(min : best)
  for (size_t b = 0; b < static_cast<size_t>(kBones); ++b) best = std::min(best, bone_distance2(b, px, py, pz));
  return best;
}

bool Skeleton::within(const Vector3d& p, double r2) const {
  for (size_t b = 0; b < static_cast<size_t>(kBones); ++b) {
    if (bone_distance2(b, p.x(), p.y(), p.z()) < r2) return true;
  }
  return false;
}

HandSplitter::HandSplitter() {
  surfaces_.reserve(kReservedSurfaces);
  claims_.reserve(kReservedSurfaces);
  ownership_.reserve(kReservedSurfaces);
  owner_.reserve(kReservedSurfaces);
  unclaimed_.reserve(kReservedSurfaces);
  skeletons_.reserve(kMaxHands);
}

void HandSplitter::claim(const DepthInputConfig& config, const CameraIntrinsics& cam, const HandsRequest& request) {
  const int w = cam.width;
  const int h = cam.height;
  skeletons_.clear();
  for (int s = 0; s < kMaxHands; ++s) {
    const auto& slot = request.slots[static_cast<size_t>(s)];
    skeleton_of_[static_cast<size_t>(s)] = -1;
    if (s >= request.max_hands || !slot.active) continue;
    skeleton_of_[static_cast<size_t>(s)] = static_cast<int>(skeletons_.size());
    skeletons_.emplace_back(slot.joints);
  }
  claims_.assign(surfaces_.size(), Claims{});
  const int stride = std::max(1, kSampleStridePx * w / 320);
  const double claim2 = kClaimMm * kClaimMm;
  for (int v = 0; v < h; v += stride) {
    for (int u = 0; u < w; u += stride) {
      const auto i = static_cast<size_t>(v) * w + u;
      const int c = component_[i];
      if (c < 0) continue;
      const Vector3d p = unproject(cam, u, v, volume_[i]);
      Claims& claims = claims_[static_cast<size_t>(c)];
      ++claims.sampled;
      claims.point_sum += p;
      for (int s = 0; s < kMaxHands; ++s) {
        const int k = skeleton_of_[static_cast<size_t>(s)];
        if (k < 0) continue;
        const Skeleton& sk = skeletons_[static_cast<size_t>(k)];
        const double reach = sk.radius() + kClaimMm;
        if ((p - sk.centre()).squaredNorm() > reach * reach) continue;
        if (sk.within(p, claim2)) ++claims.samples[static_cast<size_t>(s)];
      }
    }
  }
  owner_.assign(surfaces_.size(), kNone);
  for (size_t c = 0; c < surfaces_.size(); ++c) {
    for (int s = 0; s < kMaxHands; ++s) {
      if (claims_[c].samples[static_cast<size_t>(s)] < kMinClaimSamples) continue;
      owner_[c] = owner_[c] == kNone ? s : kShared;
    }
  }
  // A tracked hand that moved farther than the claim distance since its last pose still keeps the
  // unclaimed sizeable surface nearest to it, within one hand length of where it was.
  for (int s = 0; s < kMaxHands; ++s) {
    const int k = skeleton_of_[static_cast<size_t>(s)];
    if (k < 0 || std::find(owner_.begin(), owner_.end(), s) != owner_.end()) continue;
    bool shares = false;
    for (size_t c = 0; c < surfaces_.size(); ++c) {
      shares = shares || (owner_[c] == kShared && claims_[c].samples[static_cast<size_t>(s)] >= kMinClaimSamples);
    }
    if (shares) continue;
    int nearest = -1;
    double nearest_mm = config.hand_length_mm;
    for (size_t c = 0; c < surfaces_.size(); ++c) {
      if (owner_[c] != kNone || claims_[c].sampled == 0) continue;
      const Vector3d centroid = claims_[c].point_sum / claims_[c].sampled;
      const double d = (centroid - skeletons_[static_cast<size_t>(k)].centre()).norm();
      if (d < nearest_mm &&
          surface_area_mm2(cam, surfaces_[c].pixels, surfaces_[c].mean_depth()) >= config.min_hand_area_mm2) {
        nearest = static_cast<int>(c);
        nearest_mm = d;
      }
    }
    if (nearest >= 0) owner_[static_cast<size_t>(nearest)] = s;
  }
}

void HandSplitter::split(const DepthInputConfig& config, const DepthImage& depth, const HandsRequest& request,
                         std::array<std::vector<uint8_t>, kMaxHands>& foreign, std::array<FrameShare, kMaxHands>& share,
                         std::array<std::optional<Vector3d>, kMaxHands>& candidate) {
  const CameraIntrinsics& cam = depth.camera;
  const int w = cam.width;
  const int h = cam.height;
  const auto n = static_cast<size_t>(w) * h;
  // Every slot's mask sized on the first frame, not on the first frame that needs it (a pipeline
  // frame's first second hand may come long after start-up).
  for (auto& mask : foreign) mask.resize(n);
  body_.reserve(w, h);  // and the body eraser's room, though a body may come later
  // The surfaces of the median-filtered working volume (as HandSegmenter sees them: flying pixels
  // between two hands would otherwise join them).
  const std::vector<float>& median = median_.apply(depth, config.median_radius_px);
  volume_.resize(n);
  const auto near = static_cast<float>(config.near_mm);
  const auto far = static_cast<float>(config.far_mm);
  for (size_t i = 0; i < n; ++i) volume_[i] = (median[i] >= near && median[i] <= far) ? median[i] : 0.0F;
  // A desk the hands rest on joins them into one surface with it (support_plane.hpp).
  if (support_plane_.find(config.support_plane, cam, volume_)) support_plane_.erase(cam, volume_);
  label_surfaces(config, volume_, w, h, component_, stack_, surfaces_);
  claim(config, cam, request);
  // A free slot's new hand is not a body: the parts wider than a hand of the surfaces no hand claims
  // leave the volume (body_eraser.hpp), and what reaches out of them is labelled on its own. (A
  // claimed surface stays whole: a tracked hand keeps its surface as it finds it.)
  bool free_slot = false;
  for (int s = 0; s < request.max_hands; ++s) free_slot = free_slot || !request.slots[static_cast<size_t>(s)].active;
  if (free_slot) {
    unclaimed_.resize(surfaces_.size());
    for (size_t c = 0; c < surfaces_.size(); ++c) unclaimed_[c] = owner_[c] == kNone ? 1 : 0;
    if (body_.find(config, cam, volume_, component_, surfaces_, &unclaimed_)) {
      body_.erase(volume_);
      label_surfaces(config, volume_, w, h, component_, stack_, surfaces_);
      claim(config, cam, request);
    }
  }

  // Each slot's surface(s): an active slot its claimed ones, a free slot one new one.
  std::array<int, kMaxHands> new_surface{};
  new_surface.fill(kNone);
  // The free slots' candidates, nearest first: big enough, not a body reaching through the far
  // plane, not where a surface was recently found to be no hand.
  std::vector<int>& order = stack_;
  order.clear();
  const bool hand_tracked = !skeletons_.empty();
  for (size_t c = 0; c < surfaces_.size(); ++c) {
    const Surface& s = surfaces_[c];
    if (owner_[c] != kNone || claims_[c].sampled == 0) continue;
    if (surface_area_mm2(cam, s.pixels, s.mean_depth()) < config.min_hand_area_mm2) continue;
    // While a hand is tracked, a surface the far plane cuts is taken for its forearm, cut off from
    // it by the depth step at the wrist, whatever its reach: that forearm comes as near as the hand
    // does (a phantom second hand on it in 80 % of the frames of random, subjects 1 and 2, with
    // the reach's exception), and a second hand held that far is the rarer sight.
    const FarPlaneCut cut = far_plane_cut(config, median, component_, static_cast<int>(c), w, h);
    if (hand_tracked ? cut.share > kMaxFarPlaneCut : reaches_in_through_far_plane(config, cut)) continue;
    const Vector3d centroid = claims_[c].point_sum / claims_[c].sampled;
    bool rejected = false;
    for (int r = 0; r < request.rejected_count; ++r) {
      rejected = rejected || (centroid - request.rejected[static_cast<size_t>(r)]).norm() < kRejectedRadiusMm;
    }
    if (!rejected) order.push_back(static_cast<int>(c));
  }
  std::sort(order.begin(), order.end(),
            [&](int a, int b) { return surfaces_[static_cast<size_t>(a)].mean_depth() < surfaces_[static_cast<size_t>(b)].mean_depth(); });
  size_t next = 0;
  int fitted = 0;
  for (int s = 0; s < kMaxHands; ++s) {
    const auto& slot = request.slots[static_cast<size_t>(s)];
    candidate[static_cast<size_t>(s)].reset();
    share[static_cast<size_t>(s)] = s < request.max_hands && slot.active ? FrameShare::kOwn : FrameShare::kNothing;
    if (s < request.max_hands && !slot.active && next < order.size()) {
      const int c = order[next++];
      new_surface[static_cast<size_t>(s)] = c;
      share[static_cast<size_t>(s)] = FrameShare::kOwn;
      const Claims& claims = claims_[static_cast<size_t>(c)];
      candidate[static_cast<size_t>(s)] = Vector3d(claims.point_sum / claims.sampled);
    }
    fitted += share[static_cast<size_t>(s)] == FrameShare::kOwn ? 1 : 0;
  }
  // One hand to fit and nothing else sizeable in the working volume: the whole frame, so that one
  // hand is tracked exactly as by a Tracker alone (masking the frame changes the median filter at the
  // hand's outline, and a tracker is chaotic enough for that to move whole sequences by mm).
  if (fitted == 1) {
    const auto only = static_cast<int>(std::find(share.begin(), share.end(), FrameShare::kOwn) - share.begin());
    bool alone = true;
    for (size_t c = 0; c < surfaces_.size(); ++c) {
      const bool sizeable = surface_area_mm2(cam, surfaces_[c].pixels, surfaces_[c].mean_depth()) >= config.min_hand_area_mm2;
      const bool its_own = owner_[c] == only || static_cast<int>(c) == new_surface[static_cast<size_t>(only)];
      alone = alone && (!sizeable || its_own);
    }
    if (alone) {
      share[static_cast<size_t>(only)] = FrameShare::kWhole;
      return;
    }
  }

  // Each slot's foreign mask. Per surface and slot: the slot's, foreign, or (a surface touching
  // hands share) each pixel to the hand whose skeleton is nearest.
  ownership_.resize(surfaces_.size());
  for (size_t c = 0; c < surfaces_.size(); ++c) {
    Ownership& own = ownership_[c];
    own.touching = false;
    for (size_t s = 0; s < kMaxHands; ++s) {
      const int fresh = new_surface[s];
      const bool claims = claims_[c].samples[s] >= kMinClaimSamples;
      own.claimant[s] = skeleton_of_[s] >= 0 && claims;
      const bool nearest = fresh < 0 && owner_[c] == kShared && claims;
      own.slot[s] =
          nearest ? kNearest : ((fresh >= 0 ? static_cast<int>(c) == fresh : owner_[c] == static_cast<int>(s)) ? kMine : kForeign);
      own.touching = own.touching || nearest;
    }
  }
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const auto i = static_cast<size_t>(v) * w + u;
      const int c = component_[i];
      const Ownership* own = c < 0 ? nullptr : &ownership_[static_cast<size_t>(c)];
      // A touching pixel: its distance to the skeleton of each hand that claims its surface.
      std::array<double, kMaxHands> distance2{};
      if (own != nullptr && own->touching) {
        const Vector3d p = unproject(cam, u, v, volume_[i]);
        for (size_t s = 0; s < kMaxHands; ++s) {
          if (own->claimant[s]) distance2[s] = skeletons_[static_cast<size_t>(skeleton_of_[s])].distance2(p);
        }
      }
      for (size_t s = 0; s < kMaxHands; ++s) {
        if (share[s] != FrameShare::kOwn) continue;
        const uint8_t d = own == nullptr ? kForeign : own->slot[s];
        bool keep = d == kMine;
        if (d == kNearest) {  // the pixel is the hand's unless another claimant's skeleton is nearer
          keep = true;
          for (size_t o = 0; o < kMaxHands; ++o) {
            if (o != s && own->claimant[o]) keep = keep && distance2[s] <= distance2[o];
          }
        }
        foreign[s][i] = keep ? 0 : 1;
      }
    }
  }
}

}  // namespace handtrack
