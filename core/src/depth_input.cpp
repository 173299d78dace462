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

// The hand-mask pixels labelled background, in 4-connected regions of at least `min_area_mm2`,
// leave the hand: segmentation keeps whatever surface touches the hand near its palm (a held ball
// took the palm view from 9 to 51 mm), and the forest was trained to tell those pixels from the
// hand's parts (label 0; data/part_forest.md). A region's area is the sum of its pixels' z^2 /
// (f_x f_y). Only the hand's box (every mask pixel is in it) is scanned. `region` and `stack` are
// scratch.
void drop_background_regions(DepthInput& input, const PixelBox& box, double min_area_mm2, std::vector<int32_t>& region,
                             std::vector<int32_t>& stack) {
  const int w = input.camera.width;
  const int h = input.camera.height;
  const auto n = static_cast<size_t>(w) * static_cast<size_t>(h);
  const double pixel_area = 1.0 / (input.camera.fx * input.camera.fy);
  // Every pixel enters a region and the stack at most once: room for all of them up front, so
  // that a frame allocates nothing once a frame of its size was seen (the daemon's steady state).
  if (region.capacity() < n) region.reserve(n);
  if (stack.capacity() < n) stack.reserve(n);
  const auto background = [&](size_t i) { return input.hand_mask[i] == 1 && input.pixel_labels[i] == kBackground; };
  const auto each_box_pixel = [&](const auto& visit_pixel) {
    for (int v = box.v0; v <= box.v1; ++v) {
      for (int u = box.u0; u <= box.u1; ++u) visit_pixel(static_cast<size_t>(v) * w + u);
    }
  };
  each_box_pixel([&](size_t seed) {
    if (!background(seed)) return;
    // Flood the region (marking its pixels 2 in the mask), then drop it or give it back.
    region.clear();
    stack.assign(1, static_cast<int32_t>(seed));
    input.hand_mask[seed] = 2;
    double area = 0.0;
    flood4(
        PixelBox{0, 0, w - 1, h - 1}, w, stack,
        [&](size_t j, size_t) {
          if (!background(j)) return false;
          input.hand_mask[j] = 2;
          return true;
        },
        [&](size_t i) {
          region.push_back(static_cast<int32_t>(i));
          const double z = input.filtered_mm[i];
          area += z * z * pixel_area;
        });
    const bool drop = area >= min_area_mm2;
    for (const int32_t i : region) input.hand_mask[static_cast<size_t>(i)] = drop ? 0 : 3;
    if (drop) input.hand_pixels -= static_cast<int>(region.size());
  });
  each_box_pixel([&](size_t i) { input.hand_mask[i] = input.hand_mask[i] != 0 ? 1 : 0; });  // kept regions (3) back to 1
}
}  // namespace

struct DepthInputBuilder::Steps {
  MedianFilter median;
  SupportPlane support_plane;
  std::vector<float> without_desk;  // the median-filtered depth without the desk, for the free space
  std::vector<int32_t> region;      // drop_background_regions' scratch
  std::vector<int32_t> stack;
  HandSegmenter segmenter;
  DepthInput unhinted;  // a hinted frame segmented without its hint, for a hand-aligned labeller
  QuadtreeBuilder quadtree;
  SelfSimilarity self_similarity{kReservedLeaves};
};

DepthInputBuilder::DepthInputBuilder(DepthInputConfig config)
    : config_(config), steps_(std::make_unique<Steps>()) {
  // Steady state without allocation (the daemon's pipeline).
  out_.gaussians.reserve(kReservedLeaves);
  out_.mixture.reserve(kReservedLeaves);
}

void reserve_input(DepthInput& input, int width, int height) {
  const auto pixels = static_cast<size_t>(std::max(width, 0)) * static_cast<size_t>(std::max(height, 0));
  input.filtered_mm.reserve(pixels);
  input.hand_mask.reserve(pixels);
  input.pixel_labels.reserve(pixels);
  input.gaussians.reserve(kReservedLeaves);
  input.mixture.reserve(kReservedLeaves);
  input.free_space.reserve(width, height);
}

DepthInputBuilder::~DepthInputBuilder() = default;
DepthInputBuilder::DepthInputBuilder(DepthInputBuilder&&) noexcept = default;
DepthInputBuilder& DepthInputBuilder::operator=(DepthInputBuilder&&) noexcept = default;

const std::vector<float>& DepthInputBuilder::computed_median() const { return steps_->median.last(); }

const DepthInput& DepthInputBuilder::build(const DepthImage& depth, const std::optional<HandHint>& hint,
                                           const PixelLabeller* labeller, const std::vector<uint8_t>* foreign,
                                           const std::vector<float>* given_median) {
  out_.camera = depth.camera;
  out_.mirrored = depth.mirrored;
  // Median, then the working volume (Sec. 4): 0 outside [near, far].
  const std::vector<float>& median =
      given_median != nullptr ? *given_median : steps_->median.apply(depth, config_.median_radius_px);
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
  const bool segment_unhinted = hint && labeller != nullptr && labeller->turns_with_hand();
  if (segment_unhinted) {
    DepthInput& unhinted = steps_->unhinted;
    unhinted.camera = out_.camera;
    unhinted.filtered_mm = out_.filtered_mm;  // same size every frame: no allocation after the first
    steps_->segmenter.segment(config_, median, std::nullopt, unhinted, foreign);
  }
  steps_->segmenter.segment(config_, median, hint, out_, foreign);
  out_.unhinted_axis = segment_unhinted ? steps_->unhinted.finger_axis : out_.finger_axis;
  const std::vector<float>* seen = &median;
  if (desk && config_.free_space.enabled) {
    steps_->without_desk = median;
    steps_->support_plane.erase(out_.camera, steps_->without_desk);
    seen = &steps_->without_desk;
  }
  out_.pixel_labels.clear();
  if (labeller != nullptr && out_.hand_pixels > 0) {
    labeller->label(out_, out_.pixel_labels);
    if (config_.drop_background) {
      drop_background_regions(out_, steps_->segmenter.hand_box(), config_.drop_background_min_area_mm2, steps_->region,
                              steps_->stack);
    }
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
  const auto width = static_cast<size_t>(input.camera.width);
  for (size_t i = 0; i < labels.size(); ++i) {
    if (input.hand_mask[i] == 0) continue;
    // Pixel (u, v) of a mirrored frame is pixel (width - 1 - u, v) of the camera's.
    const size_t u = i % width;
    const size_t source = input.mirrored ? i - u + (width - 1 - u) : i;
    labels[i] = (*labels_)[source];
  }
}

}  // namespace handtrack
