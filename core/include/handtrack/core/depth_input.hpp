#pragma once
// From a depth image to the image Gaussian mixture C_I (Sec. 3.1 and 4): median filter, the working
// volume, segmentation of the hand (not the forearm, not the body behind it), and a quadtree whose
// leaves become unit-weight 2D Gaussians.

#include "handtrack/core/camera.hpp"
#include "handtrack/core/free_space.hpp"
#include "handtrack/core/image_mixture.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

namespace handtrack {

// A desk, table or wall the hand touches (support_plane.hpp; ours): its pixels leave the working
// volume before segmentation.
struct SupportPlaneConfig {
  bool enabled = true;
  // More surface than a hand and the visible forearm (~300 cm^2) can be in one plane.
  double min_area_mm2 = 40000.0;
  // Pixels within this of the plane, or beyond it, are the plane's: sensor noise (a few mm at arm's
  // length) and the fingers' lower edges on the desk.
  double band_mm = 8.0;
};

struct DepthInputConfig {
  int median_radius_px = 1;             // 3x3 median "to remove flying pixels" (Sec. 4)
  double near_mm = 150.0;               // working volume, Sec. 4: "between 150 mm and 600 mm"
  double far_mm = 600.0;
  double quadtree_threshold_mm = 20.0;  // epsilon_c, Sec. 3.1: split until max - min < 20 mm
  int quadtree_root_px = 32;            // root cell side at 320 px image width (scales with width)
  int quadtree_min_leaf_px = 2;         // smallest cell at 320 px width (scales with width)
  double min_leaf_fill = 0.5;           // a leaf must be at least this full of hand pixels
  // Ours: a leaf less full than this (a cell the hand's outline crosses) is split once more, its
  // quarters kept where at least min_leaf_fill full; 0: never (docs/TRACKER.md, "Real frames").
  double split_partial_leaf_fill = 0.8;
  double continuity_mm = 25.0;          // neighbouring pixels closer than this are one surface
  double min_hand_area_mm2 = 1500.0;    // smaller blobs are noise, not a hand
  double hand_length_mm = 190.0;        // wrist to middle fingertip, bounds the hand region
  FreeSpaceConfig free_space;           // where no part of the hand can be (E_free; ours)
  SupportPlaneConfig support_plane;     // a desk the hand rests on is not the hand (ours)
  // With part labels (Sec. 4.3): the hand-mask pixels the labeller calls background (a held object,
  // the forearm beyond the wrist) leave the hand before C_I is built, where they form a connected
  // region of at least `drop_background_min_area_mm2` (ours). Smaller ones stay: on real SR305
  // frames the forest, trained on renders, calls 2-11 % of the hand background, in regions of at
  // most 7.6 cm^2; a 35 mm ball in the hand is one region of 23-41 cm^2 (docs/TRACKER.md).
  bool drop_background = true;
  double drop_background_min_area_mm2 = 1000.0;
};

// What the tracker knows about where the hand was: lets segmentation keep the hand and cut the
// forearm at the wrist.
struct HandHint {
  Eigen::Vector3d palm_centre_mm;  // camera frame
  Eigen::Vector3d wrist_mm;
  Eigen::Vector3d finger_axis;     // unit, wrist toward the fingers
};

// One leaf of the quadtree: G_q with mu = leaf centre (pixels), sigma = a / sqrt(2), unit weight,
// and d_q = mean depth of the leaf's pixels (Sec. 3.1).
struct ImageGaussian {
  double u = 0.0;
  double v = 0.0;
  double sigma_px = 1.0;
  double depth_mm = 0.0;
  int label = 0;  // majority part label of the leaf's pixels (Sec. 4.3), 0 when unlabelled
  int side_px = 1;
};

struct DepthInput {
  CameraIntrinsics camera;
  bool mirrored = false;              // built from a mirrored DepthImage (a left hand's input)
  std::vector<float> filtered_mm;     // median-filtered depth, 0 outside the working volume
  std::vector<uint8_t> hand_mask;     // 1 = pixel belongs to the segmented hand
  std::vector<uint8_t> pixel_labels;  // part label per pixel (0 = none); empty without a labeller
  std::vector<ImageGaussian> gaussians;
  ImageMixture mixture;               // `gaussians` laid out for E_sim; assign(gaussians) after changing them
  FreeSpaceMap free_space;            // distance to where the hand can be, around the hand (E_free)
  double self_similarity = 0.0;       // E(C_I, C_I), normalises E_sim (Sec. 4.1)
  int hand_pixels = 0;
  Eigen::Vector3d hand_centroid_mm = Eigen::Vector3d::Zero();  // mean 3D point of the hand pixels
  Eigen::Vector3d palm_centre_mm = Eigen::Vector3d::Zero();    // estimated palm centre
  Eigen::Vector3d finger_axis = Eigen::Vector3d(0, -1, 0);     // estimated wrist->fingers direction
  // The wrist->fingers direction the segmentation finds without a hint (the hand-and-forearm blob's
  // axis, toward the end that stays in the image): finger_axis of a frame segmented without one.
  // With a hint it is found only for a labeller that asks (PixelLabeller::turns_with_hand), else
  // it is finger_axis.
  Eigen::Vector3d unhinted_axis = Eigen::Vector3d(0, -1, 0);
  [[nodiscard]] bool has_hand() const { return !gaussians.empty(); }
};

// Calls visit(point) with the camera-frame point (mm) of each segmented hand pixel that has a depth,
// row by row. `input` must be built (hand_mask and filtered_mm of the image's size).
template <typename Visit>
void for_each_hand_point(const DepthInput& input, const Visit& visit) {
  const CameraIntrinsics& cam = input.camera;
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const size_t i = static_cast<size_t>(v) * static_cast<size_t>(cam.width) + static_cast<size_t>(u);
      if (input.hand_mask[i] == 0 || input.filtered_mm[i] <= 0.0F) continue;
      visit(cam.unproject(u, v, input.filtered_mm[i]));
    }
  }
}

// Room in `input` for an input of a width x height image as DepthInputBuilder builds it, so that
// copying one into it (operator=) allocates nothing: a background search's copy (tracker.cpp).
void reserve_input(DepthInput& input, int width, int height);

// Gives the segmented hand's pixels part labels (Sec. 4.3): the decision forest, or in tests the
// ground-truth label image.
class PixelLabeller {
 public:
  virtual ~PixelLabeller() = default;
  // Fills `labels` (resized to the image) for the pixels where input.hand_mask is set; others 0.
  // Reads input.filtered_mm, input.hand_mask and input.camera.
  virtual void label(const DepthInput& input, std::vector<uint8_t>& labels) const = 0;
  // True when label() reads input.unhinted_axis (a hand-aligned forest, part_forest.hpp): a frame
  // segmented with a hint is then segmented once more without it, for the axis it was trained on.
  [[nodiscard]] virtual bool turns_with_hand() const { return false; }
};

// A PixelLabeller that copies a given label image (ground truth) of the camera's own frame, for
// tests and ablations; mirrored left to right for a mirrored input (a left hand's, Tracker).
class FixedLabels final : public PixelLabeller {
 public:
  explicit FixedLabels(const std::vector<uint8_t>* labels) : labels_(labels) {}
  void label(const DepthInput& input, std::vector<uint8_t>& labels) const override;

 private:
  const std::vector<uint8_t>* labels_;
};

// The four steps from a depth image to C_I: median filter, working volume, hand segmentation,
// quadtree Gaussians (and E(C_I,C_I)). Each builder owns its scratch, reused from frame to frame:
// after the first frames of a resolution, build() allocates nothing.
// Thread roles: reentrant (the daemon gives each pipeline frame its own builder).
class DepthInputBuilder {
 public:
  explicit DepthInputBuilder(DepthInputConfig config = {});
  ~DepthInputBuilder();
  DepthInputBuilder(DepthInputBuilder&&) noexcept;
  DepthInputBuilder& operator=(DepthInputBuilder&&) noexcept;

  // Builds C_I for one frame. With a `labeller`, the hand's pixels get part labels and each
  // quadtree leaf the majority label of its pixels (Sec. 4.3). `foreign` (one byte per pixel, may be
  // null): pixels that are not this hand's (another hand's: HandsTracker); they stay depth, so that
  // a model part behind another hand counts as hidden, not as floating over nothing, but are never
  // segmented as the hand. `median` (may be null): the median-filtered `depth`, when the caller
  // has it already (config().median_radius_px; another builder's computed_median() of the same
  // image, or its mirror image for the mirrored image): not filtered again. Storage is reused
  // between calls.
  const DepthInput& build(const DepthImage& depth, const std::optional<HandHint>& hint,
                          const PixelLabeller* labeller = nullptr, const std::vector<uint8_t>* foreign = nullptr,
                          const std::vector<float>* median = nullptr);
  [[nodiscard]] const DepthInput& last() const { return out_; }
  // The median-filtered depth that the last build() computed (not one it was given).
  [[nodiscard]] const std::vector<float>& computed_median() const;
  [[nodiscard]] const DepthInputConfig& config() const { return config_; }

 private:
  struct Steps;  // the four algorithms and their scratch (core/src)
  DepthInputConfig config_;
  DepthInput out_;
  std::unique_ptr<Steps> steps_;
};

// E(C_I, C_I) of paper eq. 3 for a set of image-plane Gaussians (allocates its scratch: the
// builder keeps its own).
double image_self_similarity(const std::vector<ImageGaussian>& gaussians);

}  // namespace handtrack
