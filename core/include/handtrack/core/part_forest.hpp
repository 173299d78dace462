#pragma once
// The hand-part classification forest of Sec. 4.3: a randomized decision forest that labels every
// segmented hand pixel with one of the 12 parts (or background), using the depth-comparison
// features of Shotton et al. 2011 ("Real-time human pose recognition in parts from single depth
// images", CVPR 2011, eq. 1):
//
//   f_theta(I, x) = d_I(x + u / d_I(x)) - d_I(x + v / d_I(x)),   theta = (u, v)
//
// The offsets u, v are in pixel * mm at the model's reference focal length (fx_ref, fy_ref), so
// they cover the same metric distance at any depth and, scaled by fx / fx_ref and fy / fy_ref at
// run time, at any resolution. A probe outside the image or off the hand mask reads the model's
// constant background depth (a "large positive constant" in Shotton et al.).
// A hand-aligned forest (PartForestInfo::hand_aligned; ours) reads u and v in the hand's own image
// frame: turned by the in-plane angle of the wrist->fingers axis the segmentation finds without a
// hint (DepthInput::unhinted_axis), so that a hand whose forearm enters from any image edge is
// probed as one whose fingers point up the image. Its training images are turned alike
// (train_forest), and the trees need not learn every roll of every part. The tracked pose's axis
// (the hint's) is not the one trained on: with it, tracking lost 0.7 mm (docs/FOREST.md).
// An image-aligned forest (the shipped one) turns its probes by multiples of 45 deg only, and only
// where the trees are surer of the turned labels (PartForestOptions::turned_readings).
// A pixel goes left when f < threshold. Its class distribution is the mean of the trees' leaf
// distributions (Criminisi and Shotton 2013); the label is the argmax.
//
// Model file (little-endian; written by save(), read by load()), format version 1 (probes in the
// image's axes) or 2 (hand-aligned; the one field more, and every field after it 4 bytes later):
//
//   offset  size  field
//        0     8  magic "HTFOREST"
//        8     4  u32 format version (1 or kFormatVersion = 2)
//       12     4  u32 classes (must be kPartForestClasses = 13: background + 12 parts)
//       16     4  u32 trees T (1..kMaxTrees)
//       20     4  f32 reference fx (pixels)
//       24     4  f32 reference fy (pixels)
//       28     4  f32 background depth (mm) read by probes off the hand
//      (32     4  u32 probe frame: 1 = hand-aligned; version 2 only, where it must be 1)
//       32     4  u32 metadata length M (<= kMaxMetadataBytes)
//       36     M  metadata: UTF-8 text, training command and statistics
//     ...  8 T  per tree: u32 node count N_t, u32 leaf count L_t
//     ...        per tree: N_t nodes of 16 bytes
//                            i16 u_x, u_y, v_x, v_y  (pixel * mm at the reference focal length)
//                            f32 threshold (mm)
//                            u32 child: internal node: index of the left child within the tree,
//                                the right child is the next node, both after this one;
//                                leaf: kLeafBit | leaf index
//                          then L_t leaves of 13 x u16: class probabilities * 65535 (sum > 0)
//     end-8    8  u64 FNV-1a 64 of every byte before it
//
// Only the nodes that exist are stored (the paper's full trees took 1 GB).
// Thread roles: thread-safe once loaded (immutable): label() may run on several threads at once.

#include "handtrack/core/depth_input.hpp"
#include "handtrack/core/hand_layout.hpp"

#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace handtrack {

inline constexpr int kPartForestClasses = kNumPartLabels + 1;  // background (0) + the 12 parts

struct PartForestNode {
  static constexpr uint32_t kLeafBit = 0x8000'0000U;
  std::array<int16_t, 2> u{};  // probe offsets (x, y), pixel * mm at the reference focal length
  std::array<int16_t, 2> v{};
  float threshold = 0.0F;  // mm: f < threshold goes to the left child
  uint32_t child = kLeafBit;

  [[nodiscard]] bool is_leaf() const { return (child & kLeafBit) != 0; }
  [[nodiscard]] uint32_t leaf_index() const { return child & ~kLeafBit; }
};
static_assert(sizeof(PartForestNode) == 16, "nodes are stored as 16 bytes, in memory as in the file");

// Class probabilities of a leaf, each scaled to 0..65535.
using PartForestLeaf = std::array<uint16_t, kPartForestClasses>;

struct PartForestTree {
  std::vector<PartForestNode> nodes;  // nodes[0] is the root
  std::vector<PartForestLeaf> leaves;
};

struct PartForestInfo {
  float reference_fx = static_cast<float>(SpecCamera::kFx);  // focal lengths the offsets were trained at
  float reference_fy = static_cast<float>(SpecCamera::kFy);
  float background_mm = 4000.0F;  // depth read by probes outside the image or off the hand
  bool hand_aligned = false;      // offsets in the hand's frame (hand_turn), not the image's
  std::string metadata;           // free text: how the model was trained
};

struct PartForestOptions {
  // Classify one pixel per stride x stride block (stride per 320 pixels of image width: 3 here
  // means 6 at 640x480); the block's other hand pixels take its label. Held-out accuracy (motions /
  // random poses) and time per 320x240 frame: stride 1 93.0 / 71.7 %, ~3 ms; 2 91.6 / 71.2 %,
  // 0.95 ms; 3 91.2 / 70.9 %, 0.63 ms; 4 90.0 / 70.1 %, 0.34 ms. Late-fusion tracking is the same
  // at 2, 3 and 4 (9.12 / 8.77 / 8.90 mm), but at 4 one knocked-off tracker (random, frame 140) is
  // no longer back within 30 frames (docs/FOREST.md).
  int stride_px = 3;
  // An image-aligned forest saw the motions with the forearm from the image bottom only. Where the
  // hand's axis (DepthInput::finger_axis: the tracked pose's, or the segmentation's) is more than
  // 22.5 deg from the image's up, label() labels the hand a second time with its probes turned by
  // the nearest multiple of 45 deg (eighth_turn), and keeps the labelling its trees are surer of
  // (ours; docs/FOREST.md, "A hand from another image edge").
  bool turned_readings = true;
  // The descent eight pixels at a time in AVX2 registers where the CPU has them (the same labels
  // bit for bit; src/forest_descent.hpp); false: the scalar descent, which the tests compare it with.
  bool simd_descent = true;
};

// Probe arithmetic, shared by training and inference so that both round alike, in 16.16 fixed
// point (integer multiply and shift: shorter latency than float conversions on the descent's
// critical path). The scale of pixel x is k = round(65536 (f / f_ref) / d(x)), at most 2^22;
// a probe reads pixel x + round(offset k / 65536) (halves rounded up).
inline constexpr int kProbeScaleBits = 16;
inline int32_t probe_scale(double focal_ratio, float depth_mm) {
  constexpr double kMax = 4194304.0;  // 2^22: |offset k| >> 16 stays below 2^21 pixels
  const double k = focal_ratio / static_cast<double>(depth_mm) * 65536.0;
  return static_cast<int32_t>(std::lround(std::isfinite(k) ? std::fmin(std::fmax(k, 0.0), kMax) : kMax));
}
// The turn in the image plane (y down) that takes "fingers up the image" (0, -1) to the image
// direction of `finger_axis` (its x and y; an axis along the viewing ray turns nothing):
// (x, y) -> (cos x - sin y, sin x + cos y).
struct InPlaneTurn {
  double cos = 1.0;
  double sin = 0.0;
};
InPlaneTurn hand_turn(const Eigen::Vector3d& finger_axis);
// hand_turn rounded to the nearest multiple of 45 deg (cos and sin exact at the quarter turns), the
// identity for an axis less than 22.5 deg from the image's up or along the viewing ray.
InPlaneTurn eighth_turn(const Eigen::Vector3d& finger_axis);

// A pixel's probe steps in 16.16: an offset (u_x, u_y) reads pixel
// (x + round((xx u_x + xy u_y) / 65536), y + round((yx u_x + yy u_y) / 65536)), the turn applied
// to the metric offset before each axis' scale (f / f_ref) / d(x). Without a turn: {kx, 0, 0, ky}.
struct ProbeSteps {
  int32_t xx = 0;
  int32_t xy = 0;
  int32_t yx = 0;
  int32_t yy = 0;
};
inline ProbeSteps probe_steps(double focal_ratio_x, double focal_ratio_y, float depth_mm, const InPlaneTurn& turn) {
  const int32_t kx = probe_scale(focal_ratio_x, depth_mm);
  const int32_t ky = probe_scale(focal_ratio_y, depth_mm);
  const auto step = [](int32_t k, double c) { return static_cast<int32_t>(std::lround(k * c)); };
  return {step(kx, turn.cos), step(kx, -turn.sin), step(ky, turn.sin), step(ky, turn.cos)};
}
// One coordinate of a probe: x plus the rounded step of offset (a, b) along steps (ka, kb).
inline int probe_coordinate(int x, int16_t a, int16_t b, int32_t ka, int32_t kb) {
  return x + static_cast<int>((int64_t{a} * ka + int64_t{b} * kb + (int64_t{1} << (kProbeScaleBits - 1))) >>
                              kProbeScaleBits);
}

class PartForest final : public PixelLabeller {
 public:
  static constexpr uint32_t kFormatVersion = 2;  // hand-aligned; image-aligned forests are written as 1
  static constexpr int kMaxTrees = 64;
  static constexpr uint32_t kMaxMetadataBytes = 1U << 16;
  static constexpr uint32_t kMaxNodesPerTree = 1U << 26;

  // Validates the trees (children after their parent and in range, leaf indices in range, finite
  // thresholds, leaves with some probability, positive finite focal lengths and background);
  // throws std::invalid_argument naming the first problem.
  PartForest(std::vector<PartForestTree> trees, PartForestInfo info, PartForestOptions options = {});

  // Reads a model file. Throws std::runtime_error with one line "part forest FILE: what is wrong"
  // (cannot open, truncated, bad magic, unsupported version, checksum mismatch, node index out of
  // range, bad leaf, ...). Never crashes, whatever the bytes.
  static PartForest load(const std::filesystem::path& path, PartForestOptions options = {});
  // The same from bytes in memory; `name` stands for the file in messages.
  static PartForest from_bytes(std::span<const uint8_t> bytes, const std::string& name,
                               PartForestOptions options = {});
  // Writes the model file (throws std::runtime_error naming the file when it cannot).
  void save(const std::filesystem::path& path) const;
  [[nodiscard]] std::vector<uint8_t> to_bytes() const;

  // PixelLabeller: labels (resized to the image) get the argmax class of every hand-mask pixel,
  // 0 elsewhere. No allocation once `labels` has the image's size.
  void label(const DepthInput& input, std::vector<uint8_t>& labels) const override;
  [[nodiscard]] bool turns_with_hand() const override { return info_.hand_aligned; }

  [[nodiscard]] const std::vector<PartForestTree>& trees() const { return trees_; }
  [[nodiscard]] const PartForestInfo& info() const { return info_; }
  [[nodiscard]] const PartForestOptions& options() const { return options_; }
  void set_options(const PartForestOptions& options);
  [[nodiscard]] size_t node_count() const;
  [[nodiscard]] int max_depth() const;

 private:
  static constexpr int kBatch = 32;  // pixels classified together (lockstep descent)
  struct Site {
    int x = 0;  // the pixel classified
    int y = 0;
    int block_x = 0;  // its stride x stride block
    int block_y = 0;
  };
  struct Crop {
    // (width + 2) x (height + 2), row-major: the box's hand depth, the background elsewhere and in a
    // one-pixel border around the box (box pixel (0, 0) is element width + 3).
    const float* depth_mm = nullptr;
    int x0 = 0;                       // its top-left pixel in the image
    int y0 = 0;
    int width = 0;
    int height = 0;
    double focal_ratio_x = 1.0;  // fx / fx_ref
    double focal_ratio_y = 1.0;
    InPlaneTurn turn;  // the hand's, for a hand-aligned forest
  };
  // Labels each site (out: argmax class); returns the sum over the sites of the argmax class's
  // summed leaf probability (x 65535): how sure the trees are of these labels.
  uint64_t classify_batch(const Crop& crop, const Site* sites, int count, uint8_t* out) const;
  // Labels the hand pixels of `input` (labels already of the image's size) with the crop's turn;
  // returns the sum of classify_batch's.
  uint64_t label_hand(const DepthInput& input, const Crop& crop, std::vector<uint8_t>& labels) const;

  std::vector<PartForestTree> trees_;
  PartForestInfo info_;
  PartForestOptions options_;
};

// The shipped forest (data/part_forest.htf), for programs that use it without being told where
// it is: $HANDTRACK_FOREST if set, else the source tree this library was built from, else the
// installed data directory (<prefix>/share/handtrack). nullopt when none of them has the file.
std::optional<std::filesystem::path> shipped_forest_path();

}  // namespace handtrack
