#include "handtrack/core/sequence.hpp"

#include "file_error.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace handtrack {
namespace fs = std::filesystem;
namespace {

double number_field(const nlohmann::json& j, const fs::path& file, const char* field, bool required,
                    double fallback) {
  if (!j.contains(field)) {
    if (required) throw_file_error(file, std::string("missing field '") + field + "'");
    return fallback;
  }
  if (!j[field].is_number()) throw_file_error(file, std::string("field '") + field + "' must be a number");
  return j[field].get<double>();
}

// Parses one CSV line into cells ("" for an empty cell).
std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> cells;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, ',')) cells.push_back(cell);
  if (!line.empty() && line.back() == ',') cells.emplace_back();
  for (auto& c : cells) {
    c.erase(0, c.find_first_not_of(" \t\r"));
    c.erase(c.find_last_not_of(" \t\r") + 1);
  }
  return cells;
}

std::optional<double> parse_cell(const std::string& cell, const fs::path& file, size_t line) {
  if (cell.empty()) return std::nullopt;
  size_t used = 0;
  double v = 0;
  try {
    v = std::stod(cell, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != cell.size() || !std::isfinite(v)) {
    throw_file_error(file, "line " + std::to_string(line) + ": '" + cell + "' is not a number");
  }
  return v;
}

// Frame numbers are ints written as NNNNNN (SPEC.md); the largest a file name or CSV row may hold.
constexpr int kMaxFrameNumber = 999'999'999;

// Reads a CSV whose rows are: frame, then `per_hand` numbers (possibly empty) for each of `hands`
// hands. Calls row(frame, cells).
template <typename RowFn>
void read_csv(const fs::path& file, size_t per_hand, size_t hands, RowFn&& row) {
  const size_t values = per_hand * hands;
  std::ifstream in(file);
  if (!in) throw_file_error(file, "cannot open");
  std::string line;
  size_t n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (line.empty() || line == "\r") continue;
    auto cells = split_csv(line);
    if (n == 1 && !cells.empty() && cells[0] == "frame") continue;  // header
    if (cells.size() != values + 1) {
      std::string why = "line " + std::to_string(n) + ": expected " + std::to_string(values + 1) + " cells, found " +
                        std::to_string(cells.size());
      if (hands > 1) {
        why += " (the frame, then " + std::to_string(per_hand) + " per hand for the " + std::to_string(hands) +
               " hands hand.json names)";
      } else if (cells.size() > 1 && (cells.size() - 1) % per_hand == 0) {
        why += " (" + std::to_string((cells.size() - 1) / per_hand) + " hands' columns: hand.json must name them)";
      }
      throw_file_error(file, why);
    }
    const auto frame = parse_cell(cells[0], file, n);
    if (!frame || *frame < 0 || *frame > kMaxFrameNumber || *frame != std::floor(*frame)) {
      throw_file_error(file, "line " + std::to_string(n) + ": bad frame (a whole number in [0, " +
                       std::to_string(kMaxFrameNumber) + "])");
    }
    std::vector<std::optional<double>> parsed;
    for (size_t i = 1; i < cells.size(); ++i) parsed.push_back(parse_cell(cells[i], file, n));
    row(static_cast<int>(*frame), parsed);
  }
}

std::string header(bool joints, int hands) {
  std::string h = "frame";
  const int count = joints ? kNumJoints : kNumFingers;
  for (int hand = 0; hand < hands; ++hand) {
    for (int i = 0; i < count; ++i) {
      const std::string stem = hand_column_prefix(hand) +
                               std::string(joints ? joint_name(i) : kFingerNames[static_cast<size_t>(i)]);
      for (const char* axis : {"_x", "_y", "_z"}) h += "," + stem + axis;
    }
  }
  return h;
}

// Cells first..first + 2 as a point, if all three are given.
std::optional<Eigen::Vector3d> point(const std::vector<std::optional<double>>& v, size_t first) {
  if (!v[first] || !v[first + 1] || !v[first + 2]) return std::nullopt;
  return Eigen::Vector3d(*v[first], *v[first + 1], *v[first + 2]);
}

constexpr size_t kTipValues = 3 * kNumFingers;  // per hand in groundtruth.csv
constexpr size_t kJointValues = 3 * kNumJoints;  // per hand in joints.csv

bool valid_hand_name(const std::string& name) { return name == "right" || name == "left"; }

void write_vec(std::ostream& out, const Eigen::Vector3d& v) {
  char buf[96];
  std::snprintf(buf, sizeof buf, ",%.3f,%.3f,%.3f", v.x(), v.y(), v.z());
  out << buf;
}

}  // namespace

fs::path frame_file(const fs::path& dir, int frame) {
  char name[32];
  std::snprintf(name, sizeof name, "%06d.png", frame);
  return dir / name;
}

CameraIntrinsics read_camera_json(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw_file_error(file, "cannot open (every sequence directory needs a camera.json)");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw_file_error(file, std::string("not valid JSON: ") + e.what());
  }
  if (!j.is_object()) throw_file_error(file, "expected a JSON object");
  CameraIntrinsics c;
  const double w = number_field(j, file, "width", true, 0);
  const double h = number_field(j, file, "height", true, 0);
  if (w != std::floor(w) || h != std::floor(h) || w < 1 || h < 1 || w > 8192 || h > 8192) {
    throw_file_error(file, "fields 'width' and 'height' must be whole numbers in [8, 8192]");
  }
  c.width = static_cast<int>(w);
  c.height = static_cast<int>(h);
  c.fx = number_field(j, file, "fx", true, 0);
  c.fy = number_field(j, file, "fy", true, 0);
  c.cx = number_field(j, file, "cx", true, 0);
  c.cy = number_field(j, file, "cy", true, 0);
  c.depth_scale_mm = number_field(j, file, "depth_scale_mm", false, 1.0);
  c.fps = number_field(j, file, "fps", false, 30.0);
  if (auto why = c.problem(); !why.empty()) throw_file_error(file, why);
  return c;
}

std::string hand_column_prefix(int hand) {
  if (hand == 0) return {};
  // Appended piecewise: gcc 12's -Wrestrict misfires on "h" + std::to_string(hand) + "_".
  std::string prefix = "h";
  prefix += std::to_string(hand);
  prefix += '_';
  return prefix;
}

std::vector<std::string> read_hand_json(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw_file_error(file, "cannot open");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw_file_error(file, std::string("not valid JSON: ") + e.what());
  }
  const std::string expected = "field 'hands' must list 1 to " + std::to_string(kMaxSequenceHands) +
                               " of \"right\" and \"left\", e.g. {\"hands\":[\"right\",\"left\"]}";
  if (!j.is_object() || !j.contains("hands")) throw_file_error(file, "missing " + expected);
  const auto& list = j["hands"];
  if (!list.is_array() || list.empty() || list.size() > static_cast<size_t>(kMaxSequenceHands)) {
    throw_file_error(file, expected);
  }
  std::vector<std::string> hands;
  for (const auto& h : list) {
    if (!h.is_string() || !valid_hand_name(h.get<std::string>())) throw_file_error(file, expected);
    hands.push_back(h.get<std::string>());
  }
  return hands;
}

void write_hand_json(const fs::path& file, const std::vector<std::string>& hands,
                     const std::vector<std::pair<std::string, std::string>>& extra) {
  nlohmann::json j = {{"hands", hands}};
  for (const auto& [key, value] : extra) j[key] = value;
  std::ofstream out(file);
  if (!out) throw_file_error(file, "cannot write");
  out << j.dump() << "\n";
}

void write_camera_json(const fs::path& file, const CameraIntrinsics& c) {
  nlohmann::json j = {{"width", c.width}, {"height", c.height}, {"fx", c.fx},
                      {"fy", c.fy},       {"cx", c.cx},         {"cy", c.cy},
                      {"depth_scale_mm", c.depth_scale_mm},     {"fps", c.fps}};
  std::ofstream out(file);
  if (!out) throw_file_error(file, "cannot write");
  out << j.dump(1) << "\n";
}

SequenceReader::SequenceReader(fs::path dir, Annotations annotations) : dir_(std::move(dir)) {
  if (!fs::is_directory(dir_)) throw_file_error(dir_, "not a directory");
  camera_ = read_camera_json(dir_ / "camera.json");
  const fs::path depth_dir = dir_ / "depth";
  if (!fs::is_directory(depth_dir)) {
    throw_file_error(depth_dir, "missing (a sequence keeps its frames in depth/NNNNNN.png)");
  }
  for (const auto& entry : fs::directory_iterator(depth_dir)) {
    const auto name = entry.path().filename().string();
    if (entry.path().extension() != ".png") continue;
    const auto stem = entry.path().stem().string();
    if (stem.empty() || !std::all_of(stem.begin(), stem.end(), [](char ch) { return ch >= '0' && ch <= '9'; })) {
      continue;
    }
    // A longer name is refused rather than wrapped.
    if (stem.size() > 9) {
      throw_file_error(entry.path(),
                       "frame number " + stem + " is too large (at most " + std::to_string(kMaxFrameNumber) + ")");
    }
    frames_.push_back(std::stoi(stem));
  }
  std::sort(frames_.begin(), frames_.end());
  if (frames_.empty()) throw_file_error(depth_dir, "holds no NNNNNN.png frames");
  if (annotations == Annotations::kIgnore) return;

  if (const auto hj = dir_ / "hand.json"; fs::exists(hj)) hands_ = read_hand_json(hj);
  const auto hands = static_cast<size_t>(hand_count());
  if (const auto gt = dir_ / "groundtruth.csv"; fs::exists(gt)) {
    read_csv(gt, kTipValues, hands, [&](int frame, const std::vector<std::optional<double>>& v) {
      std::vector<Fingertips> per_hand(hands);
      for (size_t h = 0; h < hands; ++h) {
        for (size_t f = 0; f < kNumFingers; ++f) per_hand[h][f] = point(v, h * kTipValues + 3 * f);
      }
      groundtruth_[frame] = std::move(per_hand);
    });
  }
  if (const auto jf = dir_ / "joints.csv"; fs::exists(jf)) {
    read_csv(jf, kJointValues, hands, [&](int frame, const std::vector<std::optional<double>>& v) {
      std::vector<std::optional<Joints>> per_hand(hands);
      for (size_t h = 0; h < hands; ++h) {
        const size_t first = h * kJointValues;
        // A hand's block all empty: not annotated in this frame; partly empty: an error.
        if (std::none_of(v.begin() + static_cast<std::ptrdiff_t>(first),
                         v.begin() + static_cast<std::ptrdiff_t>(first + kJointValues),
                         [](const std::optional<double>& c) { return c.has_value(); })) {
          continue;
        }
        Joints joints;
        for (size_t k = 0; k < kNumJoints; ++k) {
          const auto p = point(v, first + 3 * k);
          if (!p) throw_file_error(jf, "frame " + std::to_string(frame) + ": empty cell");
          joints[k] = *p;
        }
        per_hand[h] = joints;
      }
      joints_[frame] = std::move(per_hand);
    });
  }
}

size_t SequenceReader::hand_slot(int hand) const {
  if (hand < 0 || hand >= hand_count()) {
    throw std::out_of_range(dir_.string() + ": no hand " + std::to_string(hand) + " (the sequence has " +
                            std::to_string(hand_count()) + ")");
  }
  return static_cast<size_t>(hand);
}

DepthImage SequenceReader::depth(size_t i) const {
  const auto file = frame_file(dir_ / "depth", frames_.at(i));
  const auto raw = read_png_gray16(file, PngSize{camera_.width, camera_.height});
  return DepthImage::from_raw(camera_, raw.pixels);
}

std::optional<Gray8Image> SequenceReader::labels(size_t i) const {
  const auto file = frame_file(dir_ / "labels", frames_.at(i));
  if (!fs::exists(file)) return std::nullopt;
  return read_png_gray8(file, PngSize{camera_.width, camera_.height});
}

Fingertips SequenceReader::fingertips(size_t i, int hand) const {
  const size_t h = hand_slot(hand);
  const auto it = groundtruth_.find(frames_.at(i));
  return it == groundtruth_.end() ? Fingertips{} : it->second[h];
}

std::optional<Joints> SequenceReader::joints(size_t i, int hand) const {
  const size_t h = hand_slot(hand);
  const auto it = joints_.find(frames_.at(i));
  if (it == joints_.end()) return std::nullopt;
  return it->second[h];
}

SequenceWriter::SequenceWriter(fs::path dir, const CameraIntrinsics& camera) : dir_(std::move(dir)), camera_(camera) {
  if (auto why = camera.problem(); !why.empty()) throw_file_error(dir_, "bad camera: " + why);
  fs::create_directories(dir_ / "depth");
  write_camera_json(dir_ / "camera.json", camera_);
}

SequenceWriter::~SequenceWriter() {
  try {
    flush();
  } catch (const std::exception&) {
    // Destructors must not throw; callers who care about CSV errors call flush() themselves.
  }
}

void SequenceWriter::write_depth(int frame, const DepthImage& depth) {
  write_depth_raw(frame, Gray16Image{depth.width(), depth.height(), 1, depth.to_raw()});
}

void SequenceWriter::write_depth_raw(int frame, const Gray16Image& raw) {
  write_png_gray16(frame_file(dir_ / "depth", frame), raw);
}

void SequenceWriter::write_labels(int frame, const Gray8Image& labels) {
  fs::create_directories(dir_ / "labels");
  write_png_gray8(frame_file(dir_ / "labels", frame), labels);
}

void SequenceWriter::write_hands(const std::vector<std::string>& hands,
                                 const std::vector<std::pair<std::string, std::string>>& extra) {
  if (hands.empty() || hands.size() > static_cast<size_t>(kMaxSequenceHands) ||
      !std::all_of(hands.begin(), hands.end(), valid_hand_name)) {
    throw std::invalid_argument("a sequence shows 1 to " + std::to_string(kMaxSequenceHands) +
                                " hands, each \"right\" or \"left\"");
  }
  if (static_cast<int>(hands.size()) < hand_count_) {
    throw std::invalid_argument("ground truth of " + std::to_string(hand_count_) + " hands was written already");
  }
  hand_count_ = static_cast<int>(hands.size());
  write_hand_json(dir_ / "hand.json", hands, extra);
}

size_t SequenceWriter::hand_slot(int hand) const {
  if (hand < 0 || hand >= hand_count_) {
    throw std::out_of_range(dir_.string() + ": no hand " + std::to_string(hand) + " (write_hands() names " +
                            std::to_string(hand_count_) + ")");
  }
  return static_cast<size_t>(hand);
}

void SequenceWriter::write_fingertips(int frame, const Fingertips& tips, int hand) {
  const size_t h = hand_slot(hand);
  auto& row = groundtruth_[frame];
  row.resize(static_cast<size_t>(kMaxSequenceHands));
  row[h] = tips;
}

void SequenceWriter::write_joints(int frame, const Joints& joints, int hand) {
  const size_t h = hand_slot(hand);
  auto& row = joints_[frame];
  row.resize(static_cast<size_t>(kMaxSequenceHands));
  row[h] = joints;
}

void SequenceWriter::flush() {
  // One block per hand in each row; a hand without ground truth in a frame gets empty cells.
  const auto hands = static_cast<size_t>(hand_count_);
  if (!groundtruth_.empty()) {
    std::ofstream out(dir_ / "groundtruth.csv");
    if (!out) throw_file_error(dir_ / "groundtruth.csv", "cannot write");
    out << header(false, hand_count_) << "\n";
    for (const auto& [frame, per_hand] : groundtruth_) {
      out << frame;
      for (size_t h = 0; h < hands; ++h) {
        for (const auto& tip : per_hand[h].value_or(Fingertips{})) {
          if (tip) write_vec(out, *tip);
          else out << ",,,";
        }
      }
      out << "\n";
    }
  }
  if (!joints_.empty()) {
    std::ofstream out(dir_ / "joints.csv");
    if (!out) throw_file_error(dir_ / "joints.csv", "cannot write");
    out << header(true, hand_count_) << "\n";
    for (const auto& [frame, per_hand] : joints_) {
      out << frame;
      for (size_t h = 0; h < hands; ++h) {
        if (per_hand[h]) {
          for (const auto& j : *per_hand[h]) write_vec(out, j);
        } else {
          for (int k = 0; k < kNumJoints; ++k) out << ",,,";
        }
      }
      out << "\n";
    }
  }
}

}  // namespace handtrack
