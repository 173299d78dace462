#include "handtrack/core/hand_calibration.hpp"

#include "handtrack/core/optimizer.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <stdexcept>

namespace handtrack {

namespace {

// How well the model's outline matches the segmented hand: the intersection over union of the
// hand mask and the model's silhouette (every Gaussian's 1-sigma disc, radius sigma_h f / z, the
// surface of Sec. 3.2). Eq. 2's E_sim is normalised by E(C_I, C_I) alone and grows with the model
// (bigger Gaussians overlap more data), so it cannot choose a size; the IoU is largest when the
// model covers the hand and no more.
double silhouette_iou(const HandModel& model, const PosedHand& hand, const DepthInput& input,
                      std::vector<uint8_t>& silhouette) {
  const auto& cam = input.camera;
  silhouette.assign(input.hand_mask.size(), 0);
  for (int i = 0; i < hand.gaussian_count(); ++i) {
    const auto& mu = hand.centre(i);
    if (mu.z() < 1.0) continue;
    const auto uv = cam.project(mu);
    const double r = model.gaussians()[static_cast<size_t>(i)].sigma_mm * cam.focal() / mu.z();
    const int u0 = std::max(0, static_cast<int>(std::floor(uv.x() - r)));
    const int u1 = std::min(cam.width - 1, static_cast<int>(std::ceil(uv.x() + r)));
    const int v0 = std::max(0, static_cast<int>(std::floor(uv.y() - r)));
    const int v1 = std::min(cam.height - 1, static_cast<int>(std::ceil(uv.y() + r)));
    for (int v = v0; v <= v1; ++v) {
      for (int u = u0; u <= u1; ++u) {
        const double du = u - uv.x();
        const double dv = v - uv.y();
        if (du * du + dv * dv <= r * r) silhouette[static_cast<size_t>(v) * cam.width + u] = 1;
      }
    }
  }
  int both = 0;
  int either = 0;
  for (size_t i = 0; i < silhouette.size(); ++i) {
    both += (silhouette[i] && input.hand_mask[i]) ? 1 : 0;
    either += (silhouette[i] || input.hand_mask[i]) ? 1 : 0;
  }
  return either > 0 ? static_cast<double>(both) / either : 0.0;
}

}  // namespace

CalibrationResult calibrate_hand_scale(const std::vector<CalibrationFrame>& frames, const TrackerConfig& tracker,
                                       const CalibrationConfig& config) {
  EnergyWeights weights = tracker.weights;
  const PoseEnergy energy(SimilarityFactor::kDepth, weights);
  const AdaptiveGradientAscent optimizer(tracker.optimizer);
  PosedHand scratch;
  // Each frame's pose is re-fitted with eq. 2 for the scaled model; the fit is then scored with
  // the silhouette IoU, summed over the frames.
  std::vector<uint8_t> silhouette;
  const auto score = [&](const HandScale& scale) {
    const HandModel model = HandModel::default_adult(scale);
    double total = 0.0;
    for (const auto& f : frames) {
      const EnergyFrame frame{&model, f.input, nullptr, nullptr};
      const auto fit = optimizer.maximise(energy, frame, f.pose, scratch, config.iterations);
      scratch.update(model, fit.params);
      total += silhouette_iou(model, scratch, *f.input, silhouette);
    }
    return total;
  };
  CalibrationResult result;
  result.scale = tracker.scale;
  result.energy = score(result.scale);
  result.evaluations = 1;
  const std::array<double HandScale::*, 3> parameters = {&HandScale::length, &HandScale::width, &HandScale::sigma};
  for (int round = 0; round < config.rounds; ++round) {
    for (const auto member : parameters) {
      HandScale trial = result.scale;
      for (double v = config.lo; v <= config.hi + 1e-9; v += config.step) {
        trial.*member = v;
        const double e = score(trial);
        ++result.evaluations;
        if (e > result.energy) {
          result.energy = e;
          result.scale = trial;
        }
      }
    }
  }
  return result;
}

void save_hand_profile(const std::filesystem::path& file, const HandScale& scale) {
  const nlohmann::json j = {{"hand_length", scale.length}, {"hand_width", scale.width}, {"gaussian_sigma", scale.sigma}};
  std::ofstream out(file);
  if (!out) throw std::runtime_error(file.string() + ": cannot write");
  out << j.dump(1) << "\n";
}

HandScale load_hand_profile(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error(file.string() + ": cannot open hand profile");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(file.string() + ": not valid JSON: " + e.what());
  }
  HandScale scale;
  const auto field = [&](const char* name, double& value) {
    if (!j.is_object() || !j.contains(name) || !j[name].is_number()) {
      throw std::runtime_error(file.string() + ": field '" + name + "' missing or not a number");
    }
    value = j[name].get<double>();
    if (!(std::isfinite(value) && value >= 0.5 && value <= 2.0)) {
      throw std::runtime_error(file.string() + ": field '" + name + "' must be in [0.5, 2], got " + std::to_string(value));
    }
  };
  field("hand_length", scale.length);
  field("hand_width", scale.width);
  field("gaussian_sigma", scale.sigma);
  return scale;
}

}  // namespace handtrack
