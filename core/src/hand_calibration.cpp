#include "handtrack/core/hand_calibration.hpp"

#include "handtrack/core/optimizer.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace handtrack {

namespace {

// The model's surface seen from the camera: per pixel the depth of its front (mm, +inf where none)
// and how much of the pixel it covers (0..1, anti-aliased over the outline's last pixel, so that the
// score moves smoothly with scale changes far below a pixel: 5 % of a finger's width is ~0.3 px at
// 320x240 and 450 mm). Only the rectangle [u0, u1] x [v0, v1] is drawn on.
struct ModelSurface {
  std::vector<float> depth_mm;
  std::vector<float> coverage;
  int u0 = 0, v0 = 0, u1 = -1, v1 = -1;  // the rectangle drawn on since the last clear()

  void clear(const CameraIntrinsics& cam) {
    const auto size = static_cast<size_t>(cam.width) * cam.height;
    if (depth_mm.size() != size) {
      depth_mm.assign(size, std::numeric_limits<float>::infinity());
      coverage.assign(size, 0.0F);
    }
    for (int v = v0; v <= v1; ++v) {
      const auto row = static_cast<ptrdiff_t>(v) * cam.width;
      std::fill(depth_mm.begin() + row + u0, depth_mm.begin() + row + u1 + 1, std::numeric_limits<float>::infinity());
      std::fill(coverage.begin() + row + u0, coverage.begin() + row + u1 + 1, 0.0F);
    }
    u0 = cam.width;
    v0 = cam.height;
    u1 = v1 = -1;
  }
};

// Draws one sphere (centre c, radius r, camera frame): at pixel x it lies at depth
// z - sqrt(r^2 - rho^2), rho = |x - c_p| z / f in mm, and covers the pixel by
// clamp(r_px - rho_px + 1/2, 0, 1).
void draw_sphere(const Eigen::Vector3d& c, double r, const CameraIntrinsics& cam, ModelSurface& surface) {
  if (c.z() < 1.0) return;
  const Eigen::Vector2d uv = cam.project(c);
  const double mm2_per_px2 = (c.z() / cam.focal()) * (c.z() / cam.focal());
  const double r_px = r * cam.focal() / c.z();
  const double reach2 = (r_px + 0.5) * (r_px + 0.5);  // beyond: no coverage
  const double full2 = r_px > 0.5 ? (r_px - 0.5) * (r_px - 0.5) : 0.0;  // within: full coverage
  const int v0 = std::max(0, static_cast<int>(std::ceil(uv.y() - r_px - 0.5)));
  const int v1 = std::min(cam.height - 1, static_cast<int>(std::floor(uv.y() + r_px + 0.5)));
  for (int v = v0; v <= v1; ++v) {
    const double dv2 = (v - uv.y()) * (v - uv.y());
    const double half = std::sqrt(std::max(0.0, reach2 - dv2));
    const int u0 = std::max(0, static_cast<int>(std::ceil(uv.x() - half)));
    const int u1 = std::min(cam.width - 1, static_cast<int>(std::floor(uv.x() + half)));
    if (u0 > u1) continue;
    surface.u0 = std::min(surface.u0, u0);
    surface.u1 = std::max(surface.u1, u1);
    surface.v0 = std::min(surface.v0, v);
    surface.v1 = std::max(surface.v1, v);
    for (int u = u0; u <= u1; ++u) {
      const double rho2_px = (u - uv.x()) * (u - uv.x()) + dv2;
      const double covered = rho2_px <= full2 ? 1.0 : r_px - std::sqrt(rho2_px) + 0.5;
      if (covered <= 0.0) continue;
      const size_t i = static_cast<size_t>(v) * cam.width + u;
      const auto front = static_cast<float>(c.z() - std::sqrt(std::max(0.0, r * r - rho2_px * mm2_per_px2)));
      surface.depth_mm[i] = std::min(surface.depth_mm[i], front);
      surface.coverage[i] = std::max(surface.coverage[i], static_cast<float>(covered));
    }
  }
}

// Draws the solid swept by a sphere from (a, ra) to (b, rb), radius interpolated: spheres spaced at
// most half the smaller radius apart, so the outline's scallops stay under 3 % of the radius
// (sagitta r - sqrt(r^2 - (r/4)^2)).
void draw_sweep(const Eigen::Vector3d& a, double ra, const Eigen::Vector3d& b, double rb, const CameraIntrinsics& cam,
                ModelSurface& surface) {
  const int n = 1 + static_cast<int>(std::ceil((b - a).norm() / (0.5 * std::min(ra, rb))));
  for (int k = 0; k <= n; ++k) {
    const double t = static_cast<double>(k) / n;
    draw_sphere(a + t * (b - a), ra + t * (rb - ra), cam, surface);
  }
}

// Two palm Gaussians are neighbours when their 1-sigma spheres come within 0.3 (sigma_a + sigma_b)
// of touching: in the default model, the nearest ones within and between the palm's three rows,
// which triangulate it. Scale-invariant (positions and sigmas scale together up to the
// length/width ratio).
constexpr double kPalmNeighbourRatio = 1.3;

constexpr double kDepthAgreementMm = 10.0;  // data and model surface at one pixel: the same skin

// The Gaussians' 1-sigma spheres are the model's surface (Sec. 3.2), but alone they leave the hand
// full of holes (two Gaussians per bone, 5 mm apart at the knuckles), and any score that counts
// pixels then prefers fatter models. So the spheres are swept: along each finger from its base
// joint through its Gaussians in order (a finger is a chain of cone-spheres), and between
// neighbouring palm Gaussians.
void render_model(const HandModel& model, const PosedHand& hand, const CameraIntrinsics& cam, ModelSurface& surface) {
  surface.clear(cam);
  const auto& gaussians = model.gaussians();
  const auto sigma = [&](int p) { return gaussians[static_cast<size_t>(p)].sigma_mm; };
  std::array<int, kNumFingers> previous{};
  previous.fill(-1);
  std::vector<int> palm;
  for (int p = 0; p < hand.gaussian_count(); ++p) {
    const int bone = gaussians[static_cast<size_t>(p)].bone;
    if (bone == kPalmBone) {
      palm.push_back(p);
      continue;
    }
    const int f = bone / kBonesPerFinger;
    const int q = previous[static_cast<size_t>(f)];
    if (q < 0) {
      draw_sweep(hand.joints()[joint_index(f, 0)], sigma(p), hand.centre(p), sigma(p), cam, surface);
    } else {
      draw_sweep(hand.centre(q), sigma(q), hand.centre(p), sigma(p), cam, surface);
    }
    previous[static_cast<size_t>(f)] = p;
  }
  for (size_t i = 0; i < palm.size(); ++i) {
    for (size_t j = i + 1; j < palm.size(); ++j) {
      const int a = palm[i];
      const int b = palm[j];
      if ((hand.centre(a) - hand.centre(b)).norm() < kPalmNeighbourRatio * (sigma(a) + sigma(b))) {
        draw_sweep(hand.centre(a), sigma(a), hand.centre(b), sigma(b), cam, surface);
      }
    }
  }
}

void check_grid(const std::vector<CalibrationFrame>& frames, const CalibrationConfig& config) {
  if (!(config.lo > 0.0 && config.lo <= 1.0 && config.hi >= 1.0 && config.step > 0.0 && config.rounds >= 1 &&
        config.refine_steps >= 1 && config.iterations >= 0)) {
    throw std::invalid_argument(
        "hand calibration: the grid needs 0 < lo <= 1 <= hi, step > 0, rounds >= 1, refine_steps >= 1");
  }
  if (frames.empty()) throw std::invalid_argument("hand calibration: no frames (was the hand tracked?)");
  for (const auto& f : frames) {
    if (f.input == nullptr || !f.input->has_hand()) throw std::invalid_argument("hand calibration: a frame without a hand");
  }
}

// The score of one posed model on one frame: 1 - |model xor data| / |hand mask|, the area where
// model and data disagree as a share of the hand. Data is the hand mask above the model's wrist (the
// stub of forearm segmentation keeps is no part of the hand); the model at a data pixel explains it
// where their depths agree within kDepthAgreementMm and spills over it elsewhere. With coverage a
// in 0..1, a pixel costs a without data, 1 - a with agreeing data, and 1 + a with disagreeing data.
// An area difference, unlike an IoU, is not biased toward bigger models: growing the outline by
// delta adds delta outside (cost) and as much inside (gain) where the model fits, while the IoU
// I/U grows whenever I and U grow alike.
double surface_agreement(const HandModel& model, const PosedHand& hand, const DepthInput& input,
                         ModelSurface& surface) {
  const auto& cam = input.camera;
  render_model(model, hand, cam, surface);
  const Eigen::Vector3d wrist = hand.joints()[kWristJoint];
  const Eigen::Vector3d axis = (hand.joints()[joint_index(kMiddle, 0)] - wrist).normalized();
  double mismatch = 0.0;
  int hand_pixels = 0;
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const size_t i = static_cast<size_t>(v) * cam.width + u;
      const double covered = surface.coverage[i];
      if (input.hand_mask[i] != 0) ++hand_pixels;
      const bool data = input.hand_mask[i] != 0 && (cam.unproject(u, v, input.filtered_mm[i]) - wrist).dot(axis) >= 0.0;
      if (!data) {
        mismatch += covered;
      } else if (std::abs(surface.depth_mm[i] - input.filtered_mm[i]) < kDepthAgreementMm) {
        mismatch += 1.0 - covered;
      } else {
        mismatch += 1.0 + covered;
      }
    }
  }
  return hand_pixels > 0 ? 1.0 - mismatch / hand_pixels : 0.0;
}

// One grid point: re-fits each frame's pose for `scale` (`iterations` of eq. 2 from `poses`,
// updated in place) and returns the mean surface agreement over the frames. Eq. 2 as Sec. 6 says,
// without our E_free: a model larger than the hand would curl its fingers into the silhouette
// instead of overhanging it, and the score could not tell the scale (measured: every subject fitted
// at the bottom of the range); and without our coverage cap on E_sim, with which a model too wide
// for the hand lost less (a width 5.5 % off).
double fit_and_score(const std::vector<CalibrationFrame>& frames, const TrackerConfig& tracker, const HandScale& scale,
                     int iterations, std::vector<PoseParams>& poses) {
  EnergyWeights weights = tracker.weights;
  weights.free_space = 0.0;
  weights.coverage_cap = 0.0;
  const PoseEnergy energy(SimilarityFactor::kDepth, weights);
  const AdaptiveGradientAscent optimizer(tracker.optimizer);
  const HandModel model = HandModel::default_adult(scale);
  PosedHand hand;
  ModelSurface surface;
  double total = 0.0;
  for (size_t i = 0; i < frames.size(); ++i) {
    const EnergyFrame frame{&model, frames[i].input, nullptr, nullptr};
    poses[i] = optimizer.maximise(energy, frame, poses[i], hand, iterations).params;
    hand.update(model, poses[i]);
    total += surface_agreement(model, hand, *frames[i].input, surface);
  }
  return total / static_cast<double>(frames.size());
}

}  // namespace

TrackerConfig calibration_tracker_config(TrackerConfig config) {
  config.weights.smoothness = kPapersSmoothness;
  config.self_calibrate = false;  // the frames' poses are of the one model the search starts from
  return config;
}

CalibrationResult calibrate_hand_scale(const std::vector<CalibrationFrame>& frames, const TrackerConfig& tracker,
                                       const CalibrationConfig& config) {
  check_grid(frames, config);
  // The score of a grid point: the mean surface agreement less the prior on sigma / width.
  const auto score_of = [&](const HandScale& scale, std::vector<PoseParams>& poses) {
    const double log_ratio = std::log(scale.sigma / scale.width);
    return fit_and_score(frames, tracker, scale, config.iterations, poses) -
           kSigmaWidthPrior * log_ratio * log_ratio;
  };

  CalibrationResult result;
  result.scale = tracker.scale;
  std::vector<PoseParams> best_poses;
  for (const auto& f : frames) best_poses.push_back(f.pose);
  result.score = score_of(result.scale, best_poses);
  result.evaluations = 1;

  // One greedy line search: from the current best value outward, up to `reach` steps (within
  // [lo, hi]) each way, each grid point warm-started from the poses of its neighbour nearer the
  // current value. Sigma follows width in width's search (their ratio held), along the ridge the
  // prior makes: holding sigma instead, the prior pins width near sigma's current value and the
  // search creeps along the diagonal a step per round.
  const auto line_search = [&](double HandScale::*member, int reach) {
    const double start = result.scale.*member;
    const int up = std::min(reach, static_cast<int>(std::floor((config.hi - start) / config.step + 1e-9)));
    const int down = std::min(reach, static_cast<int>(std::floor((start - config.lo) / config.step + 1e-9)));
    CalibrationResult best = result;
    std::vector<PoseParams> poses_of_best = best_poses;
    for (const int direction : {+1, -1}) {
      std::vector<PoseParams> poses = best_poses;
      HandScale trial = result.scale;
      for (int k = 1; k <= (direction > 0 ? up : down); ++k) {
        trial.*member = start + direction * k * config.step;
        if (member == &HandScale::width) trial.sigma = result.scale.sigma * trial.width / start;
        const double s = score_of(trial, poses);
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
    for (const auto member : parameters) line_search(member, round == 0 ? std::numeric_limits<int>::max() : config.refine_steps);
  }
  return result;
}

bool CalibrationSet::offer(const DepthImage& depth, const TrackerOutput& tracked, const std::optional<HandHint>& hint) {
  return due(tracked, hint) && keep(depth, tracked, *hint);
}

bool CalibrationSet::due(const TrackerOutput& tracked, const std::optional<HandHint>& hint) {
  // The first kept frame too comes `stride` frames into tracking: a (re)start's own pose, straight
  // from the hypothesis search, is not yet refined by tracking, and calibrating on it moved a 1.10
  // subject's length to 1.025 when the search changed (init_iterations 40 -> 80).
  ++since_kept_;
  return !full() && hint && tracked.state == TrackingState::kTracking &&
         tracked.confidence >= options_.min_confidence && since_kept_ >= options_.stride;
}

bool CalibrationSet::keep(const DepthImage& depth, const TrackerOutput& tracked, const HandHint& hint) {
  HandHint slack = hint;
  slack.wrist_mm -= kWristSlackMm * slack.finger_axis;
  DepthInputConfig fine = input_config_;
  fine.quadtree_threshold_mm = kFineQuadtreeThresholdMm;
  fine.quadtree_min_leaf_px = 1;
  DepthInputBuilder builder(fine);
  const auto& input = builder.build(depth, slack);
  if (!input.has_hand()) return false;
  inputs_.push_back(input);
  poses_.push_back(tracked.params);
  since_kept_ = 0;
  return true;
}

void CalibrationSet::clear() {
  since_kept_ = 0;
  inputs_.clear();
  poses_.clear();
}

std::vector<CalibrationFrame> CalibrationSet::frames() const {
  std::vector<CalibrationFrame> out;
  for (size_t i = 0; i < inputs_.size(); ++i) out.push_back({&inputs_[i], poses_[i]});
  return out;
}

}  // namespace handtrack
