#pragma once
// The sequence directory of SPEC.md: camera.json, depth/NNNNNN.png, and optionally
// groundtruth.csv (fingertips), joints.csv (21 joints) and labels/NNNNNN.png (part labels).
// Loading throws std::runtime_error naming the file (and field) that is wrong.

#include "handtrack/core/camera.hpp"
#include "handtrack/core/hand_layout.hpp"
#include "handtrack/core/png_io.hpp"

#include <Eigen/Core>

#include <array>
#include <filesystem>
#include <map>
#include <optional>
#include <vector>

namespace handtrack {

using Fingertips = std::array<std::optional<Eigen::Vector3d>, kNumFingers>;  // thumb..little, mm
using Joints = std::array<Eigen::Vector3d, kNumJoints>;                       // SPEC.md joint order, mm

CameraIntrinsics read_camera_json(const std::filesystem::path& file);
void write_camera_json(const std::filesystem::path& file, const CameraIntrinsics& camera);

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
  // Annotated fingertips of the i-th frame (all empty when not annotated).
  [[nodiscard]] Fingertips fingertips(size_t i) const;
  [[nodiscard]] bool has_groundtruth() const { return !groundtruth_.empty(); }
  [[nodiscard]] std::optional<Joints> joints(size_t i) const;

 private:
  std::filesystem::path dir_;
  CameraIntrinsics camera_;
  std::vector<int> frames_;
  std::map<int, Fingertips> groundtruth_;
  std::map<int, Joints> joints_;
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
  void write_fingertips(int frame, const Fingertips& tips);
  void write_joints(int frame, const Joints& joints);
  // Flushes the CSV files (also done by the destructor).
  void flush();

 private:
  std::filesystem::path dir_;
  CameraIntrinsics camera_;
  std::map<int, Fingertips> groundtruth_;
  std::map<int, Joints> joints_;
};

std::filesystem::path frame_file(const std::filesystem::path& dir, int frame);  // dir/NNNNNN.png

}  // namespace handtrack
