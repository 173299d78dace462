#pragma once
// The sequence directory of SPEC.md: camera.json, depth/NNNNNN.png, and optionally
// groundtruth.csv (fingertips), joints.csv (21 joints), labels/NNNNNN.png (part labels) and
// hand.json (which hands, in the order of the ground-truth blocks).
// Loading throws std::runtime_error naming the file (and field) that is wrong.
//
// Several hands (issue 14; docs/SEQUENCES.md): hand.json {"hands":["right","left"]} names them, and
// each row of groundtruth.csv is the frame, then 15 columns per hand in that order: hand 0's named
// as for one hand (thumb_x,...,little_z), hand k's prefixed "hk_" (h1_thumb_x,...,h1_little_z).
// joints.csv likewise (63 columns per hand). A hand's block left empty: not annotated in that frame.
// Without hand.json a sequence has one hand, and a one-hand file is exactly SPEC.md's.

#include "handtrack/core/camera.hpp"
#include "handtrack/core/hand_layout.hpp"
#include "handtrack/core/png_io.hpp"

#include <Eigen/Core>

#include <array>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace handtrack {

using Fingertips = std::array<std::optional<Eigen::Vector3d>, kNumFingers>;  // thumb..little, mm
using Joints = std::array<Eigen::Vector3d, kNumJoints>;                       // SPEC.md joint order, mm

CameraIntrinsics read_camera_json(const std::filesystem::path& file);
void write_camera_json(const std::filesystem::path& file, const CameraIntrinsics& camera);

// The most hands a sequence's ground truth has blocks for.
inline constexpr int kMaxSequenceHands = 2;
// hand.json's "hands": 1..kMaxSequenceHands names, each "right" or "left". Its other fields (a
// writer's own, e.g. handtrack-synth's "view" and "motion") are not looked at.
std::vector<std::string> read_hand_json(const std::filesystem::path& file);
// Writes {"hands":[...]} and the `extra` string fields, one line.
void write_hand_json(const std::filesystem::path& file, const std::vector<std::string>& hands,
                     const std::vector<std::pair<std::string, std::string>>& extra = {});
// What the CSV column names of hand `hand`'s block start with: "" for hand 0, "h1_" for hand 1
// (h1_thumb_x, ...).
std::string hand_column_prefix(int hand);

class SequenceReader {
 public:
  // What to read besides camera.json and the depth frames.
  enum class Annotations {
    kRead,    // groundtruth.csv and joints.csv too (evaluation, calibration)
    kIgnore,  // neither is opened: a player of the depth (handtrackd's seq: source) never needs them
  };
  explicit SequenceReader(std::filesystem::path dir, Annotations annotations = Annotations::kRead);

  [[nodiscard]] const CameraIntrinsics& camera() const { return camera_; }
  [[nodiscard]] const std::filesystem::path& dir() const { return dir_; }
  [[nodiscard]] size_t frame_count() const { return frames_.size(); }
  // Frame number as written in the file name of the i-th depth image.
  [[nodiscard]] int frame_number(size_t i) const { return frames_.at(i); }

  // Depth of the i-th frame in mm. Throws if the PNG is missing, corrupt or of the wrong size.
  [[nodiscard]] DepthImage depth(size_t i) const;
  // Part labels of the i-th frame, if the sequence has them.
  [[nodiscard]] std::optional<Gray8Image> labels(size_t i) const;
  // The hands of the ground truth: hand.json's count, 1 without it (and with Annotations::kIgnore).
  [[nodiscard]] int hand_count() const { return hands_.empty() ? 1 : static_cast<int>(hands_.size()); }
  // hand.json's names ("right", "left") in the order of the ground-truth blocks; empty without it.
  [[nodiscard]] const std::vector<std::string>& hands() const { return hands_; }
  // Annotated fingertips of hand `hand` in the i-th frame (all empty when not annotated). Throws
  // std::out_of_range for a hand >= hand_count().
  [[nodiscard]] Fingertips fingertips(size_t i, int hand = 0) const;
  [[nodiscard]] bool has_groundtruth() const { return !groundtruth_.empty(); }
  // The 21 joints of hand `hand` in the i-th frame, if annotated.
  [[nodiscard]] std::optional<Joints> joints(size_t i, int hand = 0) const;

 private:
  [[nodiscard]] size_t hand_slot(int hand) const;

  std::filesystem::path dir_;
  CameraIntrinsics camera_;
  std::vector<int> frames_;
  std::vector<std::string> hands_;
  std::map<int, std::vector<Fingertips>> groundtruth_;           // per frame: hand_count() blocks
  std::map<int, std::vector<std::optional<Joints>>> joints_;     // per frame: hand_count() blocks
};

class SequenceWriter {
 public:
  // Creates DIR (and depth/, labels/ on demand) and writes camera.json.
  SequenceWriter(std::filesystem::path dir, const CameraIntrinsics& camera);
  ~SequenceWriter();
  SequenceWriter(const SequenceWriter&) = delete;
  SequenceWriter& operator=(const SequenceWriter&) = delete;

  void write_depth(int frame, const DepthImage& depth);
  void write_depth_raw(int frame, const Gray16Image& raw);
  void write_labels(int frame, const Gray8Image& labels);
  // The hands the sequence shows ("right" / "left"), in the order of the ground-truth blocks:
  // writes hand.json (write_hand_json, with `extra`). Without it the sequence has one hand. Call it
  // before the ground truth of a hand > 0; it throws std::invalid_argument for bad names or counts.
  void write_hands(const std::vector<std::string>& hands,
                   const std::vector<std::pair<std::string, std::string>>& extra = {});
  // Ground truth of hand `hand` (< the hands written; std::out_of_range otherwise); a hand with none
  // in a frame gets empty cells there.
  void write_fingertips(int frame, const Fingertips& tips, int hand = 0);
  void write_joints(int frame, const Joints& joints, int hand = 0);
  // Flushes the CSV files (also done by the destructor).
  void flush();

 private:
  [[nodiscard]] size_t hand_slot(int hand) const;

  std::filesystem::path dir_;
  CameraIntrinsics camera_;
  int hand_count_ = 1;
  std::map<int, std::vector<std::optional<Fingertips>>> groundtruth_;
  std::map<int, std::vector<std::optional<Joints>>> joints_;
};

std::filesystem::path frame_file(const std::filesystem::path& dir, int frame);  // dir/NNNNNN.png

}  // namespace handtrack
