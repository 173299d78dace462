// DepthInputBuilder: the four steps from a depth image to C_I (paper Sec. 3.1, 4), each in its own
// unit: median_filter, hand_segmentation, quadtree, image_self_similarity; and, ours, a desk the
// hand touches taken out before segmentation (support_plane), the pixels the part labeller calls
// background taken out of the hand, and the free space around the hand (free_space).
#include "handtrack/core/depth_input.hpp"

#include "handtrack/core/hand_layout.hpp"
#include "hand_segmentation.hpp"
#include "image_self_similarity.hpp"
#include "median_filter.hpp"
#include "quadtree.hpp"
#include "support_plane.hpp"

namespace handtrack {

namespace {
// Quadtree leaves with room reserved up front: a hand at arm's length makes 200-500 leaves; storage
// grows only for more (a hand very near the camera).
constexpr size_t kReservedLeaves = 2048;

// The hand-mask pixels whose part label is the background leave the hand: segmentation keeps
// whatever surface touches the hand near its palm (a held ball took the palm view from 9 to 51 mm),
// the forest was trained to tell those pixels from the hand's parts (label 0; data/part_forest.md).
void drop_background_pixels(DepthInput& input) {
  for (size_t i = 0; i < input.hand_mask.size(); ++i) {
    if (input.hand_mask[i] != 0 && input.pixel_labels[i] == kBackground) {
      input.hand_mask[i] = 0;
      --input.hand_pixels;
    }
  }
}
}  // namespace

struct DepthInputBuilder::Steps {
  MedianFilter median;
  SupportPlane support_plane;
  std::vector<float> without_desk;  // the median-filtered depth without the desk, for the free space
  HandSegmenter segmenter;
  QuadtreeBuilder quadtree;
  SelfSimilarity self_similarity{kReservedLeaves};
};

DepthInputBuilder::DepthInputBuilder(DepthInputConfig config)
    : config_(config), steps_(std::make_unique<Steps>()) {
  // Steady state without allocation (the daemon's pipeline).
  out_.gaussians.reserve(kReservedLeaves);
  out_.mixture.reserve(kReservedLeaves);
}

DepthInputBuilder::~DepthInputBuilder() = default;
DepthInputBuilder::DepthInputBuilder(DepthInputBuilder&&) noexcept = default;
DepthInputBuilder& DepthInputBuilder::operator=(DepthInputBuilder&&) noexcept = default;

const DepthInput& DepthInputBuilder::build(const DepthImage& depth, const std::optional<HandHint>& hint,
                                           const PixelLabeller* labeller, const std::vector<uint8_t>* foreign) {
  out_.camera = depth.camera;
  // Median, then the working volume (Sec. 4): 0 outside [near, far].
  const std::vector<float>& median = steps_->median.apply(depth, config_.median_radius_px);
  out_.filtered_mm.resize(median.size());
  const auto near = static_cast<float>(config_.near_mm);
  const auto far = static_cast<float>(config_.far_mm);
  for (size_t i = 0; i < median.size(); ++i) {
    const float m = median[i];
    out_.filtered_mm[i] = (m >= near && m <= far) ? m : 0.0F;
  }
  // A desk the hand touches: out of the working volume, and free space (the camera sees the desk
  // there, so no part of the hand is in front of it).
  const bool desk = steps_->support_plane.find(config_.support_plane, out_.camera, out_.filtered_mm);
  if (desk) steps_->support_plane.erase(out_.camera, out_.filtered_mm);
  steps_->segmenter.segment(config_, median, hint, out_, foreign);
  const std::vector<float>* seen = &median;
  if (desk && config_.free_space.enabled) {
    steps_->without_desk = median;
    steps_->support_plane.erase(out_.camera, steps_->without_desk);
    seen = &steps_->without_desk;
  }
  out_.pixel_labels.clear();
  if (labeller != nullptr && out_.hand_pixels > 0) {
    labeller->label(out_, out_.pixel_labels);
    if (config_.drop_background) drop_background_pixels(out_);
  }
  out_.free_space.build(out_.camera, *seen, out_.hand_mask, config_.free_space);
  steps_->quadtree.build(config_, steps_->segmenter.hand_box(), out_);
  out_.self_similarity = steps_->self_similarity(out_.gaussians);
  out_.mixture.assign(out_.gaussians);
  return out_;
}

void FixedLabels::label(const DepthInput& input, std::vector<uint8_t>& labels) const {
  labels.assign(input.hand_mask.size(), 0);
  if (labels_ == nullptr || labels_->size() != labels.size()) return;
  for (size_t i = 0; i < labels.size(); ++i) labels[i] = input.hand_mask[i] ? (*labels_)[i] : uint8_t{0};
}

}  // namespace handtrack
