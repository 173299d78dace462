#pragma once
// HandSplitter: shares out one frame's depth among the hand slots of a HandsTracker (the steps in
// hands_tracker.hpp): connected surfaces, claimed by the tracked hands near whose last skeleton
// they lie, split pixel by pixel between hands that touch, and the nearest unclaimed surface that
// could be a hand for each free slot. Private to core (HandsInputs); its scratch is reused from
// frame to frame.
#include "body_eraser.hpp"
#include "surfaces.hpp"
#include "median_filter.hpp"
#include "support_plane.hpp"

#include "handtrack/core/hands_tracker.hpp"

#include <Eigen/Core>

#include <array>
#include <optional>
#include <vector>

namespace handtrack {

// A hand's last pose as line segments (its bones: wrist to each finger's base, then along each
// finger), for the distance of a point to the hand.
class Skeleton {
 public:
  explicit Skeleton(const Joints& joints);
  // Squared distance (mm^2) of p to the nearest bone.
  [[nodiscard]] double distance2(const Eigen::Vector3d& p) const;
  // Whether some bone is nearer to p than sqrt(r2) (stops at the first).
  [[nodiscard]] bool within(const Eigen::Vector3d& p, double r2) const;
  // A sphere around all joints.
  [[nodiscard]] const Eigen::Vector3d& centre() const { return centre_; }
  [[nodiscard]] double radius() const { return radius_; }

 private:
  static constexpr int kBones = 4 * kNumFingers;
  [[nodiscard]] double bone_distance2(size_t bone, double px, double py, double pz) const;
  // Bone b runs from from_*[b] by along_*[b] (structure of arrays: distance2() is one vector loop).
  std::array<double, kBones> from_x_{}, from_y_{}, from_z_{};
  std::array<double, kBones> along_x_{}, along_y_{}, along_z_{};
  std::array<double, kBones> inverse_length2_{};
  Eigen::Vector3d centre_ = Eigen::Vector3d::Zero();
  double radius_ = 0.0;
};

class HandSplitter {
 public:
  HandSplitter();
  // Writes share[i], foreign[i] for kOwn (1 for every pixel that is not slot i's) and, for a free
  // slot taking a new surface, that surface's centroid into candidate[i].
  void split(const DepthInputConfig& config, const DepthImage& depth, const HandsRequest& request,
             std::array<std::vector<uint8_t>, kMaxHands>& foreign, std::array<FrameShare, kMaxHands>& share,
             std::array<std::optional<Eigen::Vector3d>, kMaxHands>& candidate);
  // The last split's median-filtered frame (what each slot's DepthInputBuilder would compute).
  [[nodiscard]] const std::vector<float>& median() const { return median_.last(); }

 private:
  // Per surface: how many sampled pixels lie within the claim distance of each slot's skeleton,
  // and the sum of the sampled points (its centroid).
  struct Claims {
    std::array<int, kMaxHands> samples{};
    int sampled = 0;
    Eigen::Vector3d point_sum = Eigen::Vector3d::Zero();
  };
  static constexpr int kShared = -2;  // owner_: claimed by more than one slot
  // Whose a surface's pixels are, for one slot (Ownership::slot).
  static constexpr uint8_t kForeign = 0;
  static constexpr uint8_t kMine = 1;
  static constexpr uint8_t kNearest = 2;  // the nearer skeleton's, pixel by pixel (touching hands)
  // Per surface, decided once a frame: whose its pixels are for each slot, the slots whose
  // skeletons compete for them pixel by pixel, and whether any slot needs that.
  struct Ownership {
    std::array<uint8_t, kMaxHands> slot{};
    std::array<bool, kMaxHands> claimant{};
    bool touching = false;
  };
  static constexpr int kNone = -1;

  void claim(const DepthInputConfig& config, const CameraIntrinsics& camera, const HandsRequest& request);

  std::vector<Ownership> ownership_;  // per surface
  MedianFilter median_;
  SupportPlane support_plane_;
  std::vector<float> volume_;  // median depth in the working volume, 0 outside
  std::vector<int> component_;
  std::vector<int> stack_;
  std::vector<Surface> surfaces_;
  std::vector<Claims> claims_;
  std::vector<int> owner_;  // per surface: the owning slot, kShared or kNone
  std::vector<uint8_t> unclaimed_;  // per surface: owner_ is kNone (BodyEraser::find)
  BodyEraser body_;
  std::vector<Skeleton> skeletons_;
  std::array<int, kMaxHands> skeleton_of_{};  // slot -> index into skeletons_, -1 when free
};

}  // namespace handtrack
