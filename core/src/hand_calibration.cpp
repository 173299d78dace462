#include "handtrack/core/hand_calibration.hpp"

#include "handtrack/core/optimizer.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <limits>
#include <stdexcept>

namespace handtrack {

namespace {

// Pixel rectangle [u0, u1] x [v0, v1].
struct PixelBox {
  int u0 = std::numeric_limits<int>::max(), v0 = std::numeric_limits<int>::max(), u1 = -1, v1 = -1;
  void add(int u, int v) {
    u0 = std::min(u0, u);
    v0 = std::min(v0, v);
    u1 = std::max(u1, u);
    v1 = std::max(v1, v);
  }
};

// Depth of the model's surface seen from the camera, per pixel (+inf where no model): the union of
// the Gaussians' 1-sigma spheres, the surface of Sec. 3.2. A sphere (centre mu, radius sigma_h)
// seen at pixel x lies at depth z - sqrt(sigma_h^2 - rho^2), rho = |x - mu_p| z / f in mm.
// `box` grows to hold every pixel drawn.
void render_model_depth(const HandModel& model, const PosedHand& hand, const CameraIntrinsics& cam,
                        std::vector<float>& depth_mm, PixelBox& box) {
  depth_mm.assign(static_cast<size_t>(cam.width) * cam.height, std::numeric_limits<float>::infinity());
  const double f = cam.focal();
  for (int p = 0; p < hand.gaussian_count(); ++p) {
    const Eigen::Vector3d& mu = hand.centre(p);
    if (mu.z() < 1.0) continue;
    const double sigma_h = model.gaussians()[static_cast<size_t>(p)].sigma_mm;
    const Eigen::Vector2d uv = cam.project(mu);
    const double r_px = sigma_h * f / mu.z();
    const int u0 = std::max(0, static_cast<int>(std::floor(uv.x() - r_px)));
    const int u1 = std::min(cam.width - 1, static_cast<int>(std::ceil(uv.x() + r_px)));
    const int v0 = std::max(0, static_cast<int>(std::floor(uv.y() - r_px)));
    const int v1 = std::min(cam.height - 1, static_cast<int>(std::ceil(uv.y() + r_px)));
    for (int v = v0; v <= v1; ++v) {
      for (int u = u0; u <= u1; ++u) {
        const double rho2_px = (u - uv.x()) * (u - uv.x()) + (v - uv.y()) * (v - uv.y());
        const double rho2_mm = rho2_px * (mu.z() / f) * (mu.z() / f);
        if (rho2_mm > sigma_h * sigma_h) continue;
        auto& d = depth_mm[static_cast<size_t>(v) * cam.width + u];
        d = std::min(d, static_cast<float>(mu.z() - std::sqrt(sigma_h * sigma_h - rho2_mm)));
        box.add(u, v);
      }
    }
  }
}

// One pass of a (2r+1) square filter along rows (du = 1) or columns, inside `box`: `nearest`
// keeps the minimum depth (grey dilation of the surface), otherwise the maximum (erosion).
void square_filter_pass(std::vector<float>& depth_mm, std::vector<float>& tmp, int width, const PixelBox& box, int r,
                        bool along_rows, bool nearest) {
  tmp = depth_mm;
  for (int v = box.v0; v <= box.v1; ++v) {
    for (int u = box.u0; u <= box.u1; ++u) {
      float m = nearest ? std::numeric_limits<float>::infinity() : -std::numeric_limits<float>::infinity();
      for (int k = -r; k <= r; ++k) {
        const int uu = along_rows ? std::clamp(u + k, box.u0, box.u1) : u;
        const int vv = along_rows ? v : std::clamp(v + k, box.v0, box.v1);
        const float d = tmp[static_cast<size_t>(vv) * width + uu];
        m = nearest ? std::min(m, d) : std::max(m, d);
      }
      depth_mm[static_cast<size_t>(v) * width + u] = m;
    }
  }
}

// Grey closing of the rendered surface (dilate by the nearest depth, then erode): fills the gaps
// narrower than 2r + 1 pixels between neighbouring spheres (between the two Gaussians of a long
// bone, and between the palm's nine) that a hand's skin does not have.
void close_gaps(std::vector<float>& depth_mm, std::vector<float>& tmp, const CameraIntrinsics& cam, PixelBox box, int r) {
  box = {std::max(0, box.u0 - r), std::max(0, box.v0 - r), std::min(cam.width - 1, box.u1 + r),
         std::min(cam.height - 1, box.v1 + r)};
  for (const bool nearest : {true, false}) {
    square_filter_pass(depth_mm, tmp, cam.width, box, r, true, nearest);
    square_filter_pass(depth_mm, tmp, cam.width, box, r, false, nearest);
  }
}

void check_grid(const std::vector<CalibrationFrame>& frames, const CalibrationConfig& config) {
  if (frames.empty()) throw std::invalid_argument("hand calibration: no frames (was the hand tracked?)");
  for (const auto& f : frames) {
    if (f.input == nullptr || !f.input->has_hand()) throw std::invalid_argument("hand calibration: a frame without a hand");
  }
  if (!(config.lo > 0.0 && config.lo <= 1.0 && config.hi >= 1.0 && config.step > 0.0 && config.rounds >= 1 &&
        config.iterations >= 0)) {
    throw std::invalid_argument("hand calibration: the grid needs 0 < lo <= 1 <= hi, step > 0, rounds >= 1");
  }
}

}  // namespace

double depth_agreement_iou(const HandModel& model, const PosedHand& hand, const DepthInput& input,
                           std::vector<float>& scratch) {
  PixelBox box;
  render_model_depth(model, hand, input.camera, scratch, box);
  if (box.u1 < 0) return 0.0;
  const int r = std::max(1, static_cast<int>(std::lround(kGapClosingPx * input.camera.width / 320.0)));
  std::vector<float> tmp;
  close_gaps(scratch, tmp, input.camera, box, r);
  // Data below the model's wrist (the stub of forearm segmentation keeps) is no part of the hand.
  const Eigen::Vector3d wrist = hand.joints()[kWristJoint];
  const Eigen::Vector3d axis = (hand.joints()[joint_index(kMiddle, 0)] - wrist).normalized();
  const auto& cam = input.camera;
  int agree = 0;
  int either = 0;
  for (size_t i = 0; i < scratch.size(); ++i) {
    const bool data = input.hand_mask[i] != 0 &&
                      (cam.unproject(static_cast<double>(i % cam.width), static_cast<double>(i / cam.width),
                                     input.filtered_mm[i]) - wrist).dot(axis) >= 0.0;
    const bool surface = std::isfinite(scratch[i]);
    if (!data && !surface) continue;
    ++either;
    if (data && surface && std::abs(scratch[i] - input.filtered_mm[i]) < kDepthAgreementMm) ++agree;
  }
  return either > 0 ? static_cast<double>(agree) / either : 0.0;
}

CalibrationResult calibrate_hand_scale(const std::vector<CalibrationFrame>& frames, const TrackerConfig& tracker,
                                       const CalibrationConfig& config) {
  check_grid(frames, config);
  const PoseEnergy energy(SimilarityFactor::kDepth, tracker.weights);
  const AdaptiveGradientAscent optimizer(tracker.optimizer);
  PosedHand scratch;
  std::vector<float> rendered;

  // Re-fits every frame's pose for `scale` from `poses` (updated in place) and returns the mean score.
  const auto fit_and_score = [&](const HandScale& scale, std::vector<PoseParams>& poses) {
    const HandModel model = HandModel::default_adult(scale);
    double total = 0.0;
    for (size_t i = 0; i < frames.size(); ++i) {
      const EnergyFrame frame{&model, frames[i].input, nullptr, nullptr};
      poses[i] = optimizer.maximise(energy, frame, poses[i], scratch, config.iterations).params;
      scratch.update(model, poses[i]);
      total += depth_agreement_iou(model, scratch, *frames[i].input, rendered);
    }
    return total / static_cast<double>(frames.size());
  };

  CalibrationResult result;
  result.scale = tracker.scale;
  std::vector<PoseParams> best_poses;
  for (const auto& f : frames) best_poses.push_back(f.pose);
  result.score = fit_and_score(result.scale, best_poses);
  result.evaluations = 1;

  // One greedy line search: from the current best value outward, up to hi and then down to lo, each
  // grid point warm-started from the poses of its neighbour nearer the current value.
  const auto line_search = [&](double HandScale::*member) {
    const double start = result.scale.*member;
    const int up = static_cast<int>(std::floor((config.hi - start) / config.step + 1e-9));
    const int down = static_cast<int>(std::floor((start - config.lo) / config.step + 1e-9));
    CalibrationResult best = result;
    std::vector<PoseParams> poses_of_best = best_poses;
    for (const int direction : {+1, -1}) {
      std::vector<PoseParams> poses = best_poses;
      HandScale trial = result.scale;
      for (int k = 1; k <= (direction > 0 ? up : down); ++k) {
        trial.*member = start + direction * k * config.step;
        const double s = fit_and_score(trial, poses);
        ++best.evaluations;
        if (s > best.score) {
          best.score = s;
          best.scale = trial;
          poses_of_best = poses;
        }
      }
    }
    result = best;
    best_poses = poses_of_best;
  };
  const std::array<double HandScale::*, 3> parameters = {&HandScale::length, &HandScale::width, &HandScale::sigma};
  for (int round = 0; round < config.rounds; ++round) {
    for (const auto member : parameters) line_search(member);
  }
  return result;
}

bool CalibrationSet::offer(const DepthImage& depth, const TrackerOutput& tracked, const std::optional<HandHint>& hint) {
  ++since_kept_;
  if (full() || !hint || tracked.state != TrackingState::kTracking || tracked.confidence < options_.min_confidence ||
      (!inputs_.empty() && since_kept_ < options_.stride)) {
    return false;
  }
  HandHint slack = *hint;
  slack.wrist_mm -= kWristSlackMm * slack.finger_axis;
  DepthInputBuilder builder(input_config_);
  const auto& input = builder.build(depth, slack);
  if (!input.has_hand()) return false;
  inputs_.push_back(input);
  poses_.push_back(tracked.params);
  since_kept_ = 0;
  return true;
}

std::vector<CalibrationFrame> CalibrationSet::frames() const {
  std::vector<CalibrationFrame> out;
  for (size_t i = 0; i < inputs_.size(); ++i) out.push_back({&inputs_[i], poses_[i]});
  return out;
}

void save_hand_profile(const std::filesystem::path& file, const HandScale& scale) {
  const nlohmann::json j = {{"hand_length", scale.length}, {"hand_width", scale.width}, {"gaussian_sigma", scale.sigma}};
  std::ofstream out(file);
  if (!out) throw std::runtime_error(file.string() + ": cannot write the hand profile");
  out << j.dump(1) << "\n";
  if (!out) throw std::runtime_error(file.string() + ": write failed");
}

HandScale load_hand_profile(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error(file.string() + ": cannot open the hand profile");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception&) {
    throw std::runtime_error(file.string() + ": not a JSON hand profile (handtrack-calibrate writes one)");
  }
  if (!j.is_object()) throw std::runtime_error(file.string() + ": a hand profile is a JSON object");
  HandScale scale;
  const auto field = [&](const char* name, double& value) {
    if (!j.contains(name) || !j[name].is_number()) {
      throw std::runtime_error(file.string() + ": field '" + std::string(name) + "' missing or not a number");
    }
    value = j[name].get<double>();
    if (!(std::isfinite(value) && value >= kMinProfileScale && value <= kMaxProfileScale)) {
      throw std::runtime_error(file.string() + ": field '" + std::string(name) + "' must be within [0.5, 2], got " +
                               j[name].dump());
    }
  };
  field("hand_length", scale.length);
  field("hand_width", scale.width);
  field("gaussian_sigma", scale.sigma);
  return scale;
}

}  // namespace handtrack
