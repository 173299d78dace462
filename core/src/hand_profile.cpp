// The hand profile file (hand_calibration.hpp): the scale handtrack-calibrate found, as JSON. Apart
// from the calibration, in handtrack::core_files with the project's other file readers.
#include "handtrack/core/hand_calibration.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <stdexcept>
#include <string>

namespace handtrack {

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
